//! Implicit solvers for the CS184 mass-spring cloth, on faer's sparse Cholesky.
//!
//! Two solvers implement [`cloth_solver::Solver`]:
//!
//! - [`ImplicitEuler`] (`implicit`): backward Euler, each step minimising the incremental
//!   potential by Newton's method with a line search. Unconditionally stable, accurate to first
//!   order in the step; for stiff cloths and one step per frame.
//! - [`FastImplicit`] (`fast-implicit`): Liu et al. 2013, "Fast Simulation of Mass-Spring
//!   Systems": the same backward-Euler step, approximated by local/global iterations with one
//!   constant, prefactored matrix, stopped on a tolerance or an iteration count. The cheapest
//!   stable option for large, stiff cloths.
//!
//! Each is offered by name through its registry entry ([`ImplicitEuler::ENTRY`],
//! [`FastImplicit::ENTRY`]), with its own options (`tolerance`, `iterations`).
//!
//! Both are meant to run at one step per frame, and both read the course's live parameters
//! ([`cloth_solver::StepParams`]): the damping becomes the drag rate
//! [`StepParams::drag_rate`](cloth_solver::StepParams::drag_rate), so it does not change with
//! the step (100 % is an infinite drag: the cloth holds still); the 10 % stretch limit is part
//! of the minimisation rather than the course's post-step sweep (a projection in the local step
//! for the fast solver, a stiff one-sided spring solved by the method of multipliers for
//! Newton; each module says how). Both own only caches and scratch memory (and Newton the
//! limit's multipliers, which a new solver starts at zero), so a live swap with
//! [`cloth_solver::Verlet`] keeps the cloth's motion; see [`retime_velocity`] for swaps that
//! change the step. Each states the memory it needs for a mesh (`memory_estimate`) and reports
//! a cloth too large for the machine as an error instead of aborting.

mod cholesky;
mod commit;
mod entries;
mod fast_implicit;
mod implicit_euler;
mod memory;
mod retime;
mod spring_energy;
mod topology;

pub use fast_implicit::{DEFAULT_ITERATIONS, FAST_TOLERANCE, FastImplicit, limit_weight};
pub use implicit_euler::{
    ImplicitEuler, LIMIT_TOLERANCE, MAX_LIMIT_UPDATES, MAX_NEWTON_ITERATIONS, MAX_PCG_ITERATIONS,
    NEWTON_TOLERANCE, REFACTOR_BUDGET,
};
pub use retime::{retime_friction, retime_velocity};
pub use spring_energy::{LIMIT_OVERSHOOT, limiter_stiffness};
