//! Implicit solvers for the CS184 mass-spring cloth, on faer's sparse Cholesky.
//!
//! Two solvers implement [`cloth_solver::Solver`]:
//!
//! - [`ImplicitEuler`] (`implicit`): backward Euler, each step minimising the same incremental
//!   potential as `fast-implicit` by Newton's method with a line search: each direction a
//!   conjugate gradient on the true Hessian (its indefinite parts clamped), preconditioned by
//!   the same constant prefactored matrix, which no motion of the cloth refactors.
//!   Unconditionally stable, accurate to first order in the step; for stiff cloths and one
//!   step per frame.
//! - [`FastImplicit`] (`fast-implicit`): the same backward-Euler step, minimised by L-BFGS with
//!   a line search over one constant, prefactored matrix (Liu et al. 2013's projective-dynamics
//!   matrix, as Liu, Bouaziz and Kavan 2017 use it), with contact and self-collision as
//!   penalties inside the minimisation; every iteration lowers the step's potential, and it
//!   stops on a tolerance or an iteration count. The cheapest stable option for large, stiff
//!   cloths.
//!
//! Each is offered by name through its registry entry ([`ImplicitEuler::ENTRY`],
//! [`FastImplicit::ENTRY`]), with its own options (`tolerance`, `iterations`).
//!
//! Both are meant to run at one step per frame, and both read the course's live parameters
//! ([`cloth_solver::StepParams`]): the damping becomes the drag rate
//! [`StepParams::drag_rate`](cloth_solver::StepParams::drag_rate), so it does not change with
//! the step (100 % is an infinite drag: the cloth holds still); the 10 % stretch limit is part
//! of the minimisation (an augmented term with a multiplier per spring, ADMM), and the course's
//! correction, swept until every spring is within the limit, ends the step (`fast_implicit.rs`
//! says how, and why neither adds energy). Both own only caches and scratch
//! memory (and the limit's multipliers, which a new solver starts at zero), so a live swap with
//! [`cloth_solver::Verlet`] keeps the cloth's motion; see [`retime_velocity`] for swaps that
//! change the step. Each states the memory it needs for a mesh (`memory_estimate`) and reports
//! a cloth too large for the machine as an error instead of aborting.
//!
//! # Friction
//!
//! The course's friction `f` keeps `1 - f` of a point's displacement in each of its steps
//! (`h_ref`, thirty a frame) in which the point crosses a collision object's surface. A point
//! pressed into an object and pulled along it by a force `F` crosses at every step and slides
//! at the speed where each step's pull is balanced by what friction takes, `(1 - f) / f * F
//! h_ref / m`. That is a drag, `m v' = F - c_f m v`, with the rate [`friction_rate`] `c_f = f /
//! ((1 - f) h_ref)`: it slides the point at `F / (m c_f)`, the same speed, at any step, and its
//! backward-Euler step keeps `1 / (1 + c_f h)` of the displacement, exactly the course's `1 -
//! f` at the course's step.
//!
//! The course's per-step friction applied after a large step cannot stand for that drag.
//! Applied once a step it lets a cloth slide off the sphere that the course's holds; retimed to
//! keep over one step what thirty keep (`(1 - f)^30`, a billionth on the plane) it glues every
//! touching point where it was, whatever pulls it: the collision undoes the solve's move of
//! the touching points, and stiff springs between a glued point and its free neighbours stay
//! stretched far past the limit for good. So both solvers put the drag into the step itself,
//! for the points that rest on an object at its start: such a point's mass term is `m (1 + (c +
//! c_f) h) / h^2` and its prediction `y = x0 + h v0 / (1 + (c + c_f) h)`, the stationarity
//! condition of backward Euler with that drag, so the solve moves the point together with the
//! springs that pull it. A point rests on an object when it starts the step within
//! [`CONTACT_DISTANCE`] of the surface and its prediction stays that near: a point lifting off
//! faster is free, as the course's is (its friction acts only on a point that crosses the
//! surface), while one that the collision has just put back at the surface offset, and that
//! therefore moves away by a fraction of the offset, still rests. The drag acts on all three
//! directions of a resting point, as the course's friction scales a point's whole
//! displacement; the collision then removes the part that went into the object.
//!
//! Both solvers put the objects and self-collision into the minimisation, and the drag on
//! every point whose prediction reaches an object (`fast_implicit.rs` says how and why).
//!
//! # Contact inside the step
//!
//! Both solvers minimise, in each step, the backward-Euler incremental potential plus one
//! one-sided penalty per free point and collision object (`k/2 min(0, s - delta)^2`, `s` the
//! point's distance to the surface on the side it starts the step on) and one per pair of
//! points closer than twice the thickness at the step's start or at their predictions (`k/2
//! min(0, |x_j - x_i| - 2 t)^2`), by L-BFGS with a line search that accepts only steps that
//! lower the potential. Each penalty is a function of the positions alone, zero away from
//! contact: a conservative potential, which the step's minimisation treats as it treats the
//! springs, so the step ends with a potential no higher than at its start and a contact gives
//! back no more energy than it stored. What it replaces, a position push after the solve,
//! moves a point without moving its previous position, which is a velocity of the push over
//! the step, made from nothing (hundreds of joules on the course's selfCollision cloth at one
//! step per frame). The only correction after the solve puts a point the penalty left inside an
//! object onto its surface and removes its velocity into the object: it takes kinetic energy
//! out. The stretch limit's multiplier update is the one part of the step that changes the
//! potential between iterations (the module documentation says why that is an argument, not a
//! proof). [`FastImplicit`] takes L-BFGS directions over the prefactored matrix,
//! [`ImplicitEuler`] Newton directions preconditioned by it; both only accept steps that lower
//! the potential.

mod cholesky;
mod commit;
mod contact;
mod entries;
mod fast_implicit;
mod implicit_euler;
mod lbfgs;
mod memory;
mod newton;
mod objective;
mod retime;
mod self_contact;
mod topology;

pub use contact::{CONTACT_DISTANCE, friction_rate, retime_friction};
pub use fast_implicit::{DEFAULT_ITERATIONS, FAST_TOLERANCE, FastImplicit, limit_weight};
pub use implicit_euler::{
    ImplicitEuler, MAX_NEWTON_ITERATIONS, MAX_PCG_ITERATIONS, NEWTON_TOLERANCE,
};
pub use retime::retime_velocity;
