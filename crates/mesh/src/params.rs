//! The live-editable parameters of a run.

use crate::{SpringKind, Vec3, Wind};

/// Every parameter that may change between two steps, in one `Copy` struct (rapier's
/// `IntegrationParameters`). Defaults are the course's.
///
/// These are the model's parameters, which every solver reads. A solver's own settings (an
/// iteration count, a thread count) are its options, given to its constructor (see
/// `cloth_solver::SolverEntry`).
///
/// Units are SI. The course's GUI shows density in g/cm^2 (the file's kg/m^2 divided by 10) and
/// damping in percent; this struct keeps the file's units and leaves display to the UI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Spring constant of structural and shearing springs, N/m (default 5000). Bending springs
    /// use `0.2 * ks`. Read by every solver.
    pub ks: f64,
    /// Surface density, kg/m^2 (default 150, shown as 15 g/cm^2). Point mass is re-derived from
    /// it every step, so an edit acts at once. Read by every solver.
    pub density: f64,
    /// Damping, percent (default 0.2): Verlet scales the implied velocity by
    /// `1 - damping / 100` each step. Implicit solvers turn it into the equivalent drag.
    pub damping: f64,
    /// Gravity, m/s^2 (default (0, -9.8, 0)).
    pub gravity: Vec3,
    /// Whether structural springs exert forces (default true).
    pub structural: bool,
    /// Whether shearing springs exert forces (default true).
    pub shearing: bool,
    /// Whether bending springs exert forces (default true).
    pub bending: bool,
    /// Simulation steps per frame (default 30). With `frames_per_sec` it sets the step
    /// `dt = 1 / frames_per_sec / steps_per_frame`; self-collision divides its correction by it.
    pub steps_per_frame: u32,
    /// Frames per second of simulated time (default 90).
    pub frames_per_sec: f64,
    /// Whether points repel each other closer than twice the thickness (default true).
    pub self_collision: bool,
    /// Whether the 10 % maximum-stretch constraint applies (default true, the course's model).
    pub stretch_limit: bool,
    /// Wind (default none): applied by the run before each step, so every solver feels it.
    pub wind: Wind,
}

impl Default for StepParams {
    fn default() -> Self {
        Self {
            ks: 5000.0,
            density: 150.0,
            damping: 0.2,
            gravity: Vec3::new(0.0, -9.8, 0.0),
            structural: true,
            shearing: true,
            bending: true,
            steps_per_frame: 30,
            frames_per_sec: 90.0,
            self_collision: true,
            stretch_limit: true,
            wind: Wind::default(),
        }
    }
}

/// A parameter outside its allowed range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{name} is {value}, but it must be {allowed}")]
pub struct ParamError {
    /// The parameter's name as in scene files (`ks`, `damping`...).
    pub name: &'static str,
    /// The bad value, as text.
    pub value: String,
    /// What is allowed.
    pub allowed: &'static str,
}

/// The course's steps per frame, the reference at which its damping factor is defined.
pub const REFERENCE_STEPS_PER_FRAME: u32 = 30;

/// The ratio of the maximum stretch constraint: springs end a step at most 10 % over rest.
pub const MAX_STRETCH: f64 = 1.1;

impl StepParams {
    /// The time step, seconds: `1 / frames_per_sec / steps_per_frame`, the course's operations
    /// in the course's order (about 1/2700 s by default).
    #[must_use]
    pub fn dt(&self) -> f64 {
        1.0 / self.frames_per_sec / f64::from(self.steps_per_frame)
    }

    /// Whether springs of `kind` exert forces.
    #[must_use]
    pub fn enabled(&self, kind: SpringKind) -> bool {
        match kind {
            SpringKind::Structural => self.structural,
            SpringKind::Shearing => self.shearing,
            SpringKind::Bending => self.bending,
        }
    }

    /// Stiffness of springs of `kind`, N/m, or 0 when the kind is disabled.
    #[must_use]
    pub fn stiffness(&self, kind: SpringKind) -> f64 {
        if self.enabled(kind) {
            self.ks * kind.stiffness_factor()
        } else {
            0.0
        }
    }

    /// Velocity drag rate, 1/s, equivalent to the course's damping: its per-step factor
    /// `1 - damping/100` at the course's step (`steps_per_frame` = 30 at `frames_per_sec`) is a
    /// drag `c = -ln(1 - damping/100) / dt_ref` (about 5.4 1/s at the defaults).
    ///
    /// Solvers that take other step sizes (the implicit ones) use this rate so that the damping
    /// a user sets means the same thing whatever the step.
    #[must_use]
    pub fn drag_rate(&self) -> f64 {
        let dt_ref = 1.0 / (self.frames_per_sec * f64::from(REFERENCE_STEPS_PER_FRAME));
        -(1.0 - self.damping / 100.0).ln() / dt_ref
    }

    /// The explicit-Verlet stability limit on `ks` for this density and step, N/m: about
    /// `m / (2 dt^2)` for a point mass `m` (the grid's largest stiffness eigenvalue is about 8 ks).
    #[must_use]
    pub fn explicit_ks_limit(&self, point_mass: f64) -> f64 {
        point_mass / (2.0 * self.dt() * self.dt())
    }

    /// Checks every field against its allowed range.
    ///
    /// # Errors
    /// The first [`ParamError`] found.
    pub fn validate(&self) -> Result<(), ParamError> {
        let bad = |name, value: String, allowed| {
            Err(ParamError {
                name,
                value,
                allowed,
            })
        };
        if !(self.ks.is_finite() && self.ks >= 0.0) {
            return bad("ks", self.ks.to_string(), "a finite number >= 0 (N/m)");
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad(
                "density",
                self.density.to_string(),
                "a finite number > 0 (kg/m^2)",
            );
        }
        if !(self.damping.is_finite() && (0.0..=100.0).contains(&self.damping)) {
            return bad(
                "damping",
                self.damping.to_string(),
                "between 0 and 100 (percent)",
            );
        }
        if !self.gravity.iter().all(|g| g.is_finite()) {
            return bad(
                "gravity",
                format!("{:?}", self.gravity.as_slice()),
                "three finite numbers (m/s^2)",
            );
        }
        let w = &self.wind;
        if !w
            .velocity
            .iter()
            .all(|v| v.is_finite() && v.abs() <= 1000.0)
        {
            return bad(
                "wind",
                format!("{:?}", w.velocity.as_slice()),
                "three numbers from -1000 to 1000 (m/s)",
            );
        }
        if !(w.drag.is_finite() && (0.0..=100.0).contains(&w.drag)) {
            return bad("wind_drag", w.drag.to_string(), "from 0 to 100");
        }
        if !(w.gust.is_finite() && (0.0..=10.0).contains(&w.gust)) {
            return bad(
                "wind_gust",
                w.gust.to_string(),
                "from 0 to 10 (of the wind)",
            );
        }
        if !(w.gust_period.is_finite() && w.gust_period >= 0.01 && w.gust_period <= 1.0e6) {
            return bad(
                "wind_gust_period",
                w.gust_period.to_string(),
                "from 0.01 to 1000000 (s)",
            );
        }
        if self.steps_per_frame == 0 || self.steps_per_frame > 10_000 {
            return bad(
                "simulation_steps",
                self.steps_per_frame.to_string(),
                "an integer from 1 to 10000",
            );
        }
        if !(self.frames_per_sec.is_finite()
            && self.frames_per_sec > 0.0
            && self.frames_per_sec <= 10_000.0)
        {
            return bad(
                "frames_per_sec",
                self.frames_per_sec.to_string(),
                "a number > 0 and <= 10000",
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_step_is_one_2700th_of_a_second_and_drag_about_5_4() {
        let p = StepParams::default();
        assert!((p.dt() - 1.0 / 2700.0).abs() < 1e-18);
        // -ln(0.998) * 2700 = 5.4054...
        assert!((p.drag_rate() - 5.4054).abs() < 1e-3);
        // 0.06 kg / (2 * (1/2700)^2) = 218,700 N/m.
        assert!((p.explicit_ks_limit(0.06) - 218_700.0).abs() < 1e-6);
    }

    #[test]
    fn out_of_range_values_are_named() {
        let e = StepParams {
            damping: 150.0,
            ..StepParams::default()
        }
        .validate()
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "damping is 150, but it must be between 0 and 100 (percent)"
        );
        assert!(
            StepParams {
                ks: f64::NAN,
                ..StepParams::default()
            }
            .validate()
            .is_err()
        );
        assert!(
            StepParams {
                density: 0.0,
                ..StepParams::default()
            }
            .validate()
            .is_err()
        );
        assert!(StepParams::default().validate().is_ok());
    }
}
