//! XPBD for the CS184 mass-spring cloth: a solver crate written only against clothsim's public
//! APIs, as an outside author would write one.
//!
//! # Method
//!
//! Extended position-based dynamics (Macklin, Müller and Chentanez 2016, "XPBD: Position-Based
//! Simulation of Compliant Constrained Dynamics"). Each spring of the course's model is a
//! distance constraint `C = |x_a - x_b| - L` with the compliance `alpha = 1 / k` of the spring it
//! replaces (`k = ks` for structural and shearing springs, `0.2 ks` for bending ones; a disabled
//! kind, or `ks = 0`, is no constraint at all).
//!
//! A step of `dt = params.dt()` is split into substeps of `h = dt / n`, as many as bring `h`
//! down to the course's step (`n = ceil(30 / steps_per_frame)`: one at the course's 30 steps
//! per frame, 30 at one step per frame) but no more than the step's `iterations` sweeps, which
//! the substeps share (`iterations / n` each, at least one). Substeps rather than more sweeps
//! (Macklin et al. 2019, "Small Steps in Physics Simulation"): for the same number of sweeps
//! they converge the stiff springs better, and they let the collisions and the stretch limit,
//! which the course applies at its own step, act at that step: applied once per frame-long
//! step, the course's per-step friction is thirty times too weak and the cloth slides off the
//! sphere, and the limit, applied after a long step's worth of stretching, leaves the cloth far
//! past it. Each substep:
//!
//! 1. prediction, with the course's damping as a drag and gravity as the only external force:
//!    `p = x + e^(-c h)(x - x_prev) + g h^2` for unpinned points, `p = x` for pinned ones,
//!    where `c` is [`StepParams::drag_rate`] and `x - x_prev` is the displacement over the
//!    substep before (the state's `x - x_last` scaled by `h / dt` at the first);
//! 2. Gauss-Seidel sweeps over the springs in the course's order, each spring with its
//!    multiplier `lambda` (zero at the start of the substep) and `alpha~ = alpha / h^2`:
//!    `dlambda = (-C - alpha~ lambda) / (w_a + w_b + alpha~)`, `lambda += dlambda`,
//!    `p_a += w_a dlambda n`, `p_b -= w_b dlambda n`, with `w = 1/m` (0 when pinned) and `n`
//!    the unit vector from `b` to `a`;
//! 3. self-collision through the shared [`SpatialHash`] (each substep counting as one of the
//!    frame's steps), the collision objects ([`apply_colliders`]) and the course's 10 %
//!    stretch limit ([`limit_stretch`]), each when the parameters ask for it, as the reference
//!    solver does at each of its steps;
//! 4. `x_prev = x`, `x = p`.
//!
//! At the end of the step `x_last` is the start of the step when there was one substep, and
//! otherwise `x - n (x - x_prev)`: the last substep's velocity over the whole step, which the
//! next step (or another solver) reads as `(x - x_last) / dt`.
//!
//! # Properties
//!
//! The multipliers make the stiffness independent of the iteration count and the step (PBD's
//! flaw): at a static equilibrium `C = -alpha~ lambda` with the constraint force
//! `lambda / dt^2`, which is Hooke's law `f = -k C`, so a hanging spring stretches by `m g / k`
//! as the mass-spring model says. With few iterations the sweep does not converge and the cloth
//! looks softer and more damped, never unstable: every update moves points towards satisfying
//! a constraint, so large steps (one per frame) stay bounded.
//!
//! The multipliers start from zero each substep, so what the sweeps of one substep do not carry
//! from the middle of the cloth to its pins is lost: with too few sweeps for the grid a hanging
//! cloth creeps down instead of coming to rest. The entry's defaults, one step per frame and 30
//! sweeps, are thirty substeps of one sweep, at the course's own step.
//!
//! The course loses `damping` % of the velocity per step, which ties the damping to the step
//! size: at one step per frame a cloth would keep 30 times less drag than the course gives it at
//! its 30 steps per frame. Read as the drag rate `c` that the course's factor implies at its own
//! step, `e^(-c dt)` equals `1 - damping/100` at 30 steps per frame and keeps the same decay per
//! second at any step, as the implicit solvers do; 100 % (an infinite rate) holds the cloth still.

use cloth_solver::{
    ClothMesh, ClothState, Collider, MAX_STRETCH, OptionError, OptionKind,
    REFERENCE_STEPS_PER_FRAME, SolveError, Solver, SolverEntry, SolverOption, SpatialHash,
    StepParams, StepReport, Vec3, apply_colliders, limit_stretch,
};
use serde_json::Value;

/// Gauss-Seidel sweeps per step of [`Xpbd::new`].
pub const DEFAULT_ITERATIONS: u32 = 30;

/// The XPBD solver. Owns only scratch memory: the multipliers and the predicted positions of
/// the step under way, and the self-collision hash.
#[derive(Debug, Default, Clone)]
pub struct Xpbd {
    iterations: u32,
    /// One multiplier per spring, N s^2, reset each step.
    lambda: Vec<f64>,
    /// The predicted, then corrected, positions of the substep.
    predicted: Vec<Vec3>,
    /// The positions at the start of the substep.
    start: Vec<Vec3>,
    /// Each point's displacement over the substep before.
    moved: Vec<Vec3>,
    hash: SpatialHash,
}

impl Xpbd {
    /// The registry entry: `xpbd`, one step per frame, option `iterations`.
    pub const ENTRY: SolverEntry = SolverEntry::new(
        "xpbd",
        "XPBD (Macklin et al. 2016): springs as compliant distance constraints, Gauss-Seidel",
        build,
    )
    .with_steps_per_frame(1)
    .with_options(&[SolverOption {
        name: "iterations",
        description: "Gauss-Seidel sweeps over the springs per step: more is stiffer",
        kind: OptionKind::Integer {
            min: 1,
            max: 1000,
            default: DEFAULT_ITERATIONS as i64,
        },
    }]);

    /// A solver doing [`DEFAULT_ITERATIONS`] sweeps per step.
    #[must_use]
    pub fn new() -> Self {
        Self::with_iterations(DEFAULT_ITERATIONS)
    }

    /// A solver doing `iterations` sweeps per step (0 counts as 1).
    #[must_use]
    pub fn with_iterations(iterations: u32) -> Self {
        Self {
            iterations: iterations.max(1),
            ..Self::default()
        }
    }

    /// Sweeps per step.
    #[must_use]
    pub fn iterations(&self) -> u32 {
        self.iterations
    }
}

fn build(_mesh: &ClothMesh, options: &Value) -> Result<Box<dyn Solver>, OptionError> {
    let iterations = Xpbd::ENTRY.integer(options, "iterations")?;
    // The entry's range (1 to 1000) fits a u32.
    Ok(Box::new(Xpbd::with_iterations(iterations as u32)))
}

impl Solver for Xpbd {
    fn name(&self) -> &'static str {
        "xpbd"
    }

    fn step(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &mut ClothState,
    ) -> Result<StepReport, SolveError> {
        params.validate()?;
        let dt = params.dt();
        let substeps = substeps(params.steps_per_frame, self.iterations);
        let sweeps = (self.iterations / substeps).max(1);
        let h = dt / f64::from(substeps);
        let mass = mesh.point_mass(params.density);
        let inverse_mass = 1.0 / mass;
        // NOTE: at 100 % damping the rate is infinite and `exp` gives exactly 0.
        let keep = (-params.drag_rate() * h).exp();
        let pinned = mesh.pinned();
        let springs = mesh.springs();
        let gravity_step = params.gravity * (h * h);
        // Self-collision divides its push by the steps per frame, so each substep counts as one.
        let collision_steps = params.steps_per_frame.saturating_mul(substeps);

        // The substep's start positions and its displacement over the substep before: the
        // state's velocity, rescaled from the step to the substep.
        self.start.clone_from(&state.positions);
        let to_substep = h / dt;
        self.moved.clear();
        self.moved.extend(
            state
                .positions
                .iter()
                .zip(&state.last)
                .map(|(x, last)| (x - last) * to_substep),
        );
        let mut residual = 0.0_f64;
        for _ in 0..substeps {
            // 1. Prediction.
            self.predicted.clear();
            self.predicted.extend(
                self.start
                    .iter()
                    .zip(&self.moved)
                    .zip(pinned)
                    .map(|((&x, &d), &pin)| if pin { x } else { x + d * keep + gravity_step }),
            );

            // 2. Gauss-Seidel over the distance constraints, in the course's spring order.
            self.lambda.clear();
            self.lambda.resize(springs.len(), 0.0);
            let p = &mut self.predicted;
            for sweep in 0..sweeps {
                let last_sweep = sweep + 1 == sweeps;
                for (s, lambda) in springs.iter().zip(self.lambda.iter_mut()) {
                    let k = params.stiffness(s.kind);
                    if k <= 0.0 {
                        continue;
                    }
                    let (a, b) = (s.a as usize, s.b as usize);
                    let wa = if pinned[a] { 0.0 } else { inverse_mass };
                    let wb = if pinned[b] { 0.0 } else { inverse_mass };
                    let d = p[a] - p[b];
                    let len = d.norm();
                    // NOTE: coincident ends have no direction to push along; skip the spring
                    // this sweep (self-collision keeps points apart, so this is a transient).
                    if wa + wb == 0.0 || len == 0.0 {
                        continue;
                    }
                    let c = len - s.rest;
                    let alpha_tilde = 1.0 / (k * h * h);
                    let dlambda = (-c - alpha_tilde * *lambda) / (wa + wb + alpha_tilde);
                    *lambda += dlambda;
                    let n = d / len;
                    p[a] += n * (wa * dlambda);
                    p[b] -= n * (wb * dlambda);
                    if last_sweep {
                        residual = residual.max((c + alpha_tilde * (*lambda - dlambda)).abs());
                    }
                }
            }

            // 3. The model's other constraints, through the public API, at every substep.
            if params.self_collision {
                self.hash.resolve(mesh, p, collision_steps);
            }
            apply_colliders(colliders, pinned, p, &self.start);
            if params.stretch_limit {
                limit_stretch(springs, pinned, p, MAX_STRETCH);
            }

            // 4. The corrected positions start the next substep.
            for ((d, x), &q) in self.moved.iter_mut().zip(&mut self.start).zip(p.iter()) {
                *d = q - *x;
                *x = q;
            }
        }

        // Commit. One substep: the start-of-step positions become the last ones, exactly (a
        // pinned point's are its position, which nothing above moved). More: the last ones
        // are a step's length behind at the last substep's velocity, which the next step (or
        // the next solver) reads as `(positions - last) / dt`.
        if substeps == 1 {
            std::mem::swap(&mut state.last, &mut state.positions);
        } else {
            let to_step = f64::from(substeps);
            for ((last, x), d) in state.last.iter_mut().zip(&self.start).zip(&self.moved) {
                *last = x - d * to_step;
            }
        }
        state.positions.clone_from(&self.start);
        if let Some(i) = state.first_non_finite() {
            return Err(SolveError::non_finite(mesh, i));
        }
        // The residual is the largest |C + alpha~ lambda| met by the last sweep, metres: how
        // far the step's constraint equations were from solved before its final corrections.
        Ok(StepReport {
            iterations: sweeps * substeps,
            residual,
        })
    }
}

/// Substeps per step: as many as bring the substep down to the course's step (30 per frame at
/// the same frame rate), but no more than the sweeps of a step, of which each substep spends at
/// least one.
fn substeps(steps_per_frame: u32, iterations: u32) -> u32 {
    let reference = REFERENCE_STEPS_PER_FRAME;
    let steps = steps_per_frame.max(1);
    reference.div_ceil(steps).clamp(1, iterations.max(1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn the_entry_reads_its_iteration_count_and_refuses_others() {
        let mesh = ClothMesh::new(&cloth_mesh::GridSpec::default()).unwrap();
        assert!(Xpbd::ENTRY.build(&mesh, &json!({"iterations": 3})).is_ok());
        let e = Xpbd::ENTRY
            .build(&mesh, &json!({"iterations": 0}))
            .err()
            .unwrap();
        assert_eq!(
            e.to_string(),
            "the xpbd solver's option iterations is 0, but it must be an integer from 1 to 1000"
        );
        assert_eq!(Xpbd::with_iterations(0).iterations(), 1);
    }
}
