//! Timing a solver frame by frame: the engine of `clothsim bench` and of the `frames` example.
//!
//! Criterion benches (`benches/`) are the measurement of record; this crate gives the binary a
//! quick, dependency-free way to print ms per frame, particle-steps per second and the real-time
//! factor for any solver behind the [`Solver`] trait, on any cloth (the course's at any size is
//! [`ClothMesh::pinned_grid`]). Wall-clock time is read here, between frames, never
//! inside a solver. It is a tool of the workspace, not part of any solver's API.

use std::time::Instant;

use cloth_mesh::{ClothMesh, ClothState};

use cloth_solver::{Collider, SolveError, Solver, StepParams, advance_frame};

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
    /// Wall-clock seconds of the timed frames, summed.
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
    let mut runs: [(&mut dyn Solver, &mut ClothState); 1] = [(solver, state)];
    let mut timed =
        time_interleaved(&mut runs, mesh, colliders, params, run).map_err(|(_, e)| e)?;
    Ok(timed.swap_remove(0).result)
}

/// The outcome of `frame_seconds.len()` frames of `mesh` at `params`, in `seconds` in all.
fn result(
    mesh: &ClothMesh,
    params: &StepParams,
    seconds: f64,
    frame_seconds: &mut [f64],
) -> BenchResult {
    BenchResult {
        points: mesh.len(),
        springs: mesh.springs().len(),
        frames: frame_seconds.len() as u32,
        steps_per_frame: params.steps_per_frame,
        seconds,
        median_frame_seconds: median(frame_seconds).unwrap_or(0.0),
        frame_time: 1.0 / params.frames_per_sec,
    }
}

/// One run of [`time_interleaved`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterleavedResult {
    /// Its frames, timed as [`time_frames`] times them.
    pub result: BenchResult,
    /// The median over rounds of this run's frame time over the first run's frame time in the
    /// same round (1 for the first run): a speed ratio that the machine's drift, which moves
    /// both frames of a round alike, hardly touches.
    pub time_ratio_to_first: f64,
}

/// [`time_frames`] for several runs on one mesh, each a solver advancing its own state, with their
/// frames taken in turn (with one run, that is [`time_frames`]): every run warms up, then each
/// round times one frame of every run. On a shared machine whose speed drifts by tens of percent
/// within a minute (as cloud machines' do), runs timed one after the other compare moments as much
/// as code; runs timed in turn see the same moments.
///
/// # Errors
/// The index of the run and the first [`SolveError`] of any of its frames.
pub fn time_interleaved(
    runs: &mut [(&mut dyn Solver, &mut ClothState)],
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    run: BenchRun,
) -> Result<Vec<InterleavedResult>, (usize, SolveError)> {
    let each = vec![*params; runs.len()];
    time_interleaved_each(runs, mesh, colliders, &each, run)
}

/// [`time_interleaved`] with parameters of its own for each run (`params[i]` for `runs[i]`):
/// solvers compared at the steps per frame each is meant for. Runs without parameters of
/// their own take the last ones given (or the defaults when none are).
///
/// # Errors
/// The index of the run and the first [`SolveError`] of any of its frames.
///
pub fn time_interleaved_each(
    runs: &mut [(&mut dyn Solver, &mut ClothState)],
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &[StepParams],
    run: BenchRun,
) -> Result<Vec<InterleavedResult>, (usize, SolveError)> {
    let fallback = StepParams::default();
    let at = |i: usize| params.get(i).or(params.last()).unwrap_or(&fallback);
    let seconds = time_in_turn(runs.len(), run, |i| {
        let (solver, state) = &mut runs[i];
        advance_frame(&mut **solver, mesh, colliders, at(i), state).map(|_| ())
    })?;
    Ok(in_turn_results(seconds, mesh, |i| *at(i)))
}

/// Times `run.frames` frames of each of `runs` runs in turn, after `run.warmup_frames` untimed
/// frames of each: `frame(i)` advances run `i` by one frame, whatever steps it (a solver on its
/// state, or an application's whole frame). Returns each run's frame times in seconds.
///
/// # Errors
/// The index of the run and the first error of any of its frames.
pub fn time_in_turn<E>(
    runs: usize,
    run: BenchRun,
    mut frame: impl FnMut(usize) -> Result<(), E>,
) -> Result<Vec<Vec<f64>>, (usize, E)> {
    for i in 0..runs {
        for _ in 0..run.warmup_frames {
            frame(i).map_err(|e| (i, e))?;
        }
    }
    let frames = run.frames as usize;
    let mut frame_seconds = vec![Vec::with_capacity(frames); runs];
    for _ in 0..frames {
        for (i, seconds) in frame_seconds.iter_mut().enumerate() {
            let start = Instant::now();
            frame(i).map_err(|e| (i, e))?;
            seconds.push(start.elapsed().as_secs_f64());
        }
    }
    Ok(frame_seconds)
}

/// The results of frames timed by [`time_in_turn`] on `mesh`, run `i` at `params(i)`: each
/// run's figures and its typical frame's ratio to the first run's in the same round.
#[must_use]
pub fn in_turn_results(
    mut frame_seconds: Vec<Vec<f64>>,
    mesh: &ClothMesh,
    params: impl Fn(usize) -> StepParams,
) -> Vec<InterleavedResult> {
    let first = frame_seconds.first().cloned().unwrap_or_default();
    frame_seconds
        .iter_mut()
        .enumerate()
        .map(|(i, seconds)| {
            let mut ratios: Vec<f64> = seconds.iter().zip(&first).map(|(t, t0)| t / t0).collect();
            let total = seconds.iter().sum();
            InterleavedResult {
                result: result(mesh, &params(i), total, seconds),
                time_ratio_to_first: median(&mut ratios).unwrap_or(1.0),
            }
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

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
    fn interleaved_runs_advance_as_runs_timed_alone() {
        // Taking frames in turn must not change what each run computes: every state ends as a
        // run of its own with the same frames would leave it, bit for bit. The second run is a
        // different solver, so the runs really are independent.
        let mesh = ClothMesh::pinned_grid(10).unwrap();
        let params = StepParams::default();
        let run = BenchRun {
            warmup_frames: 2,
            frames: 3,
        };
        let mut alone = [ClothState::new(&mesh), ClothState::new(&mesh)];
        let mut verlet = cloth_solver::Verlet::new();
        let mut parallel =
            cloth_solver::Verlet::new().with_order(cloth_solver::ConstraintOrder::Parallel);
        time_frames(&mut verlet, &mesh, &[], &params, &mut alone[0], run).unwrap();
        time_frames(&mut parallel, &mesh, &[], &params, &mut alone[1], run).unwrap();

        let (mut a, mut b) = (ClothState::new(&mesh), ClothState::new(&mesh));
        let mut verlet = cloth_solver::Verlet::new();
        let mut parallel =
            cloth_solver::Verlet::new().with_order(cloth_solver::ConstraintOrder::Parallel);
        let mut runs: Vec<(&mut dyn Solver, &mut ClothState)> =
            vec![(&mut verlet, &mut a), (&mut parallel, &mut b)];
        let timed = time_interleaved(&mut runs, &mesh, &[], &params, run).unwrap();
        assert_eq!(a.positions, alone[0].positions);
        assert_eq!(b.positions, alone[1].positions);
        assert_eq!(timed.len(), 2);
        for t in &timed {
            assert_eq!(t.result.frames, 3);
            assert_eq!(t.result.points, 100);
            assert!(t.result.median_frame_seconds > 0.0 && t.result.seconds > 0.0);
            assert!(t.time_ratio_to_first.is_finite() && t.time_ratio_to_first > 0.0);
        }
        // Each round's ratio of the first run to itself is exactly 1.
        assert_eq!(timed[0].time_ratio_to_first, 1.0);
    }

    #[test]
    fn each_interleaved_run_takes_its_own_steps_per_frame() {
        // A run at 3 steps per frame advances exactly as one timed alone at 3 steps, beside a
        // run at 30; the results report each run's own steps.
        let mesh = ClothMesh::pinned_grid(8).unwrap();
        let thirty = StepParams::default();
        let three = StepParams {
            steps_per_frame: 3,
            ..thirty
        };
        let run = BenchRun {
            warmup_frames: 1,
            frames: 2,
        };
        let mut alone = ClothState::new(&mesh);
        time_frames(
            &mut cloth_solver::Verlet::new(),
            &mesh,
            &[],
            &three,
            &mut alone,
            run,
        )
        .unwrap();
        let (mut a, mut b) = (ClothState::new(&mesh), ClothState::new(&mesh));
        let (mut va, mut vb) = (cloth_solver::Verlet::new(), cloth_solver::Verlet::new());
        let mut runs: Vec<(&mut dyn Solver, &mut ClothState)> =
            vec![(&mut va, &mut a), (&mut vb, &mut b)];
        let timed = time_interleaved_each(&mut runs, &mesh, &[], &[thirty, three], run).unwrap();
        assert_eq!(b.positions, alone.positions);
        assert_ne!(a.positions, alone.positions, "30 steps are not 3");
        assert_eq!(timed[0].result.steps_per_frame, 30);
        assert_eq!(timed[1].result.steps_per_frame, 3);
    }

    #[test]
    fn an_interleaved_run_that_fails_is_named_by_its_index() {
        let mesh = ClothMesh::pinned_grid(6).unwrap();
        let params = StepParams::default();
        let mut good = cloth_solver::Verlet::new();
        let mut bad = cloth_solver::Verlet::new();
        let (mut a, mut b) = (ClothState::new(&mesh), ClothState::new(&mesh));
        // A non-finite position makes the second run's first step fail.
        b.positions[7].x = f64::NAN;
        let mut runs: Vec<(&mut dyn Solver, &mut ClothState)> =
            vec![(&mut good, &mut a), (&mut bad, &mut b)];
        let run = BenchRun {
            warmup_frames: 1,
            frames: 1,
        };
        let (index, _) = time_interleaved(&mut runs, &mesh, &[], &params, run).unwrap_err();
        assert_eq!(index, 1);
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
