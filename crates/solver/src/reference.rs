//! The course's step, written as plainly as the model states it: the reference every fast path
//! of [`Verlet`](crate::Verlet) is held to.
//!
//! This module is the twin of the model's section 4 ("One simulation step, in this order"): the
//! points and springs as the course lays them out ([`ClothMesh::springs`] in its emission order),
//! and its loops in its order, spring by spring and point by point:
//!
//! 1. forces: gravity on every point, then every enabled spring pulls its ends together by
//!    `k (|pa - pb| - rest)`, in spring order;
//! 2. damped Verlet on the unpinned points;
//! 3. self-collision through a plain spatial hash (a map from box to the points in it, filled in
//!    index order), then every unpinned point in index order, each seeing the corrections made
//!    before it;
//! 4. the collision objects, point by point;
//! 5. the 10 % stretch limit, one in-place sweep in spring order.
//!
//! It allocates, hashes with the standard library's map and takes square roots it could skip:
//! it is written to be read and to be right, not to be fast. The solver's tests run it beside
//! the fast path and require the same bits.

use std::collections::HashMap;

use cloth_mesh::{ClothMesh, ClothState, Vec3};

use crate::MAX_STRETCH;
use crate::{Collider, SolveError, SpatialHash, StepParams};

/// Advances `state` by one step of `params.dt()` seconds, exactly as the course's step does.
///
/// # Errors
/// [`SolveError`] when `params` are out of range or the step left a non-finite position.
pub fn reference_step(
    mesh: &ClothMesh,
    colliders: &[Collider],
    params: &StepParams,
    state: &mut ClothState,
) -> Result<(), SolveError> {
    params.validate()?;
    let pinned = mesh.pinned();
    let mass = mesh.point_mass(params.density);
    let dt = params.dt();
    let positions = &mut state.positions;

    // 1. Forces: the external force, then the springs in their emission order (the order of the
    //    sums is part of the result).
    let mut forces = vec![params.gravity * mass; positions.len()];
    for s in mesh.springs() {
        let k = params.stiffness(s.kind);
        if k == 0.0 {
            continue;
        }
        let (a, b) = (s.a as usize, s.b as usize);
        let d = positions[b] - positions[a];
        let len = d.norm();
        // NOTE: a spring of zero length has no direction to pull along (the course would make
        // NaN here); it exerts no force.
        if len == 0.0 {
            continue;
        }
        // Pulls a towards b when stretched.
        let f = d * (k * (len - s.rest) / len);
        forces[a] += f;
        forces[b] -= f;
    }

    // 2. Damped Verlet on the unpinned points; the old position becomes the last one.
    let keep = 1.0 - params.damping / 100.0;
    let scale = dt * dt / mass;
    for i in 0..positions.len() {
        if pinned[i] {
            continue;
        }
        let x = positions[i];
        positions[i] = x + (x - state.last[i]) * keep + forces[i] * scale;
        state.last[i] = x;
    }

    // 3. Self-collision.
    if params.self_collision {
        self_collide(mesh, positions, params.steps_per_frame);
    }

    // 4. Collision objects; the last positions stay as they are.
    for (i, p) in positions.iter_mut().enumerate() {
        if pinned[i] {
            continue;
        }
        for c in colliders {
            if let Some(q) = c.resolve(state.last[i], *p) {
                *p = q;
            }
        }
    }

    // 5. Provot's stretch limit: every spring, enabled or not, in spring order, in place.
    if params.stretch_limit {
        for s in mesh.springs() {
            let (a, b) = (s.a as usize, s.b as usize);
            let d = positions[b] - positions[a];
            let len = d.norm();
            let max = MAX_STRETCH * s.rest;
            if len <= max {
                continue;
            }
            let excess = d * ((len - max) / len);
            match (pinned[a], pinned[b]) {
                (true, true) => {}
                (true, false) => positions[b] -= excess,
                (false, true) => positions[a] += excess,
                (false, false) => {
                    let half = excess * 0.5;
                    positions[a] += half;
                    positions[b] -= half;
                }
            }
        }
    }

    match state.first_non_finite() {
        Some(i) => Err(SolveError::non_finite(mesh, i)),
        None => Ok(()),
    }
}

/// The course's self-collision: a map from each box to its points, built from the positions
/// after the Verlet update; then every unpinned point, in index order, moves by the average of
/// its repulsions from the other points of its box closer than `2 * thickness`, divided by the
/// steps per frame. A point reads the others' current positions, so it sees the corrections of
/// the points before it.
fn self_collide(mesh: &ClothMesh, positions: &mut [Vec3], steps_per_frame: u32) {
    let (w, h, t) = SpatialHash::box_size(mesh);
    let box_of = |p: &Vec3| {
        (
            (p.x / w).floor() as i64,
            (p.y / h).floor() as i64,
            (p.z / t).floor() as i64,
        )
    };
    let mut boxes: HashMap<(i64, i64, i64), Vec<usize>> = HashMap::new();
    let keys: Vec<_> = positions.iter().map(box_of).collect();
    for (i, key) in keys.iter().enumerate() {
        boxes.entry(*key).or_default().push(i);
    }
    let reach = 2.0 * mesh.thickness();
    let steps = f64::from(steps_per_frame);
    for (i, key) in keys.iter().enumerate() {
        if mesh.pinned()[i] {
            continue;
        }
        let p = positions[i];
        let mut correction = Vec3::zeros();
        let mut count = 0u32;
        for &j in &boxes[key] {
            if j == i {
                continue;
            }
            let d = p - positions[j];
            let dist = d.norm();
            // NOTE: coincident points (dist == 0) have no direction to separate along; the
            // course would make NaN here, this skips the pair.
            if dist < reach && dist > 0.0 {
                correction += d * ((reach - dist) / dist);
                count += 1;
            }
        }
        if count > 0 {
            positions[i] = p + correction / f64::from(count) / steps;
        }
    }
}
