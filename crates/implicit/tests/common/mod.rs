//! Shared set-up of the implicit solvers' tests.
#![allow(dead_code)]

use cloth_mesh::{ClothMesh, ClothState, GridSpec, Vec3};
use cloth_solver::{SolveError, Solver, StepParams, advance_frame};

/// The course's 1 m horizontal cloth with `n x n` points and the given pins.
pub fn cloth(n: usize, pinned: Vec<(usize, usize)>) -> ClothMesh {
    ClothMesh::new(&GridSpec {
        num_width_points: n,
        num_height_points: n,
        pinned,
        ..GridSpec::default()
    })
    .unwrap()
}

/// The course's `pinned4` pins on an `n x n` grid: the four corners.
pub fn pinned4(n: usize) -> ClothMesh {
    cloth(n, vec![(0, 0), (n - 1, 0), (0, n - 1), (n - 1, n - 1)])
}

/// The course's `pinned2` pins on an `n x n` grid: both ends of row 0.
pub fn pinned2(n: usize) -> ClothMesh {
    cloth(n, vec![(0, 0), (n - 1, 0)])
}

/// The largest distance between corresponding points.
pub fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}

/// Runs frames until a frame moves no point farther than `still` metres, at most `max_frames`;
/// returns the frames run and the last frame's largest move.
pub fn settle(
    solver: &mut dyn Solver,
    mesh: &ClothMesh,
    params: &StepParams,
    state: &mut ClothState,
    still: f64,
    max_frames: usize,
) -> Result<(usize, f64), SolveError> {
    let mut moved = f64::INFINITY;
    for frame in 1..=max_frames {
        let before = state.positions.clone();
        advance_frame(solver, mesh, &[], params, state)?;
        moved = max_distance(&before, &state.positions);
        if moved <= still {
            return Ok((frame, moved));
        }
    }
    Ok((max_frames, moved))
}
