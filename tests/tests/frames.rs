//! Snapshot frames of every bundled scene, as `clothsim render` prints them.
//!
//! Found by globbing `crates/scene/scenes/`, so a new scene is covered with no new code: side
//! and top views at 80 x 40 after a fixed number of frames, plus the other views and modes on
//! `pinned4`.
//! Deterministic: fixed sizes, frame counts and seeds, no clock, ordered dithering.
//! Review a changed snapshot by eye (`cargo insta review`): it must look like a cloth.

use cloth_mesh::ClothState;
use cloth_render::{
    AsciiFrame, Bounds, Extent, FrameSize, Mode, RenderOptions, Renderer, View, ViewSpec,
};
use cloth_scene::Scene;
use cloth_solver::{Solver, Verlet, advance_frame};

/// 150 frames = 1.67 s of simulated time: cloths have fallen, draped or come to rest.
const FRAMES: usize = 150;

fn simulate(scene: &Scene, frames: usize) -> ClothState {
    let mut solver = Verlet::new();
    let mut state = ClothState::new(&scene.mesh);
    for f in 0..frames {
        advance_frame(
            &mut solver as &mut dyn Solver,
            &scene.mesh,
            &scene.colliders,
            &scene.params,
            &mut state,
        )
        .unwrap_or_else(|e| panic!("{}: frame {f}: {e}", scene.origin));
    }
    state
}

/// The frame `clothsim render` prints for one final frame: fitted to that frame's scene box,
/// no colour.
fn frame(scene: &Scene, state: &ClothState, view: View, mode: Mode, size: &str) -> String {
    let size: FrameSize = size.parse().unwrap();
    let mut frame = AsciiFrame::new(size);
    let extent = Bounds::of_scene(&state.positions, &scene.colliders).unwrap();
    let spec = ViewSpec {
        extent: Extent::Fixed(extent),
        ..ViewSpec::new(view, &scene.mesh)
    };
    let options = RenderOptions {
        mode,
        color: false,
        ..RenderOptions::default()
    };
    Renderer::new()
        .render(
            &scene.mesh,
            state,
            &scene.colliders,
            &spec,
            &options,
            &mut frame,
        )
        .unwrap();
    let text = frame.to_plain();
    // The contract of the plain format: exactly H lines of W columns.
    assert_eq!(text.lines().count(), size.height);
    assert!(text.lines().all(|l| l.chars().count() == size.width));
    text
}

#[test]
fn every_scene_side_and_top_after_150_frames() {
    insta::glob!("../../crates/scene/scenes", "*.json", |path| {
        let scene = cloth_scene::load(path.to_str().unwrap(), &[]).unwrap();
        let state = simulate(&scene, FRAMES);
        let side = frame(&scene, &state, View::Side, Mode::Ascii, "80x40");
        let top = frame(&scene, &state, View::Top, Mode::Ascii, "80x40");
        insta::assert_snapshot!(format!(
            "{}\n{side}\n{}\n{top}",
            View::Side.describe(),
            View::Top.describe()
        ));
    });
}

#[test]
fn pinned4_in_every_other_view_and_mode() {
    let scene = clothsim_tests::scene("pinned4");
    let state = simulate(&scene, FRAMES);
    for (view, mode) in [
        (View::Bottom, Mode::Ascii),
        (View::Front, Mode::Ascii),
        (View::Orbit, Mode::Ascii),
        (View::Top, Mode::Half),
        (View::Side, Mode::Braille),
        (View::Top, Mode::Braille),
    ] {
        let text = frame(&scene, &state, view, mode, "60x24");
        insta::assert_snapshot!(format!("pinned4_{view}_{mode}"), text, view.describe());
    }
}
