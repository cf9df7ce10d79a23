//! fast-implicit's collision objects and self-collision act inside its minimisation, as
//! one-sided penalties, so a cloth that falls onto the floor and folds onto itself gains no
//! energy, and its layers are still kept apart.

use cloth_implicit::FastImplicit;
use cloth_mesh::{ClothMesh, ClothState, Vec3};
use cloth_scene::Scene;
use cloth_solver::{StepParams, advance_frame};

/// The selfCollision scene (a vertical cloth dropped onto a floor, where it folds onto itself)
/// on a 20 x 20 grid, its thickness scaled with the spacing so that self-collision reaches as
/// far in spacings as on the course's 50 x 50 cloth.
fn folding_cloth() -> Scene {
    let sets = [
        "cloth.num_width_points=20".to_owned(),
        "cloth.num_height_points=20".to_owned(),
        format!("cloth.thickness={}", 0.0095 * 49.0 / 19.0),
    ];
    cloth_scene::load("selfCollision", &sets).unwrap_or_else(|e| panic!("{e}"))
}

/// The total energy, J: kinetic from the step velocity, every enabled spring's, and gravity's
/// (`-m g . x`).
fn energy(mesh: &ClothMesh, params: &StepParams, state: &ClothState) -> f64 {
    let m = mesh.point_mass(params.density);
    let h = params.dt();
    let mut total = 0.0;
    for (x, l) in state.positions.iter().zip(&state.last) {
        total += 0.5 * m * ((x - l) / h).norm_squared() - m * params.gravity.dot(x);
    }
    for s in mesh.springs() {
        let k = params.stiffness(s.kind);
        let e = (state.positions[s.b as usize] - state.positions[s.a as usize]).norm() - s.rest;
        total += 0.5 * k * e * e;
    }
    total
}

/// The least distance between two points of the cloth that no spring joins, m.
fn closest_unjoined(mesh: &ClothMesh, positions: &[Vec3]) -> f64 {
    let mut joined = std::collections::HashSet::new();
    for s in mesh.springs() {
        joined.insert((s.a.min(s.b), s.a.max(s.b)));
    }
    let mut least = f64::INFINITY;
    for i in 0..positions.len() {
        for j in i + 1..positions.len() {
            if !joined.contains(&(i as u32, j as u32)) {
                least = least.min((positions[i] - positions[j]).norm());
            }
        }
    }
    least
}

/// Runs the folding cloth for 2 s at one step per frame; returns the sum of the rises of the
/// energy from frame to frame and the final state.
fn fold(ks_scale: f64, self_collision: bool) -> (f64, f64, ClothState, Scene) {
    let scene = folding_cloth();
    let params = StepParams {
        steps_per_frame: 1,
        ks: scene.params.ks * ks_scale,
        self_collision,
        ..scene.params
    };
    let mut solver = FastImplicit::new();
    let mut state = ClothState::new(&scene.mesh);
    let mut last = energy(&scene.mesh, &params, &state);
    let mut rises = 0.0;
    for f in 1..=180 {
        advance_frame(
            &mut solver,
            &scene.mesh,
            &scene.colliders,
            &params,
            &mut state,
        )
        .unwrap_or_else(|e| panic!("frame {f}: {e}"));
        let now = energy(&scene.mesh, &params, &state);
        rises += (now - last).max(0.0);
        last = now;
    }
    let scale = scene.mesh.point_mass(params.density) * scene.mesh.len() as f64 * 9.8;
    (rises, scale, state, scene)
}

#[test]
fn a_cloth_folding_onto_the_floor_and_itself_gains_no_energy() {
    // Why the bound: gravity is counted in the energy, the drag and friction only take energy
    // out, and the contact terms are potentials of the positions that are zero away from
    // contact: what the energy can rise by from frame to frame is what a contact term gives
    // back of what it stored (its share of a point's weight over its stiffness, micrometres,
    // times the weight: microjoules) and rounding. 0.1 % of the energy of a fall of the cloth's
    // own size (the check's bound on the same sum) is far above that and far below what a push
    // after the step adds (hundreds of joules on the course's cloth).
    for ks_scale in [1.0, 1.0002] {
        let (rises, scale, _, _) = fold(ks_scale, true);
        assert!(
            rises <= 1e-3 * scale,
            "ks x {ks_scale}: the energy rose by {rises:.3e} J in all, bound {:.3e} J",
            1e-3 * scale
        );
    }
}

#[test]
fn self_collision_inside_the_step_keeps_the_layers_apart() {
    // The penalty lets two points overlap by their pressing force over its stiffness (a
    // fraction of a millimetre under a few layers' weight), so layers stay nearly twice the
    // thickness apart; without self-collision the folds pass through each other and points
    // of different layers meet. Half the reach separates the two.
    let (_, _, on, scene) = fold(1.0, true);
    let reach = 2.0 * scene.mesh.spec().thickness;
    let apart = closest_unjoined(&scene.mesh, &on.positions);
    let (_, _, off, _) = fold(1.0, false);
    let together = closest_unjoined(&scene.mesh, &off.positions);
    assert!(
        apart >= 0.5 * reach,
        "with self-collision two unjoined points are {apart:.4} m apart, reach {reach:.4} m"
    );
    assert!(
        together < 0.5 * reach,
        "without self-collision the closest unjoined points are {together:.4} m apart: the \
         case does not fold onto itself"
    );
}
