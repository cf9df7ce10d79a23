//! The orbit view of `clothsim render`, run as a user would run it: every bundled scene shows
//! its whole cloth, with room around it, large enough to read.

use std::process::Command;

use cloth_render::{BACK_RAMP, FRONT_RAMP, PIN_GLYPH};

/// The frame size a user would try in a small terminal: 20 rows leave little room, so a
/// careless fit shows at once.
const SIZE: (usize, usize) = (60, 20);

/// The rows and columns holding cloth in a frame printed as plain text: `(first row, last row,
/// first column, last column)`, or `None` when no cell shows cloth.
///
/// Cloth is what the cloth's glyphs draw (its front and back ramps and its pins); spheres and
/// floors have glyphs of their own, so they are not counted.
fn cloth_cells(text: &str) -> Option<(usize, usize, usize, usize)> {
    let mut found: Option<(usize, usize, usize, usize)> = None;
    for (y, line) in text.lines().enumerate() {
        for (x, c) in line.chars().enumerate() {
            if FRONT_RAMP.contains(&c) || BACK_RAMP.contains(&c) || c == PIN_GLYPH {
                found = Some(match found {
                    None => (y, y, x, x),
                    Some((y0, y1, x0, x1)) => (y0.min(y), y1.max(y), x0.min(x), x1.max(x)),
                });
            }
        }
    }
    found
}

/// Renders `scene` after `frames` frames in the orbit view at [`SIZE`] and checks the picture:
/// the whole cloth is inside the frame with at least one empty row or column between it and
/// each edge (the fitted orbit keeps 1.5 cells, so one is kept whatever the rounding), and it
/// spans at least a quarter of the frame's height or width. Returns what was wrong, if anything.
fn check(scene: &str, frames: u64) -> Option<String> {
    let (w, h) = SIZE;
    let o = Command::new(env!("CARGO_BIN_EXE_clothsim"))
        .args([
            "render",
            scene,
            "--frames",
            &frames.to_string(),
            "--view",
            "orbit",
        ])
        .args(["--size", &format!("{w}x{h}")])
        .output()
        .expect("the binary runs");
    let text = String::from_utf8_lossy(&o.stdout);
    let tag = format!("{scene} at frame {frames}");
    if !o.status.success() {
        return Some(format!(
            "{tag}: failed: {}",
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    assert_eq!(text.lines().count(), h, "{tag}");
    let Some((y0, y1, x0, x1)) = cloth_cells(&text) else {
        return Some(format!("{tag}: no cloth drawn\n{text}"));
    };
    let inside = y0 >= 1 && x0 >= 1 && y1 + 2 <= h && x1 + 2 <= w;
    // Spans in cells, counting both ends: a quarter of 20 rows is 5, of 60 columns 15.
    let large = 4 * (y1 - y0 + 1) >= h || 4 * (x1 - x0 + 1) >= w;
    (!(inside && large)).then(|| {
        format!(
            "{tag}: cloth in rows {y0}-{y1} and columns {x0}-{x1} of {w}x{h} (inside with a \
             border: {inside}; a quarter of the frame: {large})\n{text}"
        )
    })
}

/// Checks every bundled scene at each of `frames`, and reports every failure at once.
fn check_every_scene(frames: &[u64]) {
    let failures: Vec<String> = cloth_scene::BUNDLED
        .iter()
        .flat_map(|b| frames.iter().filter_map(move |&f| check(b.name, f)))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_scene_at_its_start_shows_the_whole_cloth_in_the_orbit_view() {
    check_every_scene(&[0]);
}

/// Simulates every scene for 90 and 270 frames (3 s): a few seconds in the test profile, but
/// most of a minute unoptimised, so it runs with the long tests.
#[test]
#[ignore = "simulates every bundled scene for 270 frames; run with --ignored"]
fn every_scene_after_90_and_270_frames_shows_the_whole_cloth_in_the_orbit_view() {
    check_every_scene(&[90, 270]);
}
