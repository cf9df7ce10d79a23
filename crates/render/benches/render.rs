//! Rendering speed: a 50 x 50 cloth into a 200 x 60 frame must take well under 1 ms.

use std::hint::black_box;

use cloth_mesh::{ClothMesh, ClothState, GridSpec};
use cloth_render::{AsciiFrame, Mode, RenderOptions, Renderer, View, ViewSpec};
use cloth_solver::{Solver, StepParams, Verlet, advance_frame};
use criterion::{Criterion, criterion_group, criterion_main};

fn pinned4_at_rest() -> (ClothMesh, ClothState) {
    let mesh = ClothMesh::new(&GridSpec {
        pinned: vec![(0, 0), (0, 49), (49, 0), (49, 49)],
        ..GridSpec::default()
    })
    .expect("the standard grid is valid");
    let mut state = ClothState::new(&mesh);
    let mut solver = Verlet::new();
    for _ in 0..120 {
        advance_frame(
            &mut solver as &mut dyn Solver,
            &mesh,
            &[],
            &StepParams::default(),
            &mut state,
        )
        .expect("pinned4 is stable");
    }
    (mesh, state)
}

fn render(c: &mut Criterion) {
    let (mesh, state) = pinned4_at_rest();
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
