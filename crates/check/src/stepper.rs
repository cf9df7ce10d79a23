//! What the kit asks of a running cloth, answered by the application's own [`Run`]: a solver
//! built from its entry, the state it advances a frame at a time, and the swaps and edits of a
//! run, each keeping the velocity in the one place the run does.
//!
//! The run's divergence guard is off: the kit measures every frame the solver makes, however
//! wild, and a step's own error still stops the run.

use std::sync::Arc;

use cloth_mesh::{ClothState, StepParams};
use cloth_run::{Command, Run};
use cloth_scene::Scene;
use cloth_solver::{Registry, SolverEntry, Verlet};
use serde_json::Value;

use crate::CheckError;

/// A running cloth: the scene, the live parameters, the solver and the state, in a [`Run`].
pub(crate) struct Stepper {
    run: Run,
}

impl Stepper {
    /// `entry`'s solver, built with `options`, on `scene`'s cloth at rest with `params`.
    pub(crate) fn new(
        scene: &Arc<Scene>,
        params: StepParams,
        entry: &SolverEntry,
        options: &Value,
    ) -> Result<Self, CheckError> {
        entry.check(options).map_err(|source| CheckError::Build {
            solver: entry.name().to_owned(),
            source,
        })?;
        // NOTE: the entry under check and the reference it swaps with, by name; an entry
        // that takes the reference's own name stands in for it, as in any registry.
        let registry = Registry::new().with(Verlet::ENTRY).with(*entry);
        let mut run = Run::with_options(Arc::clone(scene), registry, entry.name(), options)
            .map_err(|e| CheckError::Run {
                solver: entry.name().to_owned(),
                reason: format!("{e:#}"),
            })?;
        run.set_guarded(false);
        run.set_recording(false);
        // At rest, so the previous positions need no rescale for the parameters' step.
        run.settings.params = params;
        Ok(Self { run })
    }

    /// `entry`'s solver on `state`, reached after `frames` frames of `params` (its previous
    /// positions one step of `params` ago).
    pub(crate) fn from_state(
        scene: &Arc<Scene>,
        params: StepParams,
        entry: &SolverEntry,
        options: &Value,
        state: ClothState,
        frames: u64,
    ) -> Result<Self, CheckError> {
        let mut stepper = Self::new(scene, params, entry, options)?;
        let time = frames as f64 / params.frames_per_sec;
        stepper.run.start_from(state, frames, time);
        Ok(stepper)
    }

    /// Advances one frame of `1 / frames_per_sec` seconds.
    ///
    /// # Errors
    /// What stopped the frame, in one sentence.
    pub(crate) fn frame(&mut self) -> Result<(), String> {
        self.run.step_frame().map_err(|f| f.what)
    }

    /// Hands the state to `entry`'s solver (registered with this run) built with `options`,
    /// at `steps_per_frame`, keeping the velocity.
    pub(crate) fn swap(
        &mut self,
        entry: &SolverEntry,
        options: &Value,
        steps_per_frame: u32,
    ) -> Result<(), CheckError> {
        self.run
            .set_solver_with(entry.name(), options)
            .map_err(|e| CheckError::Run {
                solver: entry.name().to_owned(),
                reason: format!("{e:#}"),
            })?;
        self.set_steps(steps_per_frame)
    }

    /// Edits the steps per frame, keeping the velocity.
    pub(crate) fn set_steps(&mut self, steps_per_frame: u32) -> Result<(), CheckError> {
        let mut settings = self.run.settings.clone();
        settings.params.steps_per_frame = steps_per_frame;
        self.run
            .apply(Command::Settings(settings))
            .map_err(|reason| CheckError::Run {
                solver: self.run.entry().name().to_owned(),
                reason,
            })
    }

    /// The state after the last frame.
    pub(crate) fn state(&self) -> &ClothState {
        &self.run.state
    }

    /// The live parameters.
    pub(crate) fn params(&self) -> &StepParams {
        &self.run.settings.params
    }
}
