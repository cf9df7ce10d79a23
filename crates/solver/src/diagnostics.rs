//! Quantities a user watches to see the cloth settle.

use cloth_mesh::{ClothMesh, ClothState};

/// Kinetic energy, joules, from the Verlet velocity `(x - x_last) / dt` and the point mass.
#[must_use]
pub fn kinetic_energy(state: &ClothState, point_mass: f64, dt: f64) -> f64 {
    let sum: f64 = state
        .positions
        .iter()
        .zip(&state.last)
        .map(|(p, l)| (p - l).norm_squared())
        .sum();
    0.5 * point_mass * sum / (dt * dt)
}

/// The largest `length / rest` over all springs (1.1 means a spring at the stretch limit).
#[must_use]
pub fn max_stretch_ratio(mesh: &ClothMesh, state: &ClothState) -> f64 {
    mesh.springs()
        .iter()
        .map(|s| (state.positions[s.a as usize] - state.positions[s.b as usize]).norm() / s.rest)
        .fold(0.0, f64::max)
}
