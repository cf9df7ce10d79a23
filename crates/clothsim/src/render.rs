//! `clothsim render`: simulate a scene headless and print its frames as text.
//!
//! Plain text by default: each frame is exactly H lines of W columns, frames are separated by a
//! line holding only a form feed (`\x0c`). `--format ansi` adds colour escapes; `--format cast`
//! writes an asciinema v2 recording of the same frames at their simulated times. Never touches
//! terminal modes, so it works the same into a pipe or a file.

use std::fmt::Write as _;
use std::str::FromStr;

use cloth_mesh::{ClothMesh, ClothState, Collider, Vec3};
use cloth_render::{
    AsciiFrame, Bounds, ColorChoice, ColorDepth, ColorEnv, Extent, FrameSize, Mode, RenderError,
    RenderOptions, Renderer, View, ViewSpec,
};
use cloth_solver::Registry;

use cloth_run::guard::Divergence;
use cloth_run::memory::{self, Need};
use cloth_run::output::Stdout;
use cloth_run::progress::{Progress, When};
use cloth_run::state_file::StateFile;
use cloth_run::{Cause, Fault, Run};
use cloth_run::{export, headless, solvers, study};

/// Columns between the panels of `--view all`.
const GAP: &str = " | ";

/// One view, or `all` (side, top and front next to each other).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewArg {
    /// A single view.
    One(View),
    /// Side, top and front side by side, labelled.
    All,
}

impl ViewArg {
    fn views(self) -> Vec<View> {
        match self {
            ViewArg::One(v) => vec![v],
            ViewArg::All => vec![View::Side, View::Top, View::Front],
        }
    }
}

impl FromStr for ViewArg {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("all") {
            return Ok(ViewArg::All);
        }
        s.parse()
            .map(ViewArg::One)
            .map_err(|_| RenderError::Unknown {
                what: "view",
                value: s.to_owned(),
                allowed: "side, top, bottom, front, orbit or all",
            })
    }
}

/// How frames are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Glyphs only, no escape sequences.
    Plain,
    /// Glyphs with SGR colour escapes (depth from `--color`).
    Ansi,
    /// An asciinema v2 recording (`asciinema play FILE`): a header line, then each frame as an
    /// event at its simulated time, with colour as for `ansi`.
    Cast,
}

/// Arguments of `clothsim render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A bundled scene name (see `clothsim scenes`) or a scene JSON file; a path with a folder
    /// or ending in .json is always a file (`./plane` is the file, `plane` the bundled scene).
    #[arg(value_hint = clap::ValueHint::FilePath)]
    scene: String,
    /// Frames to simulate (each 1/frames_per_sec seconds of simulated time); 0 shows the start.
    #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u64).range(0..=10_000_000))]
    frames: u64,
    /// Print every K-th frame (frames K, 2K, ... and always the last); default: only the last.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(1..))]
    every: Option<u64>,
    /// Which way the scene is looked at (orbit is the course's perspective camera).
    #[arg(long, default_value = "side", value_name = "VIEW", ignore_case = true,
          value_parser = crate::cli::view_parser())]
    view: ViewArg,
    /// Size of each frame (each panel with `--view all`) in character cells.
    #[arg(long, default_value = "80x40", value_name = "WxH")]
    size: FrameSize,
    /// How pixels become characters.
    #[arg(long, default_value = "ascii", value_name = "MODE", ignore_case = true,
          value_parser = crate::cli::mode_parser())]
    mode: Mode,
    /// Colour with `--format ansi`: auto (the terminal's depth from COLORTERM and TERM, 256
    /// when they say nothing, none under NO_COLOR or CLICOLOR=0), always, never, 16, 256 or
    /// truecolor. Plain format never writes colour.
    #[arg(long, default_value = "auto", value_name = "WHEN", ignore_case = true,
          value_parser = crate::cli::color_parser())]
    color: ColorChoice,
    /// How frames are written.
    #[arg(long, value_enum, default_value_t = Format::Plain)]
    format: Format,
    /// Override a scene value: a dotted key and a JSON value, e.g. `cloth.ks=100000`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// The solver (overrides the scene's `simulation.solver`; `clothsim solvers` lists them).
    /// Without `simulation.simulation_steps` in the scene or a `--set`, the run takes the
    /// solver's recommended steps per frame.
    #[arg(long)]
    solver: Option<String>,
    #[command(flatten)]
    flags: crate::args::SolverFlags,
    /// Progress on stderr: auto (a bar when stderr is a terminal and the frames go elsewhere),
    /// always (also a line every 10 s when stderr is not a terminal), never. `--progress` alone
    /// means always.
    #[arg(long, value_name = "WHEN", default_value = "auto", value_parser = crate::args::when_parser(),
          num_args = 0..=1, default_missing_value = "always")]
    progress: When,
    /// Start from a state that `simulate` wrote (its positions and last positions, so the
    /// cloth keeps its velocity) instead of the scene's flat start; its grid and pins must be
    /// the scene's. Frame 0 is that state.
    #[arg(long, value_name = "STATE.json")]
    from: Option<std::path::PathBuf>,
    /// Touch the cloth as a script says (grab, drag, release, poke, pin, unpin, cut), as
    /// `simulate --actions` does; docs/files-and-output.md gives the format.
    #[arg(long, value_name = "FILE", value_hint = clap::ValueHint::FilePath, conflicts_with = "vary")]
    actions: Option<std::path::PathBuf>,
    /// Most memory the run may take (e.g. 512M, 4G; powers of 1024): a cloth whose solver,
    /// states and frames would need more is refused before they are allocated. Default: the
    /// memory the system has available.
    #[arg(long, value_name = "SIZE", value_parser = cloth_run::memory::parse_size)]
    max_memory: Option<u64>,
    /// Render one variant per value of a scene key next to each other, titled, at the same
    /// frames and with one fixed extent: `KEY=V1,V2,...` with 2 to 6 values, the key and
    /// values as `--set` takes them (including `simulation.solver`); twice for a grid (the
    /// first key across, the second down). Takes one view.
    #[arg(long = "vary", value_name = "KEY=V1,V2,...")]
    vary: Vec<cloth_run::study::Axis>,
}

/// Whether frame `f` (1-based; 0 is the start) of `frames` is printed.
fn printed(f: u64, frames: u64, every: Option<u64>) -> bool {
    f == frames || every.is_some_and(|k| f > 0 && f.is_multiple_of(k))
}

/// How many frames of `frames` are printed (see [`printed`]).
fn printed_count(frames: u64, every: Option<u64>) -> u64 {
    match every {
        Some(k) if frames > 0 => frames / k + u64::from(!frames.is_multiple_of(k)),
        _ => 1,
    }
}

/// Runs the command.
pub fn run(args: &Args, registry: &Registry) -> anyhow::Result<()> {
    let depth = match args.format {
        Format::Plain => ColorDepth::None,
        // The user asked for escapes, so a pipe does not turn them off; NO_COLOR still does.
        Format::Ansi | Format::Cast => {
            let env = ColorEnv::read(|k| std::env::var(k).ok());
            match args.color.resolve(true, &env) {
                // Escapes asked for, and TERM says nothing of the reader: 256 colours.
                ColorDepth::None
                    if args.color == ColorChoice::Auto
                        && env.dumb_terminal()
                        && env.no_color.as_ref().is_none_or(String::is_empty)
                        && env.clicolor.as_deref() != Some("0") =>
                {
                    ColorDepth::Ansi256
                }
                d => d,
            }
        }
    };
    if !args.vary.is_empty() {
        return run_study(args, registry, depth);
    }
    let mut scene = cloth_scene::load(&args.scene, &args.sets)?;
    let choice = solvers::prepare(
        registry,
        &mut scene,
        args.solver.as_deref(),
        &args.flags.to_flags(),
    )?;
    let views = args.view.views();
    // The start, the running state and the last good one.
    let drawing = memory::drawing(
        scene.mesh.len(),
        views.len(),
        args.size.width * args.size.height,
        args.mode,
    );
    let need = Need::new(&choice.entry, &choice.options, &scene.mesh, 3, drawing);
    memory::check(
        &scene.origin,
        &memory::solver(&choice.entry),
        &scene.mesh,
        need,
        (args.max_memory, memory::SMALLER_SCENE),
    )?;
    let start = match &args.from {
        Some(path) => StateFile::read(path, &scene.mesh, scene.params.dt())?.1,
        None => ClothState::new(&scene.mesh),
    };
    let options = RenderOptions {
        mode: args.mode,
        color: depth != ColorDepth::None,
        ..RenderOptions::default()
    };

    headless::note_shadowing(&args.scene);
    // One pass: frames are written as they are made. A single frame is fitted on its own. For
    // an animation, the extent starts as where the scene can take the cloth (see
    // `predicted_extent`), so the views keep one scale, and grows should the cloth go further.
    // The orbit view also frames the start, as the live UI's does (see `orbit_extent`).
    let mut extent = if printed_count(args.frames, args.every) > 1 {
        Some(predicted_extent(&scene, &start, args.frames)?)
    } else {
        None
    };
    let start_box = Bounds::of_scene(&start.positions, &scene.colliders)?;
    let mut renderer = Renderer::new();
    let mut panels: Vec<AsciiFrame> = views.iter().map(|_| AsciiFrame::new(args.size)).collect();
    let mut text = String::new();
    let mut out = Stdout::new();
    let mut first = true;
    if args.format == Format::Cast {
        let (width, height) = if views.len() == 1 {
            (args.size.width, args.size.height)
        } else {
            (
                views.len() * args.size.width + (views.len() - 1) * GAP.chars().count(),
                args.size.height + 1,
            )
        };
        out.write_all_or_fail(export::cast_header(width, height, &scene.origin).as_bytes())?;
    }
    let cast = args.format == Format::Cast;
    let fps = scene.params.frames_per_sec;
    let diverged = simulate(&scene, &choice, registry, args, &start, |f, mesh, state| {
        let now = Bounds::of_scene(&state.positions, &scene.colliders)?;
        let fitted = extent.map_or(now, |e| e.union(&now));
        if extent.is_some() {
            extent = Some(fitted);
        }
        for (view, panel) in views.iter().zip(panels.iter_mut()) {
            let spec = ViewSpec {
                extent: Extent::Fixed(orbit_extent(*view, fitted, &start_box)),
                ..ViewSpec::new(*view, mesh)
            };
            renderer.render(mesh, state, &scene.colliders, &spec, &options, panel)?;
        }
        text.clear();
        if !first && !cast {
            text.push_str("\x0c\n");
        }
        if views.len() == 1 {
            panels[0].write_ansi(&mut text, depth)?;
        } else {
            let labels: Vec<String> = views
                .iter()
                .map(|v| v.describe().chars().take(args.size.width).collect())
                .collect();
            side_by_side_titled(&labels, &panels, args.size, depth, &mut text)?;
        }
        if cast {
            text = export::cast_frame(f as f64 / fps, &text, first);
        }
        first = false;
        // A reader that stops early (`| head`) ends the run here: main treats it as a
        // normal end. Each frame is flushed, so a reader sees it as soon as it is made.
        out.write_all_or_fail(text.as_bytes())?;
        out.flush_or_fail()
    })?;
    out.finish()?;
    diverged_error(&scene, &choice.entry, args, diverged)
}

/// `render --vary`: the variants stepped in lockstep, each printed frame a grid of panels (the
/// first axis across, the second down), each titled with its values, all fitted to one extent.
fn run_study(args: &Args, registry: &Registry, depth: ColorDepth) -> anyhow::Result<()> {
    let ViewArg::One(view) = args.view else {
        anyhow::bail!(
            "--view all shows three views of one run; with --vary choose one view (side, top, \
             bottom, front or orbit)"
        );
    };
    let variants = study::variants(
        registry,
        &args.scene,
        &args.sets,
        args.solver.as_deref(),
        &args.vary,
    )?;
    let columns = args.vary[0].values.len();
    let mut starts = Vec::with_capacity(variants.len());
    for v in &variants {
        starts.push(match &args.from {
            Some(path) => StateFile::read(path, &v.scene.mesh, v.scene.params.dt())?.1,
            None => ClothState::new(&v.scene.mesh),
        });
    }
    let mut start_box: Option<Bounds> = None;
    for (v, start) in variants.iter().zip(&starts) {
        let b = Bounds::of_scene(&start.positions, &v.scene.colliders)?;
        start_box = Some(start_box.map_or(b, |a| a.union(&b)));
    }
    let mut runs = Vec::with_capacity(variants.len());
    for (v, start) in variants.iter().zip(&starts) {
        runs.push(study::Run::new(v, Some(start))?);
    }
    headless::note_shadowing(&args.scene);
    // One extent for every variant and frame, so the shapes compare honestly: where any
    // variant can go (see `predicted_extent`), grown should one of them go further.
    let mut extent = if printed_count(args.frames, args.every) > 1 {
        let mut all: Option<Bounds> = None;
        for (v, start) in variants.iter().zip(&starts) {
            let e = predicted_extent(&v.scene, start, args.frames)?;
            all = Some(all.map_or(e, |a| a.union(&e)));
        }
        all
    } else {
        None
    };
    let options = RenderOptions {
        mode: args.mode,
        color: depth != ColorDepth::None,
        ..RenderOptions::default()
    };
    let mut renderer = Renderer::new();
    let mut panels: Vec<AsciiFrame> = runs.iter().map(|_| AsciiFrame::new(args.size)).collect();
    let mut text = String::new();
    let mut out = Stdout::new();
    let steps = variants
        .iter()
        .map(|v| u64::from(v.scene.params.steps_per_frame))
        .sum::<u64>();
    let label = format!("{} ({} variants)", variants[0].scene.origin, variants.len());
    let mut progress = Progress::new(
        args.progress,
        &label,
        args.frames,
        steps as u32,
        Stdout::is_terminal(),
    );
    let threads = study::threads_for(runs.len());
    let mut draw = |runs: &[study::Run<'_>], text: &mut String| -> anyhow::Result<()> {
        let mut fitted = extent;
        for run in runs {
            let now = Bounds::of_scene(&run.state().positions, &run.variant.scene.colliders)?;
            fitted = Some(fitted.map_or(now, |e| e.union(&now)));
        }
        let Some(fitted) = fitted else {
            return Ok(());
        };
        if extent.is_some() {
            extent = Some(fitted);
        }
        for (run, panel) in runs.iter().zip(panels.iter_mut()) {
            let scene = &run.variant.scene;
            let spec = ViewSpec {
                extent: Extent::Fixed(start_box.map_or(fitted, |b| orbit_extent(view, fitted, &b))),
                ..ViewSpec::new(view, &scene.mesh)
            };
            renderer.render(
                &scene.mesh,
                run.state(),
                &scene.colliders,
                &spec,
                &options,
                panel,
            )?;
        }
        let titles: Vec<String> = runs
            .iter()
            .map(|r| match (&r.diverged, &r.failed) {
                (Some((f, _)), _) => format!("{} (diverged at frame {f})", r.variant.title),
                (None, Some(_)) => format!("{} (failed)", r.variant.title),
                (None, None) => r.variant.title.clone(),
            })
            .collect();
        grid(&titles, &panels, columns, args.size, depth, text)
    };
    let result = (|| -> anyhow::Result<()> {
        let mut first = true;
        if printed(0, args.frames, args.every) {
            text.clear();
            draw(&runs, &mut text)?;
            out.write_all_or_fail(text.as_bytes())?;
            out.flush_or_fail()?;
            first = false;
        }
        for f in 1..=args.frames {
            study::advance_all(&mut runs, f, args.frames, threads, &mut progress);
            if printed(f, args.frames, args.every) {
                text.clear();
                if !first {
                    text.push_str("\x0c\n");
                }
                first = false;
                draw(&runs, &mut text)?;
                out.write_all_or_fail(text.as_bytes())?;
                out.flush_or_fail()?;
            }
        }
        Ok(())
    })();
    progress.finish();
    result?;
    out.finish()?;
    let stopped: Vec<String> = runs
        .iter()
        .filter_map(|r| r.reason().map(|why| format!("{}: {why}", r.variant.title)))
        .collect();
    if !stopped.is_empty() {
        anyhow::bail!(
            "{}: {} of {} variants stopped (their panels show the last good frame):\n  {}",
            variants[0].scene.origin,
            stopped.len(),
            variants.len(),
            stopped.join("\n  ")
        );
    }
    Ok(())
}

/// Writes `panels` as a grid of `columns` across, each row of panels under a line of their
/// `titles`.
fn grid(
    titles: &[String],
    panels: &[AsciiFrame],
    columns: usize,
    size: FrameSize,
    depth: ColorDepth,
    out: &mut String,
) -> anyhow::Result<()> {
    for (row_titles, row) in titles.chunks(columns).zip(panels.chunks(columns)) {
        let labels: Vec<String> = row_titles
            .iter()
            .map(|t| t.chars().take(size.width).collect())
            .collect();
        side_by_side_titled(&labels, row, size, depth, out)?;
    }
    Ok(())
}

/// The box `view` is fitted to, given the box of the frames shown (`fitted`) and of the start:
/// the orbit view frames the start too, so that its camera, which keeps the course's direction,
/// still sees a cloth that has come to rest flat on a floor from above its starting height, as
/// the live UI's orbit view (fitted to the run so far) sees it; the orthographic views frame
/// what is shown.
fn orbit_extent(view: View, fitted: Bounds, start: &Bounds) -> Bounds {
    if view == View::Orbit {
        fitted.union(start)
    } else {
        fitted
    }
}

/// Where the scene can take the cloth in `frames` frames, as the box the views are fitted to.
///
/// The start (cloth, spheres and the floor under them), grown along gravity by how far the
/// cloth can go: a pinned cloth hangs at most 1.1 times (the stretch limit) its longest reach
/// from a pin below its pins; a free cloth falls `g t^2 / 2` in the run's time, or, when a
/// collider is there to catch it, at most 1.1 times its own diagonal. A floor facing up stops
/// the fall. The cloth rarely fills the whole box, and when it leaves it (a swing past the
/// vertical) the box grows from that frame on.
fn predicted_extent(
    scene: &cloth_scene::Scene,
    start: &ClothState,
    frames: u64,
) -> anyhow::Result<Bounds> {
    let solid = Bounds::of_solids(&start.positions, &scene.colliders)?;
    let cloth = Bounds::of_points(&start.positions)?.unwrap_or(solid);
    let g = scene.params.gravity;
    let g_size = g.norm();
    if g_size == 0.0 || !g_size.is_finite() {
        return Ok(solid.with_floors(&solid, &scene.colliders));
    }
    let down = g / g_size;
    let pins: Vec<Vec3> = scene
        .mesh
        .pinned()
        .iter()
        .zip(&start.positions)
        .filter_map(|(&p, x)| p.then_some(*x))
        .collect();
    let reach = if pins.is_empty() {
        let t = frames as f64 / scene.params.frames_per_sec;
        let fall = 0.5 * g_size * t * t;
        if scene.colliders.is_empty() {
            fall
        } else {
            fall.min(1.1 * cloth.diagonal())
        }
    } else {
        // NOTE: the distance to a subset of the pins is at least the distance to the nearest
        // pin, so at most 64 of them keep this an upper bound at a bounded cost.
        let stride = pins.len().div_ceil(64);
        let nearest = |x: &Vec3| {
            pins.iter()
                .step_by(stride)
                .map(|p| (x - p).norm())
                .fold(f64::INFINITY, f64::min)
        };
        1.1 * start.positions.iter().map(nearest).fold(0.0, f64::max)
    };
    let shift = down * reach;
    let mut fallen = Bounds {
        min: cloth.min + shift,
        max: cloth.max + shift,
    };
    for c in &scene.colliders {
        // A floor facing against gravity stops the fall at its height.
        if let Collider::Plane(p) = c
            && p.normal.dot(&down) < -0.99
            && down.y < -0.99
        {
            fallen.min.y = fallen.min.y.max(p.point.y);
            fallen.max.y = fallen.max.y.max(fallen.min.y);
        }
    }
    let predicted = solid.union(&fallen);
    Ok(predicted.with_floors(&predicted, &scene.colliders))
}

/// The error of a run the guard stopped (after the frames before it were printed).
fn diverged_error(
    scene: &cloth_scene::Scene,
    entry: &cloth_solver::SolverEntry,
    args: &Args,
    diverged: Option<(u64, Divergence)>,
) -> anyhow::Result<()> {
    let Some((frame, d)) = diverged else {
        return Ok(());
    };
    anyhow::bail!(
        "{}: the run diverged at frame {frame} of {} (t = {:.3} s): {}; {}; the frames before \
         it were printed",
        scene.origin,
        args.frames,
        frame as f64 / scene.params.frames_per_sec,
        d.describe(),
        cloth_run::headless::divergence_advice(scene, &scene.params, entry, &d)
    )
}

/// Simulates `args.frames` frames from `start`, calling `each` with the frame number and state
/// of every printed frame, and of the last good frame when the guard stops the run; returns the
/// frame the guard stopped at and why.
fn simulate(
    scene: &cloth_scene::Scene,
    choice: &solvers::Choice,
    registry: &Registry,
    args: &Args,
    start: &ClothState,
    mut each: impl FnMut(u64, &ClothMesh, &ClothState) -> anyhow::Result<()>,
) -> anyhow::Result<Option<(u64, Divergence)>> {
    let mut run = Run::new(scene.clone(), registry.clone(), Some(choice.entry.name()))?;
    run.set_recording(false);
    run.start_from(start.clone(), 0, 0.0);
    let mut actions = (args.actions.as_deref())
        .map(|path| cloth_run::actions::Actions::read(path, run.scene.mesh.len()))
        .transpose()?;
    let mut progress = Progress::new(
        args.progress,
        &scene.origin,
        args.frames,
        scene.params.steps_per_frame,
        Stdout::is_terminal(),
    );
    let mut frames = || -> anyhow::Result<Option<(u64, Divergence)>> {
        if printed(0, args.frames, args.every) {
            each(0, &run.scene.mesh, &run.state)?;
        }
        for f in 1..=args.frames {
            let stepped = match &mut actions {
                Some(a) => a.step_frame(&mut run, &mut || progress.step())?,
                None => run.step_frame_with(&mut || progress.step()),
            };
            match stepped.map_err(|f| *f) {
                Ok(()) => {}
                Err(Fault {
                    cause: Cause::Diverged(d),
                    ..
                }) => {
                    // The last good frame is shown, as the live UI shows it.
                    if f > 1 && !printed(f - 1, args.frames, args.every) {
                        each(f - 1, &run.scene.mesh, &run.state)?;
                    }
                    return Ok(Some((f, d)));
                }
                Err(fault) => {
                    return Err(headless::fault_error(
                        scene,
                        &scene.params,
                        choice.entry.is_explicit(),
                        (f, args.frames),
                        &fault,
                    ));
                }
            }
            if printed(f, args.frames, args.every) {
                each(f, &run.scene.mesh, &run.state)?;
            }
        }
        Ok(None)
    };
    let result = frames();
    progress.finish();
    if let Ok(None) = &result
        && let Some(warning) =
            cloth_run::headless::stretch_warning(&run.scene, &run.settings.params, &run.state)
    {
        // Nowhere else to say it; a lost warning does not change the frames printed.
        use std::io::Write as _;
        let program = cloth_run::headless::program_name();
        let _ = writeln!(std::io::stderr(), "{program}: warning: {warning}");
    }
    result
}

/// Writes the panels next to each other under a line of their `labels` (each at most a
/// panel wide).
fn side_by_side_titled(
    labels: &[String],
    panels: &[AsciiFrame],
    size: FrameSize,
    depth: ColorDepth,
    out: &mut String,
) -> anyhow::Result<()> {
    for (i, label) in labels.iter().enumerate() {
        if i > 0 {
            out.push_str(GAP);
        }
        let _ = write!(out, "{label:<w$}", w = size.width);
    }
    out.push('\n');
    // Render each panel's rows as text once, then interleave them line by line.
    let mut texts = Vec::with_capacity(panels.len());
    for p in panels {
        let mut s = String::new();
        p.write_ansi(&mut s, depth)?;
        texts.push(s);
    }
    let mut lines: Vec<std::str::Lines<'_>> = texts.iter().map(|t| t.lines()).collect();
    for _ in 0..size.height {
        for (i, l) in lines.iter_mut().enumerate() {
            if i > 0 {
                out.push_str(GAP);
            }
            out.push_str(l.next().unwrap_or(""));
        }
        out.push('\n');
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_k_prints_multiples_of_k_and_always_the_last() {
        let shown: Vec<u64> = (0..=10).filter(|&f| printed(f, 10, Some(4))).collect();
        assert_eq!(shown, vec![4, 8, 10]);
        let shown: Vec<u64> = (0..=10).filter(|&f| printed(f, 10, None)).collect();
        assert_eq!(shown, vec![10]);
        assert!(printed(0, 0, None), "--frames 0 shows the start");
        for (frames, every) in [
            (10, Some(4)),
            (10, None),
            (0, None),
            (0, Some(3)),
            (8, Some(4)),
            (3, Some(5)),
        ] {
            let counted = (0..=frames).filter(|&f| printed(f, frames, every)).count() as u64;
            assert_eq!(printed_count(frames, every), counted, "{frames} {every:?}");
        }
    }

    #[test]
    fn views_parse_with_all_and_name_the_choices() {
        assert_eq!("all".parse::<ViewArg>(), Ok(ViewArg::All));
        assert_eq!("top".parse::<ViewArg>(), Ok(ViewArg::One(View::Top)));
        assert_eq!(
            "sideways".parse::<ViewArg>().unwrap_err().to_string(),
            "unknown view 'sideways'; expected side, top, bottom, front, orbit or all"
        );
    }
}
