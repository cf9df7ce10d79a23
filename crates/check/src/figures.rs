//! Verlet's own figures on every case, the reference that several bounds scale with.
//!
//! They are constants of the tree (`verlet_figures.json`), written by the ignored generator
//! test of this module, so a check never runs Verlet at 200 steps per frame. Rerun it after a
//! change to Verlet, to the bundled scenes or to the measures:
//! `CLOTH_CHECK_WRITE_FIGURES=1 cargo test -p cloth-check --release -- --ignored
//! write_verlet_figures`.

use std::collections::BTreeMap;

use crate::CheckError;
#[cfg(test)]
use crate::case::reference_steps;
#[cfg(test)]
use cloth_mesh::{Collider, StepParams};
#[cfg(test)]
use cloth_solver::REFERENCE_STEPS_PER_FRAME;
use serde::{Deserialize, Serialize};

/// The file the figures are kept in, beside this module.
pub(crate) const FILE: &str = "src/verlet_figures.json";

/// The perturbations of `ks` under which Verlet's settling speed is taken: the bound is the
/// largest, so that a verdict does not hang on where one run of the reference happens to be in
/// its creep.
pub const KS_PERTURBATIONS: [f64; 3] = [1.0, 1.0 - 2e-4, 1.0 + 2e-4];

/// Verlet's figures on one scene with one set of switches and stiffness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct VerletFigure {
    /// The steps per frame Verlet ran at.
    pub steps_per_frame: u32,
    /// `max H - H(0)`, J.
    pub energy_peak: f64,
    /// The sum of the rises of `H` after 2 s, J.
    pub energy_rise: f64,
    /// The largest stretch after 1 s.
    pub max_stretch: f64,
    /// The settling speed, m/s, at each of [`KS_PERTURBATIONS`].
    pub settle: [f64; 3],
}

impl VerletFigure {
    /// The largest settling speed over the perturbations, m/s.
    pub(crate) fn settle_max(&self) -> f64 {
        self.settle.iter().copied().fold(0.0, f64::max)
    }
}

/// Verlet's figures by [`figure_key`](crate::case::figure_key).
pub(crate) type Figures = BTreeMap<String, VerletFigure>;

/// The figures kept in the tree.
pub(crate) fn load() -> Result<Figures, CheckError> {
    serde_json::from_str(include_str!("verlet_figures.json")).map_err(|e| CheckError::Data {
        file: FILE,
        reason: e.to_string(),
    })
}

/// The parameters and colliders of Verlet's reference run of a case: the case's switches and
/// `ks` at [`reference_steps`], with the damping and the friction retimed to keep their rates
/// where that is not the course's 30 steps per frame, so that the reference is the same
/// physical cloth: the course's per-step damping applied 200 times a frame would be a drag
/// almost seven times the model's.
#[cfg(test)]
pub(crate) fn reference_params(
    params: StepParams,
    colliders: &[Collider],
    nominal_ks: f64,
    retime_friction: impl Fn(&[Collider], &StepParams, &mut Vec<Collider>),
) -> (StepParams, Vec<Collider>) {
    let mut reference = StepParams {
        steps_per_frame: reference_steps(nominal_ks),
        ..params
    };
    let mut out = colliders.to_vec();
    if reference.steps_per_frame != REFERENCE_STEPS_PER_FRAME {
        reference.damping = 100.0 * -(-params.drag_rate() * reference.dt()).exp_m1();
        retime_friction(colliders, &reference, &mut out);
    }
    (reference, out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::{Kind, bundled_names, cases};
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};

    use std::sync::Arc;

    use cloth_scene::Scene;
    use cloth_solver::Verlet;
    use serde_json::json;

    use crate::measure::{self, RunFigures};

    /// Verlet's reference run of a case with `params`, at [`reference_steps`].
    fn reference_run(
        scene: &Scene,
        params: StepParams,
        nominal_ks: f64,
        retime_friction: impl Fn(&[Collider], &StepParams, &mut Vec<Collider>),
    ) -> Result<RunFigures, CheckError> {
        let (params, colliders) =
            reference_params(params, &scene.colliders, nominal_ks, retime_friction);
        let scene = Arc::new(Scene {
            colliders,
            ..scene.clone()
        });
        measure::run(&scene, params, &Verlet::ENTRY, &json!({}), None)
    }

    /// Every key of the full set of every scene: scene, switches and stiffness.
    fn every_key() -> Vec<(&'static str, bool, bool, f64)> {
        let scenes: Vec<(&'static str, StepParams)> = bundled_names()
            .map(|n| (n, cloth_scene::load(n, &[]).unwrap().params))
            .collect();
        let mut keys = Vec::new();
        for case in cases(1, &scenes, true) {
            if let Kind::Run {
                stretch_limit,
                self_collision,
                ks,
                ..
            } = case.kind
            {
                let key = (case.scene, stretch_limit, self_collision, ks);
                if !keys.contains(&key) {
                    keys.push(key);
                }
            }
        }
        keys
    }

    #[test]
    fn the_tree_has_verlet_s_figures_for_every_case_of_the_full_set() {
        let figures = load().unwrap();
        for (scene, limit, collision, ks) in every_key() {
            let key = crate::case::figure_key(scene, limit, collision, ks);
            let f = figures
                .get(&key)
                .unwrap_or_else(|| panic!("no figures for {key}"));
            assert_eq!(f.steps_per_frame, reference_steps(ks), "{key}");
            assert!(f.settle.iter().all(|s| s.is_finite()), "{key}");
        }
    }

    /// Writes Verlet's figures for every key of the full set into [`FILE`], on two threads,
    /// when `CLOTH_CHECK_WRITE_FIGURES=1` asks for it (so that a run of every ignored test, as
    /// CI's long runs are, leaves the constants alone).
    #[test]
    #[ignore = "the generator of src/verlet_figures.json: CLOTH_CHECK_WRITE_FIGURES=1 (release: about ten minutes)"]
    fn write_verlet_figures() {
        if std::env::var_os("CLOTH_CHECK_WRITE_FIGURES").is_none_or(|v| v != "1") {
            eprintln!("set CLOTH_CHECK_WRITE_FIGURES=1 to rewrite {FILE}");
            return;
        }
        let keys = every_key();
        let next = AtomicUsize::new(0);
        let out = Mutex::new(Figures::new());
        std::thread::scope(|scope| {
            for _ in 0..2 {
                scope.spawn(|| {
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(&(scene_name, stretch_limit, self_collision, ks)) = keys.get(i)
                        else {
                            break;
                        };
                        let scene = cloth_scene::load(scene_name, &[]).unwrap();
                        let mut settle = [0.0; 3];
                        let mut first = None;
                        for (j, factor) in KS_PERTURBATIONS.iter().enumerate() {
                            let params = StepParams {
                                ks: ks * factor,
                                stretch_limit,
                                self_collision,
                                ..scene.params
                            };
                            let run =
                                reference_run(&scene, params, ks, cloth_implicit::retime_friction)
                                    .unwrap();
                            let key = crate::case::figure_key(
                                scene_name,
                                stretch_limit,
                                self_collision,
                                ks,
                            );
                            assert!(run.complete(), "Verlet on {key}: {:?}", run.error);
                            settle[j] = run.settle;
                            if j == 0 {
                                first = Some(run);
                            }
                        }
                        let run = first.unwrap();
                        let key =
                            crate::case::figure_key(scene_name, stretch_limit, self_collision, ks);
                        eprintln!(
                            "{key}: rise {:.4e} J, stretch {:.4}, settle {:?} m/s ({:.1} s)",
                            run.energy_rise, run.max_stretch, settle, run.seconds
                        );
                        out.lock().unwrap().insert(
                            key,
                            VerletFigure {
                                steps_per_frame: reference_steps(ks),
                                energy_peak: run.energy_peak,
                                energy_rise: run.energy_rise,
                                max_stretch: run.max_stretch,
                                settle,
                            },
                        );
                    }
                });
            }
        });
        let figures = out.into_inner().unwrap();
        let text = serde_json::to_string_pretty(&figures).unwrap();
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(FILE);
        std::fs::write(&path, text + "\n").unwrap();
    }
}
