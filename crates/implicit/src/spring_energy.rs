//! The spring energy the Newton solver minimises, with the stretch limit as a term whose
//! force offset the solver's multiplier updates set.

use cloth_mesh::ClothMesh;
use cloth_solver::{MAX_STRETCH, StepParams};

/// Gravity used to size the stretch limiter when the live gravity is weaker, m/s^2: a cloth in
/// zero gravity still gets a limiter as stiff as on Earth.
const STANDARD_GRAVITY: f64 = 9.8;

/// How far past `1.1 * rest` the limiter lets a spring rest under the cloth's whole weight, as a
/// fraction of the shortest rest length (0.1 %, so a spring rests below `1.101 * rest`).
pub const LIMIT_OVERSHOOT: f64 = 1e-3;

/// The stretch limit's penalty over the stiffest thing it competes with (see [`limit_penalty`]).
const PENALTY_RATIO: f64 = 10.0;

/// Stiffness of the stretch limit, N/m: at rest a spring over `1.1 * rest` by `g` carries the
/// limit tension `k_lim g`, on every spring (enabled or not, as the course's limit does).
///
/// # Why this value
///
/// A compliant limit lets a constraint be violated by `force / stiffness`. The largest force a
/// single spring can carry at rest is the weight of the whole cloth, `W = M g` (all of it
/// hanging from one spring), so `k_lim = W / (LIMIT_OVERSHOOT * L_min)` keeps every spring
/// below `(1.1 + 0.001) * rest` in any static state: 7.2e7 N/m for the course's 50 x 50 cloth.
/// It is never less than `100 ks`, so the limiter dominates the spring it limits. Stiffer would
/// only slow the Newton solver's steps at rest, where its matrix carries `k_lim` (the condition
/// number grows with `k_lim h^2 / m`, about 1.4e5 at one step per frame, harmless for a
/// double-precision Cholesky; a moving cloth's matrix carries a softer penalty, see the Newton
/// solver); softer would let heavy cloths sag visibly past the limit.
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

/// The least penalty `rho` of the stretch limit's multiplier method, N/m, for a step whose mass
/// term per point is `inertia = m (1 + c h) / h^2`: `10 max(ks, inertia)`, at most `k_lim`
/// (the Newton solver raises it towards `k_lim` when the multipliers converge too slowly and
/// at rest).
///
/// # Why this value
///
/// The multipliers carry the limit's force; the penalty only sets how fast they converge and
/// how far a spring that starts to bind overshoots before they do. One multiplier update takes
/// a multiplier's error down by `(1 - rho / k_lim) / (1 + rho C)`, with `C` the compliance of
/// the spring's length against the rest of the system (at least about `1 / (4 ks + inertia)`
/// on the grid), so `rho = 10 ks` takes it down threefold or more per update (the mass term
/// is 515 N/m at the course's defaults and one step per frame). A much stiffer penalty would
/// make each spring that starts or stops binding a large change of the Newton matrix, which
/// the factor kept as preconditioner no longer approximates; a much softer one would need many
/// updates. At `rho = k_lim` the method is the plain stiff penalty.
pub(crate) fn limit_penalty(params: &StepParams, inertia: f64, k_lim: f64) -> f64 {
    (PENALTY_RATIO * params.ks.max(inertia)).min(k_lim)
}

/// The energy law of one spring, `k/2 (l - L)^2`, with the stretch limit's term of penalty
/// `rho` and force offset `a >= 0` of its length `l`:
///
/// ```text
/// psi(l) = (max(0, a + rho g)^2 - a^2) / (2 rho),   g = l - 1.1 L,
/// ```
///
/// whose force along the spring is `max(0, a + rho g)`: with `a = 0`, the one-sided spring
/// `rho/2 max(0, g)^2`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SpringLaw {
    /// Spring constant, N/m (0 when its type is switched off).
    pub(crate) k: f64,
    /// Rest length, m.
    pub(crate) rest: f64,
    /// The limit's penalty `rho`, N/m (0 when the stretch limit is off).
    pub(crate) rho: f64,
    /// The limit's force offset `a`, N (0 when the limit is off).
    pub(crate) offset: f64,
}

impl SpringLaw {
    /// How far `len` is over the limit, m (negative under it).
    pub(crate) fn over(self, len: f64) -> f64 {
        len - MAX_STRETCH * self.rest
    }

    /// The limit's tension at length `len`, N: `max(0, a + rho g)`.
    pub(crate) fn limit_force(self, len: f64) -> f64 {
        if self.rho == 0.0 {
            return 0.0;
        }
        (self.offset + self.rho * self.over(len)).max(0.0)
    }

    /// Energy, J, at length `len`.
    pub(crate) fn energy(self, len: f64) -> f64 {
        let e = len - self.rest;
        let spring = 0.5 * self.k * e * e;
        if self.rho == 0.0 {
            return spring;
        }
        let g = self.over(len);
        // Both branches are `psi`, the active one written without the cancelling squares.
        let limit = if self.offset + self.rho * g > 0.0 {
            g * (self.offset + 0.5 * self.rho * g)
        } else {
            -self.offset * self.offset / (2.0 * self.rho)
        };
        spring + limit
    }

    /// Tension `dE/dl`, N (positive when the spring pulls its ends together), and the
    /// stiffness `d^2E/dl^2`, N/m, at length `len`.
    pub(crate) fn tension_and_stiffness(self, len: f64) -> (f64, f64) {
        let spring = self.k * (len - self.rest);
        if self.rho == 0.0 {
            return (spring, self.k);
        }
        let limit = self.offset + self.rho * self.over(len);
        if limit > 0.0 {
            (spring + limit, self.k + self.rho)
        } else {
            (spring, self.k)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tension_and_stiffness_are_the_derivatives_of_the_energy() {
        // Without an offset (the kink at 1.1 L = 0.022 m) and with one of 35 kN (the kink at
        // 1.1 L - a / rho = 0.0215 m).
        for offset in [0.0, 3.5e4] {
            check_derivatives(SpringLaw {
                k: 5000.0,
                rest: 0.02,
                rho: 7e7,
                offset,
            });
        }
    }

    fn check_derivatives(law: SpringLaw) {
        // Central differences with step 1e-9 m, away from the kinks at L and the limit's: a
        // piecewise quadratic has no truncation error there, and rounding is about eps * E / step
        // (2e-16 * 2e3 J / 1e-9 m = 4e-4 N against tensions of 5e5 N, i.e. 1e-9 relative), so
        // a relative 1e-6 can only fail on a wrong derivative.
        let step = 1e-9;
        for len in [0.015, 0.021, 0.0225, 0.03] {
            let (tension, stiffness) = law.tension_and_stiffness(len);
            let t = (law.energy(len + step) - law.energy(len - step)) / (2.0 * step);
            assert!((t - tension).abs() <= 1e-6 * tension.abs().max(1.0));
            let s = (law.tension_and_stiffness(len + step).0
                - law.tension_and_stiffness(len - step).0)
                / (2.0 * step);
            assert!((s - stiffness).abs() <= 1e-6 * s.abs());
        }
    }
}
