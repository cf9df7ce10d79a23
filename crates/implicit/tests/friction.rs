//! The collision objects' friction in the implicit solvers: a drag on the points resting on an
//! object, inside the step (see the `contact` module doc of `cloth-implicit`).

use cloth_implicit::{FastImplicit, ImplicitEuler};
use cloth_mesh::{ClothMesh, ClothState, Collider, GridSpec, Plane, SURFACE_OFFSET, Vec3};
use cloth_solver::{Solver, StepParams, advance_frame};

/// A solver's name and constructor.
type Build = (&'static str, fn() -> Box<dyn Solver>);

/// The course's step, s: a thirtieth of a frame at 90 frames per second.
const H_REF: f64 = 1.0 / 2700.0;

/// A plane through the origin tilted by `angle` about the z axis, with `friction`.
fn slope(angle: f64, friction: f64) -> Plane {
    Plane {
        point: Vec3::zeros(),
        normal: Vec3::new(-angle.sin(), angle.cos(), 0.0),
        friction,
    }
}

#[test]
fn points_resting_on_a_slope_slide_at_the_terminal_speed_of_the_friction_drag_at_any_step() {
    // Four free points without springs (ks = 0) lying on a plane tilted by 30 degrees, the
    // course's surface offset above it. Resting on it, each slides under the slope's share of
    // gravity, g sin(30) = 4.9 m/s^2, against the drag of the cloth's damping and of the
    // plane's friction, c + c_f with c_f = f / ((1 - f) h_ref), and reaches the terminal speed
    // g sin(30) / (c + c_f): 1.8 mm/s at friction 0.5 and the course's damping, whatever the
    // step. The backward-Euler recurrence v' = (v + h a) / (1 + (c + c_f) h) contracts by
    // 1 / (1 + (c + c_f) h) per step, at most 0.5 at 30 steps per frame, so after a second of
    // 90 to 2700 steps the speed is the terminal one up to rounding: the displacement of a step
    // (a few um) against positions of about a metre leaves some 1e-10 of it, and 1e-8 is far
    // below the friction retimed as the course's thirty steps in one, which holds the points
    // still, or applied once a step, which lets them slide thirty times faster.
    let angle = std::f64::consts::FRAC_PI_6;
    let plane = slope(angle, 0.5);
    let mesh = ClothMesh::new(&GridSpec {
        num_width_points: 2,
        num_height_points: 2,
        width: 0.1,
        height: 0.1,
        pinned: Vec::new(),
        ..GridSpec::default()
    })
    .unwrap_or_else(|e| panic!("mesh: {e}"));
    let colliders = [Collider::Plane(plane)];
    let along = Vec3::new(-angle.cos(), -angle.sin(), 0.0);
    let start: Vec<Vec3> = (0..4)
        .map(|i| {
            let across = Vec3::new(0.0, 0.0, 0.05 * f64::from(i));
            plane.normal * SURFACE_OFFSET + across - along * (0.05 * f64::from(i))
        })
        .collect();
    let solvers: [Build; 2] = [
        // NOTE: converged to rounding: the fast solver stops by default once an iteration
        // moves no point farther than 0.1 um, which here leaves the speed off by about a
        // millionth, and this test is about the drag's rate, not about that tolerance.
        ("fast-implicit", || {
            Box::new(FastImplicit::with_iterations(200).with_tolerance(1e-15))
        }),
        ("implicit", || Box::new(ImplicitEuler::new())),
    ];
    for steps_per_frame in [1, 5, 30] {
        let params = StepParams {
            ks: 0.0,
            steps_per_frame,
            self_collision: false,
            stretch_limit: false,
            ..StepParams::default()
        };
        let c_f = 0.5 / (0.5 * H_REF);
        let terminal = params.gravity.dot(&along) / (params.drag_rate() + c_f);
        for (name, build) in solvers {
            let mut solver = build();
            let mut state = ClothState {
                positions: start.clone(),
                last: start.clone(),
            };
            for f in 1..=90 {
                advance_frame(solver.as_mut(), &mesh, &colliders, &params, &mut state)
                    .unwrap_or_else(|e| panic!("{name}, {steps_per_frame} steps: frame {f}: {e}"));
            }
            for (i, (x, l)) in state.positions.iter().zip(&state.last).enumerate() {
                let v = (x - l) / params.dt();
                let height = (x - plane.point).dot(&plane.normal);
                assert!(
                    (v.dot(&along) - terminal).abs() <= 1e-8 * terminal,
                    "{name}, {steps_per_frame} steps, point {i}: velocity {v} (along the slope \
                     {:.6e} m/s), terminal {terminal:.6e} m/s",
                    v.dot(&along)
                );
                // The collision puts a point that crosses the slope back at the offset, from as
                // low as the slope: up by at most the offset in that step, after which it
                // coasts on by at most that times the sum of 1 / (1 + (c + c_f) h)^k, k >= 1,
                // which is 1 / ((c + c_f) h) <= 1 at up to 30 steps per frame (c_f h >= 1).
                assert!(
                    height > 0.0 && height <= 2.0 * SURFACE_OFFSET,
                    "{name}, {steps_per_frame} steps, point {i}: {height} m above the slope"
                );
            }
        }
    }
}
