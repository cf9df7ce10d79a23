//! Renders pinned4 at rest with a grazing light to see its folds.
use cloth_mesh::{ClothMesh, ClothState, GridSpec, Vec3};
use cloth_render::{AsciiFrame, Light, RenderOptions, Renderer, View, ViewSpec};
use cloth_solver::{Solver, StepParams, Verlet, advance_frame};
fn main() {
    let mesh = ClothMesh::new(&GridSpec {
        pinned: vec![(0, 0), (0, 49), (49, 0), (49, 49)],
        ..GridSpec::default()
    })
    .unwrap();
    let mut state = ClothState::new(&mesh);
    let mut s = Verlet::new();
    for _ in 0..250 {
        advance_frame(
            &mut s as &mut dyn Solver,
            &mesh,
            &[],
            &StepParams::default(),
            &mut state,
        )
        .unwrap();
    }
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let o = RenderOptions {
        light: Light::Direction(Vec3::new(args[0], args[1], args[2])),
        fill: args[3],
        diffuse: args[4],
        ambient: 0.0,
        color: false,
        ..RenderOptions::default()
    };
    let mut f = AsciiFrame::with_size(120, 50).unwrap();
    Renderer::new()
        .render(
            &mesh,
            &state,
            &[],
            &ViewSpec::new(View::Top, &mesh),
            &o,
            &mut f,
        )
        .unwrap();
    print!("{}", f.to_plain());
}
