//! Timing a solver frame by frame: the engine of `clothsim bench`.
//!
//! Criterion benches (`benches/`) are the measurement of record; this module gives the binary a
//! quick, dependency-free way to print ms per frame, particle-steps per second and the real-time
//! factor for any solver behind the [`Solver`] trait. Wall-clock time is read here, between
//! frames, never inside a solver.

use std::time::Instant;

use cloth_mesh::{ClothMesh, ClothState, GridSpec, MeshError, Orientation};

use crate::{Collider, SolveError, Solver, StepParams, advance_frame};

/// How long to run a benchmark.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BenchRun {
    /// Frames simulated before timing starts, so the cloth has fallen, stretched and come into
    /// self-contact (a cloth at its flat start does less work than one in motion).
    pub warmup_frames: u32,
    /// Frames timed.
    pub frames: u32,
}

impl Default for BenchRun {
    /// One simulated second of warm-up, then one timed second (90 frames each at 90 fps).
    fn default() -> Self {
        Self {
            warmup_frames: 90,
            frames: 90,
        }
    }
}

/// The outcome of one benchmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BenchResult {
    /// Points in the cloth.
    pub points: usize,
    /// Springs in the cloth.
    pub springs: usize,
    /// Frames timed.
    pub frames: u32,
    /// Steps per frame.
    pub steps_per_frame: u32,
    /// Wall-clock seconds for the timed frames.
    pub seconds: f64,
    /// The median of the timed frames' wall-clock seconds: unlike the mean, it shrugs off the
    /// frames during which another process took the CPU.
    pub median_frame_seconds: f64,
    /// Simulated seconds per frame (`1 / frames_per_sec`).
    pub frame_time: f64,
}

impl BenchResult {
    /// Mean wall-clock milliseconds per frame.
    #[must_use]
    pub fn ms_per_frame(&self) -> f64 {
        1e3 * self.seconds / f64::from(self.frames.max(1))
    }

    /// Median wall-clock milliseconds per frame.
    #[must_use]
    pub fn median_ms_per_frame(&self) -> f64 {
        1e3 * self.median_frame_seconds
    }

    /// Points advanced by one step per wall-clock second, at the median frame time: the usual
    /// throughput figure of cloth simulators, comparable across grid sizes and step counts.
    #[must_use]
    pub fn particle_steps_per_sec(&self) -> f64 {
        self.points as f64 * f64::from(self.steps_per_frame) / self.median_frame_seconds
    }

    /// Simulated time per wall-clock time at the median frame time: above 1 the cloth runs
    /// faster than real time.
    #[must_use]
    pub fn realtime_factor(&self) -> f64 {
        self.frame_time / self.median_frame_seconds
    }
}

/// Runs `run.warmup_frames` untimed frames, then times `run.frames` frames of `solver` on
/// `state` (which it advances).
///
/// # Errors
/// The first [`SolveError`] of any frame.
pub fn time_frames(
    solver: &mut dyn Solver,
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    state: &mut ClothState,
    run: BenchRun,
) -> Result<BenchResult, SolveError> {
    for _ in 0..run.warmup_frames {
        advance_frame(solver, mesh, colliders, params, state)?;
    }
    // Allocated before the clock starts; one clock reading per frame costs tens of nanoseconds.
    let mut frame_seconds = Vec::with_capacity(run.frames as usize);
    let start = Instant::now();
    let mut frame_start = start;
    for _ in 0..run.frames {
        advance_frame(solver, mesh, colliders, params, state)?;
        let now = Instant::now();
        frame_seconds.push((now - frame_start).as_secs_f64());
        frame_start = now;
    }
    let seconds = start.elapsed().as_secs_f64();
    Ok(BenchResult {
        points: mesh.len(),
        springs: mesh.springs().len(),
        frames: run.frames,
        steps_per_frame: params.steps_per_frame,
        seconds,
        median_frame_seconds: median(&mut frame_seconds).unwrap_or(0.0),
        frame_time: 1.0 / params.frames_per_sec,
    })
}

/// The median of `values` (the mean of the middle two for an even count); `None` when empty.
fn median(values: &mut [f64]) -> Option<f64> {
    values.sort_unstable_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(values[n / 2]),
        _ => Some(0.5 * (values[n / 2 - 1] + values[n / 2])),
    }
}

/// The course's `pinned4` cloth scaled to `n x n` points at the standard cloth's spacing
/// (1/49 m, so the cloth is `(n - 1) / 49` m wide) and thickness, pinned at its four corners.
///
/// Keeping the spacing (rather than squeezing `n` points into 1 m) keeps every point's
/// neighbourhood, stretch and self-contact the same as in the standard scene, so the cost per
/// point measured on a big grid is the cost per point of the course's cloth. `n = 50` is exactly
/// `pinned4`.
///
/// # Errors
/// [`MeshError`] when `n < 2` or `n * n` exceeds [`cloth_mesh::MAX_POINTS`].
pub fn pinned_grid(n: usize) -> Result<ClothMesh, MeshError> {
    let last = n.saturating_sub(1);
    let size = last as f64 / 49.0;
    ClothMesh::new(&GridSpec {
        width: size,
        height: size,
        num_width_points: n,
        num_height_points: n,
        thickness: 0.0095,
        orientation: Orientation::Horizontal,
        pinned: vec![(0, 0), (last, 0), (0, last), (last, last)],
        ..GridSpec::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pinned_grid_of_50_is_the_courses_pinned4() {
        let mesh = pinned_grid(50).unwrap();
        assert_eq!(mesh.spec().width, 1.0);
        assert_eq!(mesh.springs().len(), 14_502);
        assert_eq!(mesh.pinned().iter().filter(|&&p| p).count(), 4);
        // The big cloth: 256 x 256 has 390,658 springs.
        assert_eq!(pinned_grid(256).unwrap().springs().len(), 390_658);
        assert!(pinned_grid(1).is_err());
    }

    #[test]
    fn throughput_figures_follow_from_the_timing() {
        let r = BenchResult {
            points: 2500,
            springs: 14_502,
            frames: 90,
            steps_per_frame: 30,
            seconds: 0.09,
            median_frame_seconds: 0.0008,
            frame_time: 1.0 / 90.0,
        };
        // Mean 1 ms per frame. Median 0.8 ms: 2500 * 30 steps in 0.8 ms = 93.75 M/s, and a
        // frame of 1/90 s simulated in 0.8 ms = 13.9 x real time.
        assert!((r.ms_per_frame() - 1.0).abs() < 1e-12);
        assert!((r.median_ms_per_frame() - 0.8).abs() < 1e-12);
        assert!((r.particle_steps_per_sec() - 93.75e6).abs() < 1e-3);
        assert!((r.realtime_factor() - 1.0 / 90.0 / 0.0008).abs() < 1e-9);
    }

    #[test]
    fn the_median_is_the_middle_value() {
        assert_eq!(median(&mut []), None);
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
        // One frame slowed down by another process moves the mean, not the median.
        assert_eq!(median(&mut [1.0, 1.0, 50.0, 1.0, 1.0]), Some(1.0));
    }
}
