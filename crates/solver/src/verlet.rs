//! The course's explicit damped position Verlet: the faithful reference solver.
//!
//! # Method
//!
//! One step of `dt = 1 / fps / steps_per_frame` seconds, in the course's order:
//!
//! 1. `F_i = m g + sum_springs k (|x_a - x_b| - L) u`, `k = ks` (structural, shearing) or
//!    `0.2 ks` (bending), disabled types skipped;
//! 2. unpinned points: `x' = x + (1 - d/100)(x - x_last) + F/m dt^2`, `x_last = x`;
//! 3. self-collision through a [`SpatialHash`] (when enabled);
//! 4. sphere and plane collisions with friction;
//! 5. the 10 % stretch limit, one sequential sweep over all springs.
//!
//! # Stability
//!
//! Explicit: stable while `ks` stays below about `m / (2 dt^2)` (2.2e5 N/m at the defaults,
//! see [`StepParams::explicit_ks_limit`]). Damping acts as a drag of `(d/100)/dt` per second, so
//! changing the steps per frame changes the effective drag, as it does in the course.
//!
//! # Fast paths and their invariant
//!
//! Steps 1 and 2 run as one sweep over the grid's rows (`sweep`), self-collision through a
//! [`SpatialHash`] that skips boxes provably clear, and the stretch limit checks only the springs
//! a pre-pass could not prove inside the limit (`limit`). With [`ConstraintOrder::Faithful`] (the
//! default) every one of them makes the course's operations in the course's order, so the
//! results are those of [`reference_step`](crate::reference_step) bit for bit, on any thread
//! count and with or without AVX2 (the solver's tests hold them to it).
//! [`ConstraintOrder::Parallel`] and [`ConstraintOrder::Colored`] change only the order of the
//! stretch limit's corrections (`colored`). How the speed is obtained, and what it is, is in
//! `docs/performance.md`.

mod colored;
mod limit;
mod sweep;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use cloth_mesh::{ClothMesh, ClothState, Vec3};
use rayon::prelude::*;

use crate::MAX_STRETCH;
use crate::self_collision::PARALLEL_CHUNK;
use crate::simd::{Avx2, Simd};
use crate::stretch::StretchBands;
use crate::{Collider, SolveError, Solver, SpatialHash, StepParams, StepReport, apply_colliders};
use limit::StretchSweep;
use sweep::{Band, RowScratch, Stencil, SweepParams};

/// The order in which the two sequential constraint passes (self-collision and the stretch
/// limit) visit points and springs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ConstraintOrder {
    /// The course's order: one in-place sweep in spring order for the stretch limit, points in
    /// index order each seeing earlier corrections for self-collision. Results are the course's.
    /// Self-collision still shares its boxes out among the threads (boxes are independent, so
    /// that changes no bit); the stretch limit's sweep runs on one thread.
    #[default]
    Faithful,
    /// An order that threads can share: the stretch limit sweeps row blocks at once, then the
    /// two-row seams between them. Every spring is treated once with the course's formula, so
    /// the constraint is the same; only the order of the corrections differs, which moves a
    /// settled cloth by far less than its thickness (see the solver's tests). Self-collision is
    /// the faithful one (its boxes are independent, so threads share it exactly). Results do
    /// not depend on the thread count.
    Parallel,
    /// The order with no chains, for big cloths: the stretch limit takes each spring direction
    /// in two classes of springs that share no point, so the corrections of a class are
    /// independent (the processor overlaps them, threads share them by rows). Every spring is
    /// treated once a step with the course's formula; the order of the corrections differs
    /// more than in [`ConstraintOrder::Parallel`], and the solver's tests bound what that
    /// moves. Self-collision is the faithful one. Results do not depend on the thread count.
    Colored,
}

/// The faithful explicit Verlet solver. Owns only scratch memory and caches.
#[derive(Debug, Default, Clone)]
pub struct Verlet {
    /// The vector instructions the CPU runs, detected when the solver is built.
    simd: Simd,
    /// Worker threads (`None`: run on the caller's thread).
    pool: Option<Arc<rayon::ThreadPool>>,
    order: ConstraintOrder,
    /// The mesh's springs by direction, rebuilt only when the mesh changes.
    stencil: Option<Stencil>,
    /// Row buffers, one per band of rows.
    scratch: Vec<RowScratch>,
    /// Last positions of the pinned points, kept across the ping-pong swap.
    pinned_last: Vec<Vec3>,
    hash: SpatialHash,
    /// The stretch limit's bands for [`ConstraintOrder::Parallel`], rebuilt with the stencil.
    bands: StretchBands,
    /// Scratch of the faithful stretch-limit sweep.
    stretch: StretchSweep,
}

impl Verlet {
    /// A new single-threaded, faithful solver; its scratch arrays grow on the first step.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Runs the force and integration sweep and self-collision on `threads` worker threads (1 or
    /// 0: the caller's thread). The results are bit-identical for any thread count; the stretch
    /// limit shares the threads only with [`ConstraintOrder::Parallel`].
    ///
    /// # Errors
    /// [`SolveError::Method`] when the thread pool cannot be created.
    pub fn with_threads(mut self, threads: usize) -> Result<Self, SolveError> {
        self.pool = if threads <= 1 {
            None
        } else {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| SolveError::Method {
                    solver: "verlet",
                    reason: format!("cannot start {threads} threads: {e}"),
                })?;
            Some(Arc::new(pool))
        };
        Ok(self)
    }

    /// Chooses the constraint order (see [`ConstraintOrder`]).
    #[must_use]
    pub fn with_order(mut self, order: ConstraintOrder) -> Self {
        self.order = order;
        self
    }

    /// Worker threads in use (1 when running on the caller's thread).
    #[must_use]
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.current_num_threads())
    }

    /// The constraint order in use.
    #[must_use]
    pub fn order(&self) -> ConstraintOrder {
        self.order
    }

    /// Bytes the solver allocates for `mesh` on `threads` threads in `order`, self-collision
    /// included (it can be turned on at any step): the springs by direction, the row buffers
    /// of each band of the force sweep (one band on one thread, two per thread otherwise), the
    /// stretch limit's bounds and band copies, the pins' last positions and the
    /// [`SpatialHash`] ([`SpatialHash::memory_estimate`]). The state is the caller's and not
    /// counted, nor are the worker threads' stacks.
    #[must_use]
    pub fn memory_estimate(mesh: &ClothMesh, threads: usize, order: ConstraintOrder) -> u64 {
        let (nw, nh, n) = (mesh.nw(), mesh.nh(), mesh.len());
        let pins = mesh.pinned().iter().filter(|&&p| p).count();
        let threads = threads.max(1);
        let bands = if threads == 1 {
            1
        } else {
            (2 * threads).min(nh)
        };
        Stencil::bytes_for(n, pins)
            + (pins * size_of::<Vec3>()) as u64
            + bands as u64 * RowScratch::bytes_for(nw)
            + StretchSweep::bytes_for(nw, nh, order)
            + SpatialHash::memory_estimate(n, threads)
    }
}

impl Solver for Verlet {
    fn name(&self) -> &'static str {
        "verlet"
    }

    fn step(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &mut ClothState,
    ) -> Result<StepReport, SolveError> {
        if !mesh.is_whole() {
            // NOTE: the fast sweeps hold the springs by grid direction and need every one of
            // them; a cloth cut by hand is stepped by the course's plain loops, which take any
            // list of springs and give the same physics.
            return crate::reference_step(mesh, colliders, params, state)
                .map(|()| StepReport::default());
        }
        let Some(pool) = self.pool.clone() else {
            return self.step_here(mesh, colliders, params, state);
        };
        // NOTE: the whole step runs on one of the pool's threads, and the others spend it
        // polling for its work instead of going to sleep between its threaded passes: a pass
        // then starts on every thread at once. A sleeping worker takes a futex call to wake and
        // tens of microseconds to run, several times a step. The pollers are `join` jobs, on
        // the stack: they allocate nothing.
        let pollers = pool.current_num_threads() - 1;
        let done = AtomicBool::new(false);
        let mut step = || {
            // Set when the step ends, even by a panic: `join` waits for the pollers.
            let _stop = Stop(&done);
            self.step_here(mesh, colliders, params, state)
        };
        pool.install(|| polled(pollers, &done, &mut step))
    }
}

impl Verlet {
    /// One step on the current thread (see [`Solver::step`]).
    fn step_here(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &mut ClothState,
    ) -> Result<StepReport, SolveError> {
        params.validate()?;
        let mass = mesh.point_mass(params.density);
        let simd = self.simd;
        let dt = params.dt();
        let sweep = SweepParams {
            k: sweep::DIRECTIONS.map(|(_, _, kind)| params.stiffness(kind)),
            weight: params.gravity * mass,
            keep: 1.0 - params.damping / 100.0,
            scale: dt * dt / mass,
        };

        // 1 and 2. Forces and damped Verlet. The sweep writes the new positions over the last
        // ones; swapping the arrays makes the old positions the new last ones. Pinned points
        // keep their last position too, as in the course.
        let stencil = match self.stencil.take() {
            Some(stencil) if stencil.matches(mesh) => stencil,
            _ => {
                let stencil = Stencil::new(mesh)?;
                self.bands = StretchBands::new(mesh);
                self.stretch = StretchSweep::new(&stencil, MAX_STRETCH, simd);
                stencil
            }
        };
        let stencil = &*self.stencil.insert(stencil);
        self.pinned_last.clear();
        self.pinned_last
            .extend(stencil.pins.iter().map(|&i| state.last[i]));
        let (pool, pinned) = (self.pool.as_deref(), mesh.pinned());
        forces_and_verlet(
            stencil,
            pool,
            &mut self.scratch,
            simd,
            pinned,
            &sweep,
            state,
        );
        std::mem::swap(&mut state.positions, &mut state.last);
        for (&i, l) in stencil.pins.iter().zip(&self.pinned_last) {
            state.last[i] = *l;
        }
        let positions = &mut state.positions;

        // 3. Self-collision.
        if params.self_collision {
            self.hash
                .resolve_in(mesh, positions, params.steps_per_frame, pool);
        }

        // 4. Collision objects.
        apply_colliders(colliders, pinned, positions, &state.last);

        // 5. Stretch limit.
        if params.stretch_limit {
            match self.order {
                ConstraintOrder::Colored => {
                    colored::limit_colored(stencil, pinned, positions, MAX_STRETCH, pool, simd);
                }
                ConstraintOrder::Parallel => {
                    let bands = &self.bands;
                    self.stretch
                        .limit_bands(stencil, bands, pinned, positions, pool);
                }
                ConstraintOrder::Faithful => self.stretch.limit(stencil, pinned, positions),
            }
        }

        // NOTE: the last positions are checked at the pins only. Anywhere else a non-finite last
        // position made the new one non-finite within this step (Verlet's `x + keep (x - last)`
        // is not finite then, whatever `keep`), and no later pass makes a non-finite position
        // finite (collisions and corrections add to it or compute from it); a pinned point's
        // last position is only ever kept. So this passes exactly when both arrays are finite,
        // for half the reads.
        let last_finite = (stencil.pins.iter()).all(|&i| all_finite(simd, &state.last[i..=i]));
        if last_finite && finite_on(simd, &state.positions, pool) {
            return Ok(StepReport::default());
        }
        match state.first_non_finite() {
            Some(i) => Err(SolveError::non_finite(mesh, i)),
            None => Ok(StepReport::default()),
        }
    }
}

/// Steps 1 and 2: forces and the Verlet update, on `pool`'s threads when there is one, leaving
/// the new positions in `state.last` and the old ones in `state.positions` (the caller swaps
/// them).
fn forces_and_verlet(
    stencil: &Stencil,
    pool: Option<&rayon::ThreadPool>,
    scratch: &mut Vec<RowScratch>,
    simd: Simd,
    pinned: &[bool],
    params: &SweepParams,
    state: &mut ClothState,
) {
    let (nw, nh) = (stencil.nw(), stencil.nh());
    let positions = &state.positions;
    let Some(pool) = pool else {
        scratch.resize_with(1, RowScratch::default);
        let next = &mut state.last;
        let band = Band {
            positions,
            pinned,
            next,
            rows: 0..nh,
        };
        stencil.sweep(simd, &mut scratch[0], params, band);
        return;
    };
    // Two bands per thread: one thread can take a band of a slower one (the threads may share
    // their cores with other processes), while each band's first two rows, emitted again by
    // the band after, stay few.
    let bands = (2 * pool.current_num_threads()).min(nh);
    let rows = nh.div_ceil(bands);
    scratch.resize_with(nh.div_ceil(rows), RowScratch::default);
    pool.install(|| {
        (state.last.par_chunks_mut(rows * nw))
            .zip(scratch.par_iter_mut())
            .enumerate()
            .for_each(|(k, (next, scratch))| {
                let rows = k * rows..((k + 1) * rows).min(nh);
                let band = Band {
                    positions,
                    pinned,
                    next,
                    rows,
                };
                stencil.sweep(simd, scratch, params, band);
            });
    });
}

/// Sets its flag when dropped.
struct Stop<'a>(&'a AtomicBool);

impl Drop for Stop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

/// Runs `step` on this thread with `pollers` more of the pool's workers running its pending
/// work (`poll_until`) until `done` is set (which `step` must do).
fn polled<R: Send>(pollers: usize, done: &AtomicBool, step: &mut (dyn FnMut() -> R + Send)) -> R {
    if pollers == 0 {
        return step();
    }
    rayon::join(|| polled(pollers - 1, done, step), || poll_until(done)).0
}

/// Runs the pool's pending work, on the calling worker, until `done` is set. A poller no
/// worker picked up is run by the joining thread once `done` is set, and returns at once.
fn poll_until(done: &AtomicBool) {
    while !done.load(Ordering::Acquire) {
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            // NOTE: the OS's yield, not a spin: with more threads than cores a spinning poller
            // would hold a core the step's own thread needs.
            std::thread::yield_now();
        }
    }
}

/// Whether every coordinate of `points` is finite, on `pool`'s threads for a big cloth, in
/// tasks of the threaded passes' size.
fn finite_on(simd: Simd, points: &[Vec3], pool: Option<&rayon::ThreadPool>) -> bool {
    match pool {
        Some(pool) if points.len() > PARALLEL_CHUNK => pool.install(|| {
            points
                .par_chunks(PARALLEL_CHUNK)
                .all(|chunk| all_finite(simd, chunk))
        }),
        _ => all_finite(simd, points),
    }
}

/// Whether every coordinate is finite.
fn all_finite(simd: Simd, points: &[Vec3]) -> bool {
    // NOTE: over the coordinates as one flat run of f64s, not point by point, and on AVX2 where
    // the CPU has it: the loop is then a subtraction, a compare and an `and` per four values,
    // with no shuffles to gather each point's `x y z`.
    let coordinates: &[f64] = bytemuck::cast_slice(points);
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = simd.avx2() {
        // SAFETY: the CPU runs AVX2: an `Avx2` exists.
        #[allow(unsafe_code)]
        return unsafe { all_finite_avx2(avx2, coordinates) };
    }
    finite_run(coordinates)
}

/// [`finite_run`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn all_finite_avx2(_: Avx2, values: &[f64]) -> bool {
    finite_run(values)
}
/// Whether every value is finite, without early exit so it vectorises: `v - v` is 0 for a
/// finite `v` and NaN for a NaN or an infinity.
#[inline(always)]
#[allow(clippy::inline_always)]
fn finite_run(values: &[f64]) -> bool {
    let mut ok = true;
    // NOTE: a plain loop, not a fold: a closure would not be inlined into the AVX2 build.
    for &v in values {
        // NOTE: `&`, not `&&`: no early exit, so the loop vectorises.
        #[allow(clippy::eq_op)]
        let finite = v - v == 0.0;
        ok &= finite;
    }
    ok
}
