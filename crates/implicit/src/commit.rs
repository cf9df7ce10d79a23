//! What both implicit solvers do around their solve: the inertial prediction before it, and
//! after it the commit of the new positions and the collisions, exactly as Verlet does them.

use cloth_mesh::{ClothMesh, ClothState, Vec3};
use cloth_solver::{Collider, SolveError, SpatialHash, StepParams, apply_colliders};

/// Writes the damped inertial prediction `y = x0 + h v0 / (1 + c h)`, with the velocity
/// `v0 = (x0 - last) / h` of `state`, into `y`: `x0 + (x0 - last) / (1 + c h)`. Pinned points
/// stay where they are.
pub(crate) fn inertial_prediction(
    mesh: &ClothMesh,
    state: &ClothState,
    ch: f64,
    y: &mut Vec<Vec3>,
) {
    y.clear();
    y.extend(
        state
            .positions
            .iter()
            .zip(&state.last)
            .zip(mesh.pinned())
            .map(|((&p, &l), &pin)| if pin { p } else { p + (p - l) / (1.0 + ch) }),
    );
}

/// The step under an infinite drag (damping 100 %, where [`StepParams::drag_rate`] is
/// infinite): the velocity is removed and the free points stay where they are, which is the
/// limit of the backward-Euler step `x1 = x0 + h v1` with `v1 = (v0 + h F / m) / (1 + c h)` as
/// `c` grows without bound. Collisions are still applied, so a cloth left inside an object is
/// pushed out.
///
/// # Errors
/// [`SolveError::NonFinite`] for the first non-finite point.
pub(crate) fn hold_still(
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    state: &mut ClothState,
    hash: &mut SpatialHash,
) -> Result<(), SolveError> {
    let x = state.positions.clone();
    let free: Vec<u32> = (0..mesh.len() as u32)
        .filter(|&i| !mesh.pinned()[i as usize])
        .collect();
    commit(mesh, colliders, params, state, &free, &x, hash)
}

/// Moves the free points to `x` with `last` at their start-of-step positions (so
/// `(positions - last) / h` is the new velocity), then applies self-collision and the collision
/// objects as Verlet does, and checks the result.
///
/// # Errors
/// [`SolveError::NonFinite`] for the first non-finite point.
pub(crate) fn commit(
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    state: &mut ClothState,
    free_points: &[u32],
    x: &[Vec3],
    hash: &mut SpatialHash,
) -> Result<(), SolveError> {
    for &p in free_points {
        let p = p as usize;
        state.last[p] = state.positions[p];
        state.positions[p] = x[p];
    }
    // NOTE: a diverged solve is reported before self-collision, whose spatial hash cannot
    // index non-finite positions.
    if let Some(i) = state.first_non_finite() {
        return Err(SolveError::non_finite(mesh, i));
    }
    if params.self_collision {
        hash.resolve(mesh, &mut state.positions, params.steps_per_frame);
    }
    apply_colliders(colliders, mesh.pinned(), &mut state.positions, &state.last);
    match state.first_non_finite() {
        Some(i) => Err(SolveError::non_finite(mesh, i)),
        None => Ok(()),
    }
}
