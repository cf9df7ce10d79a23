//! Running the cases of a check and judging each measure against its bound.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cloth_mesh::StepParams;
use cloth_scene::Scene;
use cloth_solver::{REFERENCE_STEPS_PER_FRAME, SolverEntry, Verlet};
use serde_json::{Value, json};

use crate::case::{Case, Kind, bundled_names, cases, reference_steps};
use crate::figures::{self, Figures};
use crate::measure::{self, RUN_SECONDS, frames_in};
use crate::report::{CaseReport, Measure, Report, Verdict};
use crate::stepper::Stepper;
use crate::{CheckError, expected};

/// The state stayed finite: simulated seconds before the first non-finite state or error.
pub const FINITE: &str = "finite";
/// Pinned points that moved by any bit.
pub const PINS: &str = "pins";
/// `max H - H(0)`, J.
pub const ENERGY_PEAK: &str = "energy peak";
/// The sum of `H`'s rises between frames after 2 s, J.
pub const ENERGY_RISE: &str = "energy rise";
/// The largest spring length over its rest length after 1 s.
pub const STRETCH: &str = "stretch";
/// The settling speed, m/s.
pub const SETTLE: &str = "settle";
/// Wall-clock seconds of the case.
pub const TIME: &str = "time";
/// The relative change of kinetic energy over the first frame after a swap to the solver.
pub const SWAP_TO: &str = "swap to";
/// The relative change of kinetic energy over the first frame after a swap back to Verlet.
pub const SWAP_BACK: &str = "swap back";
/// The relative change of kinetic energy over the first frame after an edit of steps per frame.
pub const EDIT: &str = "edit";
/// The wind case's measure: how far the curtain's centre goes downwind against Verlet.
pub const WIND: &str = "wind";

/// `H` may exceed `H(0)` by this share of `E = M |g| L`.
pub const PEAK_SHARE: f64 = 1e-3;
/// The sum of `H`'s rises after 2 s may reach this share of `E`, or [`RISE_VERLET_FACTOR`]
/// times Verlet's, whichever is larger.
pub const RISE_SHARE: f64 = 1e-3;
/// See [`RISE_SHARE`].
pub const RISE_VERLET_FACTOR: f64 = 3.0;
/// The largest stretch after 1 s may reach this, or [`STRETCH_VERLET_FACTOR`] times Verlet's.
pub const STRETCH_BOUND: f64 = 1.122;
/// See [`STRETCH_BOUND`].
pub const STRETCH_VERLET_FACTOR: f64 = 1.02;
/// The RMS point speed at the end of a run without contact may reach this, m/s, or
/// [`SETTLE_VERLET_FACTOR`] times the largest of Verlet's.
pub const SETTLED_SPEED: f64 = 0.01;
/// The mean RMS speed over the last second of a run in contact may reach this, m/s, or
/// [`SETTLE_VERLET_FACTOR`] times the largest of Verlet's.
pub const CONTACT_SPEED: f64 = 0.02;
/// See [`CONTACT_SPEED`].
pub const SETTLE_VERLET_FACTOR: f64 = 3.0;
/// The relative change of kinetic energy a swap or an edit may make over its first frame.
pub const SWAP_SHARE: f64 = 0.05;
/// Most relative difference of the wind case's distance downwind from Verlet's.
pub const WIND_SHARE: f64 = 0.05;
/// A case may take this many times Verlet's time on it, as measured by the calibration: its
/// first frames, cheaper than its later ones (Verlet's own whole runs take two to eleven times
/// what the calibration gives them), so the multiple is generous.
pub const BUDGET_MULTIPLE: f64 = 40.0;
/// And this many seconds more, for building the solver (a factorisation) and for the noise of
/// a shared machine on short runs.
pub const BUDGET_FLOOR: f64 = 5.0;

/// What to check, beyond the solver.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckOptions {
    /// The bundled scenes to run (by name); empty for all.
    pub scenes: Vec<String>,
    /// The full set (steps 1, 2, 5, 10, 30 and the solver's own, self-collision on and off)
    /// instead of the quick one.
    pub full: bool,
    /// Only the runs at these steps per frame (empty for every count of the set); the swap and
    /// wind cases, at the solver's own steps, are kept.
    pub steps: Vec<u32>,
    /// A factor on every case's spring constant, for checking that verdicts do not hang on
    /// noise (1 for a check).
    pub ks_scale: f64,
    /// Cases run at once, each on its own thread (at least 1). Each case's time is held to a
    /// budget measured on one core, so more threads than free cores make cases too slow.
    pub threads: usize,
}

impl Default for CheckOptions {
    /// The quick set on every bundled scene, unperturbed, one case per core at a time.
    fn default() -> Self {
        Self {
            scenes: Vec::new(),
            full: false,
            steps: Vec::new(),
            ks_scale: 1.0,
            threads: std::thread::available_parallelism().map_or(1, std::num::NonZero::get),
        }
    }
}

/// Checks the solver of `entry`, built with `options` (a JSON object, as in a scene's
/// `solver_options`), on the cases `check` asks for; see the crate's documentation for the
/// cases, the measures and the budgets.
///
/// # Errors
/// [`CheckError`] when the solver cannot be built with `options`, a scene asked for is not
/// bundled, or the kit's own data does not parse. What the solver does on the cases is the
/// report, not an error.
pub fn check(
    entry: &SolverEntry,
    options: &Value,
    check: &CheckOptions,
) -> Result<Report, CheckError> {
    check_each(entry, options, check, &mut |_| {})
}

/// [`check`], calling `on_case` with each case as it ends (in the order they end when
/// `check.threads` is above 1), so a command can print rows as they come.
///
/// # Errors
/// As [`check`].
pub fn check_each(
    entry: &SolverEntry,
    options: &Value,
    check: &CheckOptions,
    on_case: &mut (dyn FnMut(&CaseReport) + Send),
) -> Result<Report, CheckError> {
    let started = Instant::now();
    entry.check(options).map_err(|source| CheckError::Build {
        solver: entry.name().to_owned(),
        source,
    })?;
    let verlet_figures = figures::load()?;
    let expected = expected::load()?;
    let scenes = load_scenes(&check.scenes)?;
    let named: Vec<(&'static str, StepParams)> =
        scenes.iter().map(|(n, s)| (*n, s.params)).collect();
    let cases = cases(entry.steps_per_frame(), &named, check.full);
    let cases = only_steps(cases, &check.steps, check.full)?;
    let timing = calibrate(&scenes, &cases)?;

    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, Result<CaseReport, CheckError>)>> = Mutex::new(Vec::new());
    let on_case = Mutex::new(on_case);
    let context = Context {
        entry,
        options,
        check,
        figures: &verlet_figures,
        scenes: &scenes,
        timing: &timing,
    };
    std::thread::scope(|scope| {
        for _ in 0..check.threads.max(1) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = cases.get(i) else { break };
                    let mut report = context.run(case);
                    if let Ok(r) = &mut report {
                        expected::apply(&expected, entry.name(), r);
                        r.judge();
                        let mut f = on_case
                            .lock()
                            .unwrap_or_else(std::sync::PoisonError::into_inner);
                        (*f)(r);
                    }
                    (results
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner))
                    .push((i, report));
                }
            });
        }
    });
    let mut results = results
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    results.sort_by_key(|(i, _)| *i);
    let cases = results
        .into_iter()
        .map(|(_, r)| r)
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Report {
        solver: entry.name().to_owned(),
        options: options.clone(),
        full: check.full,
        ks_scale: check.ks_scale,
        cases,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The bundled scenes named (all when none are), in the bundled order.
fn load_scenes(names: &[String]) -> Result<Vec<(&'static str, Arc<Scene>)>, CheckError> {
    for name in names {
        if !bundled_names().any(|b| b == name) {
            return Err(CheckError::UnknownScene {
                name: name.clone(),
                available: bundled_names().collect::<Vec<_>>().join(", "),
            });
        }
    }
    bundled_names()
        .filter(|b| names.is_empty() || names.iter().any(|n| n == b))
        .map(|b| Ok((b, Arc::new(cloth_scene::load(b, &[])?))))
        .collect()
}

/// Verlet's wall-clock seconds per step on each scene with self-collision on and off, as the
/// cases need them.
type Timing = BTreeMap<(&'static str, bool), f64>;

/// Frames of a calibration run, and the runs whose fastest is taken.
const CALIBRATION: (usize, usize) = (3, 3);

/// Times Verlet's steps on the scenes and switches of `cases`: the fastest of a few short runs
/// from rest, at the course's steps per frame. Times are of this machine now, so they cannot be
/// constants; the fastest run is the one least disturbed by other work.
fn calibrate(scenes: &[(&'static str, Arc<Scene>)], cases: &[Case]) -> Result<Timing, CheckError> {
    let mut timing = Timing::new();
    for case in cases {
        let self_collision = match case.kind {
            Kind::Run { self_collision, .. } => self_collision,
            Kind::Swap { .. } => true,
            Kind::Wind => false,
        };
        if timing.contains_key(&(case.scene, self_collision)) {
            continue;
        }
        let Some((_, scene)) = scenes.iter().find(|(n, _)| *n == case.scene) else {
            continue;
        };
        let params = StepParams {
            steps_per_frame: REFERENCE_STEPS_PER_FRAME,
            self_collision,
            ..scene.params
        };
        let mut best = f64::INFINITY;
        for _ in 0..CALIBRATION.1 {
            let mut stepper = Stepper::new(scene, params, &Verlet::ENTRY, &json!({}))?;
            let started = Instant::now();
            for _ in 0..CALIBRATION.0 {
                // A calibration run from rest does not fail; if it did, its time still counts.
                if stepper.frame().is_err() {
                    break;
                }
            }
            best = best.min(started.elapsed().as_secs_f64());
        }
        let steps = (CALIBRATION.0 as u32 * REFERENCE_STEPS_PER_FRAME) as f64;
        timing.insert((case.scene, self_collision), best / steps);
    }
    Ok(timing)
}

/// What every case of one check shares.
struct Context<'a> {
    entry: &'a SolverEntry,
    options: &'a Value,
    check: &'a CheckOptions,
    figures: &'a Figures,
    scenes: &'a [(&'static str, Arc<Scene>)],
    timing: &'a Timing,
}

/// `|a / b - 1|`, 0 when both are 0.
/// `cases` but for the runs at steps per frame not in `steps` (all of them when it is empty).
///
/// # Errors
/// [`CheckError::UnknownSteps`] for a count in `steps` at which no case of the set runs.
fn only_steps(mut cases: Vec<Case>, steps: &[u32], full: bool) -> Result<Vec<Case>, CheckError> {
    if steps.is_empty() {
        return Ok(cases);
    }
    let mut counts: Vec<u32> = cases
        .iter()
        .filter_map(|case| match case.kind {
            Kind::Run { steps, .. } => Some(steps),
            Kind::Swap { .. } | Kind::Wind => None,
        })
        .collect();
    counts.sort_unstable();
    counts.dedup();
    if let Some(&asked) = steps.iter().find(|s| !counts.contains(s)) {
        return Err(CheckError::UnknownSteps {
            asked,
            set: if full { "full" } else { "quick" },
            available: counts
                .iter()
                .map(u32::to_string)
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    cases.retain(|case| match case.kind {
        Kind::Run { steps: s, .. } => steps.contains(&s),
        Kind::Swap { .. } | Kind::Wind => true,
    });
    Ok(cases)
}

fn relative_change(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a / b - 1.0).abs() }
}

/// The difference of two kinetic energies `a` and `b` as a share of the energy of the motion
/// `motion` (kinetic plus elastic) they are taken from.
///
/// NOTE: not relative to `b` itself: at a swing's turning point the kinetic energy falls to a
/// small share of the motion's, the rest held by the springs, and there the same truncation
/// of two integrators over a frame, a small share of the motion's energy all along, becomes a
/// large share of the kinetic energy. A swap that loses the velocity loses the kinetic part of
/// the motion whole, which away from a turning point is most of it.
fn share_of(a: f64, b: f64, motion: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / motion.max(b.abs()).max(f64::MIN_POSITIVE)
    }
}

impl Context<'_> {
    fn run(&self, case: &Case) -> Result<CaseReport, CheckError> {
        let Some((_, scene)) = self.scenes.iter().find(|(n, _)| *n == case.scene) else {
            return Err(CheckError::UnknownScene {
                name: case.scene.to_owned(),
                available: bundled_names().collect::<Vec<_>>().join(", "),
            });
        };
        match case.kind {
            Kind::Run {
                steps,
                stretch_limit,
                self_collision,
                ks,
            } => {
                let params = StepParams {
                    steps_per_frame: steps,
                    stretch_limit,
                    self_collision,
                    ks: ks * self.check.ks_scale,
                    ..scene.params
                };
                self.run_case(case, scene, params, ks)
            }
            Kind::Swap { at } => self.swap_case(case, scene, at),
            Kind::Wind => self.wind_case(case, scene),
        }
    }

    /// The time budget of a case Verlet would run at `reference_steps` per frame, s.
    fn budget(&self, scene: &str, self_collision: bool, steps: u32, params: &StepParams) -> f64 {
        let per_step = self
            .timing
            .get(&(scene, self_collision))
            .copied()
            .unwrap_or(0.0);
        let verlet = per_step * f64::from(steps) * frames_in(RUN_SECONDS, params) as f64;
        BUDGET_MULTIPLE * verlet + BUDGET_FLOOR
    }

    fn blank(case: &Case, steps: u32, ks: f64) -> CaseReport {
        let (stretch_limit, self_collision, swap_frame) = match case.kind {
            Kind::Run {
                stretch_limit,
                self_collision,
                ..
            } => (Some(stretch_limit), Some(self_collision), None),
            Kind::Swap { at } => (None, None, Some(at)),
            Kind::Wind => (Some(true), Some(false), None),
        };
        CaseReport {
            id: case.id(),
            scene: case.scene.to_owned(),
            steps_per_frame: steps,
            stretch_limit,
            self_collision,
            ks,
            swap_frame,
            wind: (case.kind == Kind::Wind).then_some(crate::case::WIND_VELOCITY),
            measures: Vec::new(),
            verdict: Verdict::Pass,
            note: None,
        }
    }

    fn run_case(
        &self,
        case: &Case,
        scene: &Arc<Scene>,
        params: StepParams,
        ks: f64,
    ) -> Result<CaseReport, CheckError> {
        let mut report = Self::blank(case, params.steps_per_frame, ks);
        let mass = scene.mesh.point_mass(params.density);
        if self.entry.is_explicit() && params.ks > params.explicit_ks_limit(mass) {
            report.verdict = Verdict::Skipped;
            report.note = Some(format!(
                "an explicit solver is unstable above {:.4e} N/m at this step",
                params.explicit_ks_limit(mass)
            ));
            return Ok(report);
        }
        let budget = self.budget(
            case.scene,
            params.self_collision,
            reference_steps(ks),
            &params,
        );
        let deadline = Instant::now() + Duration::from_secs_f64(budget);
        let run = measure::run(scene, params, self.entry, self.options, Some(deadline))?;
        let fps = params.frames_per_sec;
        let m = &mut report.measures;
        m.push(Measure::at_least(
            FINITE,
            if run.error.is_some() {
                run.frames as f64 / fps
            } else {
                RUN_SECONDS
            },
            RUN_SECONDS,
            "s",
        ));
        m.push(Measure::at_most(PINS, run.pins_moved as f64, 0.0, ""));
        m.push(Measure::at_most(
            ENERGY_PEAK,
            run.energy_peak,
            PEAK_SHARE * run.energy_scale,
            "J",
        ));
        if run.complete() {
            let verlet = case.figure_key().and_then(|k| self.figures.get(&k));
            if verlet.is_none() {
                report.note = Some("no Verlet figures for this case: absolute bounds".to_owned());
            }
            let rise = verlet.map_or(0.0, |v| RISE_VERLET_FACTOR * v.energy_rise);
            m.push(Measure::at_most(
                ENERGY_RISE,
                run.energy_rise,
                (RISE_SHARE * run.energy_scale).max(rise),
                "J",
            ));
            if params.stretch_limit {
                let stretch = verlet.map_or(0.0, |v| STRETCH_VERLET_FACTOR * v.max_stretch);
                m.push(Measure::at_most(
                    STRETCH,
                    run.max_stretch,
                    STRETCH_BOUND.max(stretch),
                    "",
                ));
            }
            let verlet_settle = verlet.map_or(0.0, |v| SETTLE_VERLET_FACTOR * v.settle_max());
            let bound = if scene.colliders.is_empty() {
                SETTLED_SPEED.max(verlet_settle)
            } else {
                CONTACT_SPEED.max(verlet_settle)
            };
            m.push(Measure::at_most(SETTLE, run.settle, bound, "m/s"));
        } else if let Some(e) = &run.error {
            report.note = Some(e.clone());
        } else if run.stopped {
            report.note = Some(format!(
                "stopped at its budget after {} of {} frames",
                run.frames, run.planned
            ));
        }
        let time = if run.stopped {
            run.seconds.max(budget + f64::EPSILON)
        } else {
            run.seconds
        };
        report
            .measures
            .push(Measure::at_most(TIME, time, budget, "s"));
        Ok(report)
    }

    /// The wind case: the solver at its own steps and Verlet at the course's, each with the
    /// curtain's self-collision off (the case is about the wind, and it stays quick), under
    /// [`WIND_VELOCITY`](crate::case::WIND_VELOCITY) for 3 s.
    fn wind_case(&self, case: &Case, scene: &Arc<Scene>) -> Result<CaseReport, CheckError> {
        let steps = self.entry.steps_per_frame();
        let mut report = Self::blank(case, steps, scene.params.ks);
        let params = StepParams {
            steps_per_frame: steps,
            self_collision: false,
            ks: scene.params.ks * self.check.ks_scale,
            ..scene.params
        };
        let budget = self.budget(case.scene, false, REFERENCE_STEPS_PER_FRAME, &params);
        let wind = cloth_mesh::Vec3::from(crate::case::WIND_VELOCITY);
        let solver = measure::downwind(scene, params, self.entry, self.options, wind)?;
        let reference = StepParams {
            steps_per_frame: REFERENCE_STEPS_PER_FRAME,
            ..params
        };
        let verlet = measure::downwind(scene, reference, &Verlet::ENTRY, &json!({}), wind)?;
        let m = &mut report.measures;
        match &solver.error {
            Some(e) => {
                m.push(Measure::at_least(FINITE, 0.0, 1.0, ""));
                report.note = Some(e.clone());
            }
            None => m.push(Measure::at_most(
                WIND,
                relative_change(solver.distance, verlet.distance),
                WIND_SHARE,
                "",
            )),
        }
        m.push(Measure::at_most(TIME, solver.seconds, budget, "s"));
        Ok(report)
    }

    fn swap_case(
        &self,
        case: &Case,
        scene: &Arc<Scene>,
        at: usize,
    ) -> Result<CaseReport, CheckError> {
        let steps = self.entry.steps_per_frame();
        let mut report = Self::blank(case, steps, scene.params.ks);
        let params = StepParams {
            ks: scene.params.ks * self.check.ks_scale,
            ..scene.params
        };
        let budget = self.budget(
            case.scene,
            params.self_collision,
            REFERENCE_STEPS_PER_FRAME,
            &params,
        );
        match measure::swap(scene, params, self.entry, self.options, steps, at) {
            Ok(swap) => {
                let m = &mut report.measures;
                let change = share_of(swap.to, swap.verlet, swap.motion_to);
                m.push(Measure::at_most(SWAP_TO, change, SWAP_SHARE, ""));
                let change = share_of(swap.back, swap.solver, swap.motion_handed);
                m.push(Measure::at_most(SWAP_BACK, change, SWAP_SHARE, ""));
                let change = share_of(swap.edit, swap.solver, swap.motion_handed);
                m.push(Measure::at_most(EDIT, change, SWAP_SHARE, ""));
                m.push(Measure::at_most(TIME, swap.seconds, budget, "s"));
            }
            Err(CheckError::Swap { reason, .. }) => {
                report
                    .measures
                    .push(Measure::at_least(FINITE, 0.0, 1.0, ""));
                report.note = Some(reason);
            }
            Err(e) => return Err(e),
        }
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::{ClothMesh, ClothState, Collider};
    use cloth_solver::{OptionError, SolveError, Solver, StepReport};

    /// Verlet, with something done to the state after every step.
    struct Broken {
        verlet: Box<dyn Solver>,
        steps: usize,
        after: fn(&ClothMesh, &mut ClothState, usize),
    }

    impl Solver for Broken {
        fn name(&self) -> &'static str {
            "broken"
        }

        fn step(
            &mut self,
            mesh: &ClothMesh,
            colliders: &[Collider],
            params: &StepParams,
            state: &mut ClothState,
        ) -> Result<StepReport, SolveError> {
            if self.steps == 0 {
                (self.after)(mesh, state, 0);
            }
            let report = self.verlet.step(mesh, colliders, params, state)?;
            self.steps += 1;
            (self.after)(mesh, state, self.steps);
            Ok(report)
        }
    }

    fn broken(
        mesh: &ClothMesh,
        after: fn(&ClothMesh, &mut ClothState, usize),
    ) -> Result<Box<dyn Solver>, OptionError> {
        Ok(Box::new(Broken {
            verlet: Verlet::ENTRY.build(mesh, &json!({}))?,
            steps: 0,
            after,
        }))
    }

    /// Runs one case of `entry`, judged, with no list of expected failures.
    fn run_one(entry: &SolverEntry, case: &Case) -> CaseReport {
        let scenes = load_scenes(&[case.scene.to_owned()]).unwrap();
        let timing = calibrate(&scenes, std::slice::from_ref(case)).unwrap();
        let figures = figures::load().unwrap();
        let check = CheckOptions::default();
        let context = Context {
            entry,
            options: &json!({}),
            check: &check,
            figures: &figures,
            scenes: &scenes,
            timing: &timing,
        };
        let mut report = context.run(case).unwrap();
        report.judge();
        report
    }

    fn pinned4_run() -> Case {
        Case {
            scene: "pinned4",
            kind: Kind::Run {
                steps: 30,
                stretch_limit: true,
                self_collision: true,
                ks: 5000.0,
            },
        }
    }

    fn outcome(report: &CaseReport, name: &str) -> crate::Outcome {
        report
            .measure(name)
            .unwrap_or_else(|| panic!("no {name} in {report}"))
            .outcome
    }

    #[test]
    fn verlet_passes_a_hanging_cloth_and_a_swap() {
        let run = run_one(&Verlet::ENTRY, &pinned4_run());
        assert_eq!(run.verdict, Verdict::Pass, "{run}");
        assert_eq!(run.measures.len(), 7, "{run}");
        let swap = run_one(
            &Verlet::ENTRY,
            &Case {
                scene: "sphere",
                kind: Kind::Swap { at: 40 },
            },
        );
        assert_eq!(swap.verdict, Verdict::Pass, "{swap}");
    }

    #[test]
    fn a_solver_that_adds_energy_fails_the_energy_measures() {
        // Each step hands on its velocity 0.3 % larger than it was: more than the damping
        // (0.2 % a step) takes out, so the swing grows instead of dying.
        const PUMP: SolverEntry = SolverEntry::new("pump", "adds energy", |mesh, _| {
            broken(mesh, |_, state, _| {
                for (l, p) in state.last.iter_mut().zip(&state.positions) {
                    *l = p - (p - *l) * 1.003;
                }
            })
        });
        let run = run_one(&PUMP, &pinned4_run());
        assert!(run.verdict.fails(), "{run}");
        assert_eq!(outcome(&run, ENERGY_PEAK), crate::Outcome::Fail, "{run}");
        assert_eq!(outcome(&run, PINS), crate::Outcome::Pass, "{run}");
    }

    #[test]
    fn a_solver_that_moves_a_pin_by_a_bit_fails_the_pins() {
        const CREEP: SolverEntry = SolverEntry::new("creep", "moves a pin", |mesh, _| {
            broken(mesh, |mesh, state, steps| {
                if steps == 100
                    && let Some(i) = mesh.pinned().iter().position(|p| *p)
                {
                    state.positions[i].x = f64::from_bits(state.positions[i].x.to_bits() + 1);
                    state.last[i] = state.positions[i];
                }
            })
        });
        let run = run_one(&CREEP, &pinned4_run());
        assert_eq!(run.verdict, Verdict::Fail, "{run}");
        assert_eq!(outcome(&run, PINS), crate::Outcome::Fail, "{run}");
        assert_eq!(outcome(&run, ENERGY_PEAK), crate::Outcome::Pass, "{run}");
    }

    /// Verlet that keeps the velocity of its own last step, as a solver holding a velocity of
    /// its own does: what is done to the state between its steps is lost.
    struct OwnVelocity {
        verlet: Box<dyn Solver>,
        last: Option<Vec<cloth_mesh::Vec3>>,
    }

    impl Solver for OwnVelocity {
        fn name(&self) -> &'static str {
            "own-velocity"
        }

        fn step(
            &mut self,
            mesh: &ClothMesh,
            colliders: &[Collider],
            params: &StepParams,
            state: &mut ClothState,
        ) -> Result<StepReport, SolveError> {
            if let Some(last) = &self.last {
                state.last.clone_from(last);
            }
            let report = self.verlet.step(mesh, colliders, params, state)?;
            self.last = Some(state.last.clone());
            Ok(report)
        }
    }

    #[test]
    fn verlet_passes_the_wind_and_a_solver_that_keeps_its_own_velocity_fails_it() {
        const OWN: SolverEntry =
            SolverEntry::new("own-velocity", "loses the wind's push", |mesh, _| {
                Ok(Box::new(OwnVelocity {
                    verlet: Verlet::ENTRY.build(mesh, &json!({}))?,
                    last: None,
                }))
            });
        let wind = Case {
            scene: "curtain",
            kind: Kind::Wind,
        };
        let verlet = run_one(&Verlet::ENTRY, &wind);
        assert_eq!(verlet.verdict, Verdict::Pass, "{verlet}");
        let own = run_one(&OWN, &wind);
        assert_eq!(own.verdict, Verdict::Fail, "{own}");
        assert_eq!(outcome(&own, WIND), crate::Outcome::Fail, "{own}");
    }

    #[test]
    fn steps_keep_the_runs_at_those_counts_and_every_swap_and_refuse_a_count_the_set_lacks() {
        let scenes = [
            ("pinned4", StepParams::default()),
            ("curtain", StepParams::default()),
        ];
        let full = cases(1, &scenes, true);
        let kept = only_steps(full.clone(), &[1, 2], true).unwrap();
        let runs = |cases: &[Case], steps: u32| {
            cases
                .iter()
                .filter(|c| matches!(c.kind, Kind::Run { steps: s, .. } if s == steps))
                .count()
        };
        for steps in [1, 2] {
            assert_eq!(runs(&kept, steps), runs(&full, steps));
        }
        for steps in [5, 10, 30] {
            assert!(runs(&full, steps) > 0);
            assert_eq!(runs(&kept, steps), 0);
        }
        let others = |cases: &[Case]| {
            cases
                .iter()
                .filter(|c| !matches!(c.kind, Kind::Run { .. }))
                .count()
        };
        assert!(others(&full) > 0);
        assert_eq!(others(&kept), others(&full));
        assert_eq!(only_steps(full.clone(), &[], true).unwrap(), full);
        let e = only_steps(cases(1, &scenes, false), &[5], false).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--steps 5: the quick set runs at 1, 2 steps per frame"
        );
    }

    #[test]
    fn a_solver_that_drops_the_velocity_it_takes_over_fails_the_swap() {
        // A solver that keeps its own velocity, starting from rest, ignores the state's.
        const FORGETS: SolverEntry =
            SolverEntry::new("forgets", "drops a swap's velocity", |mesh, _| {
                broken(mesh, |_, state, steps| {
                    if steps == 0 {
                        state.last.clone_from(&state.positions);
                    }
                })
            });
        // At every frame the kit swaps at, the turning point of the rebound (frame 40, where
        // the kinetic energy is a quarter of the motion's) among them.
        for at in crate::SWAP_FRAMES {
            let swap = run_one(
                &FORGETS,
                &Case {
                    scene: "pinned4",
                    kind: Kind::Swap { at },
                },
            );
            assert_eq!(swap.verdict, Verdict::Fail, "{swap}");
            assert_eq!(outcome(&swap, SWAP_TO), crate::Outcome::Fail, "{swap}");
        }
    }

    #[test]
    fn a_run_past_its_deadline_stops_and_is_too_slow() {
        let scene = Arc::new(cloth_scene::load("pinned4", &[]).unwrap());
        let run = measure::run(
            &scene,
            scene.params,
            &Verlet::ENTRY,
            &json!({}),
            Some(Instant::now()),
        )
        .unwrap();
        assert!(run.stopped && !run.complete(), "{run:?}");
        let mut report = CaseReport {
            id: pinned4_run().id(),
            scene: "pinned4".to_owned(),
            steps_per_frame: 30,
            stretch_limit: Some(true),
            self_collision: Some(true),
            ks: 5000.0,
            swap_frame: None,
            wind: None,
            measures: vec![Measure::at_most(TIME, 3.0, 2.0, "s")],
            verdict: Verdict::Pass,
            note: None,
        };
        report.judge();
        assert_eq!(report.verdict, Verdict::TooSlow);
    }

    #[test]
    fn an_unknown_scene_or_a_bad_option_is_an_error_not_a_report() {
        let only = |name: &str| CheckOptions {
            scenes: vec![name.to_owned()],
            ..CheckOptions::default()
        };
        let e = check(&Verlet::ENTRY, &json!({}), &only("moon")).unwrap_err();
        assert!(e.to_string().starts_with("unknown scene \"moon\""), "{e}");
        let e = check(&Verlet::ENTRY, &json!({"threads": 0}), &only("pinned4")).unwrap_err();
        assert!(e.to_string().contains("threads is 0"), "{e}");
    }
}
