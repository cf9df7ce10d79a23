//! The implicit solvers' frame times as ratios to Verlet's, timed in turn in one run.
//!
//! `cargo run -p cloth-implicit --release --example ratios -- [GRID] [FRAMES] [--only SOLVER]
//! [--group default|stiff] [--limit off]` (defaults 50 and 450, every solver and both groups,
//! the stretch limit on): the course's `pinned4` scaled to GRID x GRID points (thickness
//! scaled with the spacing), self-collision on, from the flat start. Each configuration
//! advances its own cloth; every round times one frame of each, so a machine whose speed
//! drifts slows all of them alike. The mean over all frames (the fall, the swing and the rest)
//! is what a user waits for.
//!
//! Configurations: Verlet at 30 steps per frame (the reference), fast-implicit and implicit at
//! one step per frame; then at ks = 1e6, Verlet at 200 steps per frame (the fewest that keep
//! it stable there on the 50 x 50 cloth) against fast-implicit and implicit at one. `--only`
//! (repeatable) keeps the named implicit solvers' rows and Verlet's; `--group` keeps one group;
//! `--limit off` runs every configuration without the stretch limit, which measures what the
//! implicit solvers cost without it.

use std::time::Instant;

use cloth_implicit::{FastImplicit, ImplicitEuler};
use cloth_mesh::{ClothMesh, ClothState, GridSpec};
use cloth_solver::{Solver, StepParams, Verlet, advance_frame, max_stretch_ratio};

fn pinned4(n: usize) -> ClothMesh {
    let spec = GridSpec {
        num_width_points: n,
        num_height_points: n,
        pinned: vec![(0, 0), (n - 1, 0), (0, n - 1), (n - 1, n - 1)],
        thickness: 0.0095 * 49.0 / (n - 1) as f64,
        ..GridSpec::default()
    };
    ClothMesh::new(&spec).unwrap_or_else(|e| panic!("mesh: {e}"))
}

struct Config {
    name: String,
    solver: Box<dyn Solver>,
    params: StepParams,
    state: ClothState,
    seconds: f64,
    failed: Option<String>,
}

fn group(
    mesh: &ClothMesh,
    frames: usize,
    ks: f64,
    verlet_steps: u32,
    only: &[String],
    stretch_limit: bool,
) -> Vec<Config> {
    let base = StepParams {
        ks,
        stretch_limit,
        ..StepParams::default()
    };
    let configs: [(String, Box<dyn Solver>, u32); 3] = [
        (
            format!("verlet-{verlet_steps}"),
            Box::new(Verlet::new()),
            verlet_steps,
        ),
        ("fast-implicit-1".into(), Box::new(FastImplicit::new()), 1),
        ("implicit-1".into(), Box::new(ImplicitEuler::new()), 1),
    ];
    let mut runs: Vec<Config> = configs
        .into_iter()
        .enumerate()
        .filter(|(i, (name, _, _))| {
            *i == 0 || only.is_empty() || only.iter().any(|o| name.trim_end_matches("-1") == o)
        })
        .map(|(_, c)| c)
        .map(|(name, solver, steps)| Config {
            name,
            solver,
            params: StepParams {
                steps_per_frame: steps,
                ..base
            },
            state: ClothState::new(mesh),
            seconds: 0.0,
            failed: None,
        })
        .collect();
    for _ in 0..frames {
        for c in &mut runs {
            if c.failed.is_some() {
                continue;
            }
            let t = Instant::now();
            let r = advance_frame(c.solver.as_mut(), mesh, &[], &c.params, &mut c.state);
            c.seconds += t.elapsed().as_secs_f64();
            if let Err(e) = r {
                c.failed = Some(e.to_string());
            }
        }
    }
    runs
}

fn main() {
    let mut positional = Vec::new();
    let mut only = Vec::new();
    let mut groups = Vec::new();
    let mut stretch_limit = true;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--only" => only.extend(args.next()),
            "--group" => groups.extend(args.next()),
            "--limit" => stretch_limit = args.next().as_deref() != Some("off"),
            _ => positional.push(a),
        }
    }
    let n: usize = positional
        .first()
        .and_then(|a| a.parse().ok())
        .unwrap_or(50);
    let frames: usize = positional
        .get(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(450);
    let mesh = pinned4(n);
    for (group_name, ks, verlet_steps) in [("default", 5000.0, 30), ("stiff", 1e6, 200)] {
        if !groups.is_empty() && !groups.iter().any(|g| g == group_name) {
            continue;
        }
        let runs = group(&mesh, frames, ks, verlet_steps, &only, stretch_limit);
        let reference = runs[0].seconds;
        let limit = if stretch_limit { "on" } else { "off" };
        println!(
            "{n} x {n}, ks = {ks}, self-collision on, stretch limit {limit}, \
             {frames} frames from the flat start:"
        );
        for c in &runs {
            let ms = 1e3 * c.seconds / frames as f64;
            let stretch = max_stretch_ratio(&mesh, &c.state);
            match &c.failed {
                None => println!(
                    "  {:<16} {ms:>9.3} ms/frame  {:>7.3} x {}  (stretch at end {stretch:.3})",
                    c.name,
                    c.seconds / reference,
                    runs[0].name
                ),
                Some(e) => println!("  {:<16} failed: {e}", c.name),
            }
        }
    }
}
