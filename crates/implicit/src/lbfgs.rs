//! Limited-memory BFGS over the free points' positions, with a constant initial Hessian (the
//! prefactored projective-dynamics matrix) and a backtracking (Armijo) line search: Liu,
//! Bouaziz and Kavan 2017, "Quasi-Newton methods for real-time simulation of hyperelastic
//! materials".

use std::collections::VecDeque;

use cloth_mesh::Vec3;

/// The Armijo constant: a step must lower the objective by at least this share of what its
/// slope promises.
const ARMIJO: f64 = 1e-4;

/// The relative rounding of the objective that a step's decrease may hide, for the
/// approximate Wolfe condition of Newton's line search.
const ROUNDING: f64 = 1e-12;

/// The approximate Wolfe condition's bound on the slope at the trial, over the slope at the
/// start (`2 delta - 1` with Hager and Zhang's `delta = 0.1`, negated).
const APPROXIMATE_WOLFE: f64 = 0.8;

/// Halvings of the step the line search tries before it gives up on a direction.
const MAX_HALVINGS: u32 = 30;

/// What [`Lbfgs::minimise`] minimises.
pub(crate) trait Problem {
    /// The objective at `x` and, given `grad`, its gradient with respect to the free points
    /// written into it.
    fn evaluate(&self, x: &[Vec3], grad: Option<&mut [Vec3]>) -> f64;

    /// Overwrites `q` with the initial inverse Hessian times `q`.
    ///
    /// # Errors
    /// A message when the solve fails.
    fn precondition(&mut self, q: &mut [Vec3]) -> Result<(), String>;

    /// Writes a Newton direction at `x` (with the objective's gradient `grad` there) into
    /// `direction` and returns true, or returns false to have the iteration take the L-BFGS
    /// direction instead (the default).
    ///
    /// # Errors
    /// A message when a solve fails.
    fn newton_direction(
        &mut self,
        _x: &[Vec3],
        _grad: &[Vec3],
        _direction: &mut [Vec3],
    ) -> Result<bool, String> {
        Ok(false)
    }

    /// Whether [`Problem::update`] changes the objective between iterations.
    fn has_multipliers(&self) -> bool {
        false
    }

    /// Called after each accepted iteration, at its result `x` with the objective's `value`
    /// and gradient `grad` there: may change the objective (a multiplier update), bringing
    /// `value` and `grad` up to date, and says whether the constraints it holds are met well
    /// enough to stop.
    fn update(&mut self, _x: &[Vec3], _value: &mut f64, _grad: &mut [Vec3]) -> Update {
        Update { satisfied: true }
    }
}

/// What [`Problem::update`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Update {
    /// The constraints are met within their tolerance.
    pub(crate) satisfied: bool,
}

/// One curvature pair: the step `s`, the change of gradient `t` and `1 / (t . s)`.
#[derive(Debug)]
struct Pair {
    s: Vec<Vec3>,
    t: Vec<Vec3>,
    rho: f64,
}

/// The minimiser's memory and scratch, reused from step to step.
#[derive(Debug, Default)]
pub(crate) struct Lbfgs {
    pairs: VecDeque<Pair>,
    spare: Vec<Pair>,
    alpha: Vec<f64>,
    direction: Vec<Vec3>,
    grad: Vec<Vec3>,
    trial_grad: Vec<Vec3>,
    trial: Vec<Vec3>,
}

/// How a minimisation ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Outcome {
    /// Iterations taken.
    pub(crate) iterations: u32,
    /// The largest move of a point in the last iteration, m.
    pub(crate) residual: f64,
    /// Whether it stopped on the tolerance (or on a minimum that rounding cannot improve).
    pub(crate) converged: bool,
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p.dot(q)).sum()
}

impl Lbfgs {
    /// Curvature pairs kept (Liu et al. use 5).
    pub(crate) const HISTORY: usize = 5;

    /// Minimises `objective` over the free points `free` of `x` (whose other points stay),
    /// from `x`, in at most `max_iterations` iterations: each a quasi-Newton direction whose
    /// initial inverse Hessian is `solve` (which overwrites its argument with the constant
    /// matrix's inverse times it), or the problem's Newton direction where it gives one
    /// ([`Problem::newton_direction`]; no curvature pairs are then kept), and a step along it
    /// halved until the objective falls by the Armijo share of the slope. Stops once an iteration's full step (not halved) moves no
    /// point farther than `tolerance`, or once no step along a descent direction lowers the
    /// objective in floating point.
    ///
    /// Every accepted step lowers the objective, so it ends no higher than it started, but for
    /// the last, whose step moves no point farther than the tolerance and whose change is below
    /// the objective's rounding.
    ///
    /// After each iteration the problem may change its objective ([`Problem::update`]); the
    /// iterations then go on from the same point on the new objective, keeping the curvature
    /// pairs, and stop only once the constraints it holds are met too.
    ///
    /// # Errors
    /// What the preconditioner reports.
    pub(crate) fn minimise(
        &mut self,
        x: &mut [Vec3],
        free: &[u32],
        max_iterations: u32,
        tolerance: f64,
        problem: &mut impl Problem,
    ) -> Result<Outcome, String> {
        let n = free.len();
        while let Some(p) = self.pairs.pop_front() {
            self.spare.push(p);
        }
        self.grad.resize(n, Vec3::zeros());
        self.trial_grad.resize(n, Vec3::zeros());
        self.direction.resize(n, Vec3::zeros());
        self.trial.clear();
        self.trial.extend_from_slice(x);
        let mut value = problem.evaluate(x, Some(&mut self.grad));
        let mut outcome = Outcome {
            iterations: 0,
            residual: f64::INFINITY,
            converged: false,
        };
        if n == 0 {
            outcome.residual = 0.0;
            outcome.converged = true;
            return Ok(outcome);
        }
        let mut satisfied = true;
        while outcome.iterations < max_iterations {
            outcome.iterations += 1;
            let newton = problem.newton_direction(x, &self.grad, &mut self.direction)?;
            if !newton {
                self.two_loop(problem)?;
            }
            let mut slope = dot(&self.direction, &self.grad);
            if slope.is_nan() || slope >= 0.0 {
                // The curvature pairs no longer describe a convex model here: start afresh.
                while let Some(p) = self.pairs.pop_front() {
                    self.spare.push(p);
                }
                self.two_loop(problem)?;
                slope = dot(&self.direction, &self.grad);
                if slope.is_nan() || slope >= 0.0 {
                    outcome.converged = slope == 0.0;
                    outcome.residual = 0.0;
                    break;
                }
            }
            let full = self.direction.iter().map(Vec3::norm).fold(0.0, f64::max);
            // NOTE: a full step that moves no point farther than the tolerance is the last one
            // (if the constraints are met), and is taken whole: along a descent direction, so
            // it lowers the objective in exact arithmetic, by less than the objective's
            // rounding, which the line search's test could not see. Refusing it would leave a
            // cloth that is almost at rest stuck short of its equilibrium.
            let last = full <= tolerance;
            let mut step = 1.0;
            let mut accepted = None;
            for _ in 0..=MAX_HALVINGS {
                for (&p, d) in free.iter().zip(&self.direction) {
                    self.trial[p as usize] = x[p as usize] + d * step;
                }
                let v = problem.evaluate(&self.trial, Some(&mut self.trial_grad));
                // NOTE: near a minimum a Newton step's decrease falls below the objective's
                // rounding (a spring's energy is summed from lengths rounded at 1e-16 of a
                // metre) before the step falls below a tight tolerance; there the slope along
                // the direction at the trial, which rounding does not hide, decides instead
                // (Hager and Zhang's approximate Wolfe condition), so that the iterations still
                // reach the minimum. A rise it lets through is within rounding of the value.
                let rounding = ROUNDING * value.abs();
                // NOTE: with multipliers that change the objective after every iteration, a
                // rise within rounding lets the iterations circle; there the trial must not rise.
                let allowed = if problem.has_multipliers() {
                    0.0
                } else {
                    rounding
                };
                let flat = newton
                    && satisfied
                    && v <= value + allowed
                    && -step * slope <= rounding
                    && dot(&self.direction, &self.trial_grad) <= APPROXIMATE_WOLFE * -slope;
                if last || flat || v <= value + ARMIJO * step * slope {
                    accepted = Some(v);
                    break;
                }
                step *= 0.5;
            }
            let Some(v) = accepted else {
                // No step lowers the objective in floating point: this is its minimum as far
                // as rounding lets it be found.
                outcome.residual = 0.0;
                outcome.converged = satisfied;
                break;
            };
            if newton {
                for &p in free {
                    x[p as usize] = self.trial[p as usize];
                }
                std::mem::swap(&mut self.grad, &mut self.trial_grad);
                value = v;
                outcome.residual = full * step;
                let update = problem.update(x, &mut value, &mut self.grad);
                satisfied = update.satisfied;
                if last && satisfied {
                    outcome.converged = true;
                    break;
                }
                continue;
            }
            // The curvature pair of this step.
            let mut pair = self.spare.pop().unwrap_or_else(|| Pair {
                s: Vec::new(),
                t: Vec::new(),
                rho: 0.0,
            });
            pair.s.clear();
            pair.t.clear();
            pair.s.extend(self.direction.iter().map(|d| d * step));
            pair.t
                .extend(self.trial_grad.iter().zip(&self.grad).map(|(a, b)| a - b));
            let curvature = dot(&pair.s, &pair.t);
            for (&p, _) in free.iter().zip(&self.direction) {
                x[p as usize] = self.trial[p as usize];
            }
            std::mem::swap(&mut self.grad, &mut self.trial_grad);
            value = v;
            if curvature > 0.0 {
                pair.rho = 1.0 / curvature;
                if self.pairs.len() == Self::HISTORY {
                    self.spare.extend(self.pairs.pop_front());
                }
                self.pairs.push_back(pair);
            } else {
                self.spare.push(pair);
            }
            outcome.residual = full * step;
            let update = problem.update(x, &mut value, &mut self.grad);
            satisfied = update.satisfied;
            if last && satisfied {
                outcome.converged = true;
                break;
            }
        }
        Ok(outcome)
    }

    /// `direction = -H grad`, `H` the L-BFGS inverse Hessian of the kept pairs over the
    /// constant matrix's inverse.
    fn two_loop(&mut self, problem: &mut impl Problem) -> Result<(), String> {
        let q = &mut self.direction;
        q.clone_from(&self.grad);
        self.alpha.clear();
        for pair in self.pairs.iter().rev() {
            let a = pair.rho * dot(&pair.s, q);
            for (qi, ti) in q.iter_mut().zip(&pair.t) {
                *qi -= ti * a;
            }
            self.alpha.push(a);
        }
        problem.precondition(q)?;
        for (pair, &a) in self.pairs.iter().zip(self.alpha.iter().rev()) {
            let b = pair.rho * dot(&pair.t, q);
            for (qi, si) in q.iter_mut().zip(&pair.s) {
                *qi += si * (a - b);
            }
        }
        for qi in q.iter_mut() {
            *qi = -*qi;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quartic well per point: `a_i / 2 |x_i - c_i|^2 + |x_i - c_i|^4 / 4`.
    struct Quartic {
        c: Vec<Vec3>,
        a: Vec<f64>,
    }
    impl Problem for Quartic {
        fn evaluate(&self, x: &[Vec3], g: Option<&mut [Vec3]>) -> f64 {
            let mut v = 0.0;
            let mut grad = vec![Vec3::zeros(); x.len()];
            for i in 0..x.len() {
                let d = x[i] - self.c[i];
                v += 0.5 * self.a[i] * d.norm_squared() + 0.25 * d.norm_squared().powi(2);
                grad[i] = d * (self.a[i] + d.norm_squared());
            }
            if let Some(g) = g {
                g.copy_from_slice(&grad);
            }
            v
        }
        fn precondition(&mut self, _q: &mut [Vec3]) -> Result<(), String> {
            Ok(())
        }
    }

    #[test]
    fn minimises_a_quadratic_with_a_poor_initial_hessian_and_only_ever_descends() {
        // f(x) = sum_i a_i / 2 |x_i - c_i|^2 + a quartic coupling; H0 = identity, which is off
        // from the true curvature (1 to 40) by up to forty times.
        let c: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new(f64::from(i), 1.0 - f64::from(i), 0.5))
            .collect();
        let a: Vec<f64> = (0..6).map(|i| 1.0 + 7.8 * f64::from(i)).collect();
        let mut f = Quartic {
            c: c.clone(),
            a: a.clone(),
        };
        let free: Vec<u32> = (0..6).collect();
        let mut x = vec![Vec3::new(3.0, -2.0, 1.0); 6];
        let mut values = vec![f.evaluate(&x, None)];
        let mut solver = Lbfgs::default();
        for _ in 0..200 {
            let out = solver.minimise(&mut x, &free, 1, 1e-12, &mut f).unwrap();
            values.push(f.evaluate(&x, None));
            if out.converged {
                break;
            }
        }
        // Monotone, iteration by iteration (each call is one iteration from a fresh history).
        assert!(values.windows(2).all(|w| w[1] <= w[0]), "{values:?}");
        let mut x = vec![Vec3::new(3.0, -2.0, 1.0); 6];
        let out = solver.minimise(&mut x, &free, 200, 1e-12, &mut f).unwrap();
        assert!(out.converged, "{out:?}");
        // The minimiser is c; the last step below 1e-12 m puts x within a few of that.
        for (p, q) in x.iter().zip(&c) {
            assert!((p - q).norm() < 1e-10, "{p} against {q}");
        }
    }
}
