//! `clothsim bench`: ms per frame, particle-steps per second and real-time factor.
//!
//! Frames are timed one by one; the table gives the median and the mean frame time, and the
//! throughput and real-time factor at the median, so a frame slowed down by another process on a
//! shared machine does not move the figures. Each row also gives the worst spring's stretch at
//! the end (a timing of a cloth that came apart is worth nothing) and, on Linux, the share of
//! the machine's processor time its hypervisor took meanwhile (`steal`: on a shared virtual
//! machine, the figures of a run with much of it are not the code's).
//!
//! Each configuration is the course's `pinned4` cloth scaled to `--grid N` points per side at the
//! standard spacing ([`ClothMesh::pinned_grid`]), with `pinned4`'s parameters as `--set`
//! changes them, stepped as every command steps a scene (a `cloth_run::Run`: the solver's steps,
//! the divergence guard and the frame's numbers), warmed up for `--warmup` frames (90, one
//! simulated second, by default), then timed by [`cloth_bench::time_in_turn`], alone or with
//! `--interleave` frame by frame in turn with the grid's other configurations. Any registered
//! solver can be timed by name, each at its recommended steps per frame unless `--steps` sets
//! them (for all, or for one solver by name); `--threads` and `--order` set the options of
//! those names of the solvers that have them (Verlet's). With `--interleave` each row gives two
//! ratios to the grid's first configuration: the median over rounds of the two frames' ratio
//! (the typical frame), and the ratio of the mean frame times (what a user waits for over the
//! whole run, the fall's costly frames included). `scripts/performance` runs it for the table of
//! docs/performance.md; criterion benches (`cargo bench -p cloth-solver`) time the kernels.

use std::fmt::Write as _;

use crate::steal::CpuTimes;
use anyhow::Context as _;
use clap::ValueEnum;
use cloth_bench::{BenchResult, BenchRun, in_turn_results, time_in_turn};
use cloth_mesh::ClothMesh;
use cloth_run::memory::{self, Need};
use cloth_run::{Fault, Run};
use cloth_solver::{Registry, SolverEntry, StepParams, max_stretch_ratio};
use serde_json::{Map, Value};

/// `clothsim bench` options.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Points per side of the pinned cloth (repeatable), e.g. `--grid 50 --grid 256`.
    #[arg(long = "grid", default_values_t = [50])]
    grids: Vec<usize>,
    /// Solver to time (repeatable; default: the first of `clothsim solvers`).
    #[arg(long = "solver")]
    solvers: Vec<String>,
    /// Worker threads (repeatable), e.g. `--threads 1 --threads 2`: the `threads` option of
    /// the solvers that have one (default: theirs).
    #[arg(long = "threads", value_parser = clap::value_parser!(u16).range(1..=256))]
    threads: Vec<u16>,
    /// Self-collision on or off (default: on, or as `--set simulation.self_collision` says).
    #[arg(long = "self-collision", value_enum)]
    self_collision: Option<Switch>,
    /// Constraint order (repeatable): the `order` option of the solvers that have one; Verlet's
    /// are faithful (the course's), parallel (row bands) and colored (spring classes with no
    /// shared point; the fastest on big cloths). Default: the solver's own.
    #[arg(long = "order")]
    orders: Vec<String>,
    /// Steps per frame (repeatable): `N` for every configuration, `SOLVER=N` for one solver's
    /// (`--steps verlet=200`), which wins over a plain `N`. Default: each solver's
    /// recommendation, as `clothsim solvers` lists them.
    #[arg(long = "steps", value_name = "[SOLVER=]N", value_parser = parse_steps)]
    steps: Vec<Steps>,
    /// A step parameter of the timed `pinned4` cloth, as a dotted key and a JSON value
    /// (repeatable), e.g. `--set cloth.ks=1e6`: one of `cloth.ks`, `cloth.density`,
    /// `cloth.damping`, `cloth.enable_structural`, `cloth.enable_shearing`,
    /// `cloth.enable_bending`, `simulation.gravity`, `simulation.frames_per_sec`,
    /// `simulation.stretch_limit`, `simulation.self_collision` (the grid is `--grid`'s, the
    /// steps `--steps`').
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Frames simulated before the timing starts (default 90: one simulated second at the
    /// course's 90 frames per second, so the cloth has fallen and come into tension; 0 times the
    /// run from the flat start).
    #[arg(long, value_name = "FRAMES", default_value_t = 90, value_parser = clap::value_parser!(u32).range(0..=100_000))]
    warmup: u32,
    /// Frames timed per configuration (after the warm-up).
    #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: u32,
    /// Time the configurations of each grid in turn, one frame of each per round, and add
    /// each one's time ratio to the grid's first configuration (the median over rounds): the
    /// way to compare solvers or orders on a machine whose speed drifts (thread counts on big
    /// cloths are better compared in separate runs: an idle pool sleeps between its frames).
    #[arg(long)]
    interleave: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Most memory the run may take (e.g. 512M, 4G; powers of 1024): a cloth whose solver,
    /// states and frames would need more is refused before they are allocated. Default: the
    /// memory the system has available.
    #[arg(long, value_name = "SIZE", value_parser = cloth_run::memory::parse_size)]
    max_memory: Option<u64>,
}

/// On or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Switch {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

/// A `--steps` value: steps per frame for every configuration, or for one solver's.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Steps {
    /// The solver it is for; `None` for every configuration.
    solver: Option<String>,
    /// Steps per frame, 1 to [`MAX_STEPS`].
    steps: u32,
}

/// The most steps per frame `--steps` takes.
const MAX_STEPS: u32 = 10_000;

/// Parses `N` or `SOLVER=N`.
fn parse_steps(arg: &str) -> Result<Steps, String> {
    let (solver, n) = match arg.split_once('=') {
        Some((solver, n)) if !solver.trim().is_empty() => (Some(solver.trim().to_owned()), n),
        Some(_) => return Err("expected N or SOLVER=N, e.g. 30 or verlet=200".to_owned()),
        None => (None, arg),
    };
    match n.trim().parse::<u32>() {
        Ok(steps) if (1..=MAX_STEPS).contains(&steps) => Ok(Steps { solver, steps }),
        _ => Err(format!(
            "{:?} is not a number of steps per frame: it must be a whole number from 1 to \
             {MAX_STEPS}",
            n.trim()
        )),
    }
}

/// The `--set` keys the benchmark takes: the step parameters (the grid and the steps have
/// flags of their own, and the cloth has no collision objects).
const SET_KEYS: [&str; 10] = [
    "cloth.ks",
    "cloth.density",
    "cloth.damping",
    "cloth.enable_structural",
    "cloth.enable_shearing",
    "cloth.enable_bending",
    "simulation.gravity",
    "simulation.frames_per_sec",
    "simulation.stretch_limit",
    "simulation.self_collision",
];

/// The step parameters of the timed cloth: `pinned4`'s, with the `--set` changes checked as a
/// scene file's values are, and `--self-collision` over them.
///
/// # Errors
/// A `--set` key the benchmark does not take, or a value the scene refuses.
fn step_params(args: &Args) -> anyhow::Result<StepParams> {
    for set in &args.sets {
        let key = set.split_once('=').map_or(set.as_str(), |(k, _)| k).trim();
        if !SET_KEYS.contains(&key) {
            anyhow::bail!(
                "--set {set}: bench times the pinned4 cloth at --grid N points a side, so --set \
                 takes only its step parameters: {} (the grid is --grid's, the steps --steps')",
                SET_KEYS.join(", ")
            );
        }
    }
    let scene = cloth_scene::load("pinned4", &args.sets)?;
    let mut params = scene.params;
    if let Some(switch) = args.self_collision {
        params.self_collision = switch == Switch::On;
    }
    Ok(params)
}

/// One configuration to time: a solver, its options and its steps per frame.
#[derive(Debug, Clone)]
struct Config {
    entry: SolverEntry,
    /// The options it is built with (a JSON object).
    options: Value,
    /// The step parameters it runs with.
    params: StepParams,
}

impl Config {
    /// Every configuration the options name, in the order given: solvers, then threads, then
    /// orders (for the solvers that have those options).
    fn all(args: &Args, registry: &Registry, base: &StepParams) -> anyhow::Result<Vec<Self>> {
        let entries: Vec<SolverEntry> = if args.solvers.is_empty() {
            registry.default_entry().copied().into_iter().collect()
        } else {
            args.solvers
                .iter()
                .map(|name| registry.get(name).copied())
                .collect::<Result<_, _>>()?
        };
        for steps in &args.steps {
            if let Some(name) = &steps.solver
                && !entries.iter().any(|e| e.name() == name)
            {
                let timed: Vec<&str> = entries.iter().map(SolverEntry::name).collect();
                anyhow::bail!(
                    "--steps {name}={}: {name} is not a timed solver; the timed solvers are {} \
                     (add --solver {name} to time it)",
                    steps.steps,
                    timed.join(", ")
                );
            }
        }
        // A solver's own `--steps NAME=N` wins over a plain `--steps N`; the last of each counts.
        let steps_for = |entry: &SolverEntry| {
            let named = args
                .steps
                .iter()
                .rev()
                .find(|s| s.solver.as_deref() == Some(entry.name()));
            let all = args.steps.iter().rev().find(|s| s.solver.is_none());
            named.or(all).map_or(entry.steps_per_frame(), |s| s.steps)
        };
        let mut out = Vec::new();
        for entry in entries {
            let threads: Vec<Option<Value>> =
                if entry.option("threads").is_some() && !args.threads.is_empty() {
                    args.threads.iter().map(|&t| Some(Value::from(t))).collect()
                } else {
                    vec![None]
                };
            let orders: Vec<Option<Value>> =
                if entry.option("order").is_some() && !args.orders.is_empty() {
                    args.orders
                        .iter()
                        .map(|o| Some(Value::from(o.as_str())))
                        .collect()
                } else {
                    vec![None]
                };
            for t in &threads {
                for o in &orders {
                    let mut options = Map::new();
                    if let Some(t) = t {
                        options.insert("threads".to_owned(), t.clone());
                    }
                    if let Some(o) = o {
                        options.insert("order".to_owned(), o.clone());
                    }
                    let options = Value::Object(options);
                    entry.check(&options)?;
                    let params = StepParams {
                        steps_per_frame: steps_for(&entry),
                        ..*base
                    };
                    out.push(Config {
                        entry,
                        options,
                        params,
                    });
                }
            }
        }
        Ok(out)
    }

    /// A run of this configuration on `scene`'s cloth: the solver with its options and the
    /// configuration's step parameters, stepped frame by frame as every command steps.
    fn run(&self, scene: &cloth_scene::Scene) -> anyhow::Result<Run> {
        let mut scene = scene.clone();
        let options = self.options.as_object().cloned().unwrap_or_default();
        scene.set_solver(self.entry.name(), options);
        let mut run = Run::new(
            scene,
            Registry::new().with(self.entry),
            Some(self.entry.name()),
        )?;
        run.set_recording(false);
        run.settings.params = self.params;
        Ok(run)
    }

    /// The threads it runs on, as the table shows them (1 for a solver without the option).
    fn threads(&self) -> i64 {
        if self.entry.option("threads").is_none() {
            return 1;
        }
        self.entry.integer(&self.options, "threads").unwrap_or(1)
    }

    /// Its constraint order, for a solver with the option.
    fn order(&self) -> Option<&'static str> {
        self.entry.option("order")?;
        self.entry.choice(&self.options, "order").ok()
    }

    /// How the configuration is named in errors.
    fn describe(&self, n: usize) -> String {
        match self.order() {
            Some(order) => format!(
                "{} ({} threads, {order} order) on the {n} x {n} cloth",
                self.entry.name(),
                self.threads(),
            ),
            None => format!("{} on the {n} x {n} cloth", self.entry.name()),
        }
    }
}

/// One row of the output.
struct Row {
    n: usize,
    config: Config,
    result: BenchResult,
    /// With `--interleave`: the time ratio to the grid's first configuration.
    ratio: Option<f64>,
    /// With `--interleave`: the mean frame time over the grid's first configuration's.
    mean_ratio: Option<f64>,
    /// The longest spring over its rest length after the last timed frame: a timing is only
    /// worth quoting for a cloth that held together (the course's limit keeps a hanging cloth
    /// near 1.1; an unstable run shows several times that).
    stretch: f64,
    /// The percentage of the machine's processor time its hypervisor took while the
    /// configuration ran, warm-up included (with `--interleave`: while the grid's configurations
    /// ran), where the kernel tells it (see [`crate::steal`]).
    steal: Option<f64>,
}

/// Times every configuration of the `n x n` cloth, one after the other or in turn.
fn time_grid(args: &Args, configs: &[Config], n: usize) -> anyhow::Result<Vec<Row>> {
    // Checked here, so the message gives the number as typed rather than an overflowed square.
    let max = cloth_mesh::MAX_POINTS;
    if n < 2 || n.checked_mul(n).is_none_or(|points| points > max) {
        anyhow::bail!(
            "--grid {n}: the cloth must have 2 to {} points per side ({max} points in all)",
            max.isqrt()
        );
    }
    let mesh = ClothMesh::pinned_grid(n).with_context(|| format!("--grid {n}"))?;
    check_memory(args, configs, &mesh, n)?;
    let mut scene = cloth_scene::load("pinned4", &args.sets)?;
    scene.origin = format!("the {n} x {n} cloth");
    scene.mesh = std::sync::Arc::new(mesh);
    let timing = BenchRun {
        warmup_frames: args.warmup,
        frames: args.frames,
    };
    // Without --interleave one configuration is alive at a time: each solver's memory is freed
    // before the next is built.
    let groups: Vec<&[Config]> = if args.interleave {
        vec![configs]
    } else {
        configs.chunks(1).collect()
    };
    let mut rows = Vec::new();
    for group in groups {
        let mut runs = group
            .iter()
            .map(|c| c.run(&scene).with_context(|| c.describe(n)))
            .collect::<anyhow::Result<Vec<Run>>>()?;
        let before = CpuTimes::now();
        let seconds = time_in_turn(runs.len(), timing, |i| runs[i].step_frame())
            .map_err(|(i, fault)| diverged(&fault).context(group[i].describe(n)))?;
        let steal = steal_since(before);
        let timed = in_turn_results(seconds, &scene.mesh, |i| group[i].params);
        let first_seconds = timed.first().map_or(0.0, |t| t.result.seconds);
        for (run, config) in runs.iter_mut().zip(group) {
            held_together(run).with_context(|| config.describe(n))?;
        }
        rows.extend(
            runs.iter()
                .zip(group)
                .zip(timed)
                .map(|((run, config), t)| Row {
                    n,
                    config: config.clone(),
                    result: t.result,
                    ratio: args.interleave.then_some(t.time_ratio_to_first),
                    mean_ratio: args.interleave.then_some(t.result.seconds / first_seconds),
                    stretch: max_stretch_ratio(&run.scene.mesh, &run.state),
                    steal,
                }),
        );
    }
    Ok(rows)
}

/// A run's fault while it was timed: its timing means nothing.
fn diverged(fault: &Fault) -> anyhow::Error {
    anyhow::anyhow!(
        "the run diverged, so its timing means nothing: {}; {}",
        fault.what,
        fault.advice
    )
}

/// Whether the timed cloth held together: the run's divergence guard watches one more window
/// of frames after the timing (a run that ended non-finite, or whose speed and energy are
/// still growing without bound, is no timing of a cloth).
///
/// # Errors
/// The divergence, with its advice.
fn held_together(run: &mut Run) -> anyhow::Result<()> {
    let frames = (cloth_run::guard::WINDOW * run.settings.params.frames_per_sec).ceil() as u64 + 1;
    for _ in 0..frames {
        run.step_frame().map_err(|f| diverged(&f))?;
    }
    Ok(())
}

/// Refuses grid `n` when a configuration would need more memory than `--max-memory` (or the
/// memory available): without `--interleave` one configuration at a time, with it all at once.
fn check_memory(args: &Args, configs: &[Config], mesh: &ClothMesh, n: usize) -> anyhow::Result<()> {
    let origin = format!("--grid {n}");
    let limit = (args.max_memory, "a smaller --grid");
    let needs = configs
        .iter()
        .map(|c| (c, Need::new(&c.entry, &c.options, mesh, 2, 0)));
    if args.interleave {
        // Every configuration at once, sharing the mesh, each with its own state.
        let mut all = Need {
            solver: 0,
            cloth: memory::mesh_bytes(mesh),
            drawing: 0,
        };
        for (_, need) in needs {
            all.solver = all.solver.saturating_add(need.solver);
            all.cloth = all.cloth.saturating_add(2 * memory::state_bytes(mesh));
        }
        let who = format!("--interleave's {} configurations", configs.len());
        return memory::check(&origin, &who, mesh, all, limit);
    }
    for (config, need) in needs {
        memory::check(&origin, &memory::solver(&config.entry), mesh, need, limit)?;
    }
    Ok(())
}

/// The share of processor time stolen since `before` (see [`crate::steal`]).
fn steal_since(before: Option<CpuTimes>) -> Option<f64> {
    before?.steal_percent_until(CpuTimes::now()?)
}

/// Runs every configuration and prints the table (or JSON).
///
/// # Errors
/// A grid that cannot be built, a solver that is not available, or a diverged run.
pub fn run(args: &Args, registry: &Registry) -> anyhow::Result<()> {
    let params = step_params(args)?;
    let configs = Config::all(args, registry, &params)?;
    let mut rows = Vec::new();
    for &n in &args.grids {
        rows.extend(time_grid(args, &configs, n)?);
    }
    let mut out = String::new();
    if args.json {
        let list: Vec<_> = rows
            .iter()
            .map(
                |Row {
                     n,
                     config,
                     result: r,
                     ratio,
                     mean_ratio,
                     stretch,
                     steal,
                 }| {
                    serde_json::json!({
                        "grid": n,
                        "solver": config.entry.name(),
                        "options": config.options,
                        "threads": config.threads(),
                        "steps_per_frame": r.steps_per_frame,
                        "self_collision": params.self_collision,
                        "order": config.order(),
                        "points": r.points,
                        "springs": r.springs,
                        "frames": r.frames,
                        "warmup_frames": args.warmup,
                        "ks": params.ks,
                        "ms_per_frame_median": r.median_ms_per_frame(),
                        "ms_per_frame_mean": r.ms_per_frame(),
                        "particle_steps_per_sec": r.particle_steps_per_sec(),
                        "realtime_factor": r.realtime_factor(),
                        "time_ratio_to_first": ratio,
                        "mean_time_ratio_to_first": mean_ratio,
                        "max_stretch_ratio_at_end": stretch,
                        "host_steal_percent": steal,
                    })
                },
            )
            .collect();
        out = serde_json::to_string_pretty(&list)?;
    } else {
        // NOTE: new columns go on the right, so scripts reading the first ones keep working.
        let _ = write!(
            out,
            "{:>7} {:>14} {:>8} {:>10} {:>10} {:>18} {:>10} {:>9}",
            "grid",
            "solver",
            "threads",
            "median ms",
            "mean ms",
            "particle-steps/s",
            "real-time",
            "order"
        );
        if args.interleave {
            let _ = write!(out, " {:>9}", "vs first");
        }
        let _ = write!(out, " {:>8} {:>6} {:>5}", "stretch", "steal", "steps");
        if args.interleave {
            let _ = write!(out, " {:>9}", "mean vs first");
        }
        out.push('\n');
        for Row {
            n,
            config,
            result: r,
            ratio,
            mean_ratio,
            stretch,
            steal,
        } in &rows
        {
            let _ = write!(
                out,
                "{:>7} {:>14} {:>8} {:>10.3} {:>10.3} {:>16.2}M {:>9.2}x {:>9}",
                format!("{n}x{n}"),
                config.entry.name(),
                config.threads(),
                r.median_ms_per_frame(),
                r.ms_per_frame(),
                r.particle_steps_per_sec() / 1e6,
                r.realtime_factor(),
                config.order().unwrap_or("-"),
            );
            if let Some(ratio) = ratio {
                let _ = write!(out, " {ratio:>8.3}x");
            }
            let _ = write!(out, " {stretch:>7.3}x");
            match steal {
                Some(steal) => {
                    let _ = write!(out, " {steal:>5.1}%");
                }
                None => {
                    let _ = write!(out, " {:>6}", "-");
                }
            }
            let _ = write!(out, " {:>5}", r.steps_per_frame);
            if let Some(mean_ratio) = mean_ratio {
                let _ = write!(out, " {mean_ratio:>12.3}x");
            }
            out.push('\n');
        }
    }
    let mut stdout = cloth_run::output::Stdout::new();
    stdout.write_all_or_fail(out.trim_end().as_bytes())?;
    stdout.write_all_or_fail(b"\n")?;
    stdout.finish()
}
