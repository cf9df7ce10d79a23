//! Liu et al. 2013, "Fast Simulation of Mass-Spring Systems": backward Euler by local/global
//! iterations with one constant, prefactored matrix.
//!
//! # Method
//!
//! The step minimises the same incremental potential as [`ImplicitEuler`](crate::ImplicitEuler),
//! `Phi(x) = (1 + c h)/(2 h^2) |x - y|_M^2 + E(x)`, `y = x0 + h v0 / (1 + c h)`, using the
//! identity `k/2 (|d| - L)^2 = min_{|p| = L} k/2 |d - p|^2` for each spring vector `d`. Starting
//! from `x = y`, each of the solver's `iterations` iterations does
//!
//! ```text
//! local:   p_s = L_s d_s / |d_s|                        (per spring, closed form)
//! global:  (M (1 + c h) / h^2 + sum_s k_s A_s^T A_s) x
//!              = M (1 + c h) / h^2 y + M g + sum_s A_s^T (k_s p_s - lambda_s u_s)
//! ```
//!
//! where `A_s x = x_b - x_a`. The matrix is the same for the three coordinates and does not
//! depend on `x`: it is factored (faer sparse Cholesky, one scalar unknown per free point) only
//! when `ks`, the density, the step, the drag, a spring toggle or the topology changes, and each
//! iteration is two triangular solves with three right-hand sides. Pinned points are eliminated
//! into the right-hand side.
//!
//! # The stretch limit
//!
//! The limit `|d_s| <= 1.1 L_s` is an inequality constraint on the same minimisation, handled by
//! a multiplier `lambda_s >= 0` per spring (Uzawa / augmented-Lagrangian dual ascent): after each
//! global solve `lambda_s <- max(0, lambda_s + rho_s (|d_s| - 1.1 L_s))`, and the next global
//! step applies the extra tension `lambda_s` along the spring. A stiff penalty spring, as in the
//! Newton solver, would put its stiffness into the constant matrix for every spring, active or
//! not; the local/global iteration then crawls (its convergence factor is about
//! `k_lim / (k_lim + m (1 + c h)/h^2)`, within 1e-4 of 1) and the cloth would freeze. The
//! multiplier keeps the matrix constant and converges to the constrained minimum, the same state
//! the penalty approximates. `rho_s = (m (1 + c h)/h^2 + 2 k_s) / 4` is half the inverse of the
//! largest compliance `|d_s|` can have to a tension on its own spring (that of an isolated pair of
//! points), so a single constraint's update never overshoots. The multipliers are warm-started
//! from the previous step (a cache: [`Solver::reset`] and a solver swap drop it, costing only a
//! few steps of convergence).
//!
//! # Stability
//!
//! Every global step is a convex quadratic solve, so the iteration is stable for any step and
//! stiffness; with few iterations it under-resolves stiff springs, which makes the cloth look
//! softer and more damped, never unstable. The iteration count (the solver's `iterations`
//! option, [`DEFAULT_ITERATIONS`] by default) trades accuracy for speed; at convergence the step equals [`ImplicitEuler`]'s.
//!
//! [`ImplicitEuler`]: crate::ImplicitEuler

use cloth_mesh::{ClothMesh, ClothState, Vec3};
use cloth_solver::{
    Collider, MAX_STRETCH, SolveError, Solver, SpatialHash, StepParams, StepReport,
};

use crate::cholesky::Cholesky;
use crate::commit::{commit, inertial_prediction};
use crate::topology::{NONE, Topology};

/// The fast local/global implicit solver. Owns caches (topology, factored matrix, multiplier
/// warm start) and scratch memory only.
#[derive(Debug)]
pub struct FastImplicit {
    /// Local/global iterations per step (at least 1).
    iterations: u32,
    system: Option<System>,
    /// Tension multipliers of the stretch limit, N, one per spring (warm start).
    lambda: Vec<f64>,
    rhs: Vec<f64>,
    y: Vec<Vec3>,
    x: Vec<Vec3>,
    hash: SpatialHash,
}

/// What the factored matrix depends on besides the topology, as bit patterns so that any
/// change (even to a NaN-free equal value with another sign) refactors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct MatrixKey {
    inertia: u64,
    stiffness: [u64; 3],
}

#[derive(Debug)]
struct System {
    topo: Topology,
    chol: Cholesky,
    col_ptr: Vec<usize>,
    values: Vec<f64>,
    key: Option<MatrixKey>,
}

/// Local/global iterations per step of [`FastImplicit::new`].
pub const DEFAULT_ITERATIONS: u32 = 10;

impl Default for FastImplicit {
    fn default() -> Self {
        Self::with_iterations(DEFAULT_ITERATIONS)
    }
}

impl FastImplicit {
    /// A new solver with [`DEFAULT_ITERATIONS`] iterations per step; its caches are built on the
    /// first step.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// A new solver doing `iterations` local/global iterations per step (0 counts as 1).
    #[must_use]
    pub fn with_iterations(iterations: u32) -> Self {
        Self {
            iterations: iterations.max(1),
            system: None,
            lambda: Vec::new(),
            rhs: Vec::new(),
            y: Vec::new(),
            x: Vec::new(),
            hash: SpatialHash::default(),
        }
    }

    /// Local/global iterations per step.
    #[must_use]
    pub fn iterations(&self) -> u32 {
        self.iterations
    }

    /// Makes sure the topology, the symbolic factor and the numeric factor describe `mesh` and
    /// the current parameters; returns the topology and factor.
    fn prepare(
        &mut self,
        mesh: &ClothMesh,
        params: &StepParams,
        inertia: f64,
    ) -> Result<(), SolveError> {
        if !self.system.as_ref().is_some_and(|s| s.topo.matches(mesh)) {
            self.system = None;
            self.lambda.clear();
            let topo = Topology::new(mesh);
            let (col_ptr, row_idx) = topo.scalar_pattern();
            let chol = Cholesky::new(col_ptr.clone(), row_idx, 3).map_err(method_error)?;
            let values = vec![0.0; chol.nnz()];
            self.system = Some(System {
                topo,
                chol,
                col_ptr,
                values,
                key: None,
            });
        }
        self.lambda.resize(mesh.springs().len(), 0.0);
        let Some(sys) = self.system.as_mut() else {
            return Err(method_error("no linear system was built".to_owned()));
        };
        let key = MatrixKey {
            inertia: inertia.to_bits(),
            stiffness: [
                cloth_mesh::SpringKind::Structural,
                cloth_mesh::SpringKind::Shearing,
                cloth_mesh::SpringKind::Bending,
            ]
            .map(|k| params.stiffness(k).to_bits()),
        };
        if sys.key == Some(key) {
            return Ok(());
        }
        sys.key = None;
        let topo = &sys.topo;
        let v = &mut sys.values;
        v.fill(0.0);
        for f in 0..topo.free() {
            v[sys.col_ptr[f]] = inertia;
        }
        for (s, &slot) in mesh.springs().iter().zip(&topo.spring_slot) {
            let k = params.stiffness(s.kind);
            if k == 0.0 {
                continue;
            }
            let (fa, fb) = (topo.free_index[s.a as usize], topo.free_index[s.b as usize]);
            for f in [fa, fb] {
                if f != NONE {
                    v[sys.col_ptr[f as usize]] += k;
                }
            }
            if slot != NONE {
                v[sys.col_ptr[fa.min(fb) as usize] + 1 + slot as usize] -= k;
            }
        }
        sys.chol.factorize(&sys.values).map_err(method_error)?;
        sys.key = Some(key);
        Ok(())
    }
}

fn method_error(reason: String) -> SolveError {
    SolveError::Method {
        solver: "fast-implicit",
        reason,
    }
}

impl Solver for FastImplicit {
    fn name(&self) -> &'static str {
        "fast-implicit"
    }

    fn reset(&mut self) {
        self.lambda.fill(0.0);
    }

    fn step(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &mut ClothState,
    ) -> Result<StepReport, SolveError> {
        params.validate()?;
        let h = params.dt();
        let c = params.drag_rate();
        let mass = mesh.point_mass(params.density);
        let inertia = mass * (1.0 + c * h) / (h * h);
        self.prepare(mesh, params, inertia)?;
        let Some(sys) = self.system.as_mut() else {
            return Err(method_error("no linear system was built".to_owned()));
        };
        let topo = &sys.topo;
        let n = topo.free();
        let weight = params.gravity * mass;
        if !params.stretch_limit {
            self.lambda.fill(0.0);
        }

        inertial_prediction(mesh, state, c * h, &mut self.y);
        self.x.clone_from(&self.y);
        self.rhs.resize(3 * n, 0.0);
        let starts = mesh.start_positions();

        let mut residual = 0.0;
        for _ in 0..self.iterations {
            // Local step and right-hand side together.
            for (f, &p) in topo.free_points.iter().enumerate() {
                let b = self.y[p as usize] * inertia + weight;
                for axis in 0..3 {
                    self.rhs[axis * n + f] = b[axis];
                }
            }
            for (i, s) in mesh.springs().iter().enumerate() {
                let k = params.stiffness(s.kind);
                let lambda = self.lambda[i];
                if k == 0.0 && lambda == 0.0 {
                    continue;
                }
                let (a, b) = (s.a as usize, s.b as usize);
                let (fa, fb) = (topo.free_index[a], topo.free_index[b]);
                if fa == NONE && fb == NONE {
                    continue;
                }
                let d = self.x[b] - self.x[a];
                let len = d.norm();
                // NOTE: coincident ends have no direction; fall back on the rest direction.
                let u = if len > 0.0 {
                    d / len
                } else {
                    (starts[b] - starts[a]) / s.rest
                };
                // Force on b from the spring's quadratic and the multiplier; a gets the opposite.
                let pull = u * (k * s.rest - lambda);
                if fb != NONE {
                    let mut g = pull;
                    if fa == NONE {
                        g += self.x[a] * k;
                    }
                    add_rhs(&mut self.rhs, n, fb as usize, &g);
                }
                if fa != NONE {
                    let mut g = -pull;
                    if fb == NONE {
                        g += self.x[b] * k;
                    }
                    add_rhs(&mut self.rhs, n, fa as usize, &g);
                }
            }
            // Global step.
            sys.chol
                .solve_in_place(&mut self.rhs)
                .map_err(method_error)?;
            residual = 0.0;
            for (f, &p) in topo.free_points.iter().enumerate() {
                let new = Vec3::new(self.rhs[f], self.rhs[n + f], self.rhs[2 * n + f]);
                residual = f64::max(residual, (new - self.x[p as usize]).norm());
                self.x[p as usize] = new;
            }
            // Dual ascent on the stretch limit.
            if params.stretch_limit {
                for (i, s) in mesh.springs().iter().enumerate() {
                    let (a, b) = (s.a as usize, s.b as usize);
                    if topo.free_index[a] == NONE && topo.free_index[b] == NONE {
                        continue;
                    }
                    let len = (self.x[b] - self.x[a]).norm();
                    let rho = 0.25 * (inertia + 2.0 * params.stiffness(s.kind));
                    let violation = len - MAX_STRETCH * s.rest;
                    self.lambda[i] = (self.lambda[i] + rho * violation).max(0.0);
                }
            }
        }

        commit(
            mesh,
            colliders,
            params,
            state,
            &topo.free_points,
            &self.x,
            &mut self.hash,
        )?;
        Ok(StepReport {
            iterations: self.iterations,
            residual,
        })
    }
}

fn add_rhs(rhs: &mut [f64], n: usize, f: usize, g: &Vec3) {
    rhs[f] += g.x;
    rhs[n + f] += g.y;
    rhs[2 * n + f] += g.z;
}
