//! `clothsim bench`: ms per frame, particle-steps per second and real-time factor.
//!
//! Frames are timed one by one; the table gives the median and the mean frame time, and the
//! throughput and real-time factor at the median, so a frame slowed down by another process on a
//! shared machine does not move the figures.
//!
//! Each configuration is the course's `pinned4` cloth scaled to `--grid N` points per side at the
//! standard spacing ([`cloth_solver::pinned_grid`]), warmed up for one simulated second, then
//! timed by [`cloth_solver::time_frames`]. Criterion benches (`cargo bench -p cloth-solver`) are
//! the measurement of record; this command lets a user reproduce the README's table.

use std::fmt::Write as _;

use anyhow::Context as _;
use clap::ValueEnum;
use cloth_mesh::ClothState;
use cloth_solver::{
    BenchRun, ConstraintOrder, Solver, SolverKind, StepParams, Verlet, pinned_grid, time_frames,
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
    /// Worker threads for the Verlet solver.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=256))]
    threads: u16,
    /// Self-collision on or off.
    #[arg(long = "self-collision", value_enum, default_value_t = Switch::On)]
    self_collision: Switch,
    /// Constraint order of the Verlet solver: faithful (the course's) or parallel.
    #[arg(long, value_enum, default_value_t = Order::Faithful)]
    order: Order,
    /// Frames timed per configuration (after one simulated second of warm-up).
    #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: u32,
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
}

/// Builds the solver to time; Verlet takes the thread count and order.
fn build(kind: SolverKind, args: &Args) -> anyhow::Result<Box<dyn Solver>> {
    if kind == SolverKind::Verlet {
        let order = match args.order {
            Order::Faithful => ConstraintOrder::Faithful,
            Order::Parallel => ConstraintOrder::Parallel,
        };
        let verlet = Verlet::new()
            .with_threads(usize::from(args.threads))?
            .with_order(order);
        return Ok(Box::new(verlet));
    }
    crate::solvers::build(kind)
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
        let mesh = pinned_grid(n).with_context(|| format!("--grid {n}"))?;
        for &kind in &args.solvers {
            let mut solver = build(kind, args)?;
            let mut state = ClothState::new(&mesh);
            let run = BenchRun {
                warmup_frames: 90,
                frames: args.frames,
            };
            let r = time_frames(solver.as_mut(), &mesh, &[], &params, &mut state, run)
                .with_context(|| format!("{kind} on the {n} x {n} cloth"))?;
            rows.push((n, kind, r));
        }
    }
    let mut out = String::new();
    if args.json {
        let list: Vec<_> = rows
            .iter()
            .map(|(n, kind, r)| {
                serde_json::json!({
                    "grid": n,
                    "solver": kind.name(),
                    "threads": args.threads,
                    "self_collision": params.self_collision,
                    "order": format!("{:?}", args.order).to_lowercase(),
                    "points": r.points,
                    "springs": r.springs,
                    "frames": r.frames,
                    "ms_per_frame_median": r.median_ms_per_frame(),
                    "ms_per_frame_mean": r.ms_per_frame(),
                    "particle_steps_per_sec": r.particle_steps_per_sec(),
                    "realtime_factor": r.realtime_factor(),
                })
            })
            .collect();
        out = serde_json::to_string_pretty(&list)?;
    } else {
        let _ = writeln!(
            out,
            "{:>7} {:>14} {:>8} {:>10} {:>10} {:>18} {:>10}",
            "grid", "solver", "threads", "median ms", "mean ms", "particle-steps/s", "real-time"
        );
        for (n, kind, r) in &rows {
            let _ = writeln!(
                out,
                "{:>7} {:>14} {:>8} {:>10.3} {:>10.3} {:>16.2}M {:>9.2}x",
                format!("{n}x{n}"),
                kind.name(),
                args.threads,
                r.median_ms_per_frame(),
                r.ms_per_frame(),
                r.particle_steps_per_sec() / 1e6,
                r.realtime_factor()
            );
        }
    }
    println!("{}", out.trim_end());
    Ok(())
}
