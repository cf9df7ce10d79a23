//! Prints side and top frames of a bundled-like scene after a number of frames.
//!
//! `cargo run -p cloth-render --example frames -- pinned4 120 80x40 ascii`

use cloth_mesh::{ClothMesh, ClothState, GridSpec, Orientation, Vec3};
use cloth_render::{AsciiFrame, FrameSize, Mode, RenderOptions, Renderer, View, ViewSpec};
use cloth_solver::{Collider, Plane, Solver, Sphere, StepParams, Verlet, advance_frame};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let scene = args.get(1).map_or("pinned4", String::as_str);
    let frames: usize = args.get(2).map_or(Ok(120), |s| s.parse())?;
    let size: FrameSize = args.get(3).map_or("80x40", String::as_str).parse()?;
    let mode: Mode = args.get(4).map_or("ascii", String::as_str).parse()?;
    let views: Vec<View> = match args.get(5) {
        Some(v) => v.split(',').map(str::parse).collect::<Result<_, _>>()?,
        None => vec![View::Side, View::Top],
    };
    let floor = Collider::Plane(Plane {
        point: Vec3::zeros(),
        normal: Vec3::y(),
        friction: 0.5,
    });
    let (pinned, orientation, colliders) = match scene {
        "pinned2" => (vec![(0, 0), (49, 0)], Orientation::Horizontal, vec![]),
        "pinned4" => (
            vec![(0, 0), (0, 49), (49, 0), (49, 49)],
            Orientation::Horizontal,
            vec![],
        ),
        "sphere" => (
            vec![],
            Orientation::Horizontal,
            vec![Collider::Sphere(Sphere {
                origin: Vec3::new(0.5, 0.2, 0.5),
                radius: 0.2,
                friction: 0.3,
            })],
        ),
        "plane" => (vec![], Orientation::Horizontal, vec![floor]),
        _ => (vec![], Orientation::Vertical, vec![floor]),
    };
    let mesh = ClothMesh::new(&GridSpec {
        pinned,
        orientation,
        ..GridSpec::default()
    })?;
    let mut state = ClothState::new(&mesh);
    let params = StepParams::default();
    let mut solver = Verlet::new();
    for _ in 0..frames {
        advance_frame(
            &mut solver as &mut dyn Solver,
            &mesh,
            &colliders,
            &params,
            &mut state,
        )?;
    }
    let mut renderer = Renderer::new();
    let mut frame = AsciiFrame::new(size);
    let options = RenderOptions {
        mode,
        color: false,
        legend: true,
        ..RenderOptions::default()
    };
    for view in views {
        renderer.render(
            &mesh,
            &state,
            &colliders,
            &ViewSpec::new(view, &mesh),
            &options,
            &mut frame,
        )?;
        println!("== {} ==", view.describe());
        print!("{}", frame.to_plain());
    }
    Ok(())
}
