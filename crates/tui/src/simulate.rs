//! `clothsim simulate`: run a scene headless and write its final state.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

use cloth_mesh::{ClothMesh, ClothState, vertex_normals};
use cloth_solver::Registry;

use crate::guard::Guard;
use crate::progress::{Progress, When};
use crate::state_file::StateFile;
use crate::{headless, output, solvers, study};

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
    /// Run one variant per value of a scene key, side by side: `KEY=V1,V2,...` with 2 to 6
    /// values, the key and values as `--set` takes them (including `simulation.solver`);
    /// twice for a grid. Writes one output per variant beside `--out` (`rest.json` gives
    /// `rest.ks=1.json`, ...) and prints a summary table.
    #[arg(long = "vary", value_name = "KEY=V1,V2,...")]
    vary: Vec<crate::study::Axis>,
    /// With `--vary`, print the summary as JSON: a list of objects with the keys `variant`,
    /// `centre_height`, `lowest_height`, `max_stretch`, `kinetic_energy` and `diverged`.
    #[arg(long, requires = "vary")]
    json: bool,
}

#[derive(Clone, Copy)]
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
    if !args.vary.is_empty() {
        return run_study(args, registry, format);
    }
    if let Some(path) = &args.out {
        // Before the run, so a long simulation does not end in a folder given as the file.
        output::check_target(path)?;
        output::cleanup_on_signals()?;
    }
    let scene = cloth_scene::load(&args.scene, &args.sets)?;
    headless::note_shadowing(&args.scene);
    let choice = solvers::choose(registry, &scene, args.solver.as_deref())?;
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

/// `simulate --vary`: every variant in lockstep, one output per variant beside `--out`, the
/// summary on stdout; an error naming the variants that stopped, after the others are written.
fn run_study(args: &Args, registry: &Registry, format: Format) -> anyhow::Result<()> {
    let variants = study::variants(
        registry,
        &args.scene,
        &args.sets,
        args.solver.as_deref(),
        &args.vary,
    )?;
    let outs: Vec<PathBuf> = match &args.out {
        Some(path) => variants
            .iter()
            .map(|v| variant_name(path, &v.file_label()))
            .collect(),
        None => Vec::new(),
    };
    for path in &outs {
        output::check_target(path)?;
    }
    if !outs.is_empty() {
        output::cleanup_on_signals()?;
    }
    headless::note_shadowing(&args.scene);
    let mut starts = Vec::with_capacity(variants.len());
    for v in &variants {
        starts.push(match &args.from {
            Some(path) => {
                let (file, state) = StateFile::read(path, &v.scene.mesh, v.scene.params.dt())?;
                (file.frames, file.time, Some(state))
            }
            None => (0, 0.0, None),
        });
    }
    let mut runs = Vec::with_capacity(variants.len());
    for (v, (_, _, start)) in variants.iter().zip(&starts) {
        runs.push(study::Run::new(v, start.as_ref())?);
    }
    let steps = variants
        .iter()
        .map(|v| u64::from(v.scene.params.steps_per_frame))
        .sum::<u64>();
    let label = format!("{} ({} variants)", variants[0].scene.origin, variants.len());
    let mut progress = Progress::new(args.progress, &label, args.frames, steps as u32, false);
    let threads = study::threads_for(runs.len());
    for frame in 1..=args.frames {
        study::advance_all(&mut runs, frame, args.frames, threads, &mut progress);
        if runs.iter().all(study::Run::stopped) {
            break;
        }
    }
    progress.finish();

    let mut notes = Vec::new();
    // Without --out, only the summary is printed.
    for ((run, (start_frames, start_time, _)), path) in runs.iter().zip(&starts).zip(&outs) {
        let scene = &run.variant.scene;
        let bytes = match format {
            Format::Json => {
                let mut fs = StateFile::new(
                    &scene.mesh,
                    &run.state,
                    start_frames.saturating_add(run.frames),
                    start_time + run.frames as f64 / scene.params.frames_per_sec,
                    scene.params.dt(),
                );
                fs.diverged = run.stopped();
                let mut s = serde_json::to_string(&fs)?;
                s.push('\n');
                s.into_bytes()
            }
            Format::Obj => obj(&scene.mesh, &run.state, &scene.origin).into_bytes(),
        };
        let path = if run.stopped() {
            diverged_name(path)
        } else {
            path.clone()
        };
        let written = output::write_atomic(&path, &bytes)?;
        if let Some(note) = written.note() {
            notes.push(note.to_owned());
        }
    }
    for note in notes {
        // Nowhere else to say it; a lost note does not change the result.
        let _ = writeln!(std::io::stderr(), "clothsim: note: {note}");
    }

    let summaries: Vec<study::Summary> = runs.iter().map(study::Run::summary).collect();
    let text = if args.json {
        let mut s = serde_json::to_string_pretty(&study::json(&variants, &summaries))?;
        s.push('\n');
        s
    } else {
        study::table(&variants, &summaries)
    };
    let mut out = output::Stdout::new();
    out.write_all_or_fail(text.as_bytes())?;
    out.finish()?;

    let stopped: Vec<String> = runs
        .iter()
        .filter_map(|r| r.reason().map(|why| format!("{}: {why}", r.variant.title)))
        .collect();
    if !stopped.is_empty() {
        let kept = if outs.is_empty() {
            String::new()
        } else {
            " (the states they reached are kept as FILE.diverged)".to_owned()
        };
        anyhow::bail!(
            "{}: {} of {} variants stopped{kept}:\n  {}",
            variants[0].scene.origin,
            stopped.len(),
            variants.len(),
            stopped.join("\n  ")
        );
    }
    Ok(())
}

/// `rest.json` and the variant `ks=1` -> `rest.ks=1.json`.
fn variant_name(path: &std::path::Path, label: &str) -> PathBuf {
    let mut name = path.file_stem().map_or_else(
        || std::ffi::OsString::from("state"),
        std::ffi::OsStr::to_os_string,
    );
    name.push(".");
    name.push(label);
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
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
