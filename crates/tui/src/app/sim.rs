//! The running cloth: scene, live settings, state, solver, simulated clock and diagnostics.
//!
//! Time here is simulated time only. The app loop decides how many steps to take from the wall
//! clock; nothing in this module reads a clock, so the same calls give the same bits.

use std::collections::VecDeque;

use cloth_mesh::ClothState;
use cloth_scene::Scene;
use cloth_solver::{Registry, Solver, SolverEntry, kinetic_energy, max_stretch_ratio};
use serde_json::Value;

use super::params::Settings;
use crate::solvers::{self, Choice};

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
    /// The solvers the user can switch between.
    registry: Registry,
    /// The active solver's entry and the options it was built with.
    choice: Choice,
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
    /// Starts `scene` with the solver `name` of `registry` (or the scene's own), at rest.
    ///
    /// # Errors
    /// When the solver is not registered or refuses the scene's options for it.
    pub fn new(scene: Scene, registry: Registry, name: Option<&str>) -> anyhow::Result<Self> {
        let choice = solvers::choose(&registry, &scene, name)?;
        let built = choice.build(&scene.mesh)?;
        let state = ClothState::new(&scene.mesh);
        let settings = Settings {
            params: scene.params,
            colliders: scene.colliders.clone(),
            options: numeric_options(&choice.entry, &choice.options),
        };
        let mut sim = Self {
            last_good: state.clone(),
            state,
            settings,
            scene,
            solver: built,
            registry,
            choice,
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

    /// The scene's own settings, for "restore": its parameters, objects and the options it
    /// gives the active solver.
    pub fn scene_settings(&self) -> Settings {
        let entry = &self.choice.entry;
        let default = self.registry.default_entry().map_or("", SolverEntry::name);
        let options = self
            .scene
            .options_for(entry.name(), default, |k| entry.option(k).is_some());
        Settings {
            params: self.scene.params,
            colliders: self.scene.colliders.clone(),
            options: numeric_options(entry, &options),
        }
    }

    /// The solvers the user can switch between.
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// The active solver's entry.
    pub fn entry(&self) -> &SolverEntry {
        &self.choice.entry
    }

    /// The active solver's options, a JSON object.
    pub fn options(&self) -> &Value {
        &self.choice.options
    }

    /// The name of the solver the scene asks for (the registry's first when it names none).
    pub fn scene_solver(&self) -> &str {
        match &self.scene.solver {
            Some(name) => match self.registry.get(name) {
                Ok(entry) => entry.name(),
                Err(_) => name,
            },
            None => self.registry.default_entry().map_or("", SolverEntry::name),
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

    /// Replaces the solver by the registered one called `name`, with the options the scene
    /// gives it; the state (and so the motion) carries over.
    ///
    /// # Errors
    /// When `name` is not registered or the solver cannot be built; the current solver stays.
    pub fn set_solver(&mut self, name: &str) -> anyhow::Result<()> {
        let choice = solvers::choose(&self.registry, &self.scene, Some(name))?;
        self.solver = choice.build(&self.scene.mesh)?;
        self.settings.options = numeric_options(&choice.entry, &choice.options);
        self.choice = choice;
        Ok(())
    }

    /// Rebuilds the active solver with the numeric options of [`Self::settings`] (its other
    /// options kept); the state carries over. A solver owns only caches, so this is a swap.
    ///
    /// # Errors
    /// When the solver refuses the options; the current solver and options stay.
    pub fn apply_options(&mut self) -> anyhow::Result<()> {
        let entry = self.choice.entry;
        let mut options = self.choice.options.as_object().cloned().unwrap_or_default();
        let numeric = entry.options().iter().filter(|o| o.numeric().is_some());
        for (o, &v) in numeric.zip(&self.settings.options) {
            let value = match o.kind {
                cloth_solver::OptionKind::Integer { .. } => Value::from(v.round() as i64),
                _ => Value::from(v),
            };
            options.insert(o.name.to_owned(), value);
        }
        let choice = Choice {
            entry,
            options: Value::Object(options),
        };
        match choice.build(&self.scene.mesh) {
            Ok(solver) => {
                self.solver = solver;
                self.choice = choice;
                Ok(())
            }
            Err(e) => {
                self.settings.options = numeric_options(&entry, &self.choice.options);
                Err(e)
            }
        }
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

    /// A warning when the live settings are past an explicit solver's stability limit.
    pub fn stability_warning(&self) -> Option<String> {
        if !self.choice.entry.is_explicit() {
            return None;
        }
        let p = &self.settings.params;
        let limit = p.explicit_ks_limit(self.point_mass());
        (p.ks > limit).then(|| {
            format!(
                "ks {:.0} N/m is past {}'s stability limit of about {limit:.0} N/m at this density \
                 and step: expect it to blow up; lower ks, raise steps/frame or density",
                p.ks,
                capitalised(self.choice.entry.name())
            )
        })
    }
}

/// The values of `entry`'s numeric options in `options` (their defaults where absent), in the
/// entry's order: what the parameter panel shows as the solver's rows.
pub fn numeric_options(entry: &SolverEntry, options: &Value) -> Vec<f64> {
    entry
        .options()
        .iter()
        .filter_map(|o| {
            let (_, _, default) = o.numeric()?;
            Some(
                options
                    .get(o.name)
                    .and_then(Value::as_f64)
                    .unwrap_or(default),
            )
        })
        .collect()
}

/// A solver's name as the start of a sentence's noun: `Verlet`.
fn capitalised(name: &str) -> String {
    let mut chars = name.chars();
    chars
        .next()
        .map_or_else(String::new, |c| c.to_uppercase().chain(chars).collect())
}

/// A possibly huge number, readable: `123`, `4.6e12`.
fn short(v: f64) -> String {
    if v.abs() < 1.0e4 {
        format!("{v:.1}")
    } else {
        format!("{v:.1e}")
    }
}
