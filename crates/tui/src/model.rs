//! The app's model: everything the screen shows, and nothing about the terminal.

use std::path::PathBuf;

use cloth_render::{AsciiFrame, Bounds, ColorDepth, Mode, Orbit, Renderer, View};

use cloth_run::Settings;
use cloth_run::lockstep::{Lockstep, Rates};
use cloth_run::{Command, Run};

/// How many panes show the cloth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Layout {
    /// One pane: the focused one.
    Single,
    /// Two panes side by side (side and top at start).
    #[default]
    Two,
    /// Four panes in a 2 x 2 grid.
    Four,
}

impl Layout {
    /// How many panes are visible.
    pub fn panes(self) -> usize {
        match self {
            Layout::Single => 1,
            Layout::Two => 2,
            Layout::Four => 4,
        }
    }

    /// The next layout in the cycle.
    pub fn next(self) -> Self {
        match self {
            Layout::Single => Layout::Two,
            Layout::Two => Layout::Four,
            Layout::Four => Layout::Single,
        }
    }

    /// A name for the status line.
    pub fn name(self) -> &'static str {
        match self {
            Layout::Single => "single",
            Layout::Two => "two panes",
            Layout::Four => "four panes",
        }
    }
}

/// How bad a note is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Something done.
    Info,
    /// Worth attention.
    Warn,
    /// Something failed.
    Error,
}

/// The one-line message under the panes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Note {
    /// Severity.
    pub level: Level,
    /// Text.
    pub text: String,
}

/// What a prompt's text is for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Purpose {
    /// An exact value for the parameter at this row of [`super::params::PARAMS`].
    Value(usize),
    /// A file name to save the scene to.
    SavePath,
    /// A scene file to open.
    OpenPath,
}

/// A line of typed text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Prompt {
    /// What the text is for.
    pub purpose: Purpose,
    /// The text.
    pub text: String,
    /// Cursor, in characters.
    pub cursor: usize,
    /// Why the last submission was refused.
    pub error: Option<String>,
    /// Whether the whole text is selected (as pre-filled): typing replaces it.
    pub selected: bool,
}

impl Prompt {
    /// A prompt holding `text`, cursor at the end.
    pub fn new(purpose: Purpose, text: String) -> Self {
        Self {
            purpose,
            cursor: text.chars().count(),
            text,
            error: None,
            selected: false,
        }
    }

    /// A prompt pre-filled with `text`, all of it selected: typing replaces it, a cursor key
    /// keeps it for editing.
    pub fn prefilled(purpose: Purpose, text: String) -> Self {
        Self {
            selected: !text.is_empty(),
            ..Self::new(purpose, text)
        }
    }
}

/// What covers the panes, if anything. Keys go to the overlay first.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum Overlay {
    /// Nothing: keys go through the keymap.
    #[default]
    None,
    /// The key help.
    Help,
    /// The scene picker.
    Picker(Picker),
    /// A text prompt.
    Prompt(Prompt),
    /// "Overwrite this file?"
    ConfirmOverwrite(PathBuf),
    /// "Discard the unsaved edits?" before what would drop them.
    ConfirmDiscard(Then),
    /// "This cloth of so many points is big: open it?" (the scene waits in [`App::big`])
    ConfirmBig(usize),
    /// The simulation stopped itself; the message says why and how to recover.
    Fault,
}

/// What a discard question leads to when answered yes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Then {
    /// Leave the app.
    Quit,
    /// Open the scene picker.
    Open,
}

/// The scene picker: bundled scenes, then the scene files in the working folder, then
/// "type a path".
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Picker {
    /// The selected entry.
    pub selected: usize,
    /// `*.json` files in the working folder, sorted by name.
    pub files: Vec<String>,
    /// Which of [`Self::files`] are state files (`simulate`'s output, for `--from`), not scenes.
    pub states: Vec<bool>,
}

impl Picker {
    /// How many entries it lists.
    pub fn len(&self) -> usize {
        cloth_scene::BUNDLED.len() + self.files.len() + 1
    }
}

/// Measurements of the app loop over the last second or so.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Stats {
    /// The simulation's rates (measured by whoever steps it).
    pub rates: Rates,
    /// Frames drawn per wall second.
    pub draws_per_sec: f64,
    /// Wall time per drawn frame (render + draw + write), ms.
    pub draw_ms: f64,
    /// Whether the terminal (or `--max-rate`) held drawing back, and the bytes written.
    pub link: crate::link::Measure,
}

/// What to show in each pane slot at start: side and top first (the two-pane default).
pub const START_VIEWS: [View; 4] = [View::Side, View::Top, View::Front, View::Orbit];

/// Simulated-time rates offered by faster / slower.
pub const RATES: [f64; 9] = [
    1.0 / 16.0,
    1.0 / 8.0,
    1.0 / 4.0,
    1.0 / 2.0,
    1.0,
    2.0,
    4.0,
    8.0,
    16.0,
];

/// Index of 1x in [`RATES`].
pub const RATE_ONE: usize = 4;

/// A callback a worker calls when it has published.
pub type Notify = std::sync::Arc<dyn Fn() + Send + Sync>;

/// The whole app.
pub struct App {
    /// The cloth.
    pub sim: Run,
    /// Whether simulated time advances.
    pub running: bool,
    /// Index into the table of rates `RATES`.
    pub rate: usize,
    /// Simulated seconds owed when the cloth is stepped inline (tests; the worker keeps its own).
    pub debt: f64,
    /// Selected parameter row.
    pub selected: usize,
    /// What covers the panes.
    pub overlay: Overlay,
    /// Pane arrangement.
    pub layout: Layout,
    /// Whether the focused pane fills the view area.
    pub maximised: bool,
    /// The focused pane slot.
    pub focus: usize,
    /// The view of each pane slot.
    pub views: [View; 4],
    /// The orbit camera (shared by orbit panes): the last one drawn while it is fitted.
    pub orbit: Orbit,
    /// Whether the orbit camera is fitted to `extent` (the course's direction, refitted as the
    /// extent grows); turning or zooming makes it the user's, `0` fits it again.
    pub orbit_fitted: bool,
    /// The region every view frames (the orbit while fitted): grows to hold the cloth, so the
    /// picture does not rescale every frame; a reset or a new scene starts it again.
    pub extent: Option<Bounds>,
    /// First line of the help overlay shown (when it does not fit).
    pub help_scroll: u16,
    /// Glyph mode.
    pub mode: Mode,
    /// Whether colour is on.
    pub color: bool,
    /// Whether the terminal may show colour at all (false under `NO_COLOR` or `--color never`).
    pub color_allowed: bool,
    /// How many colours the cloth's colour uses when on.
    pub depth: ColorDepth,
    /// The message line.
    pub note: Option<Note>,
    /// Loop measurements.
    pub stats: Stats,
    /// Terminal size, cells.
    pub screen: (u16, u16),
    /// Rendered panes, by slot (filled by `panes::prepare` before each draw).
    pub frames: [Option<AsciiFrame>; 4],
    /// The renderer's scratch buffers, reused frame to frame.
    pub renderer: Renderer,
    /// The coarser grid a big cloth is drawn through (`None`: drawn as it is).
    pub display: Option<super::panes::Display>,
    /// Last mouse position while dragging in an orbit pane.
    pub drag: Option<(u16, u16)>,
    /// What the mouse's hand holds while a button is down (a point, a knife).
    pub grip: Option<super::hand::Grip>,
    /// Where the mouse was last seen (a button went down or dragged there).
    pub pointer: Option<(u16, u16)>,
    /// The panes as last drawn (filled by `panes::prepare`): what a gesture picks from.
    pub drawn: Vec<super::hand::Drawn>,
    /// Set by quit.
    pub quit: bool,
    /// What a save asked for from the quit or open dialog goes on to once the file is written.
    pub after_save: Option<Then>,
    /// Set by Ctrl-Z: the loop suspends the app (and clears it).
    pub suspend: bool,
    /// Whether the mouse is captured (wheel and drag work; the terminal cannot select text).
    pub mouse: bool,
    /// Edits that `u` takes back, newest last: the settings and the solver's name before each.
    pub undo: Vec<(Settings, &'static str)>,
    /// The settings and solver last opened or saved: edits past them are unsaved.
    pub saved: (Settings, &'static str),
    /// The pins last opened or saved, in order: a pin set or lifted by hand is unsaved.
    pub saved_pins: Vec<(usize, usize)>,
    /// Say where the cloth is once the single frame asked for arrives.
    pub step_note: bool,
    /// A scene waiting for the answer to "this cloth is big: open it?".
    pub big: Option<Box<cloth_scene::Scene>>,
    /// How a worker tells the loop it has something new (set by the loop; `None` in tests).
    pub notify: Option<Notify>,
    /// The thread stepping the cloth; `None` steps it inline (tests, and the fallback).
    pub worker: Option<Lockstep>,
    /// What the worker was last told, so an edit is sent once.
    pub sent: (Settings, &'static str),
    /// Scenes the picker offers to open a file from, and where save writes by default.
    pub cwd: PathBuf,
    /// The screen recording in progress (R starts and stops it).
    pub recording: Option<super::recording::Recording>,
    /// `--max-memory`: most bytes a scene opened may need (`None`: the memory available).
    pub max_memory: Option<u64>,
    /// Compare mode: the other variants of a study (`None`: one cloth).
    pub compare: Option<super::compare::Compare>,
}

impl App {
    /// A new app on `sim`, running or paused.
    pub fn new(sim: Run, running: bool) -> Self {
        let orbit = Orbit::course_default(&sim.scene.mesh);
        let saved = (sim.settings.clone(), sim.entry().name());
        let saved_pins = pins(&sim);
        let display = super::panes::Display::for_mesh(&sim.scene.mesh);
        Self {
            saved_pins,
            sent: saved.clone(),
            saved,
            undo: Vec::new(),
            suspend: false,
            mouse: true,
            step_note: false,
            worker: None,
            recording: None,
            notify: None,
            big: None,
            sim,
            running,
            rate: RATE_ONE,
            debt: 0.0,
            selected: 0,
            overlay: Overlay::None,
            layout: Layout::default(),
            maximised: false,
            focus: 0,
            views: START_VIEWS,
            orbit,
            orbit_fitted: true,
            extent: None,
            help_scroll: 0,
            mode: Mode::default(),
            color: false,
            color_allowed: false,
            depth: ColorDepth::TrueColor,
            note: None,
            stats: Stats::default(),
            screen: (80, 24),
            frames: [None, None, None, None],
            display,
            renderer: Renderer::new(),
            drag: None,
            grip: None,
            pointer: None,
            drawn: Vec::new(),
            quit: false,
            after_save: None,
            cwd: PathBuf::from("."),
            max_memory: None,
            compare: None,
        }
    }

    /// Whether the live settings, solver or pins differ from what was last opened or saved.
    pub fn unsaved(&self) -> bool {
        self.sim.settings != self.saved.0
            || self.sim.entry().name() != self.saved.1
            || pins(&self.sim) != self.saved_pins
    }

    /// Takes what runs now as what was last opened or saved.
    pub fn mark_saved(&mut self) {
        self.saved = (self.sim.settings.clone(), self.sim.entry().name());
        self.saved_pins = pins(&self.sim);
    }

    /// Tells the simulation's stepper: the worker (in compare mode the coordinator, for every
    /// variant) when there is one, else the simulation itself at once.
    ///
    /// # Errors
    /// What the simulation says when it applies the command itself (a solver that cannot be
    /// built, a fault of a frame stepped).
    pub fn send(&mut self, command: Command) -> Result<(), String> {
        if let Some(g) = self.group() {
            g.send(command);
            return Ok(());
        }
        self.send_members(&command);
        match &self.worker {
            Some(w) => {
                w.send(command);
                Ok(())
            }
            None => self.sim.apply(command),
        }
    }

    /// A copy of `sim` for a stepping thread, going on from its state with its live settings
    /// and solver.
    fn stepping_copy(sim: &Run) -> anyhow::Result<Run> {
        let mut copy = Run::new(
            std::sync::Arc::clone(&sim.scene),
            sim.registry().clone(),
            Some(sim.entry().name()),
        )?;
        copy.settings.clone_from(&sim.settings);
        // The live solver options may differ from the scene's: build with the live ones.
        copy.apply_options()?;
        copy.start_from(sim.state.clone(), sim.frames, sim.time);
        Ok(copy)
    }

    /// Moves the stepping of the cloth to a worker thread (replacing any worker), going on
    /// from the cloth's state (the start positions, or the state `--from` gave) with the live
    /// settings and solver; in compare mode, every variant to one lockstep coordinator. The
    /// thread's copies share the scenes (meshes included) with the UI's, and only they hold
    /// a solver.
    ///
    /// # Errors
    /// When the solver cannot be built or the thread cannot start.
    pub fn start_worker(&mut self, notify: Notify) -> anyhow::Result<()> {
        self.sent = (self.sim.settings.clone(), self.sim.entry().name());
        let n = std::sync::Arc::clone(&notify);
        // NOTE: the UI's copies let go of their solvers before the thread's are built, so a
        // big cloth never has two solvers' scratch at once (the memory check counts one each).
        self.sim.release_solver();
        if let Some(c) = &mut self.compare {
            for m in &mut c.members {
                m.sim.release_solver();
            }
            let mut sims = vec![Self::stepping_copy(&self.sim)?];
            for m in &c.members {
                sims.push(Self::stepping_copy(&m.sim)?);
            }
            let threads = cloth_run::study::threads_for(sims.len());
            c.group = Some(Lockstep::spawn(
                sims,
                self.running,
                RATES[self.rate],
                threads,
                Box::new(move || n()),
            )?);
        } else {
            self.worker = Some(Lockstep::spawn(
                vec![Self::stepping_copy(&self.sim)?],
                self.running,
                self.rate(),
                1,
                Box::new(move || n()),
            )?);
        }
        self.notify = Some(notify);
        Ok(())
    }

    /// Ends the screen recording, if one is in progress, keeping its file; its path or why it
    /// could not be kept.
    pub fn stop_recording(&mut self) -> Option<anyhow::Result<PathBuf>> {
        self.recording
            .take()
            .map(super::recording::Recording::finish)
    }

    /// Sends the worker (the coordinator, for the first variant) the live settings and solver
    /// if they changed since last sent.
    pub fn sync(&mut self) {
        self.sync_members();
        if !self.threaded() {
            return;
        }
        // NOTE: the solver goes first: the options in the settings are the new solver's, and
        // the worker's solver switch resets them to the scene's, which the settings then set.
        let name = self.sim.entry().name();
        let mut commands = Vec::new();
        if name != self.sent.1 {
            self.sent.1 = name;
            commands.push(Command::Solver(name.to_owned()));
        }
        if !commands.is_empty() || self.sim.settings != self.sent.0 {
            self.sent.0.clone_from(&self.sim.settings);
            commands.push(Command::Settings(self.sim.settings.clone()));
        }
        for command in commands {
            match (self.group(), &self.worker) {
                (Some(g), _) => g.send_to(0, command),
                (None, Some(w)) => w.send(command),
                (None, None) => {}
            }
        }
    }

    /// Simulated seconds per wall second asked for.
    pub fn rate(&self) -> f64 {
        RATES[self.rate]
    }

    /// Sets the message line.
    pub fn say(&mut self, level: Level, text: impl Into<String>) {
        self.note = Some(Note {
            level,
            text: text.into(),
        });
    }

    /// The pane slots on screen, in drawing order.
    pub fn visible_slots(&self) -> Vec<usize> {
        if self.maximised || self.layout == Layout::Single {
            vec![self.focus]
        } else {
            (0..self.layout.panes()).collect()
        }
    }
}

/// The pinned points of `sim`'s cloth by grid place, in order.
pub fn pins(sim: &Run) -> Vec<(usize, usize)> {
    let mut p = sim.scene.mesh.spec().pinned.clone();
    p.sort_unstable();
    p.dedup();
    p
}
