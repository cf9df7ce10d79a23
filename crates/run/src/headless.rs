//! What the headless commands share: a failed step or run reported with what to change, and
//! the note that a bare scene name was read as the bundled scene.

use cloth_mesh::StepParams;
use cloth_solver::SolveError;

use crate::guard::Divergence;

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
        SolveError::NonFinite { .. } | SolveError::Method { .. } => {
            let advice = cloth_scene::divergence_advice(scene, params, explicit);
            anyhow::anyhow!("{at}: {e}; {advice}")
        }
        SolveError::Params(_) => anyhow::anyhow!("{at}: {e}"),
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

/// How many times its rest length a spring may end a run with the stretch limit on before the
/// run is said to have outrun the limit: the limit holds springs near
/// [`cloth_mesh::MAX_STRETCH`] (1.1), and a settled cloth under it ends within a few percent of
/// that, so 1.5 is a limit that no longer holds.
pub const STRETCH_WARNING: f64 = 1.5;

/// A warning for a run of `scene` with `params` that ends at `state` with the stretch limit on
/// and a spring past [`STRETCH_WARNING`] times its rest length: the result is not the cloth
/// the limit describes, though the user may have asked for it; `None` otherwise.
pub fn stretch_warning(
    scene: &cloth_scene::Scene,
    params: &StepParams,
    state: &cloth_mesh::ClothState,
) -> Option<String> {
    if !params.stretch_limit {
        return None;
    }
    let stretch = cloth_solver::max_stretch_ratio(&scene.mesh, state);
    if stretch.is_nan() || stretch <= STRETCH_WARNING {
        return None;
    }
    // Gravity a hundred times the Earth's is named as the force the limit cannot hold.
    let g = params.gravity.norm();
    let cause = if g > 100.0 * 9.8 {
        format!(
            "simulation.gravity of {} m/s^2 pulls harder than its corrections can undo in a step \
             (the Earth's is 9.8)",
            crate::guard::short(g)
        )
    } else {
        "the forces on the cloth pull harder than its corrections can undo in a step".to_owned()
    };
    Some(format!(
        "{}: the stretch limit is on, yet the cloth ends with a spring at {} times its rest \
         length (the limit holds springs near {}): {cause}; raise simulation.simulation_steps \
         or lower the forces for a cloth the limit holds",
        scene.origin,
        crate::guard::short(stretch),
        cloth_mesh::MAX_STRETCH
    ))
}

/// What to change after the guard stopped a run of `scene` with `params` under `entry`: the
/// guard's advice for the cause ([`Divergence::advice`]), led by the scene's value furthest
/// from the course's cloth when a runaway or an energy rise came within the step's stability
/// limit (a density of 1e-300 is the cause, not the contacts).
pub fn divergence_advice(
    scene: &cloth_scene::Scene,
    params: &StepParams,
    entry: &cloth_solver::SolverEntry,
    d: &Divergence,
) -> String {
    let point_mass = scene.mesh.point_mass(params.density);
    let general = d.advice(entry, params, point_mass);
    let within_limit = !entry.is_explicit() || params.ks <= params.explicit_ks_limit(point_mass);
    match cloth_scene::unusual_value(scene, params) {
        Some((what, remedy)) if within_limit && !matches!(d, Divergence::NonFinite) => {
            format!("{what}: {remedy}; otherwise {general}")
        }
        _ => general,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// pinned4's start with its first structural spring (points 0 and 1, along the width)
    /// stretched to `ratio` times its rest length, and the scene.
    fn stretched(ratio: f64, sets: &[&str]) -> (cloth_scene::Scene, cloth_mesh::ClothState) {
        let sets: Vec<String> = sets.iter().map(|s| (*s).to_owned()).collect();
        let scene = cloth_scene::load("pinned4", &sets).unwrap();
        let mut state = cloth_mesh::ClothState::new(&scene.mesh);
        let rest = (state.positions[1] - state.positions[0]).norm();
        let along = (state.positions[1] - state.positions[0]) / rest;
        state.positions[1] = state.positions[0] + along * (rest * ratio);
        (scene, state)
    }

    #[test]
    fn a_cloth_past_one_and_a_half_rest_lengths_under_the_stretch_limit_is_warned_about() {
        for (ratio, warned) in [
            (STRETCH_WARNING * 0.9998, false),
            (STRETCH_WARNING * 1.0002, true),
        ] {
            let (scene, state) = stretched(ratio, &[]);
            assert!(
                (cloth_solver::max_stretch_ratio(&scene.mesh, &state) / ratio - 1.0).abs() < 1e-12
            );
            let w = stretch_warning(&scene, &scene.params, &state);
            assert_eq!(w.is_some(), warned, "{ratio}: {w:?}");
            if let Some(w) = w {
                assert!(w.contains("at 1.5 times its rest length"), "{w}");
                assert!(
                    !w.contains("gravity of"),
                    "ordinary gravity is not blamed: {w}"
                );
            }
        }
        // With the limit off, a stretched cloth is the course's experiment: nothing to say.
        let (scene, state) = stretched(3.0, &["simulation.stretch_limit=false"]);
        assert_eq!(stretch_warning(&scene, &scene.params, &state), None);
        // Gravity a hundred times the Earth's and more is named.
        let (scene, state) = stretched(3.0, &["simulation.gravity=[0,-1e4,0]"]);
        let w = stretch_warning(&scene, &scene.params, &state).unwrap();
        assert!(w.contains("simulation.gravity of 1.0e4 m/s^2"), "{w}");
    }
}
