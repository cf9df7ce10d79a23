//! The app's model: everything the screen shows, and nothing about the terminal.

use std::path::PathBuf;

use cloth_render::{AsciiFrame, Bounds, ColorDepth, Mode, Orbit, Renderer, View};

use super::sim::Simulation;

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
}

impl Prompt {
    /// A prompt holding `text`, cursor at the end.
    pub fn new(purpose: Purpose, text: String) -> Self {
        Self {
            purpose,
            cursor: text.chars().count(),
            text,
            error: None,
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
    /// The simulation stopped itself; the message says why and how to recover.
    Fault,
}

/// The scene picker: bundled scenes, then the scene files in the working folder, then
/// "type a path".
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Picker {
    /// The selected entry.
    pub selected: usize,
    /// `*.json` files in the working folder, sorted by name.
    pub files: Vec<String>,
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
    /// Simulated seconds per wall second actually achieved.
    pub realtime_factor: f64,
    /// Solver steps per wall second.
    pub steps_per_sec: f64,
    /// Frames drawn per wall second.
    pub draws_per_sec: f64,
    /// Whether the simulation could not keep up and dropped owed time.
    pub lagging: bool,
    /// Wall time per drawn frame (render + draw + write), ms.
    pub draw_ms: f64,
    /// Wall time the simulation may use per loop turn, ms.
    pub budget_ms: f64,
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

/// The whole app.
pub struct App {
    /// The cloth.
    pub sim: Simulation,
    /// Whether simulated time advances.
    pub running: bool,
    /// Index into [`RATES`].
    pub rate: usize,
    /// Simulated seconds owed to the simulation by the wall clock.
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
    /// The orbit camera (shared by orbit panes).
    pub orbit: Orbit,
    /// The region every fixed view frames: grows to hold the cloth, so the picture does not
    /// rescale every frame; a reset or a new scene starts it again.
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
    /// Rendered panes, by slot (filled by [`super::panes::prepare`] before each draw).
    pub frames: [Option<AsciiFrame>; 4],
    /// The renderer's scratch buffers, reused frame to frame.
    pub renderer: Renderer,
    /// Last mouse position while dragging in an orbit pane.
    pub drag: Option<(u16, u16)>,
    /// Set by quit.
    pub quit: bool,
    /// Scenes the picker offers to open a file from, and where save writes by default.
    pub cwd: PathBuf,
}

impl App {
    /// A new app on `sim`, running or paused.
    pub fn new(sim: Simulation, running: bool) -> Self {
        let orbit = Orbit::course_default(&sim.scene.mesh);
        Self {
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
            renderer: Renderer::new(),
            drag: None,
            quit: false,
            cwd: PathBuf::from("."),
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
