//! Verlet's memory estimate against what it really allocates: a global allocator tracks the
//! bytes live and their peak while a solver is built and stepped.
// NOTE: a global allocator must implement the unsafe `GlobalAlloc` trait; it only forwards to
// the system allocator and counts.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};

use cloth_mesh::{ClothMesh, ClothState, Vec3};
use cloth_solver::{Collider, ConstraintOrder, Solver, Sphere, StepParams, Verlet, advance_frame};
use serde_json::json;

struct Tracking;

/// Bytes allocated and not yet freed.
static LIVE: AtomicIsize = AtomicIsize::new(0);
/// The most `LIVE` has been since the last reset.
static PEAK: AtomicIsize = AtomicIsize::new(0);

fn grew(bytes: usize) {
    let live = LIVE.fetch_add(bytes as isize, Ordering::SeqCst) + bytes as isize;
    PEAK.fetch_max(live, Ordering::SeqCst);
}

fn shrank(bytes: usize) {
    LIVE.fetch_sub(bytes as isize, Ordering::SeqCst);
}

unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        grew(layout.size());
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        shrank(layout.size());
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        grew(new_size);
        shrank(layout.size());
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Tracking = Tracking;

/// The most bytes `solver` holds at once, beyond what was live before, over `frames` frames of
/// an `n` x `n` cloth pinned at its corners, falling onto a sphere under it with
/// self-collision and the stretch limit on: every pass of the step runs and every buffer grows.
fn peak_bytes(solver: &mut dyn Solver, n: usize, frames: usize) -> u64 {
    let mesh = ClothMesh::pinned_grid(n).unwrap();
    let side = (n - 1) as f64 / 49.0;
    let colliders = [Collider::Sphere(Sphere {
        origin: Vec3::new(side / 2.0, 0.7, side / 2.0),
        radius: side / 5.0,
        friction: 0.3,
    })];
    let params = StepParams::default();
    assert!(params.self_collision && params.stretch_limit);
    let mut state = ClothState::new(&mesh);
    let before = LIVE.load(Ordering::SeqCst);
    PEAK.store(before, Ordering::SeqCst);
    for _ in 0..frames {
        advance_frame(solver, &mesh, &colliders, &params, &mut state).unwrap();
    }
    (PEAK.load(Ordering::SeqCst) - before) as u64
}

// NOTE: the estimate counts what the buffers can grow to (a cloth near its rest spacing spread
// over as many self-collision boxes as it may have, the transient flags of the stencil), so it
// must not be below the peak; it assumes about twice the boxes a cloth at rest occupies, which
// is a fifth of its bytes, and the stencil's flags, a tenth more: it stays within twice the
// peak. One test function only: the counters are global, and tests run on parallel threads.
#[test]
fn the_estimate_covers_what_verlet_allocates_within_a_factor_of_two() {
    for (threads, order) in [
        (1, ConstraintOrder::Faithful),
        (1, ConstraintOrder::Colored),
        (2, ConstraintOrder::Parallel),
        (2, ConstraintOrder::Colored),
    ] {
        for n in [40, 96] {
            let mesh = ClothMesh::pinned_grid(n).unwrap();
            let estimate = Verlet::memory_estimate(&mesh, threads, order);
            // Built before the count starts: the thread pool is the process's, not the step's.
            let mut solver = Verlet::new()
                .with_threads(threads)
                .unwrap()
                .with_order(order);
            let peak = peak_bytes(&mut solver, n, 6);
            let ratio = estimate as f64 / peak as f64;
            assert!(
                (1.0..=2.0).contains(&ratio),
                "{n} x {n}, {threads} threads, {order:?}: estimate {estimate} bytes, peak \
                 {peak} bytes (ratio {ratio:.2})"
            );
        }
    }
    // The registry entry states the same figure for the same options.
    let mesh = ClothMesh::pinned_grid(64).unwrap();
    assert_eq!(
        Verlet::ENTRY.memory_estimate(&mesh, &json!({"threads": 2, "order": "colored"})),
        Verlet::memory_estimate(&mesh, 2, ConstraintOrder::Colored)
    );
    assert_eq!(
        Verlet::ENTRY.memory_estimate(&mesh, &json!({})),
        Verlet::memory_estimate(&mesh, 1, ConstraintOrder::Faithful)
    );
}
