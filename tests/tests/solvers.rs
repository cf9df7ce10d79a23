//! Every bundled scene with every registered solver: the built-in ones of `clothsim` and the
//! `xpbd` of the third-party example crate, each at the steps per frame its entry recommends,
//! with the options the scene gives it. Found through the registry and the bundle, so a new
//! scene or a new registered solver is covered with no new code.

use cloth_mesh::{ClothState, StepParams};
use cloth_solver::{Registry, advance_frame};

/// A few frames: every solver has taken a step, the cloth has started to fall and, in the
/// scenes with objects and self-contact, collisions have begun.
const FRAMES: usize = 6;

fn registry() -> Registry {
    clothsim::default_registry().with(clothsim_xpbd::Xpbd::ENTRY)
}

#[test]
fn the_registry_holds_the_built_in_solvers_and_xpbd() {
    let names: Vec<&str> = registry().names().collect();
    assert_eq!(names, ["verlet", "implicit", "fast-implicit", "xpbd"]);
}

#[test]
fn every_scene_runs_with_every_solver_and_stays_finite_with_its_pins_in_place() {
    let registry = registry();
    let default = registry
        .default_entry()
        .map(cloth_solver::SolverEntry::name)
        .unwrap_or_default();
    for bundled in cloth_scene::BUNDLED {
        let scene = cloth_scene::load(bundled.name, &[]).unwrap();
        for entry in registry.entries() {
            let what = format!("{} with {}", scene.origin, entry.name());
            let options = scene.options_for(entry.name(), default);
            let mut solver = entry
                .build(&scene.mesh, &options)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            let params = StepParams {
                steps_per_frame: entry.steps_per_frame(),
                ..scene.params
            };
            let mut state = ClothState::new(&scene.mesh);
            let start = state.positions.clone();
            for f in 0..FRAMES {
                advance_frame(
                    solver.as_mut(),
                    &scene.mesh,
                    &scene.colliders,
                    &params,
                    &mut state,
                )
                .unwrap_or_else(|e| panic!("{what}: frame {f}: {e}"));
            }
            assert_eq!(state.first_non_finite(), None, "{what}");
            // Pinned points are never moved by any step of any solver: exactly, not nearly.
            for (i, _) in scene.mesh.pinned().iter().enumerate().filter(|(_, p)| **p) {
                assert_eq!(
                    state.positions[i], start[i],
                    "{what}: pinned point {i} moved"
                );
            }
            // Something happened: gravity moved the free cloth (every scene has free points).
            assert!(
                state.positions.iter().zip(&start).any(|(p, s)| p != s),
                "{what}: nothing moved"
            );
        }
    }
}
