//! The cases of a check: which scene, steps per frame, switches and stiffness.

use cloth_mesh::{StepParams, Vec3};
use cloth_scene::BUNDLED;
use cloth_solver::REFERENCE_STEPS_PER_FRAME;

/// Spring constants of the stiff cases, N/m, run at one step per frame with the limit on.
pub const STIFF_KS: [f64; 2] = [1e5, 1e6];
/// Steps per frame of the full set (with the solver's own).
pub const FULL_STEPS: [u32; 5] = [1, 2, 5, 10, 30];
/// The scenes of the swap cases.
pub const SWAP_SCENES: [&str; 2] = ["pinned4", "sphere"];
/// The frames of Verlet's run at which the swap cases swap: the fall (10), the catch (20) and
/// the rebound or the contact (40).
pub const SWAP_FRAMES: [usize; 3] = [10, 20, 40];

/// The scene of the wind case: the hanging curtain, broadside to the wind.
pub const WIND_SCENE: &str = "curtain";
/// The wind of the wind case, m/s: across the curtain, a fresh breeze.
pub const WIND_VELOCITY: [f64; 3] = [0.0, 0.0, 10.0];

/// What a case runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Kind {
    /// The solver from rest for the run's length.
    Run {
        /// Steps per frame.
        steps: u32,
        /// Whether the stretch limit is on.
        stretch_limit: bool,
        /// Whether self-collision is on.
        self_collision: bool,
        /// The spring constant, N/m (before the check's perturbation).
        ks: f64,
    },
    /// Swaps from Verlet at a frame, back, and an edit of steps per frame.
    Swap {
        /// The frame of Verlet's run.
        at: usize,
    },
    /// The solver at its own steps under [`WIND_VELOCITY`], against Verlet under it.
    Wind,
}

/// One case of a check.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Case {
    /// The bundled scene.
    pub scene: &'static str,
    /// What it runs.
    pub kind: Kind,
}

fn on(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// The spring constant as written in case names: `5000`, `100000`.
fn ks_name(ks: f64) -> String {
    format!("{ks}")
}

impl Case {
    /// The case's name, as in reports and the list of expected failures.
    pub(crate) fn id(&self) -> String {
        match self.kind {
            Kind::Run {
                steps,
                stretch_limit,
                self_collision,
                ks,
            } => format!(
                "{} / {steps} step{} / limit {} / self-collision {} / ks {}",
                self.scene,
                if steps == 1 { "" } else { "s" },
                on(stretch_limit),
                on(self_collision),
                ks_name(ks)
            ),
            Kind::Swap { at } => format!("{} / swap at frame {at}", self.scene),
            Kind::Wind => format!(
                "{} / wind {} m/s across",
                self.scene,
                Vec3::from(WIND_VELOCITY).norm()
            ),
        }
    }

    /// The key of Verlet's figures for a run case: the scene, switches and stiffness (Verlet
    /// runs at its own steps whatever the case's).
    pub(crate) fn figure_key(&self) -> Option<String> {
        match self.kind {
            Kind::Run {
                stretch_limit,
                self_collision,
                ks,
                ..
            } => Some(figure_key(self.scene, stretch_limit, self_collision, ks)),
            Kind::Swap { .. } | Kind::Wind => None,
        }
    }
}

/// The key of Verlet's figures for `scene` with these switches and stiffness.
pub(crate) fn figure_key(
    scene: &str,
    stretch_limit: bool,
    self_collision: bool,
    ks: f64,
) -> String {
    format!(
        "{scene} / limit {} / self-collision {} / ks {}",
        on(stretch_limit),
        on(self_collision),
        ks_name(ks)
    )
}

/// The cases for a solver meant for `steps` per frame on `scenes` (names of bundled scenes,
/// each with its parameters), quick or `full`.
pub(crate) fn cases(steps: u32, scenes: &[(&'static str, StepParams)], full: bool) -> Vec<Case> {
    let mut step_counts: Vec<u32> = if full { FULL_STEPS.to_vec() } else { vec![2] };
    step_counts.push(steps);
    step_counts.sort_unstable();
    step_counts.dedup();
    let mut cases = Vec::new();
    for &(scene, params) in scenes {
        let collisions: Vec<bool> = if full {
            vec![true, false]
        } else {
            vec![params.self_collision]
        };
        for &self_collision in &collisions {
            for &steps in &step_counts {
                for stretch_limit in [true, false] {
                    cases.push(Case {
                        scene,
                        kind: Kind::Run {
                            steps,
                            stretch_limit,
                            self_collision,
                            ks: params.ks,
                        },
                    });
                }
            }
            for ks in STIFF_KS {
                cases.push(Case {
                    scene,
                    kind: Kind::Run {
                        steps: 1,
                        stretch_limit: true,
                        self_collision,
                        ks,
                    },
                });
            }
        }
    }
    if scenes.iter().any(|&(scene, _)| scene == WIND_SCENE) {
        cases.push(Case {
            scene: WIND_SCENE,
            kind: Kind::Wind,
        });
    }
    for &(scene, _) in scenes {
        if SWAP_SCENES.contains(&scene) {
            for at in SWAP_FRAMES {
                cases.push(Case {
                    scene,
                    kind: Kind::Swap { at },
                });
            }
        }
    }
    cases
}

/// The steps per frame at which Verlet is the reference for a stiffness of `ks` N/m: the
/// course's 30, or more where the springs are too stiff for them. An explicit step is stable
/// while `dt` stays below about `sqrt(2 m / (8 ks))` (the grid's largest stiffness eigenvalue
/// is about 8 ks), so the fewest stable steps go as `sqrt(ks)`: 200 keep the course's cloth
/// stable at 1e6 N/m.
pub(crate) fn reference_steps(ks: f64) -> u32 {
    let steps = (200.0 * (ks / 1e6).sqrt()).ceil();
    if steps.is_finite() {
        (steps as u32).max(REFERENCE_STEPS_PER_FRAME)
    } else {
        REFERENCE_STEPS_PER_FRAME
    }
}

/// Every bundled scene's name.
pub(crate) fn bundled_names() -> impl Iterator<Item = &'static str> {
    BUNDLED.iter().map(|b| b.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_quick_set_has_every_scene_at_two_step_counts_both_limits_the_stiff_cases_and_the_swaps()
    {
        let scenes: Vec<(&str, StepParams)> = bundled_names()
            .map(|n| (n, StepParams::default()))
            .collect();
        let quick = cases(1, &scenes, false);
        // 8 scenes x (2 step counts x 2 limits + 2 stiff) + 2 scenes x 3 swaps + the wind.
        assert_eq!(quick.len(), 8 * 6 + 6 + 1);
        let verlet = cases(30, &scenes, false);
        assert_eq!(verlet.len(), 8 * 6 + 6 + 1);
        // A solver meant for 2 steps runs them once.
        assert_eq!(cases(2, &scenes, false).len(), 8 * 4 + 6 + 1);
        // Full: 5 step counts x 2 limits + 2 stiff, self-collision on and off.
        assert_eq!(cases(1, &scenes, true).len(), 8 * 2 * 12 + 6 + 1);
        let ids: std::collections::BTreeSet<String> = quick.iter().map(Case::id).collect();
        assert_eq!(ids.len(), quick.len(), "case names are unique");
        assert!(ids.contains("sphere / 1 step / limit on / self-collision on / ks 5000"));
        assert!(ids.contains("pinned4 / 2 steps / limit off / self-collision on / ks 5000"));
        assert!(ids.contains("pinned4 / 1 step / limit on / self-collision on / ks 100000"));
        assert!(ids.contains("sphere / swap at frame 40"));
        assert!(ids.contains("curtain / wind 10 m/s across"));
    }

    #[test]
    fn verlet_runs_the_course_s_steps_below_stiff_springs_and_200_at_1e6() {
        assert_eq!(reference_steps(5000.0), 30);
        assert_eq!(reference_steps(1e5), 64);
        assert_eq!(reference_steps(1e6), 200);
    }
}
