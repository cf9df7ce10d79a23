//! `clothsim render`: simulate a scene headless and print its frames as text.
//!
//! Plain text by default: each frame is exactly H lines of W columns, frames are separated by a
//! line holding only a form feed (`\x0c`). `--format ansi` adds colour escapes. Never touches
//! terminal modes, so it works the same into a pipe or a file.

use std::fmt::Write as _;
use std::io::Write as _;
use std::str::FromStr;

use anyhow::Context;
use cloth_mesh::ClothState;
use cloth_render::{
    AsciiFrame, Bounds, ColorChoice, ColorDepth, ColorEnv, Extent, FrameSize, Mode, RenderError,
    RenderOptions, Renderer, View, ViewSpec,
};
use cloth_solver::{Registry, advance_frame};

use crate::guard::{Divergence, Guard};
use crate::solvers;

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
}

/// Arguments of `clothsim render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A bundled scene name (see `clothsim scenes`) or a path to a scene JSON file.
    scene: String,
    /// Frames to simulate (each 1/frames_per_sec seconds of simulated time); 0 shows the start.
    #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u64).range(0..=10_000_000))]
    frames: u64,
    /// Print every K-th frame (frames K, 2K, ... and always the last); default: only the last.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(1..))]
    every: Option<u64>,
    /// side (looking -z, +x right, +y up), top (looking down, +x right, +z down), bottom,
    /// front (looking +x, +z right, +y up), orbit (the course's perspective camera), or all
    /// (side, top and front next to each other, labelled).
    #[arg(long, default_value = "side", value_name = "VIEW")]
    view: ViewArg,
    /// Size of each frame (each panel with `--view all`) in character cells.
    #[arg(long, default_value = "80x40", value_name = "WxH")]
    size: FrameSize,
    /// ascii (glyph ramp), half (half blocks, two pixels per cell) or braille (2 x 4 dots).
    #[arg(long, default_value = "ascii", value_name = "MODE")]
    mode: Mode,
    /// Colour with `--format ansi`: auto (the terminal's depth from COLORTERM and TERM, 256
    /// when they say nothing, none under NO_COLOR or CLICOLOR=0), always, never, 16, 256 or
    /// truecolor. Plain format never writes colour.
    #[arg(long, default_value = "auto", value_name = "WHEN")]
    color: ColorChoice,
    /// plain (glyphs only) or ansi (with colour escapes).
    #[arg(long, value_enum, default_value_t = Format::Plain)]
    format: Format,
    /// Override a scene value: a dotted key and a JSON value, e.g. `cloth.ks=100000`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// The solver (overrides the scene's `simulation.solver`; `clothsim solvers` lists them).
    #[arg(long)]
    solver: Option<String>,
}

/// Whether frame `f` (1-based; 0 is the start) of `frames` is printed.
fn printed(f: u64, frames: u64, every: Option<u64>) -> bool {
    f == frames || every.is_some_and(|k| f > 0 && f.is_multiple_of(k))
}

/// Runs the command.
pub fn run(args: &Args, registry: &Registry) -> anyhow::Result<()> {
    let depth = match args.format {
        Format::Plain => ColorDepth::None,
        // The user asked for escapes, so a pipe does not turn them off; NO_COLOR still does.
        Format::Ansi => {
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
    let scene = cloth_scene::load(&args.scene, &args.sets)?;
    let choice = solvers::choose(registry, &scene, args.solver.as_deref())?;
    let views = args.view.views();
    let options = RenderOptions {
        mode: args.mode,
        color: depth != ColorDepth::None,
        ..RenderOptions::default()
    };

    // First pass: the box around every printed frame, so the views keep one scale and the
    // animation does not jump. The simulation is deterministic, so the second pass replays
    // exactly the same states.
    let mut extent: Option<Bounds> = None;
    let diverged = simulate(&scene, &choice, args, u64::MAX, |_, state| {
        let b = Bounds::of_scene(&state.positions, &scene.colliders)?;
        extent = Some(extent.map_or(b, |e| e.union(&b)));
        Ok(())
    })?;
    let last = diverged.as_ref().map_or(args.frames, |(f, _)| f - 1);
    let Some(extent) = extent else {
        return diverged_error(&scene, &choice.entry, args, diverged);
    };

    let mut renderer = Renderer::new();
    let mut panels: Vec<AsciiFrame> = views.iter().map(|_| AsciiFrame::new(args.size)).collect();
    let mut text = String::new();
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let mut first = true;
    let result = simulate(&scene, &choice, args, last, |_, state| {
        for (view, panel) in views.iter().zip(panels.iter_mut()) {
            let spec = ViewSpec {
                extent: Extent::Fixed(extent),
                ..ViewSpec::new(*view, &scene.mesh)
            };
            renderer.render(&scene.mesh, state, &scene.colliders, &spec, &options, panel)?;
        }
        text.clear();
        if !first {
            text.push_str("\x0c\n");
        }
        first = false;
        if views.len() == 1 {
            panels[0].write_ansi(&mut text, depth)?;
        } else {
            side_by_side(&views, &panels, args.size, depth, &mut text)?;
        }
        out.write_all(text.as_bytes())?;
        Ok(())
    })
    .and_then(|_| out.flush().map_err(anyhow::Error::from));
    match result {
        // A reader that stops early (`| head`) is not an error.
        Err(e)
            if e.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe) =>
        {
            return Ok(());
        }
        other => other.context("cannot write the frames to stdout")?,
    }
    diverged_error(&scene, &choice.entry, args, diverged)
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
    let point_mass = scene.mesh.point_mass(scene.params.density);
    anyhow::bail!(
        "{}: the run diverged at frame {frame} of {} (t = {:.3} s): {}; {}; the frames before \
         it were printed",
        scene.origin,
        args.frames,
        frame as f64 / scene.params.frames_per_sec,
        d.describe(),
        d.advice(entry, &scene.params, point_mass)
    )
}

/// Simulates `args.frames` frames (stopping after frame `last`), calling `each` with the
/// frame number and state of every printed frame, and of the last good frame when the guard
/// stops the run; returns the frame the guard stopped at and why.
fn simulate(
    scene: &cloth_scene::Scene,
    choice: &solvers::Choice,
    args: &Args,
    last: u64,
    mut each: impl FnMut(u64, &ClothState) -> anyhow::Result<()>,
) -> anyhow::Result<Option<(u64, Divergence)>> {
    let mut solver = choice.build(&scene.mesh)?;
    let mut state = ClothState::new(&scene.mesh);
    let mut guard = Guard::new();
    let point_mass = scene.mesh.point_mass(scene.params.density);
    if printed(0, args.frames, args.every) {
        each(0, &state)?;
    }
    let mut good = state.clone();
    for f in 1..=args.frames.min(last) {
        advance_frame(
            solver.as_mut(),
            &scene.mesh,
            &scene.colliders,
            &scene.params,
            &mut state,
        )
        .with_context(|| format!("{}: frame {f} of {}", scene.origin, args.frames))?;
        let time = f as f64 / scene.params.frames_per_sec;
        if let Err(d) = guard.check_state(&state, &scene.params, point_mass, time) {
            // The last good frame is shown, as the live UI shows it.
            if f > 1 && !printed(f - 1, args.frames, args.every) {
                each(f - 1, &good)?;
            }
            return Ok(Some((f, d)));
        }
        if printed(f, args.frames, args.every) || f == last {
            each(f, &state)?;
        }
        good.clone_from(&state);
    }
    Ok(None)
}

/// Writes the panels next to each other under a label line naming each view and its axes.
fn side_by_side(
    views: &[View],
    panels: &[AsciiFrame],
    size: FrameSize,
    depth: ColorDepth,
    out: &mut String,
) -> anyhow::Result<()> {
    for (i, view) in views.iter().enumerate() {
        if i > 0 {
            out.push_str(GAP);
        }
        let label: String = view.describe().chars().take(size.width).collect();
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
