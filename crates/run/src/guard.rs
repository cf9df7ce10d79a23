//! The divergence guard: tells a run that is coming apart from one that is only far from rest.
//!
//! One guard serves the live UI and the headless commands (`simulate`, `render`, `bench`), so
//! they stop the same runs and explain them the same way. It is checked once per simulated
//! frame and stops a run for one of three reasons only:
//!
//! - **Non-finite state**: a position is NaN or infinite. Nothing can be drawn or continued.
//! - **Energy from nowhere**: the total energy `H` (kinetic + spring + gravity, the measure
//!   the conformance kit uses, [`cloth_solver::energy`]) has risen above its value at the start
//!   by more than [`ENERGY_RISE`] times what the start and gravity can supply (the budget,
//!   [`Guard::start`]). In the model nothing adds energy: pins do not move, colliders stand
//!   still, damping and friction only take energy out, and gravity's work is already in `H`
//!   (a fall turns potential energy into kinetic at constant `H`). A stable step errs by a
//!   fraction of the energy in motion, which the budget bounds; so a rise of several budgets is
//!   energy made by the numbers (a collider or self-collision throwing points across a step, an
//!   unstable integration), at any run length, however few frames it took.
//! - **Runaway**: over the last [`WINDOW`] seconds of simulated time (or since the start, when
//!   shorter) the fastest point got at least [`GROWTH`] times faster *and* the kinetic energy grew
//!   at least `GROWTH^2` times, and the fastest point is faster than anything gravity could have
//!   made it (`|g| t`, plus [`SPEED_MARGIN`] for what stretched springs give back). An unstable
//!   explicit integration multiplies its error by a constant factor every step, so it passes all
//!   three tests within a few frames; a stretched cloth settling (speeds bounded by the spring
//!   energy it started with) or a free fall (speed `g t`, energy `t^2`: it never outruns gravity)
//!   passes none.
//!
//! A stretched spring is not a divergence: with the stretch limit off a hanging cloth settles
//! at several times its rest length, which is the course's experiment, not a failure.

use std::collections::VecDeque;

use cloth_mesh::{ClothMesh, ClothState};
use cloth_solver::{SolverEntry, StepParams, energy, kinetic_energy};

/// Simulated seconds the runaway test looks back over.
///
/// NOTE: a quarter second is 22 frames at the course's 90 frames/s and hundreds of steps;
/// an instability that has not grown fourfold in that many steps grows by less than 1 % per
/// step and is better seen by the user than stopped.
pub const WINDOW: f64 = 0.25;

/// Growth of the fastest point's speed over [`WINDOW`] that counts as running away (energy:
/// its square).
pub const GROWTH: f64 = 4.0;

/// m/s allowed above gravity's `|g| t` before a fast point counts as a runaway.
///
/// NOTE: a spring stretched to three times its rest length at the course's ks = 5000 N/m
/// gives back at most `ks (2 L)^2 / 2` per spring; over a point's few kilograms per square
/// metre that is a few metres per second; 20 m/s is far beyond, yet an exponential blow-up
/// crosses it within a few frames.
pub const SPEED_MARGIN: f64 = 20.0;

/// How many budgets `H` may rise above its start before the run counts as making energy
/// (see the module doc).
///
/// NOTE: the bundled scenes under every built-in solver rise by at most a small fraction of
/// one budget (see docs/performance.md); a blow-up multiplies its energy by orders of
/// magnitude a frame, so the factor costs it a frame or two.
pub const ENERGY_RISE: f64 = 10.0;

/// Why a run was stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum Divergence {
    /// A position, the speed or the energy is NaN or infinite.
    NonFinite,
    /// Total energy far above what the start and gravity can supply.
    EnergyRise {
        /// How far `H` rose above its start, J.
        rise: f64,
        /// What the start and gravity can supply, J (see [`Guard::start`]).
        budget: f64,
        /// The larger of the kinetic and the spring energy now, as words: where the energy
        /// went (`kinetic`: points thrown; `spring`: springs torn apart).
        into: &'static str,
    },
    /// Speed and energy growing without bound.
    Runaway {
        /// The fastest point's speed, m/s.
        speed: f64,
        /// How many times faster it got over the window.
        growth: f64,
        /// The window, s.
        window: f64,
    },
}

impl Divergence {
    /// Whether going on from the last good frame makes sense: after a runaway or an energy
    /// rise the user may judge the run honest; non-finite positions cannot go on.
    pub fn resumable(&self) -> bool {
        !matches!(self, Divergence::NonFinite)
    }

    /// One sentence: what happened.
    pub fn describe(&self) -> String {
        match self {
            Divergence::NonFinite => {
                "the cloth's positions are no longer finite numbers".to_owned()
            }
            Divergence::EnergyRise { rise, budget, into } => format!(
                "the cloth's total energy (kinetic + spring + gravity) rose by {} J since the \
                 start, {} times what its start and gravity can supply ({} J), mostly as {into} \
                 energy: nothing in the model adds energy, so this is not a result",
                short(*rise),
                short(rise / budget),
                short(*budget)
            ),
            Divergence::Runaway {
                speed,
                growth,
                window,
            } => format!(
                "the cloth is blowing up: its fastest point moves at {} m/s, {} times faster than \
                 {window:.2} s before, and its energy keeps growing",
                short(*speed),
                short(*growth)
            ),
        }
    }

    /// What to change, fitted to the cause and the settings: an explicit solver (the entry's
    /// [`SolverEntry::is_explicit`]) past its stability limit needs a smaller step or softer
    /// springs; otherwise a smaller step is the general cure.
    pub fn advice(&self, entry: &SolverEntry, params: &StepParams, point_mass: f64) -> String {
        if entry.is_explicit() {
            let name = capitalised(entry.name());
            let limit = params.explicit_ks_limit(point_mass);
            if params.ks > limit {
                let needed = (params.ks / limit).sqrt() * f64::from(params.steps_per_frame);
                return format!(
                    "ks {:.0} N/m is past {name}'s stability limit of about {limit:.0} N/m at this \
                     step: raise steps/frame to at least {:.0}, lower ks below {limit:.0}, or \
                     use an implicit solver",
                    params.ks,
                    needed.ceil()
                );
            }
            return match self {
                Divergence::NonFinite => format!(
                    "a step gave non-finite positions within {name}'s stability limit: raise \
                     steps/frame (a smaller step) or use an implicit solver"
                ),
                Divergence::EnergyRise { .. } => ENERGY_ADVICE.to_owned(),
                Divergence::Runaway { .. } => "energy is being pumped in faster than damping \
                     takes it out: raise steps/frame (a smaller step) or damping, or use an \
                     implicit solver"
                    .to_owned(),
            };
        }
        // Only a solver with an iterations option is told to raise it.
        let iterations = entry.options().iter().any(|o| o.name == "iterations");
        match (self, iterations) {
            (Divergence::EnergyRise { .. }, _) => ENERGY_ADVICE.to_owned(),
            (Divergence::NonFinite, true) => "the solver's iterations did not converge: raise \
                 iterations or steps/frame, or lower ks"
                .to_owned(),
            (Divergence::NonFinite, false) => {
                "the step did not converge: raise steps/frame (a smaller step) or lower ks"
                    .to_owned()
            }
            (Divergence::Runaway { .. }, true) => {
                "raise steps/frame (a smaller step) or iterations, or lower ks".to_owned()
            }
            (Divergence::Runaway { .. }, false) => {
                "raise steps/frame (a smaller step) or lower ks".to_owned()
            }
        }
    }
}

/// What to change when energy came from nowhere within the step's stability limit: what throws
/// points is a contact pushing them further in a step than the step can carry.
const ENERGY_ADVICE: &str = "a contact moved points further in one step than the cloth can \
     carry (self-collision with a cloth.thickness near or above the spacing of the points, or a \
     sphere or plane placed through the cloth), or the step is too long: check cloth.thickness \
     and the colliders, or raise steps/frame";

/// What the guard measured at the end of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measure {
    /// Simulated time, s.
    pub time: f64,
    /// Kinetic energy, J.
    pub kinetic: f64,
    /// Fastest point's speed, m/s.
    pub speed: f64,
}

impl Measure {
    /// Measures `state` at simulated time `time` (velocities from the last step of `dt`).
    pub fn of(state: &ClothState, point_mass: f64, dt: f64, time: f64) -> Self {
        let speed = state
            .positions
            .iter()
            .zip(&state.last)
            .map(|(p, l)| (p - l).norm_squared())
            .fold(
                0.0,
                |a: f64, b| if b.is_nan() { f64::NAN } else { a.max(b) },
            )
            .sqrt()
            / dt;
        Self {
            time,
            kinetic: kinetic_energy(state, point_mass, dt),
            speed,
        }
    }
}

/// The energy the guard judges a run against (see [`Guard::start`]).
#[derive(Debug, Clone, PartialEq)]
struct Budget {
    /// The parameters it was taken under: energy is measured with them, so a change of them
    /// (an edit in the UI) takes a new reference.
    params: StepParams,
    /// `H` at the reference, J.
    start: f64,
    /// What the start and gravity can supply, J.
    supply: f64,
}

/// The guard: a short history of frame measures and the energy reference.
#[derive(Debug, Clone, Default)]
pub struct Guard {
    window: VecDeque<Measure>,
    runaway_off: bool,
    budget: Option<Budget>,
}

impl Guard {
    /// A guard with no history.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the history (after a reset or a change of the state from outside).
    pub fn clear(&mut self) {
        self.window.clear();
    }

    /// Stops watching for runaways (the user chose to go on anyway); non-finite states are
    /// still stopped, since nothing can continue from them. [`Self::rearm`] undoes it.
    pub fn allow_runaway(&mut self) {
        self.runaway_off = true;
        self.window.clear();
    }

    /// Watches for runaways again.
    pub fn rearm(&mut self) {
        self.runaway_off = false;
        self.window.clear();
    }

    /// Forgets the energy reference: the next frame takes a new one. For a change of the state
    /// from outside the model (a hand that grabs, drags or pokes the cloth), which adds energy
    /// the model does not account for.
    pub fn forget_energy(&mut self) {
        self.budget = None;
    }

    /// Takes `state` of `mesh` under `params` as the energy reference: its total energy `H0`
    /// and the budget `K0 + S0 + M |g| L + M v^2 / 2`: its kinetic and spring energy, gravity's
    /// energy scale (the cloth's mass falling its own size, [`cloth_solver::energy::scale`]),
    /// and the kinetic energy of the whole cloth at [`SPEED_MARGIN`] (what the runaway test
    /// already allows springs to give back; it keeps the budget above round-off for a cloth at
    /// rest without gravity). With wind, the speed is the air's fastest when faster: drag
    /// can carry the cloth up to the air's speed, and no further.
    pub fn start(&mut self, mesh: &ClothMesh, state: &ClothState, params: &StepParams) {
        let mass = mesh.point_mass(params.density) * mesh.len() as f64;
        let wind = &params.wind;
        let air = if wind.blows() {
            wind.velocity.norm() * (1.0 + wind.gust)
        } else {
            0.0
        };
        let speed = SPEED_MARGIN.max(air);
        let budget = energy::kinetic(mesh, state, params)
            + energy::spring(mesh, state, params)
            + energy::scale(mesh, params)
            + 0.5 * mass * speed * speed;
        self.budget = Some(Budget {
            params: *params,
            start: energy::total(mesh, state, params),
            supply: budget,
        });
    }

    /// Judges the total energy of `state` against the reference (taking one first when there
    /// is none or the parameters changed).
    fn check_energy(
        &mut self,
        mesh: &ClothMesh,
        state: &ClothState,
        params: &StepParams,
    ) -> Result<(), Divergence> {
        if self.budget.as_ref().is_none_or(|b| b.params != *params) {
            self.start(mesh, state, params);
            return Ok(());
        }
        let Some(b) = &self.budget else {
            return Ok(());
        };
        let kinetic = energy::kinetic(mesh, state, params);
        let spring = energy::spring(mesh, state, params);
        let rise = kinetic + spring + energy::gravity(mesh, state, params) - b.start;
        if rise.is_nan() {
            return Err(Divergence::NonFinite);
        }
        if rise > ENERGY_RISE * b.supply {
            return Err(Divergence::EnergyRise {
                rise,
                budget: b.supply,
                into: if kinetic >= spring {
                    "kinetic"
                } else {
                    "spring"
                },
            });
        }
        Ok(())
    }

    /// Checks the end of a frame.
    ///
    /// # Errors
    /// The divergence, when the run must stop.
    pub fn check(
        &mut self,
        m: Measure,
        gravity: f64,
        positions_finite: bool,
    ) -> Result<(), Divergence> {
        if !(positions_finite && m.speed.is_finite() && m.kinetic.is_finite()) {
            return Err(Divergence::NonFinite);
        }
        self.window.push_back(m);
        // Keep the newest sample at least a window old as the front (with the frames of 1/90 s,
        // a window is 23 frames: 0.256 s).
        while self
            .window
            .get(1)
            .is_some_and(|next| m.time - next.time >= WINDOW - 1e-9)
        {
            self.window.pop_front();
        }
        if self.runaway_off {
            return Ok(());
        }
        // NOTE: a run that blows up from its first frames must be caught before it turns
        // non-finite, so a window shorter than WINDOW (since the start or a reset) is judged
        // too, from three frames on; the speed floor keeps a fall from rest from counting.
        if self.window.len() < 3 {
            return Ok(());
        }
        let Some(old) = self.window.front() else {
            return Ok(());
        };
        let floor = gravity.abs() * m.time + SPEED_MARGIN;
        let growth = m.speed / old.speed.max(f64::MIN_POSITIVE);
        let energy_growth = m.kinetic / old.kinetic.max(f64::MIN_POSITIVE);
        if m.speed > floor && growth >= GROWTH && energy_growth >= GROWTH * GROWTH {
            return Err(Divergence::Runaway {
                speed: m.speed,
                growth,
                window: m.time - old.time,
            });
        }
        Ok(())
    }

    /// Measures and checks `state` at the end of a frame.
    ///
    /// # Errors
    /// The divergence, when the run must stop.
    pub fn check_state(
        &mut self,
        mesh: &ClothMesh,
        state: &ClothState,
        params: &StepParams,
        time: f64,
    ) -> Result<Measure, Divergence> {
        let m = Measure::of(state, mesh.point_mass(params.density), params.dt(), time);
        let finite = state
            .positions
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()));
        self.check(m, params.gravity.norm(), finite)?;
        if !self.runaway_off {
            self.check_energy(mesh, state, params)?;
        }
        Ok(m)
    }
}

/// A solver's name as the start of a sentence's noun: `Verlet`.
pub fn capitalised(name: &str) -> String {
    let mut chars = name.chars();
    chars
        .next()
        .map_or_else(String::new, |c| c.to_uppercase().chain(chars).collect())
}

/// A possibly huge or tiny number, readable: `12.3`, `4.6e12`, `3.0e-25`.
pub fn short(v: f64) -> String {
    if v != 0.0 && v.abs() < 0.1 {
        format!("{v:.1e}")
    } else if v.abs() < 1.0e4 {
        format!("{v:.1}")
    } else {
        format!("{v:.1e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(time: f64, speed: f64) -> Measure {
        // Kinetic energy of one 1 kg point at this speed: the guard compares ratios only.
        Measure {
            time,
            kinetic: 0.5 * speed * speed,
            speed,
        }
    }

    #[test]
    fn a_free_fall_never_outruns_gravity_and_runs_on() {
        let mut g = Guard::new();
        // Ten seconds of free fall at 90 frames/s: v = g t from rest, unbounded but linear.
        for f in 1..=900 {
            let t = f64::from(f) / 90.0;
            assert_eq!(g.check(at(t, 9.8 * t), 9.8, true), Ok(()), "t = {t}");
        }
    }

    #[test]
    fn a_settling_oscillation_runs_on() {
        let mut g = Guard::new();
        // A stretched cloth rings down: speeds bounded, decaying.
        for f in 1..=900 {
            let t = f64::from(f) / 90.0;
            let v = 8.0 * (-t).exp() * (20.0 * t).sin().abs() + 1e-3;
            assert_eq!(g.check(at(t, v), 9.8, true), Ok(()), "t = {t}");
        }
    }

    #[test]
    fn exponential_growth_is_stopped_within_a_window_of_passing_the_floor() {
        let mut g = Guard::new();
        // A steady 1 m/s for a second, then growth by 1.3 per frame: 400 times per window.
        let mut stopped = None;
        for f in 1..=400 {
            let t = f64::from(f) / 90.0;
            let v = 1.3f64.powi((f - 90).max(0));
            if let Err(d) = g.check(at(t, v), 9.8, true) {
                stopped = Some((t, v, d));
                break;
            }
        }
        let (t, v, d) = stopped.expect("stopped");
        assert!(matches!(d, Divergence::Runaway { .. }), "{d:?}");
        // Stopped the first frame the speed is past the floor (9.8 t + 20) with a full window.
        assert!(
            v > 9.8 * t + 20.0 && v < 1.3 * (9.8 * t + 20.0),
            "v {v} at t {t}"
        );
    }

    #[test]
    fn a_blow_up_from_the_first_frames_is_caught_before_it_turns_non_finite() {
        let mut g = Guard::new();
        // Ten times faster every frame from the start.
        let caught = (1..=10).find_map(|f| {
            let t = f64::from(f) / 90.0;
            g.check(at(t, 0.01 * 10f64.powi(f)), 9.8, true)
                .err()
                .map(|d| (f, d))
        });
        let (f, d) = caught.expect("caught");
        assert!(matches!(d, Divergence::Runaway { .. }), "{d:?}");
        // 0.01 * 10^4 = 100 m/s is the first speed past the floor of about 20 m/s.
        assert_eq!(f, 4);
    }

    #[test]
    fn non_finite_values_stop_at_once_even_when_runaways_are_allowed() {
        let mut g = Guard::new();
        g.allow_runaway();
        assert_eq!(
            g.check(at(0.1, f64::NAN), 9.8, true),
            Err(Divergence::NonFinite)
        );
        assert_eq!(
            g.check(at(0.1, 1.0), 9.8, false),
            Err(Divergence::NonFinite)
        );
    }

    #[test]
    fn allowed_runaways_run_on_until_rearmed() {
        let mut g = Guard::new();
        g.allow_runaway();
        for f in 1..=200 {
            let t = f64::from(f) / 90.0;
            assert!(g.check(at(t, 0.1 * 1.3f64.powi(f)), 9.8, true).is_ok());
        }
        g.rearm();
        let stopped = (201..=260).any(|f| {
            let t = f64::from(f) / 90.0;
            g.check(at(t, 0.1 * 1.3f64.powi(f)), 9.8, true).is_err()
        });
        assert!(stopped);
    }

    /// The default 1 m cloth at rest, its parameters, and its state lifted by `dh` metres
    /// (positions and last alike: no motion, springs as they were).
    fn lifted(dh: f64) -> (ClothMesh, StepParams, ClothState, ClothState) {
        let mesh = ClothMesh::new(&cloth_mesh::GridSpec::default()).unwrap();
        let params = StepParams::default();
        let start = ClothState::new(&mesh);
        let mut up = start.clone();
        for (p, l) in up.positions.iter_mut().zip(&mut up.last) {
            p.y += dh;
            l.y += dh;
        }
        (mesh, params, start, up)
    }

    #[test]
    fn an_energy_rise_is_judged_against_the_budget_of_the_start_and_gravity() {
        let (mesh, params, start, _) = lifted(0.0);
        // Budget at rest: M |g| L + M v^2 / 2 = 150 * 9.8 * 1 + 150 * 400 / 2.
        let mass = 150.0;
        let budget = mass * 9.8 + 0.5 * mass * SPEED_MARGIN * SPEED_MARGIN;
        // A lift of h adds M g h to H exactly: place it just inside and just outside the bound.
        let bound = ENERGY_RISE * budget / (mass * 9.8);
        for (factor, trips) in [(0.9998, false), (1.0002, true)] {
            let (_, _, _, up) = lifted(bound * factor);
            let mut g = Guard::new();
            g.start(&mesh, &start, &params);
            let got = g.check_energy(&mesh, &up, &params);
            assert_eq!(got.is_err(), trips, "{factor}: {got:?}");
            if let Err(Divergence::EnergyRise {
                rise, budget: b, ..
            }) = got
            {
                assert!((b - budget).abs() < 1e-9 * budget, "{b} vs {budget}");
                assert!((rise / (mass * 9.8 * bound * factor) - 1.0).abs() < 1e-9);
            }
        }
        // A change of parameters takes a new reference rather than comparing across it.
        let (_, _, _, up) = lifted(2.0 * bound);
        let mut g = Guard::new();
        g.start(&mesh, &start, &params);
        let stiffer = StepParams {
            ks: 2.0 * params.ks,
            ..params
        };
        assert_eq!(g.check_energy(&mesh, &up, &stiffer), Ok(()));
        // Runaways allowed by the user: the energy test is off as well.
        g.start(&mesh, &start, &params);
        g.allow_runaway();
        assert!(g.check_state(&mesh, &up, &params, 0.1).is_ok());
    }

    #[test]
    fn a_long_free_fall_and_a_hanging_cloth_never_trip_the_energy_test() {
        // Two seconds of Verlet hanging from pins, then ten of free fall, which converts
        // gravity's energy into motion at constant H.
        for scene in ["pinned2", "pinned4"] {
            let scene = cloth_scene::load(scene, &[]).unwrap();
            let registry = crate::solvers::default_registry();
            let mut run = crate::Run::new(scene, registry, Some("verlet")).unwrap();
            for _ in 0..180 {
                run.step_frame().unwrap_or_else(|f| panic!("{}", f.what));
            }
        }
        let mut g = Guard::new();
        let (mesh, params, start, _) = lifted(0.0);
        let mut free = start.clone();
        g.start(&mesh, &start, &params);
        let mut solver = cloth_solver::Verlet::new();
        for f in 0..900 {
            cloth_solver::advance_frame(&mut solver, &mesh, &[], &params, &mut free).unwrap();
            assert_eq!(g.check_energy(&mesh, &free, &params), Ok(()), "frame {f}");
        }
    }

    /// The largest rise of `H` over `frames` frames of `scene` under `solver`, in units of the
    /// bound (`ENERGY_RISE` budgets): a run that trips the guard fails the caller.
    fn peak_use(scene: &str, solver: &str, frames: u32) -> f64 {
        let scene = cloth_scene::load(scene, &[]).unwrap();
        let registry = crate::solvers::default_registry();
        let mut run = crate::Run::new(scene, registry, Some(solver)).unwrap();
        let mut peak = f64::NEG_INFINITY;
        for _ in 0..frames {
            if let Err(f) = run.step_frame() {
                panic!("{solver} on {}: {}", run.scene.origin, f.what);
            }
            let b = run.guard.budget.clone().expect("a reference");
            let p = &run.settings.params;
            let rise = energy::total(&run.scene.mesh, &run.state, p) - b.start;
            peak = peak.max(rise / (ENERGY_RISE * b.supply));
        }
        peak
    }

    /// One second of each (90 frames): the falls onto the sphere and the plane, the
    /// self-collision's folds and the hanging cloths' swings. Long for the quick suite;
    /// `scripts/hostile` runs it.
    #[test]
    #[ignore = "a minute or more: run by scripts/hostile"]
    fn every_bundled_scene_under_every_built_in_solver_stays_far_inside_the_energy_bound() {
        let registry = crate::solvers::default_registry();
        let frames = 90;
        for scene in cloth_scene::BUNDLED {
            for solver in registry.names() {
                let used = peak_use(scene.name, solver, frames);
                eprintln!(
                    "{:<14} {solver:<15} peak rise {used:.2e} of the bound",
                    scene.name
                );
                assert!(used < 0.1, "{solver} on {}: {used}", scene.name);
            }
        }
    }

    #[test]
    fn advice_fits_the_cause() {
        let params = StepParams::default();
        let m = 0.01;
        let limit = params.explicit_ks_limit(m);
        let past = StepParams {
            ks: 4.0 * limit,
            ..params
        };
        let d = Divergence::NonFinite;
        let registry = crate::solvers::default_registry();
        let explicit = registry
            .entries()
            .iter()
            .find(|e| e.is_explicit())
            .expect("the default registry has an explicit solver");
        let a = d.advice(explicit, &past, m);
        // Four times the limit needs twice the steps (the limit goes as 1 / dt^2).
        let want = format!("at least {}", 2 * past.steps_per_frame);
        assert!(a.contains(&want), "{a}");
        let below = StepParams {
            ks: 0.5 * limit,
            ..params
        };
        let a = d.advice(explicit, &below, m);
        assert!(!a.contains("lower ks"), "ks is not the cause: {a}");
        // A solver not marked explicit has no stability limit to blame, whatever ks is.
        let implicit = SolverEntry::new("stiff", "not explicit", |_, _| {
            Err(cloth_solver::OptionError::NotAnObject {
                solver: "stiff",
                value: "null".to_owned(),
            })
        });
        let a = d.advice(&implicit, &past, m);
        assert!(!a.contains("stability limit"), "{a}");
        // Only a solver with an iterations option is told to raise it (Newton has none).
        #[cfg(feature = "implicit")]
        for (name, has) in [("implicit", false), ("fast-implicit", true)] {
            let entry = registry.get(name).unwrap();
            let runaway = Divergence::Runaway {
                speed: 100.0,
                growth: 5.0,
                window: 0.25,
            };
            for d in [Divergence::NonFinite, runaway] {
                let a = d.advice(entry, &params, m);
                assert_eq!(a.contains("iterations"), has, "{name}: {a}");
            }
        }
    }
}
