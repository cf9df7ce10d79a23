//! One 30-step frame of the faithful Verlet solver: the five standard scenes, big grids and
//! threads; one self-collision pass at four sizes; and the divider's floor under a big cloth's
//! step. Run with `cargo bench -p cloth-solver --bench frame`.
//!
//! Each benchmark first simulates one second (90 frames) so the cloth is hanging, stretched and
//! in self-contact, then times frames continuing from there; throughput is reported in
//! particle-steps (points x 30 steps per frame).

use std::hint::black_box;
use std::time::Duration;

use cloth_mesh::{ClothMesh, ClothState, GridSpec, Orientation, Vec3};
use cloth_solver::{
    Collider, ConstraintOrder, Plane, Solver, SpatialHash, Sphere, StepParams, Verlet,
    advance_frame,
};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

/// The five scenes of the course (spec section 1), built from their definitions.
fn standard_scenes() -> Vec<(&'static str, ClothMesh, Vec<Collider>)> {
    let cloth = |orientation, pinned| {
        ClothMesh::new(&GridSpec {
            width: 1.0,
            height: 1.0,
            num_width_points: 50,
            num_height_points: 50,
            thickness: 0.0095,
            orientation,
            pinned,
            ..GridSpec::default()
        })
        .unwrap()
    };
    let floor = Collider::Plane(Plane {
        point: Vec3::zeros(),
        normal: Vec3::y(),
        friction: 0.5,
    });
    let ball = Collider::Sphere(Sphere {
        origin: Vec3::new(0.5, 0.2, 0.5),
        radius: 0.2,
        friction: 0.3,
    });
    let h = Orientation::Horizontal;
    vec![
        ("pinned2", cloth(h, vec![(0, 0), (49, 0)]), vec![]),
        (
            "pinned4",
            cloth(h, vec![(0, 0), (49, 0), (0, 49), (49, 49)]),
            vec![],
        ),
        ("sphere", cloth(h, vec![]), vec![ball]),
        ("plane", cloth(h, vec![]), vec![floor]),
        (
            "selfCollision",
            cloth(Orientation::Vertical, vec![]),
            vec![floor],
        ),
    ]
}

/// Times frames of `solver` on `mesh` after a one-second warm-up.
fn bench_frames(
    c: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: BenchmarkId,
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    mut solver: Box<dyn Solver>,
    warmup_frames: u32,
) {
    let mut state = ClothState::new(mesh);
    for _ in 0..warmup_frames {
        advance_frame(solver.as_mut(), mesh, colliders, params, &mut state).unwrap();
    }
    c.throughput(Throughput::Elements(
        mesh.len() as u64 * u64::from(params.steps_per_frame),
    ));
    c.bench_function(id, |b| {
        b.iter(|| {
            advance_frame(solver.as_mut(), mesh, colliders, params, &mut state).unwrap();
            black_box(&state);
        });
    });
}

fn standard(c: &mut Criterion) {
    let mut g = c.benchmark_group("standard");
    g.measurement_time(Duration::from_secs(3));
    for self_collision in [false, true] {
        let params = StepParams {
            self_collision,
            ..StepParams::default()
        };
        for (name, mesh, colliders) in standard_scenes() {
            let id = BenchmarkId::new(
                name,
                if self_collision {
                    "self-on"
                } else {
                    "self-off"
                },
            );
            bench_frames(
                &mut g,
                id,
                &mesh,
                &colliders,
                &params,
                Box::new(Verlet::new()),
                90,
            );
        }
    }
    g.finish();
}

fn grids(c: &mut Criterion) {
    let mut g = c.benchmark_group("grid");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(5));
    let params = StepParams::default();
    for n in [64, 128, 256] {
        let mesh = ClothMesh::pinned_grid(n).unwrap();
        bench_frames(
            &mut g,
            BenchmarkId::new("self-on", n),
            &mesh,
            &[],
            &params,
            Box::new(Verlet::new()),
            30,
        );
    }
    g.finish();
}

/// One self-collision pass (hash rebuild and resolution) on cloths of 64, 128, 256 and 512 points
/// per side with the same local geometry: the flat cloth at the standard spacing, each point
/// jittered by up to half a spacing, so every box holds about nine points and a few pairs in
/// reach wherever the cloth is (a wrinkled cloth). A linear pass then costs about the same per
/// point at every size, up to cache effects (criterion reports points per second).
///
/// Passes alternate between that cloth and the same cloth moved by a tenth of a box (`pass`), so
/// about a tenth of the points change box from one pass to the next and the hash lays every
/// point out again; or by a hundredth (`relayout`), about one point in a hundred, which the
/// hash moves in its last layout (a 256 x 256 cloth falling onto itself changes 0.2-1 % a
/// step). The hash keeps its cells between rebuilds, and a cloth that never moved would time
/// only its best case.
fn self_collision(c: &mut Criterion) {
    let mut g = c.benchmark_group("self_collision");
    g.sample_size(20);
    g.measurement_time(Duration::from_secs(4));
    for n in [64, 128, 256, 512] {
        let mesh = ClothMesh::pinned_grid(n).unwrap();
        let h = 1.0 / 49.0;
        let mut rng = cloth_mesh::SplitMix64::new(n as u64);
        let template: Vec<Vec3> = mesh
            .start_positions()
            .iter()
            .map(|p| {
                Vec3::new(
                    p.x + rng.uniform(-h, h) / 2.0,
                    p.y + rng.uniform(-h, h) / 2.0,
                    p.z + rng.uniform(-h, h) / 2.0,
                )
            })
            .collect();
        let box_w = SpatialHash::box_size(&mesh).0;
        g.throughput(Throughput::Elements(mesh.len() as u64));
        for (name, shift) in [("pass", 10.0), ("relayout", 100.0)] {
            let moved: Vec<Vec3> = template
                .iter()
                .map(|p| p + Vec3::new(box_w / shift, 0.0, 0.0))
                .collect();
            let templates = [template.clone(), moved];
            let mut hash = SpatialHash::default();
            let mut work = templates[0].clone();
            let mut pass = 0usize;
            g.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| {
                    // The copy is linear too; it keeps every pass starting from one of two states.
                    pass += 1;
                    work.copy_from_slice(&templates[pass % 2]);
                    hash.resolve(&mesh, &mut work, 30);
                    black_box(&work);
                });
            });
        }
    }
    g.finish();
}

fn threads(c: &mut Criterion) {
    let mut g = c.benchmark_group("threads");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(5));
    let params = StepParams::default();
    let mesh = ClothMesh::pinned_grid(256).unwrap();
    for order in [
        ConstraintOrder::Faithful,
        ConstraintOrder::Parallel,
        ConstraintOrder::Colored,
    ] {
        for threads in [1, 2] {
            let solver = Verlet::new()
                .with_order(order)
                .with_threads(threads)
                .unwrap();
            let id = BenchMarkName::id(order, threads);
            bench_frames(&mut g, id, &mesh, &[], &params, Box::new(solver), 30);
        }
    }
    g.finish();
}

/// Benchmark names of the thread group: `256/<order>/<threads>`.
struct BenchMarkName;

impl BenchMarkName {
    fn id(order: ConstraintOrder, threads: usize) -> BenchmarkId {
        let order = match order {
            ConstraintOrder::Faithful => "faithful",
            ConstraintOrder::Parallel => "parallel",
            ConstraintOrder::Colored => "colored",
        };
        BenchmarkId::new(format!("256/{order}"), threads)
    }
}

/// The divider's floor under a 256 x 256 step: a square root and a division for each of the
/// cloth's 390,658 springs, four at a time on AVX2, with nothing else to do. The force pass
/// needs that for every spring, and the colored order's limit for nearly every one (a group
/// of four takes both whenever one of its springs is over the bound): so two of these are a
/// step's floor, whatever the layout. Throughput is in springs.
fn divider(c: &mut Criterion) {
    let mut g = c.benchmark_group("divider");
    g.sample_size(20);
    let springs = ClothMesh::pinned_grid(256).unwrap().springs().len();
    let len2: Vec<f64> = (0..springs)
        .map(|k| 4e-4 * (1.0 + (k % 97) as f64 * 1e-3))
        .collect();
    let rest = vec![0.02; springs];
    let mut factor = vec![0.0; springs];
    g.throughput(Throughput::Elements(springs as u64));
    g.bench_function(BenchmarkId::new("sqrt_div", 256), |b| {
        b.iter(|| {
            stretch_factors(black_box(&len2), black_box(&rest), &mut factor);
            black_box(&factor);
        });
    });
    g.finish();
}

/// `(|d| - rest) / |d|` from `|d|^2`, the factor of a spring's force and of its correction.
fn stretch_factors(len2: &[f64], rest: &[f64], factor: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        #[allow(unsafe_code)]
        unsafe {
            stretch_factors_avx2(len2, rest, factor);
        }
        return;
    }
    stretch_factors_portable(len2, rest, factor);
}

#[inline(always)]
#[allow(clippy::inline_always)]
fn stretch_factors_portable(len2: &[f64], rest: &[f64], factor: &mut [f64]) {
    for ((f, l2), r) in factor.iter_mut().zip(len2).zip(rest) {
        let len = l2.sqrt();
        *f = (len - r) / len;
    }
}

/// [`stretch_factors_portable`] compiled for AVX2: the compiler makes it packed square roots
/// and divisions, four lanes each.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[target_feature(enable = "avx2")]
unsafe fn stretch_factors_avx2(len2: &[f64], rest: &[f64], factor: &mut [f64]) {
    stretch_factors_portable(len2, rest, factor);
}

criterion_group!(benches, standard, grids, self_collision, threads, divider);
criterion_main!(benches);
