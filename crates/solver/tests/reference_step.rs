//! The fast Verlet in the faithful order makes the course's step bit for bit.
//!
//! `reference_step` is the course's step written spring by spring and point by point; the fast
//! path reorganises every pass (rows of a stencil, a counting-sort hash with skipped boxes, a
//! pre-pass before the stretch sweep, SIMD builds, threads) but promises the same operations on
//! the same values in the same order, so the same bits. These tests generate scenes over what a
//! scene file can vary and hold the two to identical bits after tens of steps: a reordered sum or
//! a missed pair differs in the last bits at once and grows from there.

use cloth_mesh::{ClothMesh, ClothState, GridSpec, Orientation, Vec3};
use cloth_solver::{
    Collider, Plane, SolveError, Solver, Sphere, StepParams, Verlet, reference_step,
};
use proptest::prelude::*;

/// One generated scene: the cloth, the objects and the parameters.
#[derive(Debug, Clone)]
struct Case {
    spec: GridSpec,
    colliders: Vec<Collider>,
    params: StepParams,
    steps: usize,
}

/// Grids of 2 to 12 points a side (odd and even widths, so every row stencil's remainder),
/// either orientation, pins anywhere, thickness from far below to above the spacing (so
/// self-collision has from no pairs to crowded boxes).
fn spec() -> impl Strategy<Value = GridSpec> {
    (
        2usize..=12,
        2usize..=12,
        0.3f64..2.0,
        0.3f64..2.0,
        0.0005f64..0.15,
        any::<bool>(),
        proptest::collection::vec((0usize..12, 0usize..12), 0..5),
        any::<u64>(),
    )
        .prop_map(
            |(nw, nh, width, height, thickness, vertical, pins, seed)| GridSpec {
                width,
                height,
                num_width_points: nw,
                num_height_points: nh,
                thickness,
                orientation: if vertical {
                    Orientation::Vertical
                } else {
                    Orientation::Horizontal
                },
                pinned: pins.into_iter().map(|(x, y)| (x % nw, y % nh)).collect(),
                seed,
            },
        )
}

/// No object, a sphere under the cloth, a floor plane (level or tilted), or both.
fn colliders() -> impl Strategy<Value = Vec<Collider>> {
    let sphere = (
        0.0f64..1.0,
        0.2f64..0.9,
        0.0f64..1.0,
        0.1f64..0.5,
        0.0f64..=1.0,
    )
        .prop_map(|(x, y, z, radius, friction)| {
            Collider::Sphere(Sphere {
                origin: Vec3::new(x, y, z),
                radius,
                friction,
            })
        });
    let plane = (0.6f64..1.0, -0.3f64..0.3, -0.3f64..0.3, 0.0f64..=1.0).prop_map(
        |(y, nx, nz, friction)| {
            Collider::Plane(Plane {
                point: Vec3::new(0.0, y, 0.0),
                normal: Vec3::new(nx, 1.0, nz).normalize(),
                friction,
            })
        },
    );
    (proptest::option::of(sphere), proptest::option::of(plane))
        .prop_map(|(s, p)| s.into_iter().chain(p).collect())
}

/// The live parameters over the course's ranges where the explicit step stays stable (ks up to
/// a tenth of the stability limit at the slowest step here), spring types and both constraints
/// switched on and off.
fn params() -> impl Strategy<Value = StepParams> {
    (
        (10.0f64..20_000.0, 20.0f64..400.0, 0.0f64..5.0),
        (any::<bool>(), any::<bool>(), any::<bool>()),
        (any::<bool>(), any::<bool>()),
        (10u32..=60, -3.0f64..3.0, -12.0f64..0.0),
    )
        .prop_map(
            |(
                (ks, density, damping),
                (structural, shearing, bending),
                (self_collision, stretch_limit),
                (steps_per_frame, gx, gy),
            )| StepParams {
                ks,
                density,
                damping,
                gravity: Vec3::new(gx, gy, 0.0),
                structural,
                shearing,
                bending,
                steps_per_frame,
                self_collision,
                stretch_limit,
                ..StepParams::default()
            },
        )
}

fn case() -> impl Strategy<Value = Case> {
    (spec(), colliders(), params(), 20usize..=60).prop_map(|(spec, colliders, params, steps)| {
        Case {
            spec,
            colliders,
            params,
            steps,
        }
    })
}

/// Steps `solver` and the reference side by side from the mesh's start, requiring the same
/// bits (positions and last positions) after every step, and the same verdict when a step
/// fails.
fn same_bits_as_the_reference(case: &Case, solver: &mut Verlet) -> Result<(), TestCaseError> {
    let mesh = ClothMesh::new(&case.spec).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let mut fast = ClothState::new(&mesh);
    let mut plain = ClothState::new(&mesh);
    for step in 0..case.steps {
        let f = solver.step(&mesh, &case.colliders, &case.params, &mut fast);
        let p = reference_step(&mesh, &case.colliders, &case.params, &mut plain);
        match (f, p) {
            (Ok(_), Ok(())) => {}
            (Err(SolveError::NonFinite { .. }), Err(SolveError::NonFinite { .. })) => {
                return Ok(());
            }
            (f, p) => prop_assert!(false, "step {step}: fast {f:?}, reference {p:?}"),
        }
        for (name, a, b) in [
            ("position", &fast.positions, &plain.positions),
            ("last position", &fast.last, &plain.last),
        ] {
            for (i, (a, b)) in a.iter().zip(b).enumerate() {
                let bits = |v: &Vec3| v.map(f64::to_bits);
                prop_assert_eq!(
                    bits(a),
                    bits(b),
                    "step {}: {} of point {}: fast {:?}, reference {:?}",
                    step,
                    name,
                    i,
                    a,
                    b
                );
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn the_fast_faithful_verlet_makes_the_reference_steps_bits(case in case()) {
        same_bits_as_the_reference(&case, &mut Verlet::new())?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    #[test]
    fn the_fast_faithful_verlet_on_two_threads_makes_the_reference_steps_bits(case in case()) {
        let mut solver = Verlet::new()
            .with_threads(2)
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        same_bits_as_the_reference(&case, &mut solver)?;
    }
}

#[test]
fn the_reference_and_the_fast_path_agree_on_a_crumpled_cloth_with_crowded_boxes() {
    // Proptest's cloths are small; this one is big enough that the fast path's threaded
    // passes split it (tens of thousands of points would be slow here, so 70 x 70 on three
    // threads, whose hash runs and box tasks still cut the cloth) and dense enough that
    // self-collision chains corrections through crowded boxes: a vertical cloth whose
    // thickness is twice its spacing, falling onto a tilted floor under a sphere.
    let spec = GridSpec {
        num_width_points: 70,
        num_height_points: 70,
        thickness: 0.03,
        orientation: Orientation::Vertical,
        pinned: vec![(0, 69), (69, 69)],
        ..GridSpec::default()
    };
    let colliders = vec![
        Collider::Sphere(Sphere {
            origin: Vec3::new(0.5, 0.3, 0.2),
            radius: 0.25,
            friction: 0.3,
        }),
        Collider::Plane(Plane {
            point: Vec3::new(0.0, 0.1, 0.0),
            normal: Vec3::new(0.1, 1.0, 0.05).normalize(),
            friction: 0.5,
        }),
    ];
    let case = Case {
        spec,
        colliders,
        params: StepParams::default(),
        steps: 90,
    };
    for threads in [1, 3] {
        let mut solver = Verlet::new().with_threads(threads).unwrap();
        same_bits_as_the_reference(&case, &mut solver).unwrap();
    }
}

#[test]
fn the_time_step_is_the_courses_one_over_fps_over_steps() {
    // The course computes `1.0 / frames_per_sec / simulation_steps`, two roundings in that
    // order; `1 / (fps * steps)` lands one ulp away at the defaults, which a run of 2,700 steps
    // turns into visible bits.
    let params = StepParams::default();
    assert_eq!(params.dt().to_bits(), (1.0f64 / 90.0 / 30.0).to_bits());
    assert_ne!(params.dt().to_bits(), (1.0f64 / (90.0 * 30.0)).to_bits());
}
