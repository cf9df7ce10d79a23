//! `clothsim simulate`: run a scene headless and write its final state.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

use cloth_mesh::{ClothMesh, ClothState, vertex_normals};
use cloth_solver::Registry;

use crate::guard::Guard;
use crate::memory::{self, Need};
use crate::progress::{Progress, When};
use crate::state_file::StateFile;
use crate::{headless, output, solvers};

/// Arguments of `clothsim simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A bundled scene name (see `clothsim scenes`) or a scene JSON file; a path with a folder
    /// or ending in .json is always a file (`./plane` is the file, `plane` the bundled scene).
    #[arg(value_hint = clap::ValueHint::FilePath)]
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
    #[arg(long, value_name = "FILE", value_hint = clap::ValueHint::FilePath)]
    out: Option<PathBuf>,
    /// Start from a state that `simulate` wrote (its positions and last positions, so the
    /// cloth keeps its velocity) instead of the scene's flat start; its grid and pins must be
    /// the scene's. The frames and time written continue from the state's.
    #[arg(long, value_name = "STATE.json", value_hint = clap::ValueHint::FilePath)]
    from: Option<PathBuf>,
    /// Progress on stderr: auto (a bar when stderr is a terminal), always (also a line every
    /// 10 s when it is not: logs, CI), never. `--progress` alone means always.
    #[arg(long, value_enum, value_name = "WHEN", default_value_t = When::Auto,
          num_args = 0..=1, default_missing_value = "always")]
    progress: When,
    /// Most memory the run may take (e.g. 512M, 4G; powers of 1024): a cloth whose solver,
    /// states and frames would need more is refused before they are allocated. Default: the
    /// memory the system has available.
    #[arg(long, value_name = "SIZE", value_parser = crate::memory::parse_size)]
    max_memory: Option<u64>,
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
    if let Some(path) = &args.out {
        // Before the run, so a long simulation does not end in a folder given as the file.
        output::check_target(path)?;
        output::cleanup_on_signals()?;
    }
    let scene = cloth_scene::load(&args.scene, &args.sets)?;
    headless::note_shadowing(&args.scene);
    let choice = solvers::choose(registry, &scene, args.solver.as_deref())?;
    // The state, and its JSON text: about three states' bytes.
    let need = Need::new(&choice.entry, &choice.options, &scene.mesh, 4, 0);
    memory::check(
        &scene.origin,
        &memory::solver(&choice.entry),
        &scene.mesh,
        need,
        (args.max_memory, memory::SMALLER_SCENE),
    )?;
    let mut solver = choice.build(&scene.mesh)?;
    let explicit = choice.entry.is_explicit();
    let params = scene.params;
    let (start_frames, start_time, mut state) = match &args.from {
        Some(path) => {
            let (file, state) = StateFile::read(path, &scene.mesh, params.dt())?;
            (file.frames, file.time, state)
        }
        None => (0, 0.0, ClothState::new(&scene.mesh)),
    };

    // The bar would share the terminal with JSON on standard output only when both are the
    // terminal and there is no --out; it is cleared at the end, before the JSON is written.
    let mut progress = Progress::new(
        args.progress,
        &scene.origin,
        args.frames,
        params.steps_per_frame,
        false,
    );
    let mut guard = Guard::new();
    let point_mass = scene.mesh.point_mass(params.density);
    let mut diverged = None;
    let mut done = 0;
    for frame in 1..=args.frames {
        let advanced = headless::advance_frame(
            solver.as_mut(),
            &scene,
            &params,
            explicit,
            &mut state,
            (frame, args.frames),
            &mut progress,
        );
        if let Err(e) = advanced {
            progress.finish();
            return Err(e);
        }
        done = frame;
        let time = frame as f64 / params.frames_per_sec;
        if let Err(d) = guard.check_state(&state, &params, point_mass, time) {
            diverged = Some((time, d));
            break;
        }
    }
    progress.finish();
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
            let mut fs = StateFile::new(
                &scene.mesh,
                &state,
                start_frames.saturating_add(done),
                start_time + done as f64 / params.frames_per_sec,
                params.dt(),
            );
            fs.diverged = diverged.is_some();
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
        let written = output::write_atomic(path, &bytes)?;
        if let Some(note) = written.note() {
            // Nowhere else to say it; a lost note does not change the result.
            let _ = writeln!(std::io::stderr(), "clothsim: note: {note}");
        }
        Ok(())
    } else {
        let mut out = output::Stdout::new();
        out.write_all_or_fail(&bytes)?;
        out.finish()
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
