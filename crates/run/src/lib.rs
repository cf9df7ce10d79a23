//! clothsim's one run: a scene stepped frame by frame under any solver of a registry, with
//! the divergence guard, the per-frame numbers and the simulated clock, used by every front
//! end (the live UI, `simulate`, `render`, `compare`, `bench`, `check`).
//!
//! [`Run`] is one cloth (scene, state, solver, guard, stats, clock): it steps a frame, applies
//! an edit of the live settings and swaps a solver, rescaling the previous positions whenever
//! the step changes (the one place that does, through [`cloth_mesh::ClothState::retime`]).
//! [`lockstep`] steps one or several against the wall clock on a thread of their own (the
//! live UI's single cloth and its compare mode alike), and [`study`] runs several to the end
//! through the same lockstep. Beside it live what a run leaves behind: [`export`]
//! (meshes, animations, tables, recordings), [`state_file`] (a state to carry on from),
//! [`output`] (standard output and atomic files) and [`memory`] (what a cloth needs).
//!
//! Nothing here touches a terminal or parses a command line.

pub mod actions;
pub mod export;
pub mod guard;
pub mod headless;
pub mod lockstep;
pub mod memory;
pub mod output;
pub mod progress;
mod run;
pub mod solvers;
pub mod state_file;
pub mod study;

pub use cloth_solver::{Registry, SolverEntry};
pub use run::{
    Cause, Command, Fault, HISTORY, Held, Run, Sample, Settings, Timed, Touch, numeric_options,
};
pub use solvers::default_registry;
