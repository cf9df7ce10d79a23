//! The incremental potential that a fast-implicit step minimises, with its contact terms, and
//! its gradient.

use cloth_mesh::{ClothMesh, Collider, MAX_STRETCH, StepParams, Vec3};

use crate::cholesky::Cholesky;
use crate::lbfgs::{Problem, Update};
use crate::newton::{NewtonScratch, conjugate_gradient};
use crate::topology::{NONE, Topology};

/// The stretch limit's multipliers are updated until no spring is over the limit by more than
/// this share of its rest length (a tenth of the 2 % the check allows over the limit).
pub(crate) const LIMIT_OVERSHOOT_TOLERANCE: f64 = 2e-3;

/// How far outside a collision object's surface its contact term starts to push, metres: the
/// course's surface offset, so that a point the term holds up rests outside the object and a
/// point pressed against it with the force the term's stiffness allows over this distance
/// still does.
pub(crate) const CONTACT_GAP: f64 = cloth_mesh::SURFACE_OFFSET;

/// A point's signed distance to `collider`'s surface, metres, on the side `from` is on, and the
/// unit direction in which it grows; `None` for a point at the sphere's centre, which has no
/// way out.
pub(crate) fn surface_distance(collider: &Collider, from: &Vec3, p: &Vec3) -> Option<(f64, Vec3)> {
    match collider {
        Collider::Sphere(s) => {
            let d = p - s.origin;
            let r = d.norm();
            (r > 0.0).then(|| (r - s.radius, d / r))
        }
        Collider::Plane(pl) => {
            // A point starting exactly on the plane counts as coming from the normal's side, as
            // in the course.
            let side = if (from - pl.point).dot(&pl.normal) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            let n = pl.normal * side;
            Some(((p - pl.point).dot(&n), n))
        }
    }
}

/// Everything the step's incremental potential depends on besides the positions.
pub(crate) struct Objective<'a> {
    pub(crate) mesh: &'a ClothMesh,
    pub(crate) topo: &'a Topology,
    pub(crate) params: &'a StepParams,
    pub(crate) colliders: &'a [Collider],
    /// Per point, its mass term `m (1 + (c + c_f) h) / h^2`, N/m.
    pub(crate) inertia: &'a [f64],
    /// Per point, its prediction.
    pub(crate) y: &'a [Vec3],
    /// The step's start, which also tells each point's side of a plane.
    pub(crate) x0: &'a [Vec3],
    /// A point's weight, `m g`, N.
    pub(crate) weight: Vec3,
    /// The stretch limit's weight per spring kind (zeros with the limit off), N/m.
    pub(crate) limits: [f64; 3],
    /// The stretch limit's scaled multipliers, one vector per spring, m.
    pub(crate) mu: &'a mut [Vec3],
    /// Per free point, the matrix's diagonal, N/m: its contact term with a collision object is
    /// half that, and at least `contact_floor`.
    pub(crate) contact_stiffness: &'a [f64],
    pub(crate) contact_floor: f64,
    /// The self-collision pairs and the stiffness of their term, N/m, and its reach (twice the
    /// thickness), m.
    pub(crate) pairs: &'a [(u32, u32)],
    pub(crate) pair_stiffness: f64,
    pub(crate) reach: f64,
}

/// The kind's index into per-kind arrays.
pub(crate) fn kind_index(kind: cloth_mesh::SpringKind) -> usize {
    match kind {
        cloth_mesh::SpringKind::Structural => 0,
        cloth_mesh::SpringKind::Shearing => 1,
        cloth_mesh::SpringKind::Bending => 2,
    }
}

impl Objective<'_> {
    /// The potential at `x` (every point; pinned ones at their place), J, up to a constant,
    /// and, when `grad` is given, its gradient with respect to the free points (in free-point
    /// order), N.
    pub(crate) fn evaluate(&self, x: &[Vec3], mut grad: Option<&mut [Vec3]>) -> f64 {
        let topo = self.topo;
        if let Some(g) = grad.as_deref_mut() {
            g.fill(Vec3::zeros());
        }
        let mut total = 0.0;
        // Inertia and gravity, measured from the step's start so that the sums stay small
        // next to their differences.
        for (f, &p) in topo.free_points.iter().enumerate() {
            let p = p as usize;
            let m = self.inertia[p];
            let off = x[p] - self.y[p];
            total += 0.5 * m * off.norm_squared() - self.weight.dot(&(x[p] - self.x0[p]));
            if let Some(g) = grad.as_deref_mut() {
                g[f] += off * m - self.weight;
            }
        }
        let starts = self.mesh.start_positions();
        for (i, s) in self.mesh.springs().iter().enumerate() {
            let (a, b) = (s.a as usize, s.b as usize);
            let (fa, fb) = (topo.free_index[a], topo.free_index[b]);
            if fa == NONE && fb == NONE {
                continue;
            }
            let k = self.params.stiffness(s.kind);
            let w = self.limits[kind_index(s.kind)];
            if k == 0.0 && w == 0.0 {
                continue;
            }
            let d = x[b] - x[a];
            let len = d.norm();
            let mut force = Vec3::zeros();
            if k != 0.0 {
                let e = len - s.rest;
                total += 0.5 * k * e * e;
                // NOTE: coincident ends have no direction; the rest direction stands in.
                let u = if len > 0.0 {
                    d / len
                } else {
                    (starts[b] - starts[a]) / s.rest
                };
                force += u * (k * e);
            }
            if w > 0.0 {
                // `w/2 dist(d + mu, ball)^2`: the limit's augmented term for fixed multipliers.
                let out = beyond(d + self.mu[i], MAX_STRETCH * s.rest);
                total += 0.5 * w * out.norm_squared();
                force += out * w;
            }
            if let Some(g) = grad.as_deref_mut() {
                if fb != NONE {
                    g[fb as usize] += force;
                }
                if fa != NONE {
                    g[fa as usize] -= force;
                }
            }
        }
        for (f, &p) in topo.free_points.iter().enumerate() {
            let p = p as usize;
            let k = (0.5 * self.contact_stiffness[f]).max(self.contact_floor);
            for c in self.colliders {
                if let Some((dist, n)) = surface_distance(c, &self.x0[p], &x[p]) {
                    let s = dist - CONTACT_GAP;
                    if s < 0.0 {
                        total += 0.5 * k * s * s;
                        if let Some(g) = grad.as_deref_mut() {
                            g[f] += n * (k * s);
                        }
                    }
                }
            }
        }
        let k = self.pair_stiffness;
        for &(i, j) in self.pairs {
            let (i, j) = (i as usize, j as usize);
            let d = x[j] - x[i];
            let len = d.norm();
            let s = self.reach - len;
            if s <= 0.0 || len == 0.0 {
                continue;
            }
            total += 0.5 * k * s * s;
            if let Some(g) = grad.as_deref_mut() {
                let force = d * (k * s / len);
                let (fi, fj) = (topo.free_index[i], topo.free_index[j]);
                if fj != NONE {
                    g[fj as usize] -= force;
                }
                if fi != NONE {
                    g[fi as usize] += force;
                }
            }
        }
        total
    }
}

/// `v - proj(v)`, `proj` onto the ball `|q| <= cap`.
fn beyond(v: Vec3, cap: f64) -> Vec3 {
    let r = v.norm();
    if r > cap {
        v * (1.0 - cap / r)
    } else {
        Vec3::zeros()
    }
}

/// A step's minimisation: its [`Objective`], the factored matrix that preconditions it and the
/// stretch limit's multiplier update.
pub(crate) struct StepProblem<'a> {
    pub(crate) objective: Objective<'a>,
    pub(crate) chol: &'a mut Cholesky,
    /// Scratch for the solves, three coordinates of each free point (axis-major).
    pub(crate) rhs: &'a mut Vec<f64>,
    /// For Newton's directions: the Hessian's blocks and the conjugate gradient's vectors, and
    /// its iterations per direction at most and the step's tolerance, m; `None` for L-BFGS.
    pub(crate) newton: Option<(&'a mut NewtonScratch, u32, f64)>,
}

/// Overwrites `q` (three coordinates per free point) with `chol`'s inverse times it.
fn solve(chol: &mut Cholesky, rhs: &mut Vec<f64>, q: &mut [Vec3]) -> Result<(), String> {
    let n = q.len();
    rhs.resize(3 * n, 0.0);
    for (f, v) in q.iter().enumerate() {
        for axis in 0..3 {
            rhs[axis * n + f] = v[axis];
        }
    }
    chol.solve_in_place(rhs)?;
    for (f, v) in q.iter_mut().enumerate() {
        *v = Vec3::new(rhs[f], rhs[n + f], rhs[2 * n + f]);
    }
    Ok(())
}

impl Problem for StepProblem<'_> {
    fn evaluate(&self, x: &[Vec3], grad: Option<&mut [Vec3]>) -> f64 {
        self.objective.evaluate(x, grad)
    }

    fn precondition(&mut self, q: &mut [Vec3]) -> Result<(), String> {
        solve(self.chol, self.rhs, q)
    }

    fn has_multipliers(&self) -> bool {
        self.objective.limits.iter().any(|&w| w > 0.0)
    }

    fn newton_direction(
        &mut self,
        x: &[Vec3],
        grad: &[Vec3],
        direction: &mut [Vec3],
    ) -> Result<bool, String> {
        let Some((scratch, max_iterations, tolerance)) = self.newton.as_mut() else {
            return Ok(false);
        };
        self.objective.hessian_blocks(x, scratch);
        let least_inertia = self
            .objective
            .topo
            .free_points
            .iter()
            .map(|&p| self.objective.inertia[p as usize])
            .fold(f64::INFINITY, f64::min);
        let (chol, rhs) = (&mut *self.chol, &mut *self.rhs);
        let done = conjugate_gradient(
            &self.objective,
            scratch,
            grad,
            direction,
            *max_iterations,
            least_inertia,
            *tolerance,
            |q| solve(chol, rhs, q),
        )?;
        Ok(done > 0)
    }

    /// The scaled multipliers' ADMM update (`u <- d + u - proj(d + u)`, the ball `|q| <= 1.1
    /// L`), after every iteration as in the local/global iteration; only the limit's terms
    /// change, so only they are taken out of `value` and `grad` and put back.
    fn update(&mut self, x: &[Vec3], value: &mut f64, grad: &mut [Vec3]) -> Update {
        let o = &mut self.objective;
        if o.limits.iter().all(|&w| w == 0.0) {
            return Update { satisfied: true };
        }
        let mut worst: f64 = 0.0;
        let topo = o.topo;
        for (s, mu) in o.mesh.springs().iter().zip(o.mu.iter_mut()) {
            let (a, b) = (s.a as usize, s.b as usize);
            let (fa, fb) = (topo.free_index[a], topo.free_index[b]);
            let w = o.limits[kind_index(s.kind)];
            if (fa == NONE && fb == NONE) || w == 0.0 {
                continue;
            }
            let cap = MAX_STRETCH * s.rest;
            let d = x[b] - x[a];
            let d2 = d.norm_squared();
            if *mu == Vec3::zeros() && d2 <= cap * cap {
                // Slack with no tension: the term is zero before and after.
                continue;
            }
            worst = worst.max((d2.sqrt() - cap) / s.rest);
            // `old` is the term's `v - proj(v)` before the update, which is also the new
            // multiplier; `out` is the term's after it.
            let old = beyond(d + *mu, cap);
            let out = beyond(d + old, cap);
            *mu = old;
            if old == Vec3::zeros() && out == Vec3::zeros() {
                continue;
            }
            *value += 0.5 * w * (out.norm_squared() - old.norm_squared());
            let change = (out - old) * w;
            if fb != NONE {
                grad[fb as usize] += change;
            }
            if fa != NONE {
                grad[fa as usize] -= change;
            }
        }
        Update {
            satisfied: worst <= LIMIT_OVERSHOOT_TOLERANCE,
        }
    }
}
