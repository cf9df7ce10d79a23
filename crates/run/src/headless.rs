//! What the headless commands share: a failed step or run reported with what to change, and
//! the note that a bare scene name was read as the bundled scene.

use cloth_mesh::StepParams;
use cloth_solver::SolveError;

/// A run's fault in frame `frame` of `frames`, naming the scene: a step's error as
/// [`frame_error`] words it, anything else as the fault says it.
pub fn fault_error(
    scene: &cloth_scene::Scene,
    params: &StepParams,
    explicit: bool,
    (frame, frames): (u64, u64),
    fault: &crate::Fault,
) -> anyhow::Error {
    match &fault.cause {
        crate::Cause::Step(e) => frame_error(scene, params, explicit, frame, frames, e),
        _ => anyhow::anyhow!(
            "{}: frame {frame} of {frames}: {}; {}",
            scene.origin,
            fault.what,
            fault.advice
        ),
    }
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

/// The running binary's name, which starts every line this crate writes to stderr (progress,
/// notes): `clothsim` until [`set_program_name`] names a plug-in binary.
static PROGRAM: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Names the running binary in the lines written to stderr; the first name set stays.
pub fn set_program_name(name: &str) {
    let _ = PROGRAM.set(name.to_owned());
}

/// The running binary's name (see [`set_program_name`]).
#[must_use]
pub fn program_name() -> &'static str {
    PROGRAM.get().map_or("clothsim", String::as_str)
}

/// Says on stderr that a bare scene name was read as the bundled scene although a file of that
/// name is in the current folder.
pub fn note_shadowing(name: &str) {
    if let Some(file) = cloth_scene::shadowing_file(name) {
        use std::io::Write as _;
        let _ = writeln!(
            std::io::stderr(),
            "{}: note: read the bundled scene {name}; for the file of that name, write {file}",
            program_name()
        );
    }
}
