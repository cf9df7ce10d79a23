//! The course's explicit damped position Verlet: the faithful reference solver.
//!
//! # Method
//!
//! One step of `dt = 1 / (fps * steps_per_frame)` seconds, in the course's order:
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

use cloth_mesh::{ClothMesh, ClothState, Vec3};

use crate::params::MAX_STRETCH;
use crate::{
    Collider, SolveError, Solver, SpatialHash, StepParams, StepReport, apply_colliders,
    limit_stretch,
};

/// The faithful explicit Verlet solver. Owns only scratch memory (forces, the spatial hash).
#[derive(Debug, Default, Clone)]
pub struct Verlet {
    forces: Vec<Vec3>,
    hash: SpatialHash,
}

impl Verlet {
    /// A new solver; its scratch arrays grow on the first step.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
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
        params.validate()?;
        let mass = mesh.point_mass(params.density);
        let dt = params.dt();
        let positions = &mut state.positions;

        // 1. Forces.
        self.forces.clear();
        self.forces.resize(positions.len(), params.gravity * mass);
        for s in mesh.springs() {
            let k = params.stiffness(s.kind);
            if k == 0.0 {
                continue;
            }
            let (a, b) = (s.a as usize, s.b as usize);
            let d = positions[b] - positions[a];
            let len = d.norm();
            if len == 0.0 {
                continue;
            }
            // Pulls a towards b when stretched.
            let f = d * (k * (len - s.rest) / len);
            self.forces[a] += f;
            self.forces[b] -= f;
        }

        // 2. Damped Verlet.
        let keep = 1.0 - params.damping / 100.0;
        let scale = dt * dt / mass;
        for (((p, l), f), &pin) in positions
            .iter_mut()
            .zip(state.last.iter_mut())
            .zip(&self.forces)
            .zip(mesh.pinned())
        {
            if pin {
                continue;
            }
            let x = *p;
            *p = x + (x - *l) * keep + f * scale;
            *l = x;
        }

        // 3. Self-collision.
        if params.self_collision {
            self.hash.resolve(mesh, positions, params.steps_per_frame);
        }

        // 4. Collision objects.
        apply_colliders(colliders, mesh.pinned(), positions, &state.last);

        // 5. Stretch limit.
        if params.stretch_limit {
            limit_stretch(mesh.springs(), mesh.pinned(), positions, MAX_STRETCH);
        }

        match state.first_non_finite() {
            Some(i) => Err(SolveError::non_finite(mesh, i)),
            None => Ok(StepReport::default()),
        }
    }
}
