//! The implicit solvers' whole-run times against Verlet's, on every bundled scene, in one run.
//!
//! `cargo run -p cloth-implicit --release --example speed_table -- [--only SOLVER]...
//! [--scene NAME]... [--frames N] [--grid N]... [--iterations N]`
//!
//! Each row runs a case from the flat start for `--frames` frames (360 by default: 4 s at 90 a
//! second) on one thread, with self-collision as the scene says and the stretch limit on:
//! Verlet at 30 steps per frame (the reference), then each implicit solver at one step per
//! frame, and prints each implicit solver's whole-run time over Verlet's. The cases: every
//! bundled scene at its own `ks`; every bundled scene at `ks` = 1e6 against Verlet at 200 steps
//! per frame (the fewest that keep it stable there); and pinned4's settings on 100 x 100 and
//! 200 x 200 grids (`--grid` replaces those sizes; `--grid 0` leaves them out). The solvers of a
//! case advance in turn, one frame each, so a machine whose speed drifts slows all of them
//! alike. `--only` (repeatable) keeps the named implicit solvers; `--scene` (repeatable) keeps
//! the named scenes; `--iterations N` caps fast-implicit's iterations and Newton's a step at
//! `N`, which with 1 measures the floor of their cost: one direction and the line search's
//! evaluations a step.
//!
//! The bounds the figures are read against: fast-implicit at most 1.5 x and implicit at most
//! 4 x Verlet at the scene's `ks`, both at most 0.25 x Verlet at 200 steps per frame at ks 1e6.

use std::fmt::Write as _;
use std::time::Instant;

use cloth_implicit::{FastImplicit, ImplicitEuler, MAX_PCG_ITERATIONS};
use cloth_mesh::{ClothMesh, ClothState, Collider, GridSpec};
use cloth_solver::{Solver, StepParams, Verlet, advance_frame};

/// One solver's run of a case.
struct Run {
    name: &'static str,
    solver: Box<dyn Solver>,
    params: StepParams,
    state: ClothState,
    seconds: f64,
    failed: Option<String>,
}

/// A case: a mesh, its collision objects and the parameters every solver shares.
struct Case {
    label: String,
    mesh: ClothMesh,
    colliders: Vec<Collider>,
    params: StepParams,
    verlet_steps: u32,
}

/// pinned4's settings on an `n` x `n` grid, the thickness scaled with the spacing.
fn pinned4(n: usize) -> Result<ClothMesh, String> {
    let spec = GridSpec {
        num_width_points: n,
        num_height_points: n,
        pinned: vec![(0, 0), (n - 1, 0), (0, n - 1), (n - 1, n - 1)],
        thickness: 0.0095 * 49.0 / (n - 1) as f64,
        ..GridSpec::default()
    };
    ClothMesh::new(&spec).map_err(|e| format!("pinned4 at {n} x {n}: {e}"))
}

/// A solver's name, constructor and steps per frame.
type Entry = (&'static str, Box<dyn Fn() -> Box<dyn Solver>>, u32);

fn times(case: &Case, frames: usize, only: &[String], iterations: Option<u32>) -> Vec<Run> {
    let fast: Box<dyn Fn() -> Box<dyn Solver>> = match iterations {
        Some(n) => Box::new(move || Box::new(FastImplicit::with_iterations(n))),
        None => Box::new(|| Box::new(FastImplicit::new())),
    };
    let newton: Box<dyn Fn() -> Box<dyn Solver>> = match iterations {
        Some(n) => {
            Box::new(move || Box::new(ImplicitEuler::new().with_iterations(n, MAX_PCG_ITERATIONS)))
        }
        None => Box::new(|| Box::new(ImplicitEuler::new())),
    };
    let solvers: [Entry; 3] = [
        (
            "verlet",
            Box::new(|| Box::new(Verlet::new())),
            case.verlet_steps,
        ),
        ("fast-implicit", fast, 1),
        ("implicit", newton, 1),
    ];
    let mut runs: Vec<Run> = solvers
        .into_iter()
        .filter(|(name, _, _)| {
            *name == "verlet" || only.is_empty() || only.iter().any(|o| o == name)
        })
        .map(|(name, build, steps)| Run {
            name,
            solver: build(),
            params: StepParams {
                steps_per_frame: steps,
                ..case.params
            },
            state: ClothState::new(&case.mesh),
            seconds: 0.0,
            failed: None,
        })
        .collect();
    for _ in 0..frames {
        for r in &mut runs {
            if r.failed.is_some() {
                continue;
            }
            let t = Instant::now();
            let out = advance_frame(
                r.solver.as_mut(),
                &case.mesh,
                &case.colliders,
                &r.params,
                &mut r.state,
            );
            r.seconds += t.elapsed().as_secs_f64();
            if let Err(e) = out {
                r.failed = Some(e.to_string());
            }
        }
    }
    runs
}

fn main() {
    let mut only = Vec::new();
    let mut scenes = Vec::new();
    let mut grids = Vec::new();
    let mut frames = 360;
    let mut iterations = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args.next();
        match (a.as_str(), value) {
            ("--only", Some(v)) => only.push(v),
            ("--scene", Some(v)) => scenes.push(v),
            ("--frames", Some(v)) => match v.parse() {
                Ok(f) => frames = f,
                Err(_) => fail(&format!("--frames {v}: expected a whole number of frames")),
            },
            ("--iterations", Some(v)) => match v.parse::<u32>() {
                Ok(n) if n >= 1 => iterations = Some(n),
                _ => fail(&format!("--iterations {v}: expected a whole number from 1")),
            },
            ("--grid", Some(v)) => match v.parse::<usize>() {
                Ok(g) => grids.push(g),
                Err(_) => fail(&format!("--grid {v}: expected a whole number of points")),
            },
            (a, _) => fail(&format!(
                "unknown or incomplete argument {a}: expected --only SOLVER, --scene NAME, \
                 --frames N, --grid N or --iterations N"
            )),
        }
    }
    if grids.is_empty() {
        grids = vec![100, 200];
    }
    let mut cases = Vec::new();
    for b in cloth_scene::BUNDLED {
        if !scenes.is_empty() && !scenes.iter().any(|s| s == b.name) {
            continue;
        }
        let scene = cloth_scene::load(b.name, &[]).unwrap_or_else(|e| fail(&e.to_string()));
        let params = StepParams {
            stretch_limit: true,
            ..scene.params
        };
        for (ks, verlet_steps) in [(params.ks, 30), (1e6, 200)] {
            cases.push(Case {
                label: format!("{} ks {ks:.0e}", b.name),
                mesh: (*scene.mesh).clone(),
                colliders: scene.colliders.clone(),
                params: StepParams { ks, ..params },
                verlet_steps,
            });
        }
    }
    for &n in grids.iter().filter(|&&n| n >= 2) {
        if !scenes.is_empty() && !scenes.iter().any(|s| s == "pinned4") {
            continue;
        }
        cases.push(Case {
            label: format!("pinned4 {n}x{n}"),
            mesh: pinned4(n).unwrap_or_else(|e| fail(&e)),
            colliders: Vec::new(),
            params: StepParams {
                stretch_limit: true,
                self_collision: true,
                ..StepParams::default()
            },
            verlet_steps: 30,
        });
    }
    println!(
        "{frames} frames from the flat start, one thread, stretch limit on; whole-run seconds, \
         and each implicit solver (1 step per frame) over Verlet"
    );
    if let Some(n) = iterations {
        println!("fast-implicit and implicit at most {n} iterations a step");
    }
    println!(
        "{:<26} {:>12} {:>22} {:>22}",
        "case", "verlet", "fast-implicit", "implicit"
    );
    for case in &cases {
        let runs = times(case, frames, &only, iterations);
        let reference = runs[0].seconds;
        let mut row = format!(
            "{:<26} {:>9.2} s  ",
            format!("{} (verlet {})", case.label, case.verlet_steps),
            reference
        );
        for name in ["fast-implicit", "implicit"] {
            let cell = match runs.iter().find(|r| r.name == name) {
                None => "-".to_owned(),
                Some(r) => match &r.failed {
                    Some(e) => format!("failed: {e}"),
                    None => format!("{:.2} s {:.2} x", r.seconds, r.seconds / reference),
                },
            };
            let _ = write!(row, " {cell:>22}");
        }
        if let Some(e) = &runs[0].failed {
            let _ = write!(row, "  (verlet failed: {e})");
        }
        println!("{row}");
    }
}

fn fail(message: &str) -> ! {
    eprintln!("speed_table: {message}");
    std::process::exit(2);
}
