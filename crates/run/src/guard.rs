//! The divergence guard: tells a run that is coming apart from one that is only far from rest.
//!
//! One guard serves the live UI and the headless commands (`simulate`, `render`, `bench`), so
//! they stop the same runs and explain them the same way. It is checked once per simulated
//! frame and stops a run for one of two reasons only:
//!
//! - **Non-finite state**: a position is NaN or infinite. Nothing can be drawn or continued.
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

use cloth_mesh::ClothState;
use cloth_solver::{SolverEntry, StepParams, kinetic_energy};

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

/// Why a run was stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum Divergence {
    /// A position, the speed or the energy is NaN or infinite.
    NonFinite,
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
    /// One sentence: what happened.
    pub fn describe(&self) -> String {
        match self {
            Divergence::NonFinite => {
                "the cloth's positions are no longer finite numbers".to_owned()
            }
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
                Divergence::Runaway { .. } => "energy is being pumped in faster than damping \
                     takes it out: raise steps/frame (a smaller step) or damping, or use an \
                     implicit solver"
                    .to_owned(),
            };
        }
        match self {
            Divergence::NonFinite => {
                "the solver's iterations did not converge: raise iterations or steps/frame, or \
                 lower ks"
                    .to_owned()
            }
            Divergence::Runaway { .. } => {
                "raise steps/frame (a smaller step) or iterations, or lower ks".to_owned()
            }
        }
    }
}

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

/// The guard: a short history of frame measures.
#[derive(Debug, Clone, Default)]
pub struct Guard {
    window: VecDeque<Measure>,
    runaway_off: bool,
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
        state: &ClothState,
        params: &StepParams,
        point_mass: f64,
        time: f64,
    ) -> Result<Measure, Divergence> {
        let m = Measure::of(state, point_mass, params.dt(), time);
        let finite = state
            .positions
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()));
        self.check(m, params.gravity.norm(), finite)?;
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

/// A possibly huge number, readable: `12.3`, `4.6e12`.
pub fn short(v: f64) -> String {
    if v.abs() < 1.0e4 {
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
    }
}
