//! The spring energy both implicit solvers minimise, with the stretch limit as a stiff
//! one-sided spring.

use cloth_mesh::ClothMesh;
use cloth_solver::{MAX_STRETCH, StepParams};

/// Gravity used to size the stretch limiter when the live gravity is weaker, m/s^2: a cloth in
/// zero gravity still gets a limiter as stiff as on Earth.
const STANDARD_GRAVITY: f64 = 9.8;

/// How far past `1.1 * rest` the limiter lets a spring go under the cloth's whole weight, as a
/// fraction of the shortest rest length (0.1 %, so a spring ends below `1.101 * rest`).
pub const LIMIT_OVERSHOOT: f64 = 1e-3;

/// Stiffness of the one-sided stretch-limit spring, N/m, that acts on every spring (enabled or
/// not, as the course's limit does) from `1.1 * rest` on.
///
/// # Why this value
///
/// A penalty spring lets a constraint be violated by `force / stiffness`. The largest force a
/// single spring can carry at rest is the weight of the whole cloth, `W = M g` (all of it
/// hanging from one spring), so `k_lim = W / (LIMIT_OVERSHOOT * L_min)` keeps every spring
/// below `(1.1 + 0.001) * rest` in any static state: 7.2e7 N/m for the course's 50 x 50 cloth.
/// It is never less than `100 ks`, so the limiter dominates the spring it limits. Stiffer would
/// only slow Newton (the Hessian's condition number grows with `k_lim h^2 / m`, about 1.4e5
/// at one step per frame, harmless for a double-precision Cholesky); softer would let heavy
/// cloths sag visibly past the limit.
#[must_use]
pub fn limiter_stiffness(mesh: &ClothMesh, params: &StepParams) -> f64 {
    let total_mass = mesh.point_mass(params.density) * mesh.len() as f64;
    let weight = total_mass * params.gravity.norm().max(STANDARD_GRAVITY);
    let shortest = mesh
        .springs()
        .iter()
        .map(|s| s.rest)
        .fold(f64::INFINITY, f64::min);
    (weight / (LIMIT_OVERSHOOT * shortest)).max(100.0 * params.ks)
}

/// The energy law of one spring: `k/2 (l - L)^2 + k_lim/2 max(0, l - 1.1 L)^2` of its length `l`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SpringLaw {
    /// Spring constant, N/m (0 when its type is switched off).
    pub(crate) k: f64,
    /// Rest length, m.
    pub(crate) rest: f64,
    /// Limiter stiffness, N/m (0 when the stretch limit is off).
    pub(crate) k_lim: f64,
}

impl SpringLaw {
    /// Energy, J, at length `len`.
    pub(crate) fn energy(self, len: f64) -> f64 {
        let e = len - self.rest;
        let over = (len - MAX_STRETCH * self.rest).max(0.0);
        0.5 * self.k * e * e + 0.5 * self.k_lim * over * over
    }

    /// Tension `dE/dl`, N (positive when the spring pulls its ends together).
    pub(crate) fn tension(self, len: f64) -> f64 {
        let over = (len - MAX_STRETCH * self.rest).max(0.0);
        self.k * (len - self.rest) + self.k_lim * over
    }

    /// The Hessian block with respect to the spring vector `d`, as `along u u^T + across
    /// (I - u u^T)`: `along = d^2E/dl^2`, `across = max(0, T / l)` with `T` the tension.
    ///
    /// NOTE: the exact `across` is `T / l`, negative under compression (`l < L`), which makes
    /// the Hessian indefinite; clamping it at 0 keeps the Newton matrix positive definite (the
    /// mass term then makes it strictly so) at the price of a slower, still descending, step
    /// for compressed springs.
    pub(crate) fn hessian(self, len: f64) -> (f64, f64) {
        let active = len > MAX_STRETCH * self.rest;
        let along = self.k + if active { self.k_lim } else { 0.0 };
        let across = (self.tension(len) / len).max(0.0);
        (along, across)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tension_and_stiffness_are_the_derivatives_of_the_energy() {
        let law = SpringLaw {
            k: 5000.0,
            rest: 0.02,
            k_lim: 7e7,
        };
        // Central differences with step 1e-9 m, away from the kinks at L and 1.1 L: a piecewise
        // quadratic has no truncation error there, and rounding is about eps * E / step
        // (2e-16 * 2e3 J / 1e-9 m = 4e-4 N against tensions of 5e5 N, i.e. 1e-9 relative), so
        // a relative 1e-6 can only fail on a wrong derivative.
        let step = 1e-9;
        for len in [0.015, 0.021, 0.0225, 0.03] {
            let t = (law.energy(len + step) - law.energy(len - step)) / (2.0 * step);
            assert!((t - law.tension(len)).abs() <= 1e-6 * law.tension(len).abs().max(1.0));
            let s = (law.tension(len + step) - law.tension(len - step)) / (2.0 * step);
            assert!((s - law.hessian(len).0).abs() <= 1e-6 * s.abs());
        }
    }
}
