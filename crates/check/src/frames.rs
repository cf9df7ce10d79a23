//! A scene's frames under a solver as text, for a solver crate's snapshot of its own frames.

use std::fmt::Write as _;
use std::sync::Arc;

use cloth_render::{
    AsciiFrame, Bounds, Extent, FrameSize, Mode, RenderOptions, Renderer, View, ViewSpec,
};
use cloth_solver::SolverEntry;
use serde_json::Value;

use crate::CheckError;
use crate::stepper::Stepper;

/// Which frames to draw, and how.
#[derive(Debug, Clone, PartialEq)]
pub struct FramesSpec {
    /// The frames to draw, counted from the start (0 is the cloth at rest), in increasing order.
    pub frames: Vec<usize>,
    /// The view of each.
    pub view: View,
    /// Columns and rows of each frame.
    pub size: FrameSize,
}

impl Default for FramesSpec {
    /// Frames 30, 90 and 270 (a third of a second, one second and three seconds at 90 frames
    /// per second: falling, caught, settled) from the side, 60 x 20 characters.
    fn default() -> Self {
        Self {
            frames: vec![30, 90, 270],
            view: View::Side,
            size: FrameSize {
                width: 60,
                height: 20,
            },
        }
    }
}

/// The frames `spec` asks for of the bundled scene `scene` run by `entry`'s solver with
/// `options`, as plain text: for each, a line naming the frame and the frame's rows, drawn as
/// `clothsim render` draws one (fitted to that frame's scene box, no colour). The solver runs
/// at the scene's steps per frame when its file gives them, else at the entry's.
///
/// Deterministic as the solver is, so a solver crate can snapshot its own frames:
///
/// ```no_run
/// let text = cloth_check::frames_as_text(
///     &cloth_solver::Verlet::ENTRY,
///     &serde_json::json!({}),
///     "sphere",
///     &cloth_check::FramesSpec::default(),
/// )?;
/// assert!(text.starts_with("sphere under verlet"));
/// # Ok::<(), cloth_check::CheckError>(())
/// ```
///
/// # Errors
/// [`CheckError`] when the scene is not bundled, the solver cannot be built with `options`, a
/// frame fails or cannot be drawn.
pub fn frames_as_text(
    entry: &SolverEntry,
    options: &Value,
    scene: &str,
    spec: &FramesSpec,
) -> Result<String, CheckError> {
    let Some(bundled) = cloth_scene::bundled(scene) else {
        return Err(CheckError::UnknownScene {
            name: scene.to_owned(),
            available: (cloth_scene::BUNDLED.iter().map(|b| b.name))
                .collect::<Vec<_>>()
                .join(", "),
        });
    };
    let loaded = Arc::new(cloth_scene::parse(bundled.json, bundled.name, &[])?);
    let mut params = loaded.params;
    if !loaded.gives_steps() {
        params.steps_per_frame = entry.steps_per_frame();
    }
    let mut stepper = Stepper::new(&loaded, params, entry, options)?;
    let mut renderer = Renderer::new();
    let render = RenderOptions {
        mode: Mode::Ascii,
        color: false,
        ..RenderOptions::default()
    };
    let mut frame = AsciiFrame::new(spec.size);
    let mut text = format!(
        "{scene} under {} at {} steps per frame, {} view\n",
        entry.name(),
        params.steps_per_frame,
        spec.view
    );
    let mut done = 0;
    for &wanted in &spec.frames {
        while done < wanted {
            stepper.frame().map_err(|reason| CheckError::Step {
                scene: scene.to_owned(),
                solver: entry.name().to_owned(),
                frame: done + 1,
                reason,
            })?;
            done += 1;
        }
        let state = stepper.state();
        let extent = Bounds::of_scene(&state.positions, &loaded.colliders)?;
        let view = ViewSpec {
            extent: Extent::Fixed(extent),
            ..ViewSpec::new(spec.view, &loaded.mesh)
        };
        renderer.render(
            &loaded.mesh,
            state,
            &loaded.colliders,
            &view,
            &render,
            &mut frame,
        )?;
        // Writing to a String cannot fail.
        let _ = writeln!(
            text,
            "frame {wanted} ({:.2} s)",
            wanted as f64 / params.frames_per_sec
        );
        text.push_str(&frame.to_plain());
        if !text.ends_with('\n') {
            text.push('\n');
        }
    }
    Ok(text)
}
