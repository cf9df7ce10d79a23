//! One frame (1/90 s of simulated time) of the `pinned4` cloth per solver and size, one group
//! per solver (`cargo bench -p cloth-implicit --bench frame -- fast-implicit`).
//!
//! Verlet takes the course's 30 substeps per frame (200 at ks = 1e6, the fewest that keep it
//! stable there); the implicit solvers one step per frame.
//! Every measurement starts from the same moving state (0.5 s after release, reached with the
//! fast solver, which is stable for every case, its velocity retimed to each solver's step),
//! cloned per iteration, with the solver's caches warm, as in an interactive run. The course's parameters otherwise, self-collision included
//! (`sc`), with the thickness scaled with the grid spacing (0.0095 m at 50 x 50, as in the
//! course; at 100 x 100 the course's thickness would exceed the spacing and push every pair of
//! neighbours apart); the `nosc` rows switch self-collision off to time the integrators alone.

use std::hint::black_box;

use cloth_implicit::{FastImplicit, ImplicitEuler, retime_velocity};
use cloth_mesh::{ClothMesh, ClothState, GridSpec};
use cloth_solver::{Solver, StepParams, Verlet, advance_frame};
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};

fn pinned4(n: usize) -> ClothMesh {
    let spec = GridSpec {
        num_width_points: n,
        num_height_points: n,
        pinned: vec![(0, 0), (n - 1, 0), (0, n - 1), (n - 1, n - 1)],
        thickness: 0.0095 * 49.0 / (n - 1) as f64,
        ..GridSpec::default()
    };
    match ClothMesh::new(&spec) {
        Ok(mesh) => mesh,
        Err(e) => panic!("bench mesh: {e}"),
    }
}

fn moving_state(mesh: &ClothMesh, ks: f64) -> ClothState {
    let params = StepParams {
        ks,
        steps_per_frame: 1,
        self_collision: false,
        ..StepParams::default()
    };
    let mut state = ClothState::new(mesh);
    let mut solver = FastImplicit::new();
    for _ in 0..45 {
        if let Err(e) = advance_frame(&mut solver, mesh, &[], &params, &mut state) {
            panic!("warm-up diverged: {e}");
        }
    }
    state
}

/// One configuration: a solver's name, constructor and steps per frame at a stiffness.
type Case = (&'static str, fn() -> Box<dyn Solver>, u32);

/// One group per solver, each timing a frame of pinned4 at 50 x 50 and 100 x 100, at the
/// course's ks and at ks = 1e6 (where Verlet needs 200 steps per frame on the 50 x 50 cloth),
/// self-collision on and off.
fn bench_group(c: &mut Criterion, group_name: &str, cases: [Case; 2]) {
    let mut group = c.benchmark_group(group_name);
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(4));
    for n in [50, 100] {
        let mesh = pinned4(n);
        for (ks, (name, build, steps)) in [5000.0, 1e6].into_iter().zip(cases) {
            let start = moving_state(&mesh, ks);
            for self_collision in [true, false] {
                let sc = if self_collision { "sc" } else { "nosc" };
                let mut solver = build();
                let params = StepParams {
                    ks,
                    steps_per_frame: steps,
                    self_collision,
                    ..StepParams::default()
                };
                // The warm-up ran at one step per frame: keep its velocity at this step.
                let mut start = start.clone();
                retime_velocity(&mut start, 1.0 / params.frames_per_sec, params.dt());
                // Warm the caches (symbolic and numeric factors) outside the measurement.
                let mut warm = start.clone();
                let _ = advance_frame(solver.as_mut(), &mesh, &[], &params, &mut warm);
                group.bench_function(format!("{name}/{n}x{n}/ks={ks}/{sc}"), |b| {
                    b.iter_batched(
                        || start.clone(),
                        |mut state| {
                            // A diverging Verlet is still timed: its cost does not depend on it.
                            let r = advance_frame(solver.as_mut(), &mesh, &[], &params, &mut state);
                            black_box((r.is_ok(), state))
                        },
                        BatchSize::LargeInput,
                    );
                });
            }
        }
    }
    group.finish();
}

fn bench_verlet(c: &mut Criterion) {
    bench_group(
        c,
        "verlet",
        [
            ("verlet-30", || Box::new(Verlet::new()), 30),
            ("verlet-200", || Box::new(Verlet::new()), 200),
        ],
    );
}

fn bench_fast_implicit(c: &mut Criterion) {
    bench_group(
        c,
        "fast-implicit",
        [
            ("fast-implicit-1", || Box::new(FastImplicit::new()), 1),
            ("fast-implicit-1", || Box::new(FastImplicit::new()), 1),
        ],
    );
}

fn bench_implicit(c: &mut Criterion) {
    bench_group(
        c,
        "implicit",
        [
            ("implicit-1", || Box::new(ImplicitEuler::new()), 1),
            ("implicit-1", || Box::new(ImplicitEuler::new()), 1),
        ],
    );
}

criterion_group!(benches, bench_verlet, bench_fast_implicit, bench_implicit);
criterion_main!(benches);
