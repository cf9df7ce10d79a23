//! The one loop the kit steps through: a solver built from its entry, the state it advances, a
//! frame at a time, and the swaps and edits of a run.
//!
//! Kept small and apart from the measures so that the application's own run type can take its
//! place: everything the kit asks of a run is here.

use cloth_mesh::{ClothMesh, ClothState, Collider, StepParams};
use cloth_solver::{SolveError, Solver, SolverEntry, advance_frame};
use serde_json::Value;

use crate::CheckError;

/// A running cloth: the scene's data, the live parameters, the solver and the state.
pub(crate) struct Stepper<'a> {
    mesh: &'a ClothMesh,
    colliders: &'a [Collider],
    params: StepParams,
    solver: Box<dyn Solver>,
    state: ClothState,
}

impl<'a> Stepper<'a> {
    /// `entry`'s solver, built with `options`, on the cloth at rest at its start positions.
    pub(crate) fn new(
        mesh: &'a ClothMesh,
        colliders: &'a [Collider],
        params: StepParams,
        entry: &SolverEntry,
        options: &Value,
    ) -> Result<Self, CheckError> {
        Self::from_state(
            mesh,
            colliders,
            params,
            entry,
            options,
            ClothState::new(mesh),
        )
    }

    /// `entry`'s solver on `state`, whose previous positions are one step of `params` ago.
    pub(crate) fn from_state(
        mesh: &'a ClothMesh,
        colliders: &'a [Collider],
        params: StepParams,
        entry: &SolverEntry,
        options: &Value,
        state: ClothState,
    ) -> Result<Self, CheckError> {
        let solver = entry
            .build(mesh, options)
            .map_err(|source| CheckError::Build {
                solver: entry.name().to_owned(),
                source,
            })?;
        Ok(Self {
            mesh,
            colliders,
            params,
            solver,
            state,
        })
    }

    /// Advances one frame of `1 / frames_per_sec` seconds.
    pub(crate) fn frame(&mut self) -> Result<(), SolveError> {
        advance_frame(
            self.solver.as_mut(),
            self.mesh,
            self.colliders,
            &self.params,
            &mut self.state,
        )?;
        Ok(())
    }

    /// Hands the state to `entry`'s solver at `steps_per_frame`, keeping the velocity.
    pub(crate) fn swap(
        &mut self,
        entry: &SolverEntry,
        options: &Value,
        steps_per_frame: u32,
    ) -> Result<(), CheckError> {
        self.solver = entry
            .build(self.mesh, options)
            .map_err(|source| CheckError::Build {
                solver: entry.name().to_owned(),
                source,
            })?;
        self.set_steps(steps_per_frame);
        Ok(())
    }

    /// Edits the steps per frame, keeping the velocity.
    pub(crate) fn set_steps(&mut self, steps_per_frame: u32) {
        let old = self.params.dt();
        self.params.steps_per_frame = steps_per_frame;
        self.state.retime(old, self.params.dt());
    }

    /// The state after the last frame.
    pub(crate) fn state(&self) -> &ClothState {
        &self.state
    }

    /// The live parameters.
    pub(crate) fn params(&self) -> &StepParams {
        &self.params
    }
}
