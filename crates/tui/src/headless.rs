//! What `simulate` and `render` share: stepping a scene frame by frame with progress, and a
//! failed step reported with what to change.

use cloth_mesh::ClothState;
use cloth_mesh::StepParams;
use cloth_solver::{SolveError, Solver};

use crate::progress::Progress;

/// Advances `state` by one frame of `scene` (`params.steps_per_frame` steps), counting each
/// step on `progress`: the same steps, in the same order, as [`cloth_solver::advance_frame`].
///
/// # Errors
/// The first step's error, as [`frame_error`] words it.
pub fn advance_frame(
    solver: &mut dyn Solver,
    scene: &cloth_scene::Scene,
    params: &StepParams,
    explicit: bool,
    state: &mut ClothState,
    (frame, frames): (u64, u64),
    progress: &mut Progress,
) -> anyhow::Result<()> {
    for _ in 0..params.steps_per_frame {
        solver
            .step(&scene.mesh, &scene.colliders, params, state)
            .map_err(|e| frame_error(scene, params, explicit, frame, frames, &e))?;
        progress.step();
    }
    Ok(())
}

/// `e` in frame `frame` of `frames`, naming the scene; a run gone non-finite also says what in
/// the scene most likely caused it and what to change (`explicit`: the solver has a step limit,
/// as Verlet has).
pub fn frame_error(
    scene: &cloth_scene::Scene,
    params: &StepParams,
    explicit: bool,
    frame: u64,
    frames: u64,
    e: &SolveError,
) -> anyhow::Error {
    let at = format!("{}: frame {frame} of {frames}", scene.origin);
    match e {
        SolveError::NonFinite { .. } => {
            let advice = cloth_scene::divergence_advice(scene, params, explicit);
            anyhow::anyhow!("{at}: {e}; {advice}")
        }
        _ => anyhow::anyhow!("{at}: {e}"),
    }
}

/// Says on stderr that a bare scene name was read as the bundled scene although a file of that
/// name is in the current folder.
pub fn note_shadowing(name: &str) {
    if let Some(file) = cloth_scene::shadowing_file(name) {
        use std::io::Write as _;
        let _ = writeln!(
            std::io::stderr(),
            "clothsim: note: read the bundled scene {name}; for the file of that name, write {file}"
        );
    }
}
