//! What both implicit solvers do around their solve: the inertial prediction before it, and
//! after it the commit of the new positions, self-collision as Verlet does it and the
//! collision objects with their friction as a drag ([`Contacts`]).

use cloth_mesh::{ClothMesh, ClothState, Vec3};
use cloth_solver::{Collider, SolveError, SpatialHash, StepParams};

use crate::contact::Contacts;

/// What a step starts from: the points of `state` resting on `colliders` (into `contacts`),
/// each free point's damped inertial prediction `y = x0 + h v0 / (1 + (c + c_f) h)` with the
/// velocity `v0 = (x0 - last) / h` (into `y`: `x0 + (x0 - last) / (1 + (c + c_f) h)`, `c_f` the
/// drag rate of the friction it rests on, 0 for most), and its mass term `m (1 + (c + c_f) h) /
/// h^2` for a point mass `mass` (into `inertia`). Pinned points stay where they are.
#[allow(clippy::too_many_arguments)]
pub(crate) fn predict(
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    state: &ClothState,
    mass: f64,
    y: &mut Vec<Vec3>,
    inertia: &mut Vec<f64>,
    contacts: &mut Contacts,
) {
    let h = params.dt();
    let ch = params.drag_rate() * h;
    y.clear();
    y.extend(
        state
            .positions
            .iter()
            .zip(&state.last)
            .zip(mesh.pinned())
            .map(|((&p, &l), &pin)| if pin { p } else { p + (p - l) / (1.0 + ch) }),
    );
    contacts.find(mesh, colliders, params, state, y);
    let free = mass * (1.0 + ch) / (h * h);
    inertia.clear();
    inertia.extend(contacts.rates().iter().map(|&rate| free + mass * rate / h));
    for (((y, &rate), &p), &l) in y
        .iter_mut()
        .zip(contacts.rates())
        .zip(&state.positions)
        .zip(&state.last)
    {
        if rate > 0.0 {
            *y = p + (p - l) / (1.0 + ch + rate * h);
        }
    }
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
    contacts: &mut Contacts,
    hash: &mut SpatialHash,
) -> Result<(), SolveError> {
    let x = state.positions.clone();
    contacts.find(mesh, colliders, params, state, &x);
    let free: Vec<u32> = (0..mesh.len() as u32)
        .filter(|&i| !mesh.pinned()[i as usize])
        .collect();
    commit(mesh, contacts, params, state, &free, &x, hash)
}

/// Moves the free points to `x` with `last` at their start-of-step positions (so
/// `(positions - last) / h` is the new velocity), then applies self-collision as Verlet does
/// and the collision objects of `contacts` ([`Contacts::resolve`]), and checks the result.
///
/// # Errors
/// [`SolveError::NonFinite`] for the first non-finite point.
pub(crate) fn commit(
    mesh: &ClothMesh,
    contacts: &Contacts,
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
    contacts.resolve(mesh.pinned(), &mut state.positions, &state.last);
    match state.first_non_finite() {
        Some(i) => Err(SolveError::non_finite(mesh, i)),
        None => Ok(()),
    }
}
