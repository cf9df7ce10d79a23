//! Implicit solvers for the CS184 mass-spring cloth, on faer's sparse Cholesky.
//!
//! Two solvers implement [`cloth_solver::Solver`]:
//!
//! - [`ImplicitEuler`] (`implicit`): backward Euler, each step minimising the incremental
//!   potential by Newton's method with a line search. Unconditionally stable, accurate to first
//!   order in the step; for stiff cloths and one step per frame.
//! - [`FastImplicit`] (`fast-implicit`): Liu et al. 2013, "Fast Simulation of Mass-Spring
//!   Systems": the same backward-Euler step, approximated by a fixed number of local/global
//!   iterations with one constant, prefactored matrix. The cheapest stable option for large,
//!   stiff cloths.
//!
//! Each is offered by name through its registry entry ([`ImplicitEuler::ENTRY`],
//! [`FastImplicit::ENTRY`]), with its own options (`tolerance`, `iterations`).
//!
//! Both read the course's live parameters ([`cloth_solver::StepParams`]): the damping becomes
//! the drag rate [`StepParams::drag_rate`](cloth_solver::StepParams::drag_rate), so it does not
//! change with the step; the 10 % stretch limit is part of the minimised energy rather than a
//! post-step projection. Both own only caches and scratch memory, so a live swap with
//! [`cloth_solver::Verlet`] keeps the cloth's motion; see [`retime_velocity`] for swaps that
//! change the step.

mod cholesky;
mod commit;
mod entries;
mod fast_implicit;
mod implicit_euler;
mod retime;
mod spring_energy;
mod topology;

pub use fast_implicit::{DEFAULT_ITERATIONS, FastImplicit};
pub use implicit_euler::{ImplicitEuler, MAX_NEWTON_ITERATIONS, NEWTON_TOLERANCE};
pub use retime::retime_velocity;
pub use spring_energy::{LIMIT_OVERSHOOT, limiter_stiffness};
