//! `clothsim simulate`: run a scene headless and write its final state.

use std::fmt::Write as _;
use std::io::{IsTerminal, Write as _};
use std::path::PathBuf;

use anyhow::Context;
use cloth_mesh::{ClothMesh, ClothState, vertex_normals};
use cloth_solver::{Registry, advance_frame};
use serde::Serialize;

use crate::guard::Guard;
use crate::{output, solvers};

/// Arguments of `clothsim simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A bundled scene name (see `clothsim scenes`) or a path to a scene JSON file.
    scene: String,
    /// Frames to simulate (each 1/frames_per_sec seconds of simulated time).
    #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u64).range(0..=10_000_000))]
    frames: u64,
    /// Override a scene value: a dotted key and a JSON value, e.g. `cloth.ks=100000`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// The solver (overrides the scene's `simulation.solver`; `clothsim solvers` lists them).
    #[arg(long)]
    solver: Option<String>,
    /// Where to write the final state: a `.json` file (positions) or a `.obj` file (mesh).
    /// Without it, JSON goes to stdout.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

/// The JSON written by `simulate`.
#[derive(Serialize)]
struct FinalState {
    num_width_points: usize,
    num_height_points: usize,
    frames: u64,
    time: f64,
    /// Whether the run was stopped by the divergence guard (the state is where it stopped).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    diverged: bool,
    positions: Vec<[f64; 3]>,
}

enum Format {
    Json,
    Obj,
}

/// Runs the command.
pub fn run(args: &Args, registry: &Registry) -> anyhow::Result<()> {
    // Decide the output format before spending time simulating.
    let format = match &args.out {
        None => Format::Json,
        Some(p) => match p
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("json") => Format::Json,
            Some("obj") => Format::Obj,
            _ => anyhow::bail!(
                "--out {}: the file name must end in .json or .obj",
                p.display()
            ),
        },
    };
    let scene = cloth_scene::load(&args.scene, &args.sets)?;
    let choice = solvers::choose(registry, &scene, args.solver.as_deref())?;
    let mut solver = choice.build(&scene.mesh)?;
    let mut state = ClothState::new(&scene.mesh);
    let params = scene.params;

    let progress = progress_bar(args.frames);
    let mut guard = Guard::new();
    let point_mass = scene.mesh.point_mass(params.density);
    let mut diverged = None;
    let mut done = 0;
    for frame in 1..=args.frames {
        advance_frame(
            solver.as_mut(),
            &scene.mesh,
            &scene.colliders,
            &params,
            &mut state,
        )
        .with_context(|| format!("{}: frame {frame} of {}", scene.origin, args.frames))?;
        done = frame;
        let time = frame as f64 / params.frames_per_sec;
        if let Err(d) = guard.check_state(&state, &params, point_mass, time) {
            diverged = Some((time, d));
            break;
        }
        if let Some(p) = &progress {
            p.inc(1);
        }
    }
    if let Some(p) = progress {
        p.finish_and_clear();
    }
    let diverged = diverged.map(|(time, d)| {
        format!(
            "{}: the run diverged at frame {done} of {} (t = {time:.3} s): {}; {}",
            scene.origin,
            args.frames,
            d.describe(),
            d.advice(&choice.entry, &params, point_mass)
        )
    });

    let bytes = match format {
        Format::Json => {
            let fs = FinalState {
                num_width_points: scene.mesh.nw(),
                num_height_points: scene.mesh.nh(),
                frames: done,
                time: done as f64 / params.frames_per_sec,
                diverged: diverged.is_some(),
                positions: state.positions.iter().map(|p| [p.x, p.y, p.z]).collect(),
            };
            let mut s = serde_json::to_string(&fs)?;
            s.push('\n');
            s.into_bytes()
        }
        Format::Obj => obj(&scene.mesh, &state, &scene.origin).into_bytes(),
    };
    if let Some(what) = diverged {
        // The state reached is kept under a name that says so, never as the result asked for.
        if let Some(path) = &args.out {
            let kept = diverged_name(path);
            output::write_atomic(&kept, &bytes)?;
            anyhow::bail!("{what}; the state it reached is in {}", kept.display());
        }
        anyhow::bail!(
            "{what}; nothing was written (with --out FILE the state it reached is kept as \
             FILE.diverged)"
        );
    }
    if let Some(path) = &args.out {
        output::write_atomic(path, &bytes)
    } else {
        let mut out = std::io::stdout().lock();
        out.write_all(&bytes)
            .and_then(|()| out.flush())
            .context("cannot write to stdout")
    }
}

/// `out.json` -> `out.diverged.json`: where a diverged run's state is kept.
fn diverged_name(path: &std::path::Path) -> PathBuf {
    let stem = path.file_stem().map_or_else(
        || std::ffi::OsString::from("state"),
        std::ffi::OsStr::to_os_string,
    );
    let mut name = stem;
    name.push(".diverged");
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
}

/// A progress bar on stderr for runs long enough to want one, only when stderr is a terminal.
fn progress_bar(frames: u64) -> Option<indicatif::ProgressBar> {
    if frames < 30 || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(frames);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} frames ({eta} left)")
    {
        bar.set_style(style);
    }
    Some(bar)
}

/// A Wavefront OBJ of the cloth: vertices, area-weighted normals and the mesh's triangles.
fn obj(mesh: &ClothMesh, state: &ClothState, origin: &str) -> String {
    let mut normals = Vec::new();
    vertex_normals(mesh, &state.positions, &mut normals);
    let mut s = String::with_capacity(mesh.len() * 80);
    let _ = writeln!(s, "# clothsim final state of {origin}");
    for p in &state.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for n in &normals {
        let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
    }
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    s
}
