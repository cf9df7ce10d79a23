//! Rendering speed: a 50 x 50 cloth into a 200 x 60 frame must take well under 1 ms.

use std::hint::black_box;

use cloth_mesh::{ClothMesh, ClothState};
use cloth_render::{AsciiFrame, Mode, RenderOptions, Renderer, View, ViewSpec};
use criterion::{Criterion, criterion_group, criterion_main};

/// The `pinned4` cloth hanging between its corners: each point lowered by up to 0.3 m, nothing
/// at the corners, half of that at the middle of an edge, all of it at the centre.
///
/// The shape is written out rather than simulated, so the renderer's benchmark needs no solver
/// (the renderer knows none); what it costs is the cloth's triangles and the pixels they cover,
/// and a sagging, tilted surface covers them as the hanging cloth does.
fn pinned4_hanging() -> (ClothMesh, ClothState) {
    let mesh = ClothMesh::pinned_grid(50).expect("the standard grid is valid");
    let mut state = ClothState::new(&mesh);
    let n = mesh.spec().num_width_points;
    let last = (n - 1) as f64;
    for (i, p) in state.positions.iter_mut().enumerate() {
        let (u, v) = ((i % n) as f64 / last, (i / n) as f64 / last);
        let sag = 0.5 * ((std::f64::consts::PI * u).sin() + (std::f64::consts::PI * v).sin());
        p.y -= 0.3 * sag;
    }
    state.last.clone_from(&state.positions);
    (mesh, state)
}

fn render(c: &mut Criterion) {
    let (mesh, state) = pinned4_hanging();
    let mut renderer = Renderer::new();
    let mut frame = AsciiFrame::with_size(200, 60).expect("valid size");
    for (name, view, mode) in [
        ("50x50_into_200x60_side_ascii", View::Side, Mode::Ascii),
        ("50x50_into_200x60_top_ascii", View::Top, Mode::Ascii),
        ("50x50_into_200x60_orbit_ascii", View::Orbit, Mode::Ascii),
        ("50x50_into_200x60_top_braille", View::Top, Mode::Braille),
        (
            "50x50_into_200x60_top_ascii_nocolor",
            View::Top,
            Mode::Ascii,
        ),
    ] {
        let spec = ViewSpec::new(view, &mesh);
        let options = RenderOptions {
            mode,
            color: !name.ends_with("nocolor"),
            ..RenderOptions::default()
        };
        c.bench_function(name, |b| {
            b.iter(|| {
                renderer
                    .render(&mesh, &state, &[], &spec, &options, &mut frame)
                    .expect("renders");
                black_box(&frame);
            });
        });
    }
}

criterion_group!(benches, render);
criterion_main!(benches);
