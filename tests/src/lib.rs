//! Shared helpers for clothsim's integration tests.

use cloth_mesh::ClothState;
use cloth_scene::Scene;
use cloth_solver::{Solver, StepParams, Verlet};

/// Loads a bundled scene, panicking with the error (tests only).
#[must_use]
pub fn scene(name: &str) -> Scene {
    cloth_scene::load(name, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Runs `steps` Verlet steps of `scene` with `params`, calling `check` after each one.
pub fn run_steps(
    scene: &Scene,
    params: &StepParams,
    steps: usize,
    mut check: impl FnMut(usize, &ClothState),
) -> ClothState {
    let mut solver = Verlet::new();
    let mut state = ClothState::new(&scene.mesh);
    for i in 0..steps {
        solver
            .step(&scene.mesh, &scene.colliders, params, &mut state)
            .unwrap_or_else(|e| panic!("{}: step {i}: {e}", scene.origin));
        check(i, &state);
    }
    state
}
