//! One frame (1/90 s of simulated time) of the `pinned4` cloth per solver and size.
//!
//! Verlet takes the course's 30 substeps per frame; the implicit solvers one step per frame.
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

fn bench_frames(c: &mut Criterion) {
    let mut group = c.benchmark_group("frame");
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(4));
    for n in [50, 100] {
        let mesh = pinned4(n);
        for (ks, self_collision) in [(5000.0, true), (1e5, true), (5000.0, false), (1e5, false)] {
            let start = moving_state(&mesh, ks);
            let sc = if self_collision { "sc" } else { "nosc" };
            let cases: [(&str, Box<dyn Solver>, u32); 3] = [
                ("verlet-30", Box::new(Verlet::new()), 30),
                ("implicit-1", Box::new(ImplicitEuler::new()), 1),
                ("fast-implicit-1", Box::new(FastImplicit::new()), 1),
            ];
            for (name, mut solver, steps) in cases {
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

criterion_group!(benches, bench_frames);
criterion_main!(benches);
