//! Compare mode (`clothsim compare SCENE --vary ...`): the variants of a study side by side.
//!
//! The app's own simulation ([`App::sim`]) is the first variant; the others are [`Member`]s,
//! each a [`Simulation`] on its own [`Worker`]. Commands (pause, step, reset, resume) go to
//! every variant; edits of the parameter panel go to every variant too, except for the values
//! a variant's own key gives it, which it keeps. A variant that diverges stops alone.

use cloth_mesh::StepParams;
use cloth_render::AsciiFrame;

use super::model::App;
use super::params::Settings;
use super::sim::{Command, Simulation};
use super::worker::Worker;

/// A variant other than the first.
pub struct Member {
    /// `ks=5000`: its values.
    pub title: String,
    /// Its simulation (the UI's copy when a worker steps it).
    pub sim: Simulation,
    /// The thread stepping it; `None` steps it inline (tests).
    pub worker: Option<Worker>,
    /// Its rendered pane.
    pub frame: Option<AsciiFrame>,
    /// The settings last sent to it.
    pub sent: Settings,
    /// Whether the worker was lagging behind real time at its last snapshot.
    pub lagging: bool,
}

/// The study: the first variant's title, the varied keys and the other variants.
pub struct Compare {
    /// The varied keys and their values, as typed (`cloth.ks = 1, 5000, 100000`).
    pub axes: Vec<(String, String)>,
    /// The first variant's title.
    pub title: String,
    /// The first variant's pane.
    pub frame: Option<AsciiFrame>,
    /// The other variants.
    pub members: Vec<Member>,
    /// Panes across (the first axis's values).
    pub columns: usize,
    /// Whether the variants run different solvers (then a solver change is not shared).
    pub solver_varied: bool,
}

impl Compare {
    /// How many variants there are.
    pub fn len(&self) -> usize {
        self.members.len() + 1
    }
}

/// `shared` with the values that `own`'s scene gives differently from `base`'s kept as
/// `own`'s (`current`: the member's settings now), so an edit of another value reaches it
/// and its own key stays its own.
pub fn settings_for(
    shared: &Settings,
    base: &StepParams,
    own: &StepParams,
    current: &Settings,
) -> Settings {
    let mut s = shared.clone();
    let p = &mut s.params;
    macro_rules! keep {
        ($($f:ident),*) => {$(
            if own.$f != base.$f {
                p.$f = current.params.$f;
            }
        )*};
    }
    keep!(
        ks,
        density,
        damping,
        gravity,
        structural,
        shearing,
        bending,
        steps_per_frame,
        frames_per_sec,
        self_collision,
        stretch_limit
    );
    if current.options.len() != shared.options.len() {
        // Another solver: its options are its own.
        s.options.clone_from(&current.options);
    }
    s
}

impl App {
    /// Sends `command` to every other variant (their workers, or their simulations inline).
    pub fn send_members(&mut self, command: &Command) {
        let Some(c) = &mut self.compare else {
            return;
        };
        for m in &mut c.members {
            match &m.worker {
                Some(w) => w.send(command.clone()),
                None => {
                    // NOTE: a failure inline (a stop) is kept in the member's fault.
                    let _ = m.sim.apply(command.clone());
                }
            }
        }
    }

    /// Sends every other variant the shared settings (their own values kept) and, unless the
    /// solver is varied, the solver, when they changed.
    pub fn sync_members(&mut self) {
        let shared = self.sim.settings.clone();
        let base = self.sim.scene.params;
        let name = self.sim.entry().name();
        let Some(c) = &mut self.compare else {
            return;
        };
        for m in &mut c.members {
            if !c.solver_varied && m.sim.entry().name() != name {
                let command = Command::Solver(name.to_owned());
                match &m.worker {
                    Some(w) => w.send(command),
                    None => {
                        let _ = m.sim.apply(command);
                    }
                }
                let _ = m.sim.set_solver(name);
            }
            let wanted = settings_for(&shared, &base, &m.sim.scene.params, &m.sim.settings);
            if wanted != m.sent {
                m.sent.clone_from(&wanted);
                m.sim.settings.clone_from(&wanted);
                let command = Command::Settings(wanted);
                match &m.worker {
                    Some(w) => w.send(command),
                    None => {
                        let _ = m.sim.apply(command);
                    }
                }
            }
        }
    }

    /// Takes in what the other variants' workers published.
    pub fn adopt_members(&mut self) -> bool {
        let Some(c) = &mut self.compare else {
            return false;
        };
        let mut any = false;
        for m in &mut c.members {
            if let Some(w) = &m.worker
                && let Some(got) = w.adopt_into(&mut m.sim)
            {
                m.lagging = got.rates.lagging;
                any = true;
            }
        }
        any
    }

    /// Steps the other variants inline by what the first took (tests: no workers).
    #[cfg(test)]
    pub fn step_members_inline(&mut self, steps: u64) {
        let Some(c) = &mut self.compare else {
            return;
        };
        for m in &mut c.members {
            if m.worker.is_none() {
                for _ in 0..steps {
                    if m.sim.step().is_err() {
                        break;
                    }
                }
            }
        }
    }
}
