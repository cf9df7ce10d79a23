//! The clap arguments shared by the commands that run a scene: the live UI's, compare's and
//! the solver options every running command takes, turned into the plain values the UI and
//! the run crate take.

use cloth_render::{ColorChoice, Mode};
use cloth_run::progress::When;
use cloth_run::solvers::Flags;

/// Solver options on the command line: any option a registered solver declares as
/// `--option KEY=VALUE` (repeatable), and the shorthands `--threads` and `--order` for the
/// options of those names. Each is checked against the chosen solver's entry.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct SolverFlags {
    /// A solver option, `KEY=VALUE` (repeatable): any option the chosen solver declares
    /// (`clothsim solvers` lists them), overriding the scene's `simulation.solver_options`.
    #[arg(long = "option", short = 'O', value_name = "KEY=VALUE",
          value_parser = parse_option)]
    pub options: Vec<(String, serde_json::Value)>,
    /// Shorthand for `--option threads=N`: worker threads of the solvers that have a
    /// `threads` option (the results do not depend on it).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=256))]
    pub threads: Option<u16>,
    /// Shorthand for `--option order=ORDER`: the constraint order of the solvers that have an
    /// `order` option (its values are listed by `clothsim solvers`).
    #[arg(long, value_name = "ORDER")]
    pub order: Option<String>,
}

/// clap's parser of `--option`'s `KEY=VALUE`.
fn parse_option(text: &str) -> Result<(String, serde_json::Value), String> {
    Flags::parse_option(text)
}

impl SolverFlags {
    /// The options given, as the run crate takes them, named as typed.
    pub fn to_flags(&self) -> Flags {
        let mut flags = Flags::default();
        if let Some(t) = self.threads {
            flags = flags.with(format!("--threads {t}"), "threads", t.into());
        }
        if let Some(o) = &self.order {
            flags = flags.with(
                format!("--order {o}"),
                "order",
                o.to_ascii_lowercase().into(),
            );
        }
        for (key, value) in &self.options {
            let shown = value
                .as_str()
                .map_or_else(|| value.to_string(), str::to_owned);
            flags = flags.with(format!("--option {key}={shown}"), key, value.clone());
        }
        flags
    }
}

/// Arguments of `clothsim tui` (and of `clothsim` with none).
#[derive(Debug, Clone, clap::Args)]
pub struct UiArgs {
    /// A bundled scene name (see `clothsim scenes`) or a scene JSON file; a path with a folder
    /// or ending in .json is always a file (`./plane` is the file, `plane` the bundled scene).
    #[arg(default_value = "pinned4", value_hint = clap::ValueHint::FilePath)]
    pub scene: String,
    /// The solver (overrides the scene's `simulation.solver`; `clothsim solvers` lists them).
    /// Without `simulation.simulation_steps` in the scene or a `--set`, steps per frame follow
    /// the solver's recommendation, also when another solver is chosen in the UI.
    #[arg(long)]
    pub solver: Option<String>,
    /// Solver options: `--option KEY=VALUE`, `--threads`, `--order`.
    #[command(flatten)]
    pub solver_flags: SolverFlags,
    /// Override a scene value: a dotted key and a JSON value, e.g. `cloth.ks=100000`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Start paused.
    #[arg(long)]
    pub paused: bool,
    /// Most frames drawn per second (1 to 240).
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=240))]
    pub fps: u32,
    /// Colour: auto (interface colours when the terminal has them and NO_COLOR, CLICOLOR and
    /// CLICOLOR_FORCE allow; glyph-only cloth), always (coloured cloth too, at the terminal's
    /// depth), never, or 16 / 256 / truecolor (coloured cloth at that depth).
    #[arg(long, value_name = "WHEN", default_value = "auto", ignore_case = true,
          value_parser = crate::cli::color_parser())]
    pub color: ColorChoice,
    /// Leave the mouse to the terminal (to select text); M toggles it in the UI.
    #[arg(long)]
    pub no_mouse: bool,
    /// Glyph mode of the cloth panes.
    #[arg(long, default_value = "ascii", ignore_case = true,
          value_parser = crate::cli::mode_parser())]
    pub mode: Mode,
    /// Start from a state that `simulate` wrote (its positions and last positions, so the
    /// cloth keeps its velocity) instead of the scene's flat start; its grid and pins must be
    /// the scene's. The clock goes on from the state's time; r resets to the scene's flat start.
    #[arg(long, value_name = "STATE.json", value_hint = clap::ValueHint::FilePath)]
    pub from: Option<std::path::PathBuf>,
    /// Most memory a cloth may take (e.g. 512M, 4G; powers of 1024): a scene whose solver,
    /// states and frames would need more is refused, at start and when opened. Default: the
    /// memory the system has available.
    #[arg(long, value_name = "SIZE", value_parser = cloth_run::memory::parse_size)]
    pub max_memory: Option<u64>,
    /// Most bytes per second written to the terminal (e.g. 16K; powers of 1024): drawing
    /// slows down to fit, the simulation does not. Without it the UI measures what the
    /// terminal takes and keeps about one frame in flight.
    #[arg(long, value_name = "BYTES_PER_SEC", value_parser = cloth_run::memory::parse_size)]
    pub max_rate: Option<u64>,
}

impl Default for UiArgs {
    fn default() -> Self {
        Self {
            scene: "pinned4".to_owned(),
            solver: None,
            solver_flags: SolverFlags::default(),
            sets: Vec::new(),
            paused: false,
            fps: 30,
            color: ColorChoice::Auto,
            no_mouse: false,
            mode: Mode::Ascii,
            from: None,
            max_memory: None,
            max_rate: None,
        }
    }
}

impl UiArgs {
    /// The UI's start values.
    pub fn to_ui(&self) -> cloth_tui::Args {
        cloth_tui::Args {
            scene: self.scene.clone(),
            solver: self.solver.clone(),
            solver_flags: self.solver_flags.to_flags(),
            sets: self.sets.clone(),
            paused: self.paused,
            fps: self.fps,
            color: self.color,
            no_mouse: self.no_mouse,
            mode: self.mode,
            from: self.from.clone(),
            max_memory: self.max_memory,
            max_rate: self.max_rate,
        }
    }
}

/// Arguments of `clothsim compare`.
#[derive(Debug, Clone, clap::Args)]
pub struct CompareArgs {
    /// The UI's arguments (the scene, `--set`, `--solver`, `--paused`, ...).
    #[command(flatten)]
    pub ui: UiArgs,
    /// The study: `KEY=V1,V2,...` with 2 to 6 values, the key and values as `--set` takes
    /// them (including `simulation.solver`); twice for a grid of up to 3 x 3 panes (the first
    /// key across, the second down).
    #[arg(long = "vary", value_name = "KEY=V1,V2,...", required = true)]
    pub vary: Vec<cloth_run::study::Axis>,
}

impl CompareArgs {
    /// Compare mode's start values.
    pub fn to_ui(&self) -> cloth_tui::CompareArgs {
        cloth_tui::CompareArgs {
            ui: self.ui.to_ui(),
            vary: self.vary.clone(),
        }
    }
}

/// clap's parser of `--progress WHEN`: one of [`When::NAMES`], in any case.
pub fn when_parser() -> impl clap::builder::TypedValueParser<Value = When> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(When::NAMES)
        .map(|s| s.parse::<When>().unwrap_or_default())
}
