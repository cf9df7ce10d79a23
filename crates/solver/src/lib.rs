//! Solvers for the CS184 mass-spring cloth, behind one [`Solver`] trait.
//!
//! A solver advances a [`ClothState`] by one time step of `params.dt()` seconds. It owns only
//! scratch memory and caches (rapier's "temporary working memory" rule), never the simulation
//! state, so the caller may swap solvers between any two steps and the cloth keeps its motion.
//!
//! [`Verlet`] is the course's explicit damped position Verlet, held bit for bit to
//! [`reference_step`], the course's step written plainly.
//! Anyone can write another solver crate against this trait; `cloth-implicit` is one. A solver
//! is offered to users by name through a [`SolverEntry`] (name, description, steps per frame,
//! options, constructor) in a [`Registry`] that the binary assembles ([`Verlet::ENTRY`] is
//! Verlet's).
//!
//! Units are SI throughout: metres, seconds, kilograms, newtons.

mod diagnostics;
mod disjoint;
pub mod energy;
mod error;
mod reference;
mod registry;
mod self_collision;
mod simd;
mod stretch;
mod verlet;
mod verlet_entry;

#[cfg(test)]
mod testing;

// NOTE: the world's data (colliders, parameters) lives in cloth-mesh, below every solver, so
// scene files and renderers need no solver crate; it is re-exported here so that a solver
// written against this crate finds everything it needs in one place.
pub use cloth_mesh::{
    ClothMesh, ClothState, Collider, MAX_STRETCH, ParamError, Plane, REFERENCE_STEPS_PER_FRAME,
    SURFACE_OFFSET, Sphere, StepParams, Vec3, apply_colliders,
};
pub use diagnostics::{kinetic_energy, max_stretch_ratio};
pub use error::SolveError;
pub use reference::reference_step;
pub use registry::{
    BuildSolver, EstimateMemory, OptionError, OptionKind, Registry, SolverEntry, SolverOption,
    UnknownSolver, default_memory_estimate,
};
pub use self_collision::SpatialHash;
pub use simd::vector_paths;
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
