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
//! standard spacing ([`cloth_solver::pinned_grid`]), warmed up for one simulated second, then
//! timed by [`cloth_solver::time_frames`], or with `--interleave` frame by frame in turn with
//! the grid's other configurations by [`cloth_solver::time_interleaved`]. Criterion benches
//! (`cargo bench -p cloth-solver`) are the measurement of record; this command lets a user
//! reproduce the README's table.

use std::fmt::Write as _;

use crate::steal::CpuTimes;
use anyhow::Context as _;
use clap::ValueEnum;
use cloth_mesh::ClothState;

use crate::guard::Guard;
use cloth_solver::{
    BenchResult, BenchRun, ConstraintOrder, Solver, SolverKind, StepParams, Verlet,
    max_stretch_ratio, pinned_grid, time_frames, time_interleaved,
};

/// `clothsim bench` options.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Points per side of the pinned cloth (repeatable), e.g. `--grid 50 --grid 256`.
    #[arg(long = "grid", default_values_t = [50])]
    grids: Vec<usize>,
    /// Solver to time (repeatable): verlet, implicit, fast-implicit.
    #[arg(long = "solver", default_values_t = [SolverKind::Verlet])]
    solvers: Vec<SolverKind>,
    /// Worker threads for the Verlet solver (repeatable), e.g. `--threads 1 --threads 2`.
    #[arg(
        long = "threads",
        default_values_t = [1],
        value_parser = clap::value_parser!(u16).range(1..=256)
    )]
    threads: Vec<u16>,
    /// Self-collision on or off.
    #[arg(long = "self-collision", value_enum, default_value_t = Switch::On)]
    self_collision: Switch,
    /// Constraint order of the Verlet solver (repeatable): faithful (the course's), parallel
    /// (row bands) or colored (spring classes with no shared point; the fastest on big cloths).
    #[arg(long = "order", value_enum, default_values_t = [Order::Faithful])]
    orders: Vec<Order>,
    /// Frames timed per configuration (after one simulated second of warm-up).
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
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Switch {
    On,
    Off,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Order {
    Faithful,
    Parallel,
    Colored,
}

impl Order {
    fn name(self) -> &'static str {
        match self {
            Order::Faithful => "faithful",
            Order::Parallel => "parallel",
            Order::Colored => "colored",
        }
    }
}

/// One configuration to time: the threads and order apply to the Verlet solver only.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Config {
    kind: SolverKind,
    threads: u16,
    order: Option<Order>,
}

impl Config {
    /// Every configuration the options name, in the order given: solvers, then threads, then
    /// orders (the other solvers have neither).
    fn all(args: &Args) -> Vec<Self> {
        let mut out = Vec::new();
        for &kind in &args.solvers {
            if kind != SolverKind::Verlet {
                out.push(Config {
                    kind,
                    threads: 1,
                    order: None,
                });
                continue;
            }
            for &threads in &args.threads {
                for &order in &args.orders {
                    out.push(Config {
                        kind,
                        threads,
                        order: Some(order),
                    });
                }
            }
        }
        out
    }

    /// The solver to time.
    fn build(self) -> anyhow::Result<Box<dyn Solver>> {
        let Some(order) = self.order else {
            return crate::solvers::build(self.kind);
        };
        let order = match order {
            Order::Faithful => ConstraintOrder::Faithful,
            Order::Parallel => ConstraintOrder::Parallel,
            Order::Colored => ConstraintOrder::Colored,
        };
        let verlet = Verlet::new()
            .with_threads(usize::from(self.threads))?
            .with_order(order);
        Ok(Box::new(verlet))
    }

    /// How the configuration is named in errors.
    fn describe(self, n: usize) -> String {
        match self.order {
            Some(order) => format!(
                "{} ({} threads, {} order) on the {n} x {n} cloth",
                self.kind,
                self.threads,
                order.name()
            ),
            None => format!("{} on the {n} x {n} cloth", self.kind),
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
fn time_grid(args: &Args, params: &StepParams, n: usize) -> anyhow::Result<Vec<Row>> {
    let mesh = pinned_grid(n).with_context(|| format!("--grid {n}"))?;
    let run = BenchRun {
        warmup_frames: 90,
        frames: args.frames,
    };
    let configs = Config::all(args);
    if !args.interleave {
        // One configuration alive at a time: each solver's memory is freed before the next.
        let mut rows = Vec::new();
        for config in &configs {
            let mut solver = config.build().with_context(|| config.describe(n))?;
            let mut state = ClothState::new(&mesh);
            let before = CpuTimes::now();
            let result = time_frames(solver.as_mut(), &mesh, &[], params, &mut state, run)
                .with_context(|| config.describe(n))?;
            held_together(solver.as_mut(), &mesh, params, &mut state, *config, run)
                .with_context(|| config.describe(n))?;
            rows.push(Row {
                n,
                config: *config,
                result,
                ratio: None,
                stretch: max_stretch_ratio(&mesh, &state),
                steal: steal_since(before),
            });
        }
        return Ok(rows);
    }
    let mut solvers = configs
        .iter()
        .map(|c| c.build().with_context(|| c.describe(n)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut states: Vec<ClothState> = configs.iter().map(|_| ClothState::new(&mesh)).collect();
    let mut runs: Vec<(&mut dyn Solver, &mut ClothState)> = solvers
        .iter_mut()
        .map(|s| &mut **s as &mut dyn Solver)
        .zip(states.iter_mut())
        .collect();
    let before = CpuTimes::now();
    let timed = time_interleaved(&mut runs, &mesh, &[], params, run)
        .map_err(|(i, e)| anyhow::Error::new(e).context(configs[i].describe(n)))?;
    let steal = steal_since(before);
    for ((solver, state), config) in solvers.iter_mut().zip(states.iter_mut()).zip(&configs) {
        held_together(solver.as_mut(), &mesh, params, state, *config, run)
            .with_context(|| config.describe(n))?;
    }
    Ok(configs
        .iter()
        .zip(timed)
        .zip(&states)
        .map(|((config, t), state)| Row {
            n,
            config: *config,
            result: t.result,
            ratio: Some(t.time_ratio_to_first),
            stretch: max_stretch_ratio(&mesh, state),
            steal,
        })
        .collect())
}

/// Whether the timed cloth held together: the divergence guard of `simulate` and `render`
/// watches one more window of frames after the timing (a run that ended non-finite, or whose
/// speed and energy are still growing without bound, is no timing of a cloth).
///
/// # Errors
/// The divergence, with its advice.
fn held_together(
    solver: &mut dyn Solver,
    mesh: &cloth_mesh::ClothMesh,
    params: &StepParams,
    state: &mut ClothState,
    config: Config,
    run: BenchRun,
) -> anyhow::Result<()> {
    let point_mass = mesh.point_mass(params.density);
    let mut guard = Guard::new();
    let frames = (crate::guard::WINDOW * params.frames_per_sec).ceil() as u64 + 1;
    for f in 0..=frames {
        if f > 0 {
            cloth_solver::advance_frame(solver, mesh, &[], params, state)?;
        }
        // Simulated time since the start: gravity's share of the speed grows with it.
        let time = (u64::from(run.warmup_frames) + u64::from(run.frames) + f) as f64
            / params.frames_per_sec;
        if let Err(d) = guard.check_state(state, params, point_mass, time) {
            anyhow::bail!(
                "the run diverged, so its timing means nothing: {}; {}",
                d.describe(),
                d.advice(config.kind, params, point_mass)
            );
        }
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
pub fn run(args: &Args) -> anyhow::Result<()> {
    let params = StepParams {
        self_collision: args.self_collision == Switch::On,
        ..StepParams::default()
    };
    let mut rows = Vec::new();
    for &n in &args.grids {
        rows.extend(time_grid(args, &params, n)?);
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
                     stretch,
                     steal,
                 }| {
                    serde_json::json!({
                        "grid": n,
                        "solver": config.kind.name(),
                        "threads": config.threads,
                        "self_collision": params.self_collision,
                        "order": config.order.map(Order::name),
                        "points": r.points,
                        "springs": r.springs,
                        "frames": r.frames,
                        "ms_per_frame_median": r.median_ms_per_frame(),
                        "ms_per_frame_mean": r.ms_per_frame(),
                        "particle_steps_per_sec": r.particle_steps_per_sec(),
                        "realtime_factor": r.realtime_factor(),
                        "time_ratio_to_first": ratio,
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
        let _ = write!(out, " {:>8} {:>6}", "stretch", "steal");
        out.push('\n');
        for Row {
            n,
            config,
            result: r,
            ratio,
            stretch,
            steal,
        } in &rows
        {
            let _ = write!(
                out,
                "{:>7} {:>14} {:>8} {:>10.3} {:>10.3} {:>16.2}M {:>9.2}x {:>9}",
                format!("{n}x{n}"),
                config.kind.name(),
                config.threads,
                r.median_ms_per_frame(),
                r.ms_per_frame(),
                r.particle_steps_per_sec() / 1e6,
                r.realtime_factor(),
                config.order.map_or("-", Order::name),
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
            out.push('\n');
        }
    }
    println!("{}", out.trim_end());
    Ok(())
}
