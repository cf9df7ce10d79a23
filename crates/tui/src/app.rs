//! `clothsim tui`: the live terminal UI (the default command).
//!
//! Elm architecture, synchronous: a model ([`App`]), messages ([`Message`]), one
//! [`update()`] function that changes the model, and a pure [`view()`]. Terminal events become
//! messages in [`input`]; the one [`keymap::KEYMAP`] dispatches keys and generates the footer
//! and the help; the one [`params::PARAMS`] table drives the parameter panel. The loop in
//! [`runner`] owns the only clock: it feeds wall time to a fixed-step accumulator with a
//! per-frame budget, draws at most `--fps` times a second and only when something changed.

mod input;
mod keymap;
mod layout;
mod message;
mod model;
mod panes;
mod params;
mod runner;
mod sim;
mod theme;
mod update;
mod view;

#[cfg(test)]
mod tests;

use std::io::IsTerminal;

use cloth_render::{ColorChoice, ColorDepth, Mode};
use cloth_solver::Registry;

pub use message::Message;
pub use model::App;
pub use update::update;
pub use view::view;

use sim::Simulation;

/// Arguments of `clothsim tui` (and of `clothsim` with none).
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// A bundled scene name (see `clothsim scenes`) or a scene JSON file; a path with a folder
    /// or ending in .json is always a file (`./plane` is the file, `plane` the bundled scene).
    #[arg(default_value = "pinned4", value_hint = clap::ValueHint::FilePath)]
    pub scene: String,
    /// The solver (overrides the scene's `simulation.solver`; `clothsim solvers` lists them).
    #[arg(long)]
    pub solver: Option<String>,
    /// Override a scene value: a dotted key and a JSON value, e.g. `cloth.ks=100000`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Start paused.
    #[arg(long)]
    pub paused: bool,
    /// Most frames drawn per second (1 to 240).
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=240))]
    pub fps: u32,
    /// Colour: under auto the interface is coloured and the cloth stays in glyphs; a depth
    /// (16, 256, truecolor) colours the cloth too.
    #[arg(long, value_name = "WHEN", default_value = "auto", ignore_case = true,
          value_parser = crate::cli::color_parser())]
    pub color: ColorChoice,
    /// Glyph mode of the cloth panes.
    #[arg(long, default_value = "ascii", ignore_case = true,
          value_parser = crate::cli::mode_parser())]
    pub mode: Mode,
}

impl Default for Args {
    fn default() -> Self {
        Self {
            scene: "pinned4".to_owned(),
            solver: None,
            sets: Vec::new(),
            paused: false,
            fps: 30,
            color: ColorChoice::Auto,
            mode: Mode::Ascii,
        }
    }
}

/// Builds the app for `args` with the solvers of `registry` (no terminal involved), as the
/// binary and the tests do.
///
/// # Errors
/// A scene that does not load or a solver that is not registered or refuses its options.
pub fn build(args: &Args, registry: &Registry, is_tty: bool) -> anyhow::Result<App> {
    let scene = cloth_scene::load(&args.scene, &args.sets)?;
    let sim = Simulation::new(scene, registry.clone(), args.solver.as_deref())?;
    let mut app = App::new(sim, !args.paused);
    let no_color = std::env::var("NO_COLOR").ok();
    let colorterm = std::env::var("COLORTERM").ok();
    let depth = args
        .color
        .resolve(is_tty, no_color.as_deref(), colorterm.as_deref());
    app.color_allowed = depth != ColorDepth::None;
    if depth != ColorDepth::None {
        app.depth = depth;
    }
    // NOTE: per-cell cloth colour multiplies the bytes per frame; under `auto` only the
    // interface is coloured and the cloth stays in glyphs (C turns its colour on).
    app.color = args.color != ColorChoice::Auto && depth != ColorDepth::None;
    app.mode = args.mode;
    if let Ok(cwd) = std::env::current_dir() {
        app.cwd = cwd;
    }
    Ok(app)
}

/// Runs the live UI until the user quits.
///
/// # Errors
/// When stdout is not a terminal, the scene does not load, or the terminal fails.
pub fn run(args: &Args, registry: &Registry) -> anyhow::Result<()> {
    if !std::io::stdout().is_terminal() {
        anyhow::bail!(
            "the live UI needs a terminal, but stdout is not one; to write frames to a file or a \
             pipe use `clothsim render` (or `clothsim simulate` for the final state)"
        );
    }
    let app = build(args, registry, true)?;
    runner::run(app, args.fps)
}
