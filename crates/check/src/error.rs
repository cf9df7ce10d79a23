//! What can stop a check before it has a report.

use cloth_solver::OptionError;

/// Why a check (or a run for frames as text) could not be made.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The solver cannot be built with the options given.
    #[error("the {solver} solver cannot be checked: {source}")]
    Build {
        /// The solver.
        solver: String,
        /// Why its entry refused.
        #[source]
        source: OptionError,
    },
    /// The run of a solver could not be started or changed (a memory check, a build).
    #[error("the {solver} solver cannot be run: {reason}")]
    Run {
        /// The solver.
        solver: String,
        /// Why, in one sentence.
        reason: String,
    },
    /// A scene asked for is not bundled.
    #[error("unknown scene {name:?}; the bundled scenes are: {available}")]
    UnknownScene {
        /// The name asked for.
        name: String,
        /// The bundled names, comma-separated.
        available: String,
    },
    /// A step count asked for has no runs in the set of cases.
    #[error("--steps {asked}: the {set} set runs at {available} steps per frame")]
    UnknownSteps {
        /// The steps per frame asked for.
        asked: u32,
        /// `quick` or `full`.
        set: &'static str,
        /// The step counts of the set, comma-separated.
        available: String,
    },
    /// A bundled scene does not load (a broken build).
    #[error(transparent)]
    Scene(#[from] cloth_scene::SceneError),
    /// A swap case could not be run to its end.
    #[error("the {solver} solver's swap at frame {frame}: {reason}")]
    Swap {
        /// The solver.
        solver: String,
        /// The frame of Verlet's run at which it swapped.
        frame: usize,
        /// What failed.
        reason: String,
    },
    /// A list of figures kept in the crate does not parse (a broken build).
    #[error("the kit's {file} does not parse: {reason}")]
    Data {
        /// The file.
        file: &'static str,
        /// The parser's message.
        reason: String,
    },
    /// A frame could not be drawn.
    #[error(transparent)]
    Render(#[from] cloth_render::RenderError),
    /// A frame of a run for frames as text failed.
    #[error("frame {frame} of {scene} under {solver}: {reason}")]
    Step {
        /// The scene.
        scene: String,
        /// The solver.
        solver: String,
        /// The frame that failed.
        frame: usize,
        /// What stopped the frame.
        reason: String,
    },
}
