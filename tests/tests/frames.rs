//! Snapshot frames of every bundled scene, as `clothsim render` prints them.
//!
//! Found by globbing `crates/scene/scenes/`, so a new scene is covered with no new code: side
//! and top views at 80 x 40 after a fixed number of frames, plus the other views and modes on
//! `pinned4`, and the orbit view of the scenes that hang, drape and collapse.
//! Deterministic: fixed sizes, frame counts and seeds, no clock, ordered dithering.
//! Review a changed snapshot by eye (`cargo insta review`): it must look like a cloth.

use cloth_mesh::ClothState;
use cloth_render::{
    AsciiFrame, BACK_RAMP, Bounds, Extent, FRONT_RAMP, FrameSize, Mode, PIN_GLYPH, RenderOptions,
    Renderer, View, ViewSpec,
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

/// The frame `clothsim render` prints for one final frame: fitted to that frame's scene box
/// (and for the orbit view, the start's too), no colour.
fn frame(scene: &Scene, state: &ClothState, view: View, mode: Mode, size: &str) -> String {
    let size: FrameSize = size.parse().unwrap();
    let mut frame = AsciiFrame::new(size);
    let mut extent = Bounds::of_scene(&state.positions, &scene.colliders).unwrap();
    if view == View::Orbit {
        let start = ClothState::new(&scene.mesh);
        extent = extent.union(&Bounds::of_scene(&start.positions, &scene.colliders).unwrap());
    }
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

/// The rows and columns holding cloth (its front and back glyphs and its pins, not the
/// spheres' or floors') in a plain frame: `(first row, last row, first column, last column)`.
fn cloth_cells(text: &str) -> Option<(usize, usize, usize, usize)> {
    let cloth = |c: char| FRONT_RAMP.contains(&c) || BACK_RAMP.contains(&c) || c == PIN_GLYPH;
    let cells = text.lines().enumerate().flat_map(|(y, line)| {
        line.chars()
            .enumerate()
            .filter(move |&(_, c)| cloth(c))
            .map(move |(x, _)| (y, x))
    });
    cells.fold(None, |found, (y, x)| {
        Some(match found {
            None => (y, y, x, x),
            Some((y0, y1, x0, x1)) => (y0.min(y), y1.max(y), x0.min(x), x1.max(x)),
        })
    })
}

#[test]
fn orbit_view_of_hanging_draped_and_collapsed_cloths_shows_all_of_each() {
    // A hammock sagging from its corners, a cloth draped over a sphere and one collapsed on the
    // floor: the shapes that leave the start's box most, at 60 x 20 where a careless fit shows.
    for name in ["pinned4", "sphere", "selfCollision"] {
        let scene = clothsim_tests::scene(name);
        let state = simulate(&scene, FRAMES);
        let text = frame(&scene, &state, View::Orbit, Mode::Ascii, "60x20");
        // The fitted orbit keeps 1.5 cells empty on each side, so at least one whole row and
        // column is empty between the cloth and every edge, and the box it frames fills one
        // axis, which the cloth spans at least a quarter of.
        let (y0, y1, x0, x1) = cloth_cells(&text).unwrap_or_else(|| panic!("{name}\n{text}"));
        assert!(
            y0 >= 1 && x0 >= 1 && y1 <= 18 && x1 <= 58,
            "{name}: rows {y0}-{y1}, columns {x0}-{x1}\n{text}"
        );
        assert!(
            4 * (y1 - y0 + 1) >= 20 || 4 * (x1 - x0 + 1) >= 60,
            "{name}: rows {y0}-{y1}, columns {x0}-{x1}\n{text}"
        );
        insta::assert_snapshot!(format!("{name}_orbit_60x20"), text, View::Orbit.describe());
    }
}
