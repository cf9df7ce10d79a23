//! Solvers for the CS184 mass-spring cloth, behind one [`Solver`] trait.
//!
//! A solver advances a [`ClothState`] by one time step of `params.dt()` seconds. It owns only
//! scratch memory and caches (rapier's "temporary working memory" rule), never the simulation
//! state, so the caller may swap solvers between any two steps and the cloth keeps its motion.
//!
//! [`Verlet`] is the reference: the course's explicit damped position Verlet, step for step.
//! Anyone can write another solver crate against this trait; `cloth-implicit` is one.
//!
//! Units are SI throughout: metres, seconds, kilograms, newtons.

mod bench;
mod collider;
mod diagnostics;
mod disjoint;
mod error;
mod kind;
mod params;
mod self_collision;
mod stretch;
mod verlet;

#[cfg(test)]
mod testing;

pub use bench::{
    BenchResult, BenchRun, InterleavedResult, pinned_grid, time_frames, time_interleaved,
};
pub use cloth_mesh::{ClothMesh, ClothState, Vec3};
pub use collider::{Collider, Plane, Sphere, apply_colliders};
pub use diagnostics::{kinetic_energy, max_stretch_ratio};
pub use error::SolveError;
pub use kind::{SolverKind, UnknownSolver};
pub use params::{MAX_STRETCH, ParamError, REFERENCE_STEPS_PER_FRAME, StepParams};
pub use self_collision::SpatialHash;
pub use stretch::limit_stretch;
pub use verlet::{ConstraintOrder, Verlet};

/// What one step did, for status lines and tests.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Inner iterations spent (Newton or local-global iterations); 0 for explicit solvers.
    pub iterations: u32,
    /// The solver's own convergence measure at the end of the step (0 when it has none).
    pub residual: f64,
}

/// A time integrator for the cloth.
///
/// `step` advances `state` by exactly `params.dt()` seconds of simulated time. It must be
/// deterministic (same inputs, same bits out) and must report non-finite results as
/// [`SolveError::NonFinite`] rather than panic. Pinned points never move.
pub trait Solver: Send {
    /// A short lowercase name, as typed on the command line (`verlet`).
    fn name(&self) -> &'static str;

    /// Advances `state` by one step of `params.dt()` seconds.
    ///
    /// # Errors
    /// [`SolveError`] when the step produced a non-finite state or the method failed; `state`
    /// may then hold the bad values, so the caller should stop or reset.
    fn step(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &mut ClothState,
    ) -> Result<StepReport, SolveError>;

    /// Drops any cached warm start, e.g. after a reset or a scene change. Caches that depend
    /// only on the mesh topology may be kept.
    fn reset(&mut self) {}
}

/// Advances one frame: `params.steps_per_frame` steps, stopping at the first error.
///
/// # Errors
/// The first step's error, with the number of steps that succeeded before it.
pub fn advance_frame(
    solver: &mut dyn Solver,
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    state: &mut ClothState,
) -> Result<StepReport, SolveError> {
    let mut total = StepReport::default();
    for _ in 0..params.steps_per_frame {
        let r = solver.step(mesh, colliders, params, state)?;
        total.iterations += r.iterations;
        total.residual = r.residual;
    }
    Ok(total)
}
