//! Compare mode (`clothsim compare SCENE --vary ...`): the variants of a study side by side.
//!
//! The app's own simulation ([`App::sim`]) is the first variant; the others are [`Member`]s.
//! These are the UI's copies: one [`Lockstep`] coordinator steps all the variants frame by
//! frame together on its own thread, and the UI adopts its snapshots, all at one frame (tests
//! step the copies inline through the same [`lockstep::advance`]). Commands (pause, step,
//! reset) go to every variant; edits of the parameter panel go to every variant too, except for
//! the values a variant's own key gives it, which it keeps. A variant that diverges stops alone
//! and the others go on; the time shown is the group's ([`Compare::clock`]).

use cloth_mesh::StepParams;
use cloth_render::AsciiFrame;

use super::model::App;
use cloth_run::Settings;
use cloth_run::lockstep::{self, Adopted, Lockstep};
use cloth_run::{Command, Run};

/// A variant other than the first.
pub struct Member {
    /// `ks=5000`: its values.
    pub title: String,
    /// Its simulation (the UI's copy when the coordinator steps it).
    pub sim: Run,
    /// Its rendered pane.
    pub frame: Option<AsciiFrame>,
    /// The settings last sent to it.
    pub sent: Settings,
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
    /// The thread stepping every variant in lockstep; `None` steps them inline (tests).
    pub group: Option<Lockstep>,
}

impl Compare {
    /// How many variants there are.
    pub fn len(&self) -> usize {
        self.members.len() + 1
    }

    /// The group's frame and simulated time, s: that of the variants that have not stopped
    /// (all at one frame), `first` being the first variant.
    pub fn clock(&self, first: &Run) -> (u64, f64) {
        let sims: Vec<&Run> = std::iter::once(first)
            .chain(self.members.iter().map(|m| &m.sim))
            .collect();
        lockstep::frame_of(&sims)
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
    /// Whether a thread steps the cloth: the worker, or in compare mode the coordinator.
    pub fn threaded(&self) -> bool {
        self.worker.is_some() || self.compare.as_ref().is_some_and(|c| c.group.is_some())
    }

    /// The coordinator stepping the variants, in compare mode once started.
    pub fn group(&self) -> Option<&Lockstep> {
        self.compare.as_ref().and_then(|c| c.group.as_ref())
    }

    /// Applies `command` to the other variants inline (no coordinator: tests).
    pub fn send_members(&mut self, command: &Command) {
        let Some(c) = &mut self.compare else {
            return;
        };
        if c.group.is_some() {
            return;
        }
        for m in &mut c.members {
            // NOTE: a failure inline (a stop) is kept in the member's fault.
            let _ = m.sim.apply(command.clone());
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
        for (k, m) in c.members.iter_mut().enumerate() {
            let mut commands = Vec::new();
            if !c.solver_varied && m.sim.entry().name() != name {
                let _ = m.sim.set_solver(name);
                commands.push(Command::Solver(name.to_owned()));
            }
            let wanted = settings_for(&shared, &base, &m.sim.scene.params, &m.sim.settings);
            if wanted != m.sent {
                m.sent.clone_from(&wanted);
                m.sim.settings.clone_from(&wanted);
                commands.push(Command::Settings(wanted));
            }
            for command in commands {
                match &c.group {
                    Some(g) => g.send_to(k + 1, command),
                    None => {
                        let _ = m.sim.apply(command);
                    }
                }
            }
        }
    }

    /// Takes in what the coordinator published into every variant's copy.
    pub fn adopt_group(&mut self) -> Option<Adopted> {
        let c = self.compare.as_mut()?;
        let group = c.group.as_ref()?;
        let mut mirrors: Vec<&mut Run> = std::iter::once(&mut self.sim)
            .chain(c.members.iter_mut().map(|m| &mut m.sim))
            .collect();
        group.adopt_into(&mut mirrors)
    }

    /// Steps every variant inline through the end of the group's next frame, in lockstep
    /// (tests: no coordinator); false when none is left to step.
    pub fn step_group_inline(&mut self) -> bool {
        let Some(c) = &mut self.compare else {
            return false;
        };
        let (frame, _) = c.clock(&self.sim);
        let mut sims: Vec<&mut Run> = std::iter::once(&mut self.sim)
            .chain(c.members.iter_mut().map(|m| &mut m.sim))
            .collect();
        if sims.iter().all(|s| s.fault.is_some()) {
            return false;
        }
        let threads = cloth_run::study::threads_for(sims.len());
        lockstep::advance(&mut sims, frame + 1, threads, &|_| false)
    }
}
