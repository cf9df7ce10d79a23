//! The running cloth: scene, live settings, state, solver, simulated clock and diagnostics.
//!
//! Time here is simulated time only. The app loop decides how many steps to take from the wall
//! clock; nothing in this module reads a clock, so the same calls give the same bits.

use std::collections::VecDeque;

use cloth_mesh::ClothState;
use cloth_scene::Scene;
use cloth_solver::{Solver, SolverKind, kinetic_energy, max_stretch_ratio};

use super::params::Settings;
use crate::solvers;

/// Plot samples kept (one per simulated frame: 20 s at 90 frames/s).
pub const HISTORY: usize = 1800;

/// Fastest point speed, m/s, beyond which the run is called exploding.
///
/// NOTE: the bundled scenes span a few metres; a free fall from 10 m ends at
/// sqrt(2 * 9.8 * 10) = 14 m/s, so 50 m/s is far beyond anything a settling cloth does, yet
/// reached within a few steps by an unstable explicit integration (its error grows by a
/// constant factor per step).
pub const MAX_SPEED: f64 = 50.0;

/// Largest spring length / rest length beyond which the run is called exploding. Cloth
/// springs three times their rest length are no longer cloth; with the course's 10 % stretch
/// limit on, this can only be reached when the limit is off.
pub const MAX_STRETCH_RATIO: f64 = 3.0;

/// One plot sample, taken at the end of each simulated frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Simulated time, s.
    pub time: f64,
    /// Kinetic energy, J.
    pub kinetic: f64,
    /// Largest spring length / rest length.
    pub stretch: f64,
}

/// Why the simulation stopped by itself.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    /// Simulated time of the failure, s.
    pub time: f64,
    /// What happened, in one sentence.
    pub what: String,
}

/// The running cloth.
pub struct Simulation {
    /// The scene as loaded (its values are what "restore" goes back to).
    pub scene: Scene,
    /// Live parameters and objects.
    pub settings: Settings,
    /// The cloth's positions: the one source of truth.
    pub state: ClothState,
    /// The state at the end of the last good frame, shown after a failure.
    last_good: ClothState,
    solver: Box<dyn Solver>,
    /// The active solver.
    pub solver_kind: SolverKind,
    /// Simulated seconds since the start or the last reset.
    pub time: f64,
    /// Steps since the start or the last reset.
    pub steps: u64,
    /// Frames completed since the start or the last reset.
    pub frames: u64,
    step_in_frame: u32,
    /// Plot samples, oldest first.
    pub history: VecDeque<Sample>,
    /// Largest kinetic energy since the start or the last reset, J (the energy plot's scale,
    /// so a settled cloth reads as zero rather than as rescaled round-off).
    pub peak_kinetic: f64,
    /// Set when the run diverged or exploded; cleared by a reset.
    pub fault: Option<Fault>,
}

impl Simulation {
    /// Starts `scene` with `solver` (or the scene's own), at rest.
    ///
    /// # Errors
    /// When the solver is not built into this binary.
    pub fn new(scene: Scene, solver: Option<SolverKind>) -> anyhow::Result<Self> {
        let kind = solver.unwrap_or(scene.solver);
        let built = solvers::build(kind)?;
        let state = ClothState::new(&scene.mesh);
        let settings = Settings {
            params: scene.params,
            colliders: scene.colliders.clone(),
        };
        let mut sim = Self {
            last_good: state.clone(),
            state,
            settings,
            scene,
            solver: built,
            solver_kind: kind,
            time: 0.0,
            steps: 0,
            frames: 0,
            step_in_frame: 0,
            history: VecDeque::with_capacity(HISTORY),
            peak_kinetic: 0.0,
            fault: None,
        };
        sim.sample();
        Ok(sim)
    }

    /// The scene's own settings, for "restore".
    pub fn scene_settings(&self) -> Settings {
        Settings {
            params: self.scene.params,
            colliders: self.scene.colliders.clone(),
        }
    }

    /// The step, s.
    pub fn dt(&self) -> f64 {
        self.settings.params.dt()
    }

    /// Mass of one point at the live density, kg.
    pub fn point_mass(&self) -> f64 {
        self.scene.mesh.point_mass(self.settings.params.density)
    }

    /// Replaces the solver; the state (and so the motion) carries over.
    ///
    /// # Errors
    /// When `kind` is not built into this binary; the current solver stays.
    pub fn set_solver(&mut self, kind: SolverKind) -> anyhow::Result<()> {
        self.solver = solvers::build(kind)?;
        self.solver_kind = kind;
        Ok(())
    }

    /// Back to the start positions at rest, keeping the live settings (the course's R key).
    pub fn reset(&mut self) {
        self.state.reset(&self.scene.mesh);
        self.last_good.clone_from(&self.state);
        self.solver.reset();
        self.time = 0.0;
        self.steps = 0;
        self.frames = 0;
        self.step_in_frame = 0;
        self.history.clear();
        self.peak_kinetic = 0.0;
        self.fault = None;
        self.sample();
    }

    /// One step of `dt`. On failure the state goes back to the last good frame and
    /// [`Self::fault`] says why.
    ///
    /// # Errors
    /// The fault, also stored in [`Self::fault`].
    pub fn step(&mut self) -> Result<(), Fault> {
        if let Some(f) = &self.fault {
            return Err(f.clone());
        }
        let dt = self.dt();
        let result = self.solver.step(
            &self.scene.mesh,
            &self.settings.colliders,
            &self.settings.params,
            &mut self.state,
        );
        if let Err(e) = result {
            return Err(self.fail(e.to_string()));
        }
        self.time += dt;
        self.steps += 1;
        self.step_in_frame += 1;
        if self.step_in_frame >= self.settings.params.steps_per_frame {
            self.step_in_frame = 0;
            self.frames += 1;
            self.end_frame()?;
        }
        Ok(())
    }

    /// Exactly one frame: `steps_per_frame` steps.
    ///
    /// # Errors
    /// The first step's fault.
    pub fn step_frame(&mut self) -> Result<(), Fault> {
        for _ in 0..self.settings.params.steps_per_frame {
            self.step()?;
        }
        Ok(())
    }

    fn end_frame(&mut self) -> Result<(), Fault> {
        let dt = self.dt();
        let speed = self
            .state
            .positions
            .iter()
            .zip(&self.state.last)
            .map(|(p, l)| (p - l).norm())
            .fold(0.0, f64::max)
            / dt;
        let sample = self.measure();
        if !(speed.is_finite() && sample.kinetic.is_finite() && sample.stretch.is_finite()) {
            return Err(self.fail("the cloth's state is no longer finite".to_owned()));
        }
        if speed > MAX_SPEED {
            return Err(self.fail(format!(
                "the cloth exploded: a point moves at {} m/s (more than {MAX_SPEED:.0} m/s)",
                short(speed)
            )));
        }
        if sample.stretch > MAX_STRETCH_RATIO {
            return Err(self.fail(format!(
                "the cloth exploded: a spring is stretched to {} times its rest length",
                short(sample.stretch)
            )));
        }
        self.push(sample);
        self.last_good.clone_from(&self.state);
        Ok(())
    }

    fn measure(&self) -> Sample {
        Sample {
            time: self.time,
            kinetic: kinetic_energy(&self.state, self.point_mass(), self.dt()),
            stretch: max_stretch_ratio(&self.scene.mesh, &self.state),
        }
    }

    fn push(&mut self, s: Sample) {
        if self.history.len() == HISTORY {
            self.history.pop_front();
        }
        self.history.push_back(s);
        self.peak_kinetic = self.peak_kinetic.max(s.kinetic);
    }

    fn sample(&mut self) {
        let s = self.measure();
        self.push(s);
    }

    fn fail(&mut self, what: String) -> Fault {
        // NOTE: the failed state may hold NaN or huge values; drawing and plotting it would
        // show garbage, so the last good frame is put back (the user sees where it was).
        self.state.clone_from(&self.last_good);
        let fault = Fault {
            time: self.time,
            what,
        };
        self.fault = Some(fault.clone());
        fault
    }

    /// A warning when the live settings are past the explicit solver's stability limit.
    pub fn stability_warning(&self) -> Option<String> {
        if self.solver_kind != SolverKind::Verlet {
            return None;
        }
        let p = &self.settings.params;
        let limit = p.explicit_ks_limit(self.point_mass());
        (p.ks > limit).then(|| {
            format!(
                "ks {:.0} N/m is past Verlet's stability limit of about {limit:.0} N/m at this density \
                 and step: expect it to blow up; lower ks, raise steps/frame or density",
                p.ks
            )
        })
    }
}

/// A possibly huge number, readable: `123`, `4.6e12`.
fn short(v: f64) -> String {
    if v.abs() < 1.0e4 {
        format!("{v:.1}")
    } else {
        format!("{v:.1e}")
    }
}
