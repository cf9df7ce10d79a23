//! CS184 "ClothSim" scene files: JSON in, a ready-to-run [`Scene`] out.
//!
//! The course's five scene files load unchanged. Every `cloth` key but `pinned` is required and
//! unknown keys are errors, as in the course's loader, so typos are caught. clothsim adds a few
//! optional keys of its own (all documented on [`SceneFile`]): a top-level `description`, and a
//! `simulation` block with `frames_per_sec`, `simulation_steps`, `gravity`, `self_collision`,
//! `stretch_limit`, `solver`, `solver_options` (the options of that solver, whatever they are)
//! and `seed`, so one file fully describes a run. The retired keys `iterations`, `threads` and
//! `constraint_order` are refused with the spelling that replaced them.
//!
//! This crate knows no solvers: it keeps the solver's name and options as written, and the
//! application checks them against the solvers it was built with.
//!
//! Every error names the file, the key, the bad value and what is allowed.

mod advice;
mod bundled;
mod error;
mod file;
mod number;
mod overrides;
mod read;
mod scene;

pub use advice::{divergence_advice, unusual_value};
pub use bundled::{BUNDLED, BundledScene, bundled};
pub use error::SceneError;
pub use file::{ClothBlock, PlaneBlock, SceneFile, SimulationBlock, SphereBlock};
pub use number::show;
pub use overrides::apply_set;
pub use read::{MAX_SCENE_BYTES, check_scene_path, read_scene_file, special_kind, utf8_text};
pub use scene::{Scene, load, parse, shadowing_file};
