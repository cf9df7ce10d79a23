//! clothsim's live terminal UI (`clothsim tui`, the default command): it draws a `cloth_run::Run`
//! and reads keys; the command line and the files are the binary's and the run crate's.
//!
//! Elm architecture: a model ([`App`]), messages ([`Message`]), one [`update()`] function that
//! changes the model, and a pure [`view()`]. Terminal events become messages in `input`
//! (after `decode` has read them from the terminal's bytes); the one `keymap::KEYMAP` dispatches keys
//! and generates the footer and the help; the one `params::PARAMS` table drives the
//! parameter panel. The cloth steps on its own thread, a `cloth_run::lockstep::Lockstep` of
//! one that owns the simulation clock (compare mode's variants on one lockstep of them all);
//! the loop in `runner` waits on one channel for keys, signals and the lockstep's snapshots,
//! answers each at once and draws at most `--fps` times a second, paced by what the terminal
//! has taken (`link`) and written as the cells that changed (`screen`).

mod compare;
mod decode;
mod hand;
mod input;
mod keymap;
mod layout;
mod link;
mod message;
mod model;
mod panes;
mod params;
mod recording;
mod runner;
mod screen;
mod sgr;
mod terminal;
mod theme;
mod update;
mod view;

#[cfg(test)]
mod tests;

use std::io::IsTerminal;

use cloth_render::{ColorChoice, ColorDepth, ColorEnv, Mode};
use cloth_solver::Registry;

pub use message::Message;
pub use model::App;
pub use update::update;
pub use view::view;

use cloth_run::Run;

/// What the live UI starts with: the command line's `clothsim tui` arguments, parsed.
#[derive(Debug, Clone)]
pub struct Args {
    /// A bundled scene name (see `clothsim scenes`) or a scene JSON file; a path with a folder
    /// or ending in .json is always a file (`./plane` is the file, `plane` the bundled scene).
    pub scene: String,
    /// The solver (overrides the scene's `simulation.solver`; `clothsim solvers` lists them).
    /// Without `simulation.simulation_steps` in the scene or a `--set`, steps per frame follow
    /// the solver's recommendation, also when another solver is chosen in the UI.
    pub solver: Option<String>,
    /// Solver options given on the command line, checked against the chosen solver.
    pub solver_flags: cloth_run::solvers::Flags,
    /// Override a scene value: a dotted key and a JSON value, e.g. `cloth.ks=100000`.
    pub sets: Vec<String>,
    /// Start paused.
    pub paused: bool,
    /// Most frames drawn per second (1 to 240).
    pub fps: u32,
    /// Colour: auto (interface colours when the terminal has them and NO_COLOR, CLICOLOR and
    /// CLICOLOR_FORCE allow; glyph-only cloth), always (coloured cloth too, at the terminal's
    /// depth), never, or 16 / 256 / truecolor (coloured cloth at that depth).
    pub color: ColorChoice,
    /// Leave the mouse to the terminal (to select text); M toggles it in the UI.
    pub no_mouse: bool,
    /// Glyph mode of the cloth panes.
    pub mode: Mode,
    /// Start from a state that `simulate` wrote (its positions and last positions, so the
    /// cloth keeps its velocity) instead of the scene's flat start; its grid and pins must be
    /// the scene's. The clock goes on from the state's time; r resets to the scene's flat start.
    pub from: Option<std::path::PathBuf>,
    /// Most memory a cloth may take (e.g. 512M, 4G; powers of 1024): a scene whose solver,
    /// states and frames would need more is refused, at start and when opened. Default: the
    /// memory the system has available.
    pub max_memory: Option<u64>,
    /// Most bytes per second written to the terminal; drawing slows down to fit, the
    /// simulation does not. Without it drawing is paced by what the terminal has taken.
    pub max_rate: Option<u64>,
}

impl Default for Args {
    fn default() -> Self {
        Self {
            scene: "pinned4".to_owned(),
            solver: None,
            solver_flags: cloth_run::solvers::Flags::default(),
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

/// Builds the app for `args` with the solvers of `registry` (no terminal involved), as the
/// binary and the tests do, with the colour environment `env` (the tests give their own).
///
/// # Errors
/// A scene that does not load or a solver that is not registered or refuses its options.
pub fn build_in(
    args: &Args,
    registry: &Registry,
    is_tty: bool,
    env: &ColorEnv,
) -> anyhow::Result<App> {
    let mut scene = cloth_scene::load(&args.scene, &args.sets)?;
    // The flags become the scene's option keys, so they reach every solver chosen in the UI.
    let choice = cloth_run::solvers::prepare(
        registry,
        &mut scene,
        args.solver.as_deref(),
        &args.solver_flags,
    )?;
    let need = cloth_run::memory::ui_need(&choice.entry, &choice.options, &scene.mesh);
    let who = cloth_run::memory::solver(&choice.entry);
    cloth_run::memory::check(
        &scene.origin,
        &who,
        &scene.mesh,
        need,
        (args.max_memory, cloth_run::memory::SMALLER_SCENE),
    )?;
    let mut sim = Run::new(scene, registry.clone(), args.solver.as_deref())?;
    if let Some(path) = &args.from {
        let (file, state) =
            cloth_run::state_file::StateFile::read(path, &sim.scene.mesh, sim.dt())?;
        sim.start_from(state, file.frames, file.time);
    }
    let mut app = App::new(sim, !args.paused);
    app.max_memory = args.max_memory;
    let depth = args.color.resolve(is_tty, env);
    app.color_allowed = depth != ColorDepth::None;
    // NOTE: with colour off, C still turns the cloth's colour on, at the terminal's depth.
    app.depth = match depth {
        ColorDepth::None => match env.depth() {
            ColorDepth::None => ColorDepth::Ansi16,
            d => d,
        },
        d => d,
    };
    // NOTE: per-cell cloth colour multiplies the bytes per frame; under `auto` only the
    // interface is coloured and the cloth stays in glyphs (C turns its colour on).
    app.color = args.color != ColorChoice::Auto && depth != ColorDepth::None;
    app.mode = args.mode;
    app.mouse = !args.no_mouse;
    let n = app.sim.scene.mesh.len();
    if n > update::BIG_CLOTH {
        app.say(
            model::Level::Warn,
            format!(
                "a big cloth ({n} points): it may run slower than real time; the keys answer \
                 at once all the same"
            ),
        );
    }
    if let Some(warning) = pins_after_resize(&app.sim.scene, &args.sets) {
        app.say(model::Level::Warn, warning);
    }
    if let Ok(cwd) = std::env::current_dir() {
        app.cwd = cwd;
    }
    Ok(app)
}

/// A warning when `--set` resized the grid but left the pins: they are grid indices, so they
/// stay where the file put them (a corner of 50 points is no corner of 1000).
fn pins_after_resize(scene: &cloth_scene::Scene, sets: &[String]) -> Option<String> {
    let key = |s: &String| s.split('=').next().unwrap_or("").trim().to_owned();
    let resized = sets
        .iter()
        .map(key)
        .any(|k| k == "cloth.num_width_points" || k == "cloth.num_height_points");
    let moved = sets.iter().map(key).any(|k| k.starts_with("cloth.pinned"));
    let pins = scene.file.cloth.pinned.as_deref().unwrap_or_default();
    if !resized || moved || pins.is_empty() {
        return None;
    }
    let (w, h) = (scene.mesh.nw(), scene.mesh.nh());
    let list: Vec<String> = pins.iter().map(|[x, y]| format!("[{x},{y}]")).collect();
    Some(format!(
        "the grid is now {w} x {h} points but the pins stay at the file's grid indices ({}); \
         --set cloth.pinned=[[0,0],[{},0],...] moves them",
        list.join(", "),
        w - 1
    ))
}

/// What compare mode starts with: the command line's `clothsim compare` arguments, parsed.
#[derive(Debug, Clone)]
pub struct CompareArgs {
    /// The UI's arguments (the scene, `--set`, `--solver`, `--paused`, ...).
    pub ui: Args,
    /// The study: `KEY=V1,V2,...` with 2 to 6 values, the key and values as `--set` takes
    /// them (including `simulation.solver`); twice for a grid of up to 3 x 3 panes (the first
    /// key across, the second down).
    pub vary: Vec<cloth_run::study::Axis>,
}

/// Most panes compare mode shows.
pub const MAX_COMPARED: usize = 9;

/// Builds the compare-mode app for `args` (see [`build_in`]): the first variant is the app's
/// simulation, the others its members.
///
/// # Errors
/// A variant that does not load, more than [`MAX_COMPARED`] variants, or a bad solver.
pub fn build_compare_in(
    args: &CompareArgs,
    registry: &Registry,
    is_tty: bool,
    env: &ColorEnv,
) -> anyhow::Result<App> {
    let variants = cloth_run::study::variants(
        registry,
        &args.ui.scene,
        &args.ui.sets,
        args.ui.solver.as_deref(),
        &args.vary,
    )?;
    if args.vary.len() == 2
        && let Some(a) = args.vary.iter().find(|a| a.values.len() > 3)
    {
        anyhow::bail!(
            "--vary {}: {} values; with two --vary compare shows a grid of up to 3 x 3, so each \
             takes at most 3 values",
            a.key,
            a.values.len()
        );
    }
    if variants.len() > MAX_COMPARED {
        anyhow::bail!(
            "--vary gives {} variants; compare shows at most {MAX_COMPARED} (3 x 3): give \
             fewer values",
            variants.len()
        );
    }
    check_compare_memory(&variants, args.ui.max_memory)?;
    let mut app = build_in(&args.ui, registry, is_tty, env)?;
    let mut variants = variants.into_iter();
    let Some(first) = variants.next() else {
        anyhow::bail!("--vary gives no variants");
    };
    // Every variant starts from `--from`'s state (read against its own grid, so a width
    // variant whose grid differs is refused with the file's name) at the file's clock.
    let start = |sim: &mut Run| -> anyhow::Result<()> {
        if let Some(path) = &args.ui.from {
            let (file, state) =
                cloth_run::state_file::StateFile::read(path, &sim.scene.mesh, sim.dt())?;
            sim.start_from(state, file.frames, file.time);
        }
        Ok(())
    };
    app.sim = Run::new(
        first.scene,
        registry.clone(),
        Some(first.choice.entry.name()),
    )?;
    start(&mut app.sim)?;
    app.mark_saved();
    app.sent = app.saved.clone();
    let solver_varied = args.vary.iter().any(|a| a.key == "simulation.solver");
    let mut members = Vec::new();
    for v in variants {
        let mut sim = Run::new(v.scene, registry.clone(), Some(v.choice.entry.name()))?;
        start(&mut sim)?;
        members.push(compare::Member {
            title: v.title,
            sent: sim.settings.clone(),
            sim,
            frame: None,
        });
    }
    app.layout = model::Layout::Single;
    app.compare = Some(compare::Compare {
        axes: args
            .vary
            .iter()
            .map(|a| (a.key.clone(), a.values.join(", ")))
            .collect(),
        title: first.title,
        frame: None,
        members,
        columns: args.vary[0].values.len().min(3),
        solver_varied,
        group: None,
    });
    Ok(app)
}

/// Refuses a study whose variants together need more memory than `max` (or than is
/// available): each variant holds its cloth, states and solver once (the UI's copies share the
/// scene and hold no solver), and the panes share the renderer's buffers.
fn check_compare_memory(
    variants: &[cloth_run::study::Variant],
    max: Option<u64>,
) -> anyhow::Result<()> {
    let Some(first) = variants.first() else {
        return Ok(());
    };
    let mut need = cloth_run::memory::Need {
        solver: 0,
        cloth: 0,
        drawing: 0,
    };
    let mut names: Vec<&str> = Vec::new();
    for v in variants {
        let n = cloth_run::memory::ui_need(&v.choice.entry, &v.choice.options, &v.scene.mesh);
        need.solver = need.solver.saturating_add(n.solver);
        need.cloth = need.cloth.saturating_add(n.cloth);
        need.drawing = need.drawing.max(n.drawing);
        if !names.contains(&v.choice.entry.name()) {
            names.push(v.choice.entry.name());
        }
    }
    let who = format!(
        "the {} solver{} run as {} variants",
        names.join(" and "),
        if names.len() > 1 { "s" } else { "" },
        variants.len()
    );
    cloth_run::memory::check(
        &first.scene.origin,
        &who,
        &first.scene.mesh,
        need,
        (max, cloth_run::memory::SMALLER_SCENE),
    )
}

/// Runs compare mode until the user quits.
///
/// # Errors
/// As [`run`].
pub fn run_compare(args: &CompareArgs, registry: &Registry) -> anyhow::Result<()> {
    if !std::io::stdout().is_terminal() {
        anyhow::bail!(
            "compare needs a terminal, but stdout is not one; to write the variants' frames to \
             a file or a pipe use `clothsim render SCENE --vary ...` (or `simulate --vary`)"
        );
    }
    let env = ColorEnv::read(|k| std::env::var(k).ok());
    if env.dumb_terminal() {
        anyhow::bail!(
            "compare needs a terminal with cursor addressing; use `clothsim render {} --vary \
             ...` for plain text",
            args.ui.scene
        );
    }
    let app = build_compare_in(args, registry, true, &env)?;
    runner::run(app, args.ui.fps, args.ui.max_rate)
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
    let env = ColorEnv::read(|k| std::env::var(k).ok());
    if env.dumb_terminal() {
        anyhow::bail!(
            "the live UI needs a terminal with cursor addressing, but TERM is {}; to see the \
             cloth as plain text use `clothsim render {}` (frames as lines of text)",
            env.term
                .as_deref()
                .map_or("unset".to_owned(), |t| format!("{t:?}")),
            args.scene
        );
    }
    let app = build_in(args, registry, true, &env)?;
    runner::run(app, args.fps, args.max_rate)
}
