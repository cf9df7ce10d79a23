//! The XPBD solver's physics: pins, the static stretch its compliance implies, and stability at
//! one step per frame.

use cloth_mesh::{ClothMesh, ClothState, GridSpec, Orientation, Vec3};
use cloth_solver::{Solver, StepParams, advance_frame, kinetic_energy};
use clothsim_xpbd::Xpbd;

#[test]
fn pinned_points_stay_put() {
    for name in ["pinned2", "pinned4", "curtain", "hammock"] {
        let scene = cloth_scene::load(name, &[]).unwrap();
        let params = StepParams {
            steps_per_frame: Xpbd::ENTRY.steps_per_frame(),
            ..scene.params
        };
        let mut state = ClothState::new(&scene.mesh);
        let start = state.positions.clone();
        let mut solver = Xpbd::new();
        for frame in 0..90 {
            advance_frame(
                &mut solver,
                &scene.mesh,
                &scene.colliders,
                &params,
                &mut state,
            )
            .unwrap_or_else(|e| panic!("{name}: frame {frame}: {e}"));
            for (i, _) in scene.mesh.pinned().iter().enumerate().filter(|(_, p)| **p) {
                assert_eq!(
                    state.positions[i], start[i],
                    "{name}: pin {i}, frame {frame}"
                );
            }
        }
    }
}

#[test]
fn a_hanging_chain_stretches_as_its_compliance_says() {
    // Two chains of five points, 0.1 m apart, side by side (a 2 x 5 horizontal grid, 0.1 m x
    // 0.4 m), hanging along -z from their pinned far row; structural springs only. By the
    // mirror symmetry between the chains the cross springs stay at rest, so each chain is on
    // its own: the spring above the j-th free point from the bottom (j = 1..4) carries the
    // weight of j points, m = 0.1 * 0.4 * 150 / 10 = 0.6 kg each, so at rest its length is
    // L + j m g / k (Hooke's law, k = 5000 N/m: 1.18 mm per point, at most 4.7 % of L, so the
    // 10 % stretch limit stays idle).
    //
    // XPBD reaches exactly this state: at a fixed point x = x_last, each step predicts
    // x + g dt^2, and the converged constraint solve with compliance alpha = 1/k returns it to x
    // only where C = -alpha~ lambda and the constraint forces lambda / dt^2 balance gravity,
    // which is Hooke's law (the compliance is the inverse stiffness). Ten sweeps converge: each
    // spring's update shrinks the residual by w / (w + alpha~) with alpha~ / w = m / (k dt^2)
    // = 875, so the sweep error is ~1e-29 of the step's motion. The motion decays at least as
    // the course's drag, 5.4 1/s, so after 20 s it is e^-108 of the 5 mm sag; what remains is
    // rounding of O(1) m coordinates over 54,000 steps, far below the 1e-9 m asked.
    let mesh = ClothMesh::new(&GridSpec {
        width: 0.1,
        height: 0.4,
        num_width_points: 2,
        num_height_points: 5,
        orientation: Orientation::Horizontal,
        pinned: vec![(0, 4), (1, 4)],
        ..GridSpec::default()
    })
    .unwrap();
    let params = StepParams {
        shearing: false,
        bending: false,
        self_collision: false,
        gravity: Vec3::new(0.0, 0.0, -9.8),
        ..StepParams::default()
    };
    let mut state = ClothState::new(&mesh);
    let mut solver = Xpbd::new();
    for _ in 0..20 * 90 {
        advance_frame(&mut solver, &mesh, &[], &params, &mut state).unwrap();
    }
    let m = mesh.point_mass(params.density);
    let rest = 0.1;
    for column in 0..2 {
        for row in 0..4 {
            let below = row + 1; // points hanging from this spring: rows 0..=row
            let (lower, upper) = (row * 2 + column, (row + 1) * 2 + column);
            let length = (state.positions[upper] - state.positions[lower]).norm();
            let expected = rest + below as f64 * m * 9.8 / params.ks;
            assert!(
                (length - expected).abs() < 1e-9,
                "column {column}, spring above row {row}: {length} m, Hooke says {expected} m"
            );
        }
    }
}

#[test]
fn a_stiffer_compliance_stretches_less_in_proportion() {
    // The same chain with ks doubled: every extension halves (e = j m g / k), whereas a
    // position-based solver without compliance would give the same shape for any ks.
    let mesh = ClothMesh::new(&GridSpec {
        width: 0.1,
        height: 0.1,
        num_width_points: 2,
        num_height_points: 2,
        orientation: Orientation::Horizontal,
        pinned: vec![(0, 1), (1, 1)],
        ..GridSpec::default()
    })
    .unwrap();
    let extension = |ks: f64| {
        let params = StepParams {
            ks,
            shearing: false,
            bending: false,
            self_collision: false,
            gravity: Vec3::new(0.0, 0.0, -9.8),
            ..StepParams::default()
        };
        let mut state = ClothState::new(&mesh);
        let mut solver = Xpbd::new();
        for _ in 0..20 * 90 {
            advance_frame(&mut solver, &mesh, &[], &params, &mut state).unwrap();
        }
        (state.positions[2] - state.positions[0]).norm() - 0.1
    };
    let (soft, stiff) = (extension(500.0), extension(1000.0));
    // m g / k = 0.375 kg * 9.8 / 500 = 7.35 mm (under the 10 % limit); settled as above, so
    // 1e-9 m.
    let m = mesh.point_mass(StepParams::default().density);
    assert!((soft - m * 9.8 / 500.0).abs() < 1e-9, "{soft}");
    assert!((stiff - soft / 2.0).abs() < 1e-9, "{stiff} vs {soft}");
}

#[test]
fn pinned4_at_one_step_per_frame_stays_finite_and_settles() {
    // One step per frame is 1/90 s, 30 times the course's step: Verlet is unstable there at
    // this ks (its limit is m / (2 dt^2) = 243 N/m for 0.06 kg points), XPBD is not, since each
    // update only moves points towards satisfying a constraint. The damping is the course's drag
    // rate, about 5.4 1/s at 0.2 %, whatever the step: over 10 s it takes the velocity down by
    // at least e^-54 (the unconverged sweeps damp it further). The cloth falls at most about
    // 0.5 m before the springs hold it, about 3 m/s, so anything left above 1 mm/s is motion the
    // solver itself keeps up; the kinetic energy must also have fallen by four orders of
    // magnitude from its peak.
    let scene = cloth_scene::load("pinned4", &[]).unwrap();
    let params = StepParams {
        steps_per_frame: 1,
        ..scene.params
    };
    assert_eq!(Xpbd::ENTRY.steps_per_frame(), 1, "the entry's own step");
    assert!(params.ks > params.explicit_ks_limit(scene.mesh.point_mass(params.density)));
    let mut state = ClothState::new(&scene.mesh);
    let mut solver = Xpbd::new();
    let m = scene.mesh.point_mass(params.density);
    let mut peak: f64 = 0.0;
    for frame in 0..10 * 90 {
        solver
            .step(&scene.mesh, &scene.colliders, &params, &mut state)
            .unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        peak = peak.max(kinetic_energy(&state, m, params.dt()));
    }
    assert_eq!(state.first_non_finite(), None);
    let speed = state
        .positions
        .iter()
        .zip(&state.last)
        .map(|(p, l)| (p - l).norm() / params.dt())
        .fold(0.0, f64::max);
    assert!(speed < 1e-3, "fastest point still moves at {speed} m/s");
    let end = kinetic_energy(&state, m, params.dt());
    assert!(end < peak * 1e-4, "kinetic energy {end} J, peak {peak} J");
    // And it hangs: the middle has sagged below the pinned corners.
    let middle = state.positions[25 * 50 + 25];
    assert!(middle.y < 1.0 - 0.05, "middle at {}", middle.y);
}
