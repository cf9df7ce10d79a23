//! Times frames of the Verlet solver on one configuration, for profiling
//! (`perf stat`, `perf record`): `cargo run --release -p cloth-bench --example frames --
//! <grid points per side> <self-collision on|off> <frames> [threads] [faithful|parallel|colored] [warm-up frames]`.

use cloth_bench::{BenchRun, time_frames};
use cloth_mesh::{ClothMesh, ClothState};
use cloth_solver::{ConstraintOrder, StepParams, Verlet};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.into());
    let n: usize = arg(0, "50").parse()?;
    let self_collision = arg(1, "on") == "on";
    let frames: u32 = arg(2, "300").parse()?;
    let threads: usize = arg(3, "1").parse()?;
    let order = match arg(4, "faithful").as_str() {
        "faithful" => ConstraintOrder::Faithful,
        "parallel" => ConstraintOrder::Parallel,
        "colored" => ConstraintOrder::Colored,
        other => {
            return Err(format!("unknown order {other:?}: faithful, parallel or colored").into());
        }
    };
    let warmup_frames: u32 = arg(5, "90").parse()?;
    let mesh = ClothMesh::pinned_grid(n)?;
    let params = StepParams {
        self_collision,
        ..StepParams::default()
    };
    let mut solver = Verlet::new().with_threads(threads)?.with_order(order);
    let mut state = ClothState::new(&mesh);
    let r = time_frames(
        &mut solver,
        &mesh,
        &[],
        &params,
        &mut state,
        BenchRun {
            warmup_frames,
            frames,
        },
    )?;
    println!(
        "{n}x{n} self-collision {self_collision} threads {threads} {order:?}: {:.3} ms/frame (median), {:.1} M particle-steps/s, real-time x{:.1}",
        r.median_ms_per_frame(),
        r.particle_steps_per_sec() / 1e6,
        r.realtime_factor()
    );
    Ok(())
}
