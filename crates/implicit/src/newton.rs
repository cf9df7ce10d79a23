//! Newton directions on a step's incremental potential: the conjugate gradient on the true
//! Hessian, its indefinite parts clamped, preconditioned by the constant prefactored matrix.

use cloth_mesh::{MAX_STRETCH, Vec3};

use crate::objective::{CONTACT_GAP, Objective, kind_index, surface_distance};
use crate::topology::NONE;

/// A symmetric 3 x 3 matrix by its six distinct entries.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Sym3 {
    xx: f64,
    yy: f64,
    zz: f64,
    xy: f64,
    xz: f64,
    yz: f64,
}

impl Sym3 {
    /// `along u u^T + across (I - u u^T)` for a unit `u`.
    fn along_across(u: &Vec3, along: f64, across: f64) -> Self {
        let w = along - across;
        Self {
            xx: across + w * u.x * u.x,
            yy: across + w * u.y * u.y,
            zz: across + w * u.z * u.z,
            xy: w * u.x * u.y,
            xz: w * u.x * u.z,
            yz: w * u.y * u.z,
        }
    }

    fn add(&mut self, o: &Self) {
        self.xx += o.xx;
        self.yy += o.yy;
        self.zz += o.zz;
        self.xy += o.xy;
        self.xz += o.xz;
        self.yz += o.yz;
    }

    fn mul(&self, v: &Vec3) -> Vec3 {
        Vec3::new(
            self.xx * v.x + self.xy * v.y + self.xz * v.z,
            self.xy * v.x + self.yy * v.y + self.yz * v.z,
            self.xz * v.x + self.yz * v.y + self.zz * v.z,
        )
    }
}

/// The Hessian's blocks at one configuration and the conjugate gradient's vectors, reused from
/// iteration to iteration.
#[derive(Debug, Default)]
pub(crate) struct NewtonScratch {
    /// Per spring, its block on `d = x_b - x_a` (spring and stretch-limit terms).
    springs: Vec<Sym3>,
    /// Per free point, its mass term on the diagonal plus its contact terms' block.
    points: Vec<Sym3>,
    /// Per self-collision pair, its block on `x_j - x_i`.
    pairs: Vec<Sym3>,
    r: Vec<Vec3>,
    z: Vec<Vec3>,
    p: Vec<Vec3>,
    ap: Vec<Vec3>,
}

impl NewtonScratch {
    /// Doubles this scratch takes for a mesh of `free` free points and `springs` springs, with
    /// room for four self-collision pairs per point.
    pub(crate) fn doubles(free: u64, springs: u64) -> u64 {
        6 * springs + 6 * free + 6 * 4 * free + 4 * 3 * free
    }
}

/// The conjugate gradient stops once its residual is below this share of the gradient: a
/// constant forcing term. Each step's Newton iterations also update the stretch limit's
/// multipliers, and those converge linearly whatever the direction's accuracy, so a loose
/// direction (two or three iterations) costs few more Newton iterations than a tight one and
/// far fewer solves with the factor.
pub(crate) const FORCING: f64 = 0.5;

impl Objective<'_> {
    /// Writes the blocks of the potential's Hessian at `x` into `s`, each clamped to be positive
    /// semi-definite: a spring's `k (u u^T + max(0, 1 - L/l) (I - u u^T))`, at most `k I`
    /// (compressed, its transverse curvature is negative and left out); the stretch limit's
    /// term for its fixed multiplier, at most `w I`; a contact term's `k n n^T` (its transverse
    /// curvature, negative for a sphere's surface and between two points, left out).
    pub(crate) fn hessian_blocks(&self, x: &[Vec3], s: &mut NewtonScratch) {
        let topo = self.topo;
        s.springs.clear();
        for (i, sp) in self.mesh.springs().iter().enumerate() {
            let (a, b) = (sp.a as usize, sp.b as usize);
            let mut block = Sym3::default();
            if topo.free_index[a] == NONE && topo.free_index[b] == NONE {
                s.springs.push(block);
                continue;
            }
            let k = self.params.stiffness(sp.kind);
            let w = self.limits[kind_index(sp.kind)];
            let d = x[b] - x[a];
            let len = d.norm();
            if k != 0.0 && len > 0.0 {
                let across = (1.0 - sp.rest / len).max(0.0);
                block.add(&Sym3::along_across(&(d / len), k, k * across));
            }
            if w > 0.0 {
                let v = d + self.mu[i];
                let r = v.norm();
                let cap = MAX_STRETCH * sp.rest;
                if r > cap {
                    block.add(&Sym3::along_across(&(v / r), w, w * (1.0 - cap / r)));
                }
            }
            s.springs.push(block);
        }
        s.points.clear();
        for (f, &p) in topo.free_points.iter().enumerate() {
            let p = p as usize;
            let m = self.inertia[p];
            let mut block = Sym3 {
                xx: m,
                yy: m,
                zz: m,
                ..Sym3::default()
            };
            let k = (0.5 * self.contact_stiffness[f]).max(self.contact_floor);
            for c in self.colliders {
                if let Some((dist, n)) = surface_distance(c, &self.x0[p], &x[p])
                    && dist - CONTACT_GAP < 0.0
                {
                    block.add(&Sym3::along_across(&n, k, 0.0));
                }
            }
            s.points.push(block);
        }
        s.pairs.clear();
        for &(i, j) in self.pairs {
            let d = x[j as usize] - x[i as usize];
            let len = d.norm();
            let block = if len > 0.0 && self.reach - len > 0.0 {
                Sym3::along_across(&(d / len), self.pair_stiffness, 0.0)
            } else {
                Sym3::default()
            };
            s.pairs.push(block);
        }
    }

    /// `out = H v` for the blocks last written by [`Objective::hessian_blocks`], `v` and `out`
    /// over the free points.
    fn hessian_times(&self, s: &NewtonScratch, v: &[Vec3], out: &mut [Vec3]) {
        let fi = &self.topo.free_index;
        for ((o, b), vi) in out.iter_mut().zip(&s.points).zip(v) {
            *o = b.mul(vi);
        }
        let at = |f: u32| {
            if f == NONE {
                Vec3::zeros()
            } else {
                v[f as usize]
            }
        };
        let couple = |fa: u32, fb: u32, block: &Sym3, out: &mut [Vec3]| {
            let w = block.mul(&(at(fb) - at(fa)));
            if fb != NONE {
                out[fb as usize] += w;
            }
            if fa != NONE {
                out[fa as usize] -= w;
            }
        };
        for (sp, block) in self.mesh.springs().iter().zip(&s.springs) {
            if *block != Sym3::default() {
                couple(fi[sp.a as usize], fi[sp.b as usize], block, out);
            }
        }
        for (&(i, j), block) in self.pairs.iter().zip(&s.pairs) {
            if *block != Sym3::default() {
                couple(fi[i as usize], fi[j as usize], block, out);
            }
        }
    }
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p.dot(q)).sum()
}

/// Solves `H dx = -grad` inexactly for the blocks in `s` by the conjugate gradient started at
/// zero, preconditioned by `precondition` (which overwrites its argument with the constant
/// matrix's inverse times it): at most `max_iterations` iterations, stopping once the residual
/// is below [`FORCING`] times the gradient, and, where `dx` then moves no point farther than
/// `tolerance` (a step that would end the minimisation), below `least_inertia * tolerance`
/// too. The least eigenvalue of `H` is at least the least mass term `least_inertia`, so a
/// residual `r` leaves `dx` within `|r| / least_inertia` of the exact Newton step: the second
/// bound keeps a step that looks converged from being a loose direction's underestimate along
/// a soft mode, and costs iterations only in the last direction of a step. Every iterate of a conjugate gradient started at
/// zero on a positive-definite `H` is a descent direction, so a solve cut short still is.
/// Returns the iterations done; `dx` is zero when not one could be taken.
///
/// # Errors
/// What `precondition` reports.
#[allow(clippy::too_many_arguments)]
pub(crate) fn conjugate_gradient(
    objective: &Objective<'_>,
    s: &mut NewtonScratch,
    grad: &[Vec3],
    dx: &mut [Vec3],
    max_iterations: u32,
    least_inertia: f64,
    tolerance: f64,
    mut precondition: impl FnMut(&mut [Vec3]) -> Result<(), String>,
) -> Result<u32, String> {
    let n = grad.len();
    let mut r = std::mem::take(&mut s.r);
    let mut z = std::mem::take(&mut s.z);
    let mut p = std::mem::take(&mut s.p);
    let mut ap = std::mem::take(&mut s.ap);
    r.clear();
    r.extend(grad.iter().map(|g| -g));
    z.clone_from(&r);
    precondition(&mut z)?;
    p.clone_from(&z);
    ap.resize(n, Vec3::zeros());
    dx.fill(Vec3::zeros());
    let loose = FORCING * dot(grad, grad).sqrt();
    let tight = loose.min(least_inertia * tolerance);
    let mut rz = dot(&r, &z);
    let mut done = 0;
    while done < max_iterations {
        objective.hessian_times(s, &p, &mut ap);
        let pap = dot(&p, &ap);
        if !(pap > 0.0 && rz.is_finite() && rz > 0.0) {
            break;
        }
        done += 1;
        let alpha = rz / pap;
        for ((x, r), (p, ap)) in dx.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&ap)) {
            *x += p * alpha;
            *r -= ap * alpha;
        }
        let residual = dot(&r, &r).sqrt();
        if residual <= tight
            || (residual <= loose && dx.iter().any(|d| d.norm_squared() > tolerance * tolerance))
        {
            break;
        }
        z.clone_from(&r);
        precondition(&mut z)?;
        let next = dot(&r, &z);
        let beta = next / rz;
        rz = next;
        for (p, z) in p.iter_mut().zip(&z) {
            *p = z + *p * beta;
        }
    }
    s.r = r;
    s.z = z;
    s.p = p;
    s.ap = ap;
    Ok(done)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::Topology;
    use cloth_mesh::{ClothMesh, GridSpec, SplitMix64, StepParams};

    #[test]
    fn the_hessian_blocks_are_the_derivative_of_the_gradient_where_nothing_is_clamped() {
        // A 5 x 4 cloth pinned at both ends of row 0, stretched 15 % along x (past the limit, so
        // its term acts) and 5 % along z (in tension, short of the limit), with a jitter of 0.5
        // mm: every spring is in tension, so no transverse term is clamped, and none is within
        // 1e-4 m of the limit's kink. There `H` must be the exact derivative of the gradient.
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 5,
            num_height_points: 4,
            pinned: vec![(0, 0), (4, 0)],
            ..GridSpec::default()
        })
        .unwrap();
        let mut rng = SplitMix64::new(5);
        let x: Vec<Vec3> = mesh
            .start_positions()
            .iter()
            .map(|p| {
                let mut j = || rng.uniform(-5e-4, 5e-4);
                Vec3::new(p.x * 1.15 + j(), p.y + j(), p.z * 1.05 + j())
            })
            .collect();
        let params = StepParams::default();
        let topo = Topology::new(&mesh);
        for s in mesh.springs() {
            let len = (x[s.b as usize] - x[s.a as usize]).norm();
            assert!(len > s.rest, "{s:?} is compressed");
            assert!(
                (len - MAX_STRETCH * s.rest).abs() > 1e-4,
                "{s:?} is at the kink"
            );
        }
        let inertia = vec![500.0; mesh.len()];
        let mut mu = vec![Vec3::zeros(); mesh.springs().len()];
        let diag = vec![0.0; topo.free()];
        let objective = Objective {
            mesh: &mesh,
            topo: &topo,
            params: &params,
            colliders: &[],
            inertia: &inertia,
            y: mesh.start_positions(),
            x0: mesh.start_positions(),
            weight: params.gravity,
            limits: [7000.0, 6000.0, 2000.0],
            mu: &mut mu,
            contact_stiffness: &diag,
            contact_floor: 0.0,
            pairs: &[],
            pair_stiffness: 0.0,
            reach: 0.0,
        };
        let mut scratch = NewtonScratch::default();
        objective.hessian_blocks(&x, &mut scratch);
        let n = topo.free();
        let (mut plus, mut minus) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
        let mut column = vec![Vec3::zeros(); n];
        // Central differences of 1e-7 m: the gradient's third derivatives (~k / L^2, 1e7) leave
        // a truncation of ~1e-7 N/m, rounding of forces of ~1e3 N ~1e-13 / 2e-7 = 5e-7 N/m; the
        // smallest true entries (the bending springs' transverse terms, ~50 N/m) are far above
        // 1e-3 N/m, which passes only a correct Hessian.
        let step = 1e-7;
        for f in 0..n {
            for axis in 0..3 {
                let mut e = vec![Vec3::zeros(); n];
                e[f][axis] = 1.0;
                objective.hessian_times(&scratch, &e, &mut column);
                let p = topo.free_points[f] as usize;
                let mut xp = x.clone();
                xp[p][axis] += step;
                objective.evaluate(&xp, Some(&mut plus));
                let mut xm = x.clone();
                xm[p][axis] -= step;
                objective.evaluate(&xm, Some(&mut minus));
                for g in 0..n {
                    let fd = (plus[g] - minus[g]) / (2.0 * step);
                    let err = (fd - column[g]).norm();
                    assert!(
                        err <= 1e-3,
                        "H[{g}][{f}.{axis}] = {} but finite differences give {fd}",
                        column[g]
                    );
                }
            }
        }
    }
}
