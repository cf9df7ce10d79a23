//! `clothsim simulate`: run a scene headless and write its final state.

use std::fmt::Write as _;
use std::io::{IsTerminal, Write as _};
use std::path::PathBuf;

use anyhow::Context;
use cloth_mesh::{ClothMesh, ClothState, vertex_normals};
use cloth_solver::{Registry, advance_frame};

use crate::state_file::StateFile;
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
    /// Where to write the final state: a `.json` file (positions and last positions) or a
    /// `.obj` file (mesh). Without it, JSON goes to stdout.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Start from a state that `simulate` wrote (its positions and last positions, so the
    /// cloth keeps its velocity) instead of the scene's flat start; its grid and pins must be
    /// the scene's. The frames and time written continue from the state's.
    #[arg(long, value_name = "STATE.json")]
    from: Option<PathBuf>,
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
    let mut solver =
        solvers::choose(registry, &scene, args.solver.as_deref())?.build(&scene.mesh)?;
    let params = scene.params;
    let (start_frames, start_time, mut state) = match &args.from {
        Some(path) => {
            let (file, state) = StateFile::read(path, &scene.mesh, params.dt())?;
            (file.frames, file.time, state)
        }
        None => (0, 0.0, ClothState::new(&scene.mesh)),
    };

    let progress = progress_bar(args.frames);
    for frame in 0..args.frames {
        advance_frame(
            solver.as_mut(),
            &scene.mesh,
            &scene.colliders,
            &params,
            &mut state,
        )
        .with_context(|| format!("{}: frame {} of {}", scene.origin, frame + 1, args.frames))?;
        if let Some(p) = &progress {
            p.inc(1);
        }
    }
    if let Some(p) = progress {
        p.finish_and_clear();
    }

    let bytes = match format {
        Format::Json => {
            let fs = StateFile::new(
                &scene.mesh,
                &state,
                start_frames.saturating_add(args.frames),
                start_time + args.frames as f64 / params.frames_per_sec,
                params.dt(),
            );
            let mut s = serde_json::to_string(&fs)?;
            s.push('\n');
            s.into_bytes()
        }
        Format::Obj => obj(&scene.mesh, &state, &scene.origin).into_bytes(),
    };
    if let Some(path) = &args.out {
        output::write_atomic(path, &bytes)
    } else {
        let mut out = std::io::stdout().lock();
        out.write_all(&bytes)
            .and_then(|()| out.flush())
            .context("cannot write to stdout")
    }
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
