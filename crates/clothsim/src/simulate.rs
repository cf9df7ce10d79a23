//! `clothsim simulate`: run a scene headless and write its final state.

use std::io::Write as _;

use anyhow::Context as _;
use std::path::PathBuf;

use cloth_solver::Registry;

use cloth_run::export::{Animation, AnimationKind, Sampling, StatsFormat, StatsRow, StatsTable};
use cloth_run::memory::{self, Need};
use cloth_run::progress::{Progress, When};
use cloth_run::state_file::StateFile;
use cloth_run::{Cause, Fault, Run, export, headless, output, solvers, study};

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
    /// Without `simulation.simulation_steps` in the scene or a `--set`, the run takes the
    /// solver's recommended steps per frame.
    #[arg(long)]
    solver: Option<String>,
    #[command(flatten)]
    flags: crate::args::SolverFlags,
    /// Where to write the run: the final state as a `.json` file (positions and last
    /// positions) or an `.obj` file (mesh with texture coordinates and normals); or the
    /// animation as a `.pc2` (Blender's Point Cache 2) or `.mdd` point cache (with the first
    /// frame's mesh next to it as `NAME.obj`), or as one OBJ per frame through a pattern such as
    /// `frames/f_%04d.obj`. Without it, JSON goes to stdout.
    #[arg(long, value_name = "FILE", value_hint = clap::ValueHint::FilePath)]
    out: Option<PathBuf>,
    /// With an animation `--out`: keep every K-th frame (the start, K, 2K, ...).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(1..))]
    every: Option<u64>,
    /// Write one row of numbers per frame to a `.csv` or `.json` file: time, kinetic energy,
    /// largest stretch, lowest and centre heights, steps and the frame's wall time.
    #[arg(long, value_name = "FILE", value_hint = clap::ValueHint::FilePath)]
    stats: Option<PathBuf>,
    /// Start from a state that `simulate` wrote (its positions and last positions, so the
    /// cloth keeps its velocity) instead of the scene's flat start; its grid and pins must be
    /// the scene's. The frames and time written continue from the state's.
    #[arg(long, value_name = "STATE.json", value_hint = clap::ValueHint::FilePath)]
    from: Option<PathBuf>,
    /// Touch the cloth as a script says: JSON lines of a frame and an action (grab a point
    /// and hold it at a position, drag it, release it, poke it, pin or unpin it, cut the
    /// springs a stroke crosses), each applied once that many frames have been stepped;
    /// docs/files-and-output.md gives the format.
    #[arg(long, value_name = "FILE", value_hint = clap::ValueHint::FilePath, conflicts_with = "vary")]
    actions: Option<PathBuf>,
    /// Progress on stderr: auto (a bar when stderr is a terminal), always (also a line every
    /// 10 s when it is not: logs, CI), never. `--progress` alone means always.
    #[arg(long, value_name = "WHEN", default_value = "auto", value_parser = crate::args::when_parser(),
          num_args = 0..=1, default_missing_value = "always")]
    progress: When,
    /// Most memory the run may take (e.g. 512M, 4G; powers of 1024): a cloth whose solver,
    /// states and frames would need more is refused before they are allocated. Default: the
    /// memory the system has available.
    #[arg(long, value_name = "SIZE", value_parser = cloth_run::memory::parse_size)]
    max_memory: Option<u64>,
    /// Run one variant per value of a scene key, side by side: `KEY=V1,V2,...` with 2 to 6
    /// values, the key and values as `--set` takes them (including `simulation.solver`);
    /// twice for a grid. Writes one output per variant beside `--out` (`rest.json` gives
    /// `rest.ks=1.json`, ...) and prints a summary table.
    #[arg(long = "vary", value_name = "KEY=V1,V2,...")]
    vary: Vec<cloth_run::study::Axis>,
    /// With `--vary`, print the summary as JSON: a list of objects with the keys `variant`,
    /// `centre_height`, `lowest_height`, `max_stretch`, `kinetic_energy` and `diverged`.
    #[arg(long, requires = "vary")]
    json: bool,
}

#[derive(Clone)]
enum Format {
    Json,
    Obj,
    Animation(AnimationKind),
}

/// The format `--out` asks for.
fn format_of(out: Option<&std::path::Path>) -> anyhow::Result<Format> {
    let Some(p) = out else {
        return Ok(Format::Json);
    };
    if let Some(kind) = AnimationKind::of(p)? {
        return Ok(Format::Animation(kind));
    }
    match p
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("json") => Ok(Format::Json),
        Some("obj") => Ok(Format::Obj),
        _ => anyhow::bail!(
            "--out {}: the file name must end in .json or .obj (the final state), .pc2 or .mdd \
             (an animation), or be an OBJ sequence pattern such as frames/f_%04d.obj",
            p.display()
        ),
    }
}

/// Runs the command.
pub fn run(args: &Args, registry: &Registry) -> anyhow::Result<()> {
    // Decide the output format before spending time simulating.
    let format = format_of(args.out.as_deref())?;
    if !args.vary.is_empty() {
        if matches!(format, Format::Animation(_)) || args.every.is_some() || args.stats.is_some() {
            anyhow::bail!(
                "--vary writes each variant's final state (--out a .json or .obj file); it does \
                 not take an animation --out, --every or --stats"
            );
        }
        return run_study(args, registry, &format);
    }
    if args.every.is_some() && !matches!(format, Format::Animation(_)) {
        anyhow::bail!(
            "--every applies to an animation: give --out a .pc2 or .mdd file or a pattern such \
             as frames/f_%04d.obj"
        );
    }
    if let Some(path) = &args.stats {
        StatsFormat::of(path)?;
        output::check_target(path)?;
    }
    if let Some(path) = &args.out {
        // Before the run, so a long simulation does not end in a folder given as the file.
        if !matches!(format, Format::Animation(AnimationKind::ObjSequence { .. })) {
            output::check_target(path)?;
        }
        // A diverged run's state goes beside it, under a longer name.
        if matches!(format, Format::Json | Format::Obj) {
            check_diverged_name(path)?;
        }
    }
    let mut scene = cloth_scene::load(&args.scene, &args.sets)?;
    headless::note_shadowing(&args.scene);
    let choice = solvers::prepare(
        registry,
        &mut scene,
        args.solver.as_deref(),
        &args.flags.to_flags(),
    )?;
    // The state, and its JSON text: about three states' bytes.
    let need = Need::new(&choice.entry, &choice.options, &scene.mesh, 4, 0);
    memory::check(
        &scene.origin,
        &memory::solver(&choice.entry),
        &scene.mesh,
        need,
        (args.max_memory, memory::SMALLER_SCENE),
    )?;
    let explicit = choice.entry.is_explicit();
    let params = scene.params;
    let mut run = Run::new(scene, registry.clone(), Some(choice.entry.name()))?;
    run.set_recording(false);
    let (start_frames, start_time) = match &args.from {
        Some(path) => {
            let (file, state) = StateFile::read(path, &run.scene.mesh, params.dt())?;
            run.start_from(state, file.frames, file.time);
            (file.frames, file.time)
        }
        None => (0, 0.0),
    };
    let mut actions = (args.actions.as_deref())
        .map(|path| cloth_run::actions::Actions::read(path, run.scene.mesh.len()))
        .transpose()?;
    let scene = std::sync::Arc::clone(&run.scene);

    // The bar would share the terminal with JSON on standard output only when both are the
    // terminal and there is no --out; it is cleared at the end, before the JSON is written.
    let mut progress = Progress::new(
        args.progress,
        &scene.origin,
        args.frames,
        params.steps_per_frame,
        false,
    );
    let point_mass = scene.mesh.point_mass(params.density);
    let every = args.every.unwrap_or(1);
    let mut animation = match (&format, &args.out) {
        (Format::Animation(kind), Some(path)) => {
            let sampling = Sampling {
                first_frame: start_frames,
                every,
                samples: args.frames / every + 1,
                frames_per_sec: params.frames_per_sec,
            };
            let mut a = Animation::create(
                kind.clone(),
                path,
                scene.mesh.len(),
                sampling,
                &scene.origin,
            )?;
            a.push(&scene.mesh, start_frames, &run.state.positions)?;
            Some(a)
        }
        _ => None,
    };
    let mut stats = args.stats.as_deref().map(StatsTable::create).transpose()?;
    let mut diverged = None;
    let mut done = 0;
    for frame in 1..=args.frames {
        let started = std::time::Instant::now();
        let stepped = match &mut actions {
            Some(a) => a.step_frame(&mut run, &mut || progress.step())?,
            None => run.step_frame_with(&mut || progress.step()),
        }
        .map_err(|f| *f);
        let time = frame as f64 / params.frames_per_sec;
        match stepped {
            Ok(()) => {}
            Err(Fault {
                cause: Cause::Diverged(d),
                ..
            }) => {
                done = frame;
                diverged = Some((time, d));
                break;
            }
            Err(fault) => {
                progress.finish();
                // The table records the run up to its last good frame, as for a divergence.
                if let Some(table) = stats {
                    table.finish()?;
                }
                return Err(headless::fault_error(
                    &scene,
                    &params,
                    explicit,
                    (frame, args.frames),
                    &fault,
                ));
            }
        }
        done = frame;
        if let Some(table) = stats.as_mut() {
            table.push(&StatsRow::measure(
                &run.scene.mesh,
                &run.state,
                point_mass,
                params.dt(),
                start_frames + frame,
                start_time + time,
                u64::from(params.steps_per_frame),
                Some(started.elapsed().as_secs_f64()),
            ))?;
        }
        if let Some(a) = animation.as_mut()
            && frame.is_multiple_of(every)
        {
            a.push(&run.scene.mesh, start_frames + frame, &run.state.positions)?;
        }
    }
    progress.finish();
    // NOTE: a cut or a pin by an action changed the mesh: what is written is the cloth run.
    let scene = std::sync::Arc::clone(&run.scene);
    // The table records the run, a diverged one too (up to its last good frame).
    if let Some(table) = stats {
        table.finish()?;
    }
    // A diverged run's result is the state the guard refused, kept under a name that says so.
    let state = run.failed_state().unwrap_or(&run.state);
    let diverged = diverged.map(|(time, d)| {
        format!(
            "{}: the run diverged at frame {done} of {} (t = {time:.3} s): {}; {}",
            scene.origin,
            args.frames,
            d.describe(),
            headless::divergence_advice(&scene, &params, &choice.entry, &d)
        )
    });

    let bytes = match format {
        Format::Json => {
            let mut fs = StateFile::new(
                &scene.mesh,
                state,
                start_frames.saturating_add(done),
                start_time + done as f64 / params.frames_per_sec,
                params.dt(),
            );
            fs.diverged = diverged.is_some();
            let mut s = serde_json::to_string(&fs)?;
            s.push('\n');
            s.into_bytes()
        }
        Format::Obj => export::obj(
            &scene.mesh,
            &state.positions,
            &format!("{} after {done} frames", scene.origin),
        )
        .into_bytes(),
        Format::Animation(_) => Vec::new(),
    };
    if let Some(what) = diverged {
        if animation.is_some() {
            // Dropping the unfinished cache removes its temporary file; the files of an OBJ
            // sequence are each whole, and those written stay.
            drop(animation);
            if matches!(format, Format::Animation(AnimationKind::ObjSequence { .. })) {
                anyhow::bail!("{what}; the OBJ files of the frames before it were written");
            }
            anyhow::bail!("{what}; the animation was not written");
        }
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
    if let Some(warning) = headless::stretch_warning(&scene, &params, state) {
        // Nowhere else to say it; a lost warning does not change the result.
        let program = headless::program_name();
        let _ = writeln!(std::io::stderr(), "{program}: warning: {warning}");
    }
    if let Some(a) = animation {
        return a.finish();
    }
    if let Some(path) = &args.out {
        let written = output::write_atomic(path, &bytes)?;
        if let Some(note) = written.note() {
            // Nowhere else to say it; a lost note does not change the result.
            let program = cloth_run::headless::program_name();
            let _ = writeln!(std::io::stderr(), "{program}: note: {note}");
        }
        Ok(())
    } else if output::Stdout::is_terminal() {
        // Pages of coordinates help no one on a terminal: a summary, and how to get them.
        let end = StatsRow::measure(
            &scene.mesh,
            state,
            point_mass,
            params.dt(),
            start_frames + done,
            start_time + done as f64 / params.frames_per_sec,
            u64::from(params.steps_per_frame),
            None,
        );
        let text = summary(&scene.origin, choice.entry.name(), &end, scene.mesh.len());
        let mut out = output::Stdout::new();
        out.write_all_or_fail(text.as_bytes())?;
        out.finish()
    } else {
        let mut out = output::Stdout::new();
        out.write_all_or_fail(&bytes)?;
        out.finish()
    }
}

/// What `simulate` without `--out` prints on a terminal: where the cloth ended, and how to get
/// the state itself.
fn summary(origin: &str, solver: &str, end: &StatsRow, points: usize) -> String {
    format!(
        "{origin}: {} frames ({:.3} s) with {solver}\n  centre height {:.6} m, lowest point \
         {:.6} m, largest stretch {:.4}, kinetic energy {:.4e} J\n\
         The final state ({points} points) is JSON: write it with --out state.json (or .obj), \
         or pipe it (clothsim simulate ... | jq .); --stats FILE writes the numbers per frame.\n",
        end.frame,
        end.time_s,
        end.centre_y_m,
        end.lowest_y_m,
        end.max_stretch,
        end.kinetic_energy_j
    )
}

/// `simulate --vary`: every variant in lockstep, one output per variant beside `--out`, the
/// summary on stdout; an error naming the variants that stopped, after the others are written.
fn run_study(args: &Args, registry: &Registry, format: &Format) -> anyhow::Result<()> {
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
        check_diverged_name(path)?;
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
        let bytes = match &format {
            Format::Json => {
                let mut fs = StateFile::new(
                    &scene.mesh,
                    run.state(),
                    start_frames.saturating_add(run.frames),
                    start_time + run.frames as f64 / scene.params.frames_per_sec,
                    scene.params.dt(),
                );
                fs.diverged = run.stopped();
                let mut s = serde_json::to_string(&fs)?;
                s.push('\n');
                s.into_bytes()
            }
            Format::Obj => export::obj(
                &scene.mesh,
                &run.state().positions,
                &format!("{} after {} frames", scene.origin, run.frames),
            )
            .into_bytes(),
            // Refused before the run.
            Format::Animation(_) => Vec::new(),
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
        let program = cloth_run::headless::program_name();
        let _ = writeln!(std::io::stderr(), "{program}: note: {note}");
    }
    for run in runs.iter().filter(|r| !r.stopped()) {
        let scene = &run.variant.scene;
        if let Some(warning) = headless::stretch_warning(scene, &scene.params, run.state()) {
            let title = &run.variant.title;
            let program = headless::program_name();
            let _ = writeln!(std::io::stderr(), "{program}: warning: {title}: {warning}");
        }
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

/// Checks before the run that a diverged run's state could be kept beside `path`.
fn check_diverged_name(path: &std::path::Path) -> anyhow::Result<()> {
    let kept = diverged_name(path);
    output::check_target(&kept).with_context(|| {
        format!(
            "--out {}: a run that diverges keeps the state it reached as {}, and that name must \
             work too",
            path.display(),
            kept.display()
        )
    })
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
