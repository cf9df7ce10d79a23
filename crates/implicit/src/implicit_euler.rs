//! Backward Euler by Newton's method on the incremental potential.
//!
//! # Method
//!
//! With drag `c` ([`StepParams::drag_rate`]), backward Euler for `m v' = F(x) - c m v` over a
//! step `h` is
//!
//! ```text
//! v1 = v0 + h (F(x1)/m - c v1),   x1 = x0 + h v1
//! ```
//!
//! which is the stationarity condition of the *incremental potential*
//!
//! ```text
//! Phi(x) = (1 + c h) / (2 h^2) |x - y|_M^2 + E(x),   y = x0 + h v0 / (1 + c h),
//! E(x)   = sum_springs [k/2 (|d| - L)^2 + psi(|d|)] - sum_i m g . x_i
//! ```
//!
//! (`y` is the damped inertial prediction, `d = x_b - x_a`, `psi` the stretch limit's term,
//! below). Each step minimises `Phi` over the free points by Newton's method, starting from
//! `y`: the Hessian is the mass term `m (1 + c h) / h^2 I` plus, per spring,
//! `K = E'' u u^T + max(0, T/|d|) (I - u u^T)` on the blocks of its ends (`T` the tension; the
//! clamp keeps `K` positive semi-definite under compression). The system `H dx = -grad Phi` is
//! solved inexactly: by a conjugate gradient preconditioned by the last Cholesky factor
//! (faer's sparse `L L^T`, in single precision where the springs are at least as stiff as the
//! mass term, see `single_precision`, except on a step that starts on the stiff limit, below;
//! the iterations and everything else run in double), kept across iterations, multiplier
//! updates, penalty changes and steps while it still brings the residual below three tenths of
//! the gradient within [`MAX_PCG_ITERATIONS`] iterations and the solves with it have not
//! together spent [`REFACTOR_BUDGET`] iterations beyond the first of each, and refactored at
//! the current `H` otherwise. The fill-reducing ordering and symbolic factor are computed once
//! per topology (points, springs, pins) and again when the factor's precision changes. A backtracking (Armijo) line search on `Phi` makes every iteration
//! a descent step (a preconditioned conjugate gradient started at zero always returns a
//! descent direction of a positive-definite `H`). A Newton solve has converged once a step
//! moves no point farther than the tolerance over the steps per frame ([`NEWTON_TOLERANCE`]),
//! or once the line search finds no decrease that rounding can see; it gives up after
//! [`MAX_NEWTON_ITERATIONS`]. Pinned points are not unknowns: their springs add to their
//! neighbours' diagonal blocks and gradients only.
//!
//! # The stretch limit
//!
//! The course keeps springs at most 10 % over rest by a sweep after each step (Provot's
//! correction): one spring after another, so that later corrections stretch earlier springs
//! again, which a large step outruns and which leaves a falling cloth's springs up to about
//! 1.17 L. Here the limit is a force inside the step's minimisation, on all springs at once and
//! weighed against the mass and the springs. Its model is the stiff one-sided spring
//! `k_lim/2 max(0, g)^2`, `g = |d| - 1.1 L` ([`limiter_stiffness`](crate::limiter_stiffness):
//! the whole cloth's weight stretches a spring at most 0.1 % of its rest length past the
//! limit); the rest states of this solver are that spring's. Newton does not carry `k_lim`
//! while the cloth moves: a spring that starts or stops binding would change the Newton matrix
//! by `k_lim`, which the kept factor no longer approximates. The limit is instead solved by the
//! method of multipliers, with one multiplier `lambda >= 0` (the limit tension, N) per spring
//! and a penalty `rho` per spring from `10 max(ks, m (1 + c h) / h^2)` up to `k_lim`
//! (`limit_penalty` in `spring_energy.rs`), in the term
//!
//! ```text
//! psi(|d|) = (max(0, a + rho g)^2 - a^2) / (2 rho),   a = lambda (1 - rho / k_lim),
//! ```
//!
//! whose force along the spring is `max(0, a + rho g)` (at `rho = k_lim`, `psi` is the stiff
//! spring itself). A step:
//!
//! 1. starts from the last step's multipliers extrapolated along their change over that step,
//!    `max(0, lambda_n + (lambda_n - lambda_(n-1)) / 2)` (a falling cloth's limit tensions
//!    grow from step to step, and a closer start saves multiplier updates, each a Newton
//!    solve; zero after [`Solver::reset`], a change of topology or with the limit off, and the
//!    last step's alone when there is no step before it), and its penalty (below);
//! 2. solves `Phi` by Newton for fixed `lambda` and `rho`;
//! 3. after a converged solve, sets every multiplier to the limit force of the solved state,
//!    `lambda <- max(0, a + rho g)` (fixed point: `lambda = k_lim max(0, g)`, the stiff
//!    spring's tension);
//! 4. stops once no spring is over `1.1 L` by more than [`LIMIT_TOLERANCE`] of its rest
//!    length over the steps per frame and no spring that carries limit tension is short of
//!    `1.1 L` by more than [`SLACK_SHARE`] times that (the limit's solution puts tension only
//!    on springs at the limit), or once every spring still off by more has `rho = k_lim` (its
//!    solve was then of the stiff spring), or after [`MAX_LIMIT_UPDATES`] updates; otherwise
//!    multiplies by 10 (at most `k_lim`) the penalty of each spring off by more than half that
//!    whose error has not fallen to a quarter of the last update's (Bertsekas' rule, spring by
//!    spring), and goes back to 2 from the current positions.
//!
//! Each spring has its own penalty because a cloth that pulls taut converges unevenly: a few
//! hundred springs of its hanging columns take several updates while the rest converge at once.
//! Raised on every spring, the penalty would change the Newton matrix as much on the springs
//! that were already right, and the stiff penalty on springs just inside the limit switches
//! their limit on and off between Newton iterations, which costs line-search halvings and
//! refactorisations; raised only where the limit converges slowly, the matrix changes where it
//! must and the kept factor still preconditions it.
//!
//! Across steps the penalty starts at its least value, except that a step that starts with a spring
//! more than [`LIMIT_TOLERANCE`] past the limit (as the course's sweep, a swap from Verlet or an
//! edit of `ks` leave them) is solved with `rho = k_lim` at once, so that the stretch is taken up
//! by the stiff spring instead of springing back; and a step whose Newton solve did not converge
//! (whose multipliers are therefore left as they were) makes the next one's ten times larger, and a
//! step that moves no point faster than 1 mm/s doubles it; both up to `k_lim`. A cloth at rest thus
//! ends on the stiff spring, whose rest state the multipliers need not reach, while a moving cloth
//! keeps the soft penalty that lets the factor be reused.
//!
//! The friction of a collision object is a drag on the points resting on it at the start of the
//! step, inside `Phi`: such a point's mass term is `m (1 + (c + c_f) h) / h^2`, with its own
//! prediction ([Friction](crate#friction) in the crate's documentation gives the rate `c_f`
//! that stands for the course's per-step friction, and why the course's friction after a large
//! step cannot). After the solve, self-collision is applied as in [`cloth_solver::Verlet`] and
//! the collision objects push points out of them (the resting points without friction, a point
//! that reaches an object during the step with one step's drag), and `last` is set to the
//! start-of-step positions, so that `(positions - last) / h` is the new velocity.
//!
//! # Velocity and solver swaps
//!
//! The velocity is `(positions - last) / h` with the current `h = params.dt()`, exactly
//! Verlet's implied velocity; besides its caches the solver keeps only the limit's multipliers
//! (of the last two steps) and penalty between steps, which start from zero and the least
//! penalty on a new solver. A live swap with Verlet at the same `steps_per_frame` therefore
//! keeps the motion. When `h` changes (a different `steps_per_frame` or `frames_per_sec`),
//! `positions - last` is reinterpreted over the new step, as in the course's own simulator
//! when the steps per frame are edited; call [`retime_velocity`](crate::retime_velocity) first
//! to keep the velocity instead.
//!
//! # Stability
//!
//! Backward Euler is unconditionally stable for this energy: there is no step-size limit like
//! Verlet's `ks < m / (2 dt^2)`. It damps high frequencies numerically (first-order accurate),
//! on top of the drag `c`, which is why large-step runs look softer. For fixed multipliers and
//! penalty, `psi` is convex and continuously differentiable in `|d|` and bounded below by
//! `-a^2 / (2 rho)`, so `Phi` is a well-defined potential, bounded below, with a positive
//! definite Newton matrix, and every Newton iteration is a descent step on it. The multipliers
//! are the limit tensions of a solved state (non-negative and finite), so the force a step
//! carries over is of the size of the forces the last step balanced; a spring that starts far
//! beyond the limit (a swap from Verlet, an edit of `ks`) is pulled back by a force that grows
//! with its excess, and the step cannot overshoot. The limit holds after a large step where a
//! single Provot sweep could not undo a step's worth of stretch. The solver is meant to run at
//! one step per frame.
//!
//! # Damping
//!
//! At 100 % damping the drag rate is infinite: the step keeps the cloth where it is with no
//! velocity (the limit of the damped step as the drag grows), and only the collisions act.

use cloth_mesh::{ClothMesh, ClothState, MAX_STRETCH, Vec3};
use cloth_solver::{Collider, SolveError, Solver, SpatialHash, StepParams, StepReport};

use crate::cholesky::{AnyCholesky, Cholesky};
use crate::commit::{commit, hold_still, predict};
use crate::contact::Contacts;
use crate::memory::{Allocation, try_filled};
use crate::spring_energy::{SpringLaw, limit_penalty, limiter_stiffness};
use crate::topology::{NONE, Topology};

/// By default Newton stops once its step moves no point farther than this per frame, metres:
/// at `steps_per_frame` steps a frame, once a step moves no point farther than this over
/// `steps_per_frame` (a velocity error under `NEWTON_TOLERANCE * frames_per_sec`, 0.9 mm/s at
/// 90 frames per second, whatever the step). 10 um is half a thousandth of a 2 cm spring, far
/// below a terminal cell, and a tenth of the 1 cm/s at which a cloth counts as moving; each
/// iteration costs a linear solve, so a tighter default would mostly buy invisible digits. See
/// [`ImplicitEuler::with_tolerance`].
pub const NEWTON_TOLERANCE: f64 = 1e-5;

/// At most this many Newton iterations per solve (a step solves once, and again after each
/// update of the stretch limit's multipliers); a solve that has not converged by then keeps its
/// last (energy-decreasing) iterate, the step reports its residual and leaves the multipliers
/// as they were.
pub const MAX_NEWTON_ITERATIONS: u32 = 50;

/// At most this many updates of the stretch limit's multipliers per step, each followed by a
/// Newton solve; a step that has not met [`LIMIT_TOLERANCE`] by then keeps its last
/// (energy-decreasing) iterate and carries its multipliers to the next step. Bertsekas' rule
/// takes the penalty from its least value to the stiff limit's in four updates that make no
/// progress (a factor of about 1,400 at the course's defaults), so twelve leave room for as
/// many that do.
pub const MAX_LIMIT_UPDATES: u32 = 12;

/// A step updates the stretch limit's multipliers and solves again while a spring is over
/// `1.1 rest` by more than this fraction of its rest length (or, carrying limit tension, short
/// of it by more than ten times this), divided by the steps per frame:
/// 0.1 % at one step per frame, a hundredth of the limit's own 10 %. Divided, because a spring that
/// each step leaves anywhere within the tolerance moves its ends by up to that much from one
/// step to the next: 20 um on a 2 cm spring, a jitter of 1.8 mm/s at one step per frame that
/// would be 1.8 cm/s at ten, the speed of a cloth that counts as moving; over the steps per
/// frame it stays 1.8 mm/s at any step (as [`NEWTON_TOLERANCE`] does). A looser tolerance lets
/// every spring of a falling cloth's hanging column give a little, and the cloth then drops
/// farther and gathers more kinetic energy than the course's model gives it (the swap test in
/// `tests/stability.rs` bounds that energy by Verlet's: 0.1 % keeps within it, 0.5 % does
/// not). Once the cloth rests (no point faster than 1 mm/s) the penalty grows
/// to the stiff limit's, which holds every spring within
/// [`LIMIT_OVERSHOOT`](crate::LIMIT_OVERSHOOT) of the limit.
pub const LIMIT_TOLERANCE: f64 = 0.001;

/// A step that moves no point faster than this, m/s, counts as at rest for the stretch limit's
/// penalty, which then doubles each step up to the stiff limit's `k_lim` (a tenth of the 1 cm/s
/// at which a cloth counts as settled).
const RESTING_SPEED: f64 = 1e-3;

/// A spring's limit penalty grows by this factor after a multiplier update that did not take
/// its error down to [`ERROR_DECREASE`] of the last one (Bertsekas' rule), and every
/// spring's for the next step after a step whose Newton solve did not converge.
const PENALTY_GROWTH: f64 = 10.0;

/// The fraction of its last error (see [`SLACK_SHARE`]) a multiplier update must leave a
/// spring for its penalty to stay.
const ERROR_DECREASE: f64 = 0.25;

/// A spring's penalty grows only while its error (see [`SLACK_SHARE`]) is over this share of
/// [`LIMIT_TOLERANCE`]: a spring well inside the tolerance needs no stiffer penalty, and one
/// that nears it gets one an update before it would keep the step from ending.
const RAISE_SHARE: f64 = 0.5;

/// A spring that carries limit tension while shorter than the limit is off the limit's
/// solution (where a spring under the limit carries none) by its shortfall over this: the step
/// solves again while a tensed spring is short of the limit by more than `SLACK_SHARE` times
/// [`LIMIT_TOLERANCE`] of its rest length (1 % at one step per frame). The multipliers leave
/// such tension on a spring that the motion has just slackened after it was pulled hard; held
/// up by it, the cloth springs back and gains kinetic energy that the converged step does not
/// give it (the swap tests in `tests/stability.rs` bound that energy). Looser than
/// [`LIMIT_TOLERANCE`]: each update it forces is a Newton solve, and a few tenths of a
/// millimetre of slack in a tensed spring store little energy.
const SLACK_SHARE: f64 = 10.0;

/// A step's multipliers start from the last step's limit tensions moved on by this share of
/// their change over the last step: a falling cloth's tensions grow from step to step, and
/// each multiplier update a step saves is a Newton solve. Half the change, rather than all of
/// it, because the trend turns where the cloth swings back, and a tension overestimated there
/// costs updates of its own.
const MULTIPLIER_TREND: f64 = 0.5;

/// Armijo's sufficient-decrease constant.
const ARMIJO: f64 = 1e-4;

/// Halvings of the line search before giving up on an iteration (step scaled by 2^-40).
const MAX_HALVINGS: u32 = 40;

/// At most this many conjugate-gradient iterations with the last factor as preconditioner
/// before the matrix is refactored: a preconditioner that needs more describes a matrix too far
/// from the current one, and a fresh factor is then cheaper than more iterations.
pub const MAX_PCG_ITERATIONS: u32 = 6;

/// The kept factor is replaced once the solves with it have together needed this many
/// conjugate-gradient iterations beyond the first of each: about what one numeric
/// factorisation costs on the course's grid (each iteration is two triangular solves with the
/// factor and a product with the matrix), so a factor that has become a poor preconditioner is
/// not paid for again and again.
pub const REFACTOR_BUDGET: u32 = 16;

/// The inexact Newton step is accepted once the linear residual is below this fraction of the
/// gradient (a constant forcing term: Newton then converges linearly at about this rate, and
/// the line search keeps every iteration a descent). The step tolerance is met within a few
/// iterations more than with a tighter forcing, each of which costs fewer conjugate-gradient
/// iterations and lets the kept factor serve longer before it is replaced.
const FORCING: f64 = 0.3;

/// The implicit (backward Euler) solver: Newton's method with a line search on the incremental
/// potential, on faer's sparse Cholesky. See the module documentation for the method.
///
/// Owns only caches (the topology and the symbolic factor) and scratch memory.
#[derive(Debug)]
pub struct ImplicitEuler {
    tolerance: f64,
    system: Option<System>,
    /// The gradient of `Phi` (3 per free point).
    grad: Vec<f64>,
    /// Lower-triangle values of the Newton matrix, in the block pattern's order.
    values: Vec<f64>,
    /// The negated gradient, then the Newton step (3 per free point).
    rhs: Vec<f64>,
    /// The conjugate gradient's residual, preconditioned residual and direction, and the
    /// matrix times the direction (3 per free point each).
    cg: [Vec<f64>; 4],
    y: Vec<Vec3>,
    x: Vec<Vec3>,
    trial: Vec<Vec3>,
    /// The stretch limit's multipliers, N, one per spring: the limit tensions of the last
    /// step, from which the next one's warm start is extrapolated.
    lambda: Vec<f64>,
    /// The limit tensions of the step before the last (empty when there was none since the
    /// multipliers were last dropped).
    lambda_before: Vec<f64>,
    /// The factor on the limit's least penalty for the next step.
    stiffening: f64,
    /// Each spring's error after the last multiplier update, as a share of its rest length: how
    /// far it is past the limit, or a tensed spring's shortfall over [`SLACK_SHARE`]
    /// (Bertsekas' rule compares the next one with it).
    limit_error: Vec<f64>,
    /// The points resting on collision objects, and the colliders that finish a step.
    contacts: Contacts,
    /// Per point, its mass term with the drag of the friction it rests on (scratch lent to
    /// each step's [`Problem`]).
    point_inertia: Vec<f64>,
    hash: SpatialHash,
}

/// The cached linear system of one topology.
#[derive(Debug)]
struct System {
    topo: Topology,
    chol: AnyCholesky,
    /// The block pattern (a copy of the factor's, borrowed while assembling and multiplying).
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Whether the factor holds a matrix of the current parameters' kind: any factor of a
    /// positive-definite matrix is a valid preconditioner, this only says one exists.
    factored: bool,
    /// Conjugate-gradient iterations beyond the first of each solve since the last
    /// factorisation (see [`REFACTOR_BUDGET`]).
    extra: u32,
}

/// Everything one Newton step needs besides positions.
struct Problem<'a> {
    mesh: &'a ClothMesh,
    topo: &'a Topology,
    laws: Vec<SpringLaw>,
    /// `m (1 + c h) / h^2`, N/m: the mass term of a point that rests on nothing, the least
    /// of them.
    inertia: f64,
    /// Per point, `m (1 + (c + c_f) h) / h^2`, N/m, with the drag rate `c_f` of the friction
    /// it rests on ([`Contacts`]).
    point_inertia: Vec<f64>,
    /// `m g`, N.
    weight: Vec3,
    /// Scratch of [`Problem::assemble`]: each spring's length, m, and its inverse.
    lengths: Vec<(f64, f64)>,
}

impl ImplicitEuler {
    /// A new solver with the default [`NEWTON_TOLERANCE`]; its caches are built on the first
    /// step.
    #[must_use]
    pub fn new() -> Self {
        Self::with_tolerance(NEWTON_TOLERANCE)
    }

    /// A new solver whose Newton iterations stop once a step moves no point farther than
    /// `tolerance` metres over the steps per frame (`tolerance` itself at one step per frame;
    /// non-finite or negative values mean the default).
    #[must_use]
    pub fn with_tolerance(tolerance: f64) -> Self {
        let tolerance = if tolerance.is_finite() && tolerance >= 0.0 {
            tolerance
        } else {
            NEWTON_TOLERANCE
        };
        Self {
            tolerance,
            system: None,
            grad: Vec::new(),
            values: Vec::new(),
            rhs: Vec::new(),
            cg: Default::default(),
            y: Vec::new(),
            x: Vec::new(),
            trial: Vec::new(),
            lambda: Vec::new(),
            lambda_before: Vec::new(),
            stiffening: 1.0,
            limit_error: Vec::new(),
            contacts: Contacts::default(),
            point_inertia: Vec::new(),
            hash: SpatialHash::default(),
        }
    }

    /// Bytes this solver allocates for `mesh`: the topology, the block matrix's pattern and
    /// values, its Cholesky factor and workspace, and the per-point and per-spring scratch. The
    /// factor's size comes from faer's symbolic analysis of the scalar pattern (one unknown per
    /// point), whose fill each 3 x 3 block repeats nine times over; the self-collision hash, the
    /// same as Verlet's, is not counted.
    ///
    /// The analysis takes memory in proportion to the scalar pattern (a small part of the
    /// total); when even that fails, the estimate is `u64::MAX`.
    #[must_use]
    pub fn memory_estimate(mesh: &ClothMesh) -> u64 {
        let topo = Topology::new(mesh);
        let (col_ptr, row_idx) = topo.scalar_pattern();
        let Ok(scalar) = Cholesky::<f64>::analyse(&col_ptr, &row_idx, 1) else {
            return u64::MAX;
        };
        Self::estimate(&topo, mesh, scalar.factor_len() as u64)
    }

    /// [`ImplicitEuler::memory_estimate`] from the topology and the scalar factor's length.
    fn estimate(topo: &Topology, mesh: &ClothMesh, scalar_factor: u64) -> u64 {
        let n = topo.free() as u64;
        let nbrs = topo.neighbours.len() as u64;
        // Block pattern: 6 entries per diagonal block's lower triangle, 9 per neighbour block.
        let entries = 6 * n + 9 * nbrs;
        let pattern = 8 * (2 * (3 * n + 1) + 2 * entries);
        let values = 8 * entries;
        // Each scalar entry of L becomes a 3 x 3 block, less the upper triangles of the
        // diagonal blocks; the workspace is of the order of the largest supernode, bounded by
        // the factor itself. Counted in double precision, the most the factor takes: in single
        // it takes half, and the matrix's values rounded to single (half of `values`) fit in
        // the other half.
        let factor = 8 * (9 * scalar_factor).saturating_sub(3 * n);
        let workspace = factor / 4;
        // grad, rhs and the four conjugate-gradient vectors (3 per free point); y, x and trial
        // (3 per point); the limit's multipliers of the last two steps, the errors, the
        // laws and the lengths (two, one, four and two per spring).
        let scratch = 8 * (6 * 3 * n + 9 * mesh.len() as u64 + 9 * mesh.springs().len() as u64);
        topo.bytes() + pattern + values + factor + workspace + scratch
    }

    /// Makes sure the topology and symbolic factor describe `mesh`, a new factor in single
    /// precision when `single`.
    fn prepare(&mut self, mesh: &ClothMesh, single: bool) -> Result<(), SolveError> {
        if self.system.as_ref().is_some_and(|s| s.topo.matches(mesh)) {
            return Ok(());
        }
        self.system = None;
        self.lambda.clear();
        self.lambda_before.clear();
        let topo = Topology::new(mesh);
        let (col_ptr, row_idx) = topo.block_pattern();
        let chol =
            AnyCholesky::new(col_ptr.clone(), row_idx.clone(), 1, single).map_err(method_error)?;
        self.values =
            try_filled(chol.nnz(), 0.0, "the implicit solver's matrix").map_err(alloc_error)?;
        self.system = Some(System {
            topo,
            chol,
            col_ptr,
            row_idx,
            factored: false,
            extra: 0,
        });
        Ok(())
    }
}

fn alloc_error(a: Allocation) -> SolveError {
    method_error(a.to_string())
}

fn method_error(reason: String) -> SolveError {
    SolveError::Method {
        solver: "implicit",
        reason,
    }
}

impl Default for ImplicitEuler {
    fn default() -> Self {
        Self::new()
    }
}

impl Problem<'_> {
    fn law(&self, s: usize) -> SpringLaw {
        self.laws[s]
    }

    /// `Phi(x) - Phi(y)` up to the spring energy's constant, computed relative to `y` so that
    /// the large `m g . x` terms cancel exactly rather than in rounding.
    fn potential(&self, x: &[Vec3], y: &[Vec3]) -> f64 {
        let mut phi = 0.0;
        for &p in &self.topo.free_points {
            let dx = x[p as usize] - y[p as usize];
            phi += 0.5 * self.point_inertia[p as usize] * dx.norm_squared() - self.weight.dot(&dx);
        }
        for (i, s) in self.mesh.springs().iter().enumerate() {
            let law = self.law(i);
            if law.k == 0.0 && law.rho == 0.0 {
                continue;
            }
            let len = (x[s.b as usize] - x[s.a as usize]).norm();
            phi += law.energy(len);
        }
        phi
    }

    /// Writes `grad Phi` at `x` into `grad` (3 per free point) and, when `values` is given, the
    /// Newton matrix's lower triangle into it.
    fn assemble(
        &mut self,
        x: &[Vec3],
        y: &[Vec3],
        col_ptr: &[usize],
        grad: &mut [f64],
        mut values: Option<&mut [f64]>,
    ) {
        let topo = self.topo;
        if let Some(v) = values.as_deref_mut() {
            v.fill(0.0);
        }
        for (f, &p) in topo.free_points.iter().enumerate() {
            let inertia = self.point_inertia[p as usize];
            let g = (x[p as usize] - y[p as usize]) * inertia - self.weight;
            grad[3 * f..3 * f + 3].copy_from_slice(g.as_slice());
            if let Some(v) = values.as_deref_mut() {
                for c in 0..3 {
                    v[col_ptr[3 * f + c]] += inertia;
                }
            }
        }
        // The lengths first, in a pass of their own: its square roots and divisions do not wait
        // on each other, while in the pass below each spring's would wait on the last one's
        // additions to the matrix.
        self.lengths.clear();
        self.lengths.extend(self.mesh.springs().iter().map(|s| {
            let len = (x[s.b as usize] - x[s.a as usize]).norm();
            (len, 1.0 / len)
        }));
        for (i, s) in self.mesh.springs().iter().enumerate() {
            let law = self.law(i);
            if law.k == 0.0 && law.rho == 0.0 {
                continue;
            }
            let (a, b) = (s.a as usize, s.b as usize);
            let (fa, fb) = (topo.free_index[a], topo.free_index[b]);
            if fa == NONE && fb == NONE {
                continue;
            }
            let d = x[b] - x[a];
            let (len, inv) = self.lengths[i];
            // NOTE: coincident ends have no direction; the energy is not differentiable there
            // and the spring is skipped for this iteration (the mass term keeps H definite).
            if len == 0.0 {
                continue;
            }
            let u = d * inv;
            let (tension, along) = law.tension_and_stiffness(len);
            let f = u * tension;
            // dE/dx_b = T u, dE/dx_a = -T u.
            if fb != NONE {
                add3(grad, fb as usize, &f);
            }
            if fa != NONE {
                add3(grad, fa as usize, &(-f));
            }
            let Some(v) = values.as_deref_mut() else {
                continue;
            };
            // The spring's block, `along u u^T + across (I - u u^T)` with `along = d^2E/dl^2`
            // and `across = max(0, T / l)`, by its lower triangle.
            // NOTE: the exact `across` is `T / l`, negative under compression (`l < L`), which
            // makes the Hessian indefinite; clamping it at 0 keeps the Newton matrix positive
            // definite (the mass term then makes it strictly so) at the price of a slower, still
            // descending, step for compressed springs.
            let across = (tension * inv).max(0.0);
            let w = along - across;
            let (k00, k11, k22) = (
                across + w * u.x * u.x,
                across + w * u.y * u.y,
                across + w * u.z * u.z,
            );
            let (k10, k20, k21) = (w * u.y * u.x, w * u.z * u.x, w * u.z * u.y);
            for fr in [fa, fb] {
                if fr == NONE {
                    continue;
                }
                let f = 3 * fr as usize;
                let (c0, c1, c2) = (col_ptr[f], col_ptr[f + 1], col_ptr[f + 2]);
                v[c0] += k00;
                v[c0 + 1] += k10;
                v[c0 + 2] += k20;
                v[c1] += k11;
                v[c1 + 1] += k21;
                v[c2] += k22;
            }
            let slot = topo.spring_slot[i];
            if slot != NONE {
                // The off-diagonal block is `-K`, symmetric, so column `c` holds `-K`'s row `c`.
                let lo = 3 * fa.min(fb) as usize;
                let t = 3 * slot as usize;
                let (b0, b1, b2) = (
                    col_ptr[lo] + 3 + t,
                    col_ptr[lo + 1] + 2 + t,
                    col_ptr[lo + 2] + 1 + t,
                );
                v[b0] -= k00;
                v[b0 + 1] -= k10;
                v[b0 + 2] -= k20;
                v[b1] -= k10;
                v[b1 + 1] -= k11;
                v[b1 + 2] -= k21;
                v[b2] -= k20;
                v[b2 + 1] -= k21;
                v[b2 + 2] -= k22;
            }
        }
    }
}

/// A symmetric matrix stored as its lower triangle in compressed columns.
struct Matrix<'a> {
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
    values: &'a [f64],
}

impl Matrix<'_> {
    /// `out = A v`.
    fn mul(&self, v: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for j in 0..self.col_ptr.len() - 1 {
            let vj = v[j];
            let mut acc = 0.0;
            for e in self.col_ptr[j]..self.col_ptr[j + 1] {
                let (r, a) = (self.row_idx[e], self.values[e]);
                out[r] += a * vj;
                if r != j {
                    acc += a * v[r];
                }
            }
            out[j] += acc;
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves `A dx = -grad` by the conjugate gradient preconditioned by `factor` (the Cholesky
/// factor of an earlier `A`), writing `dx`; true when the residual fell below
/// [`FORCING`]` |grad|` within `max_iterations`: the iterations it took, or `None`.
///
/// # Errors
/// A solve with the factor failed.
fn pcg(
    a: &Matrix<'_>,
    factor: &mut AnyCholesky,
    grad: &[f64],
    dx: &mut [f64],
    [r, z, p, ap]: &mut [Vec<f64>; 4],
    max_iterations: u32,
) -> Result<Option<u32>, SolveError> {
    let target = FORCING * dot(grad, grad).sqrt();
    dx.fill(0.0);
    for (r, g) in r.iter_mut().zip(grad) {
        *r = -g;
    }
    z.copy_from_slice(r);
    factor.solve_in_place(z).map_err(method_error)?;
    p.copy_from_slice(z);
    let mut rz = dot(r, z);
    for done in 1..=max_iterations {
        a.mul(p, ap);
        let pap = dot(p, ap);
        if !(pap > 0.0 && rz.is_finite()) {
            return Ok(None);
        }
        let alpha = rz / pap;
        for ((x, r), (p, ap)) in dx.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(ap.iter())) {
            *x += alpha * p;
            *r -= alpha * ap;
        }
        if dot(r, r).sqrt() <= target {
            return Ok(Some(done));
        }
        z.copy_from_slice(r);
        factor.solve_in_place(z).map_err(method_error)?;
        let rz_next = dot(r, z);
        let beta = rz_next / rz;
        rz = rz_next;
        for (p, z) in p.iter_mut().zip(z.iter()) {
            *p = z + beta * *p;
        }
    }
    Ok(None)
}

/// Whether the factor kept as preconditioner is computed in single precision, for a step whose
/// mass term per point is `inertia` (N/m) on a cloth of spring constant `ks`: where the springs
/// are at least as stiff as the mass term (one or two steps per frame at the course's
/// defaults). A factor in `f32` streams half the memory through the factorisation and the
/// triangular solves, and the preconditioned iterations, in `f64`, make up for its rounding.
/// Where the mass term dominates, the fill of the factor decays by about `ks / inertia` per
/// elimination level, its far entries fall below `f32`'s normal range, and arithmetic on
/// subnormal numbers makes the single-precision factorisation slower than the double one.
fn single_precision(inertia: f64, ks: f64) -> bool {
    inertia <= ks
}

/// Replaces the last step's limit tensions `lambda` by the warm start of the next step,
/// `max(0, lambda + MULTIPLIER_TREND (lambda - before))` with `before` the tensions of the
/// step before it (`lambda` itself when there is none), and keeps the last step's tensions in
/// `before` for the next call.
fn extrapolate_multipliers(lambda: &mut [f64], before: &mut Vec<f64>) {
    if before.len() == lambda.len() {
        for (l, b) in lambda.iter_mut().zip(before.iter_mut()) {
            let last = *l;
            *l = (last + MULTIPLIER_TREND * (last - *b)).max(0.0);
            *b = last;
        }
    } else {
        before.clear();
        before.extend_from_slice(lambda);
    }
}

fn add3(v: &mut [f64], f: usize, g: &Vec3) {
    v[3 * f] += g.x;
    v[3 * f + 1] += g.y;
    v[3 * f + 2] += g.z;
}

/// `x += alpha dx` on the free points (`dx` stored 3 per free point).
fn apply_step(free_points: &[u32], x: &mut [Vec3], dx: &[f64], alpha: f64) {
    for (&p, d) in free_points.iter().zip(dx.chunks_exact(3)) {
        x[p as usize] += Vec3::new(d[0], d[1], d[2]) * alpha;
    }
}

/// The largest point displacement of a step stored 3 per free point.
fn max_point_norm(dx: &[f64]) -> f64 {
    dx.chunks_exact(3)
        .map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt())
        .fold(0.0, f64::max)
}

impl Solver for ImplicitEuler {
    fn name(&self) -> &'static str {
        "implicit"
    }

    /// Drops the factor kept as the conjugate gradient's preconditioner, so a run after a reset
    /// takes the same path, bit for bit, as a run with a new solver.
    fn reset(&mut self) {
        if let Some(sys) = self.system.as_mut() {
            sys.factored = false;
        }
        self.lambda.clear();
        self.lambda_before.clear();
        self.stiffening = 1.0;
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
        if !inertia.is_finite() {
            hold_still(
                mesh,
                colliders,
                params,
                state,
                &mut self.contacts,
                &mut self.hash,
            )?;
            return Ok(StepReport::default());
        }
        let (k_lim, base) = if params.stretch_limit {
            let k_lim = limiter_stiffness(mesh, params);
            (k_lim, limit_penalty(params, inertia, k_lim))
        } else {
            (0.0, 0.0)
        };
        // A step that starts with a spring already past the limit by more than the tolerance
        // (the course's sweep leaves such springs, so does a swap from Verlet or an edit of
        // `ks`) is solved with the stiff spring itself: a soft penalty would let that stretch
        // spring back and turn it into kinetic energy, which the stiff one absorbs.
        let stretched_start = k_lim > 0.0
            && mesh.springs().iter().any(|s| {
                let len = (state.positions[s.b as usize] - state.positions[s.a as usize]).norm();
                len - MAX_STRETCH * s.rest > LIMIT_TOLERANCE * s.rest
            });
        // A step solved with the stiff limit from its start carries `k_lim` (five orders of
        // magnitude over the mass term at the defaults) on every stretched spring, and a
        // single-precision factor of that matrix preconditions it too coarsely: a cloth taken
        // over from Verlet's fall then gains kinetic energy (the swap test in
        // `tests/stability.rs`). Such a step factors in double.
        let single = single_precision(inertia, params.ks) && !stretched_start;
        self.prepare(mesh, single)?;
        let Some(System {
            topo,
            chol,
            col_ptr,
            row_idx,
            factored,
            extra,
        }) = self.system.as_mut()
        else {
            return Err(method_error("no linear system was built".to_owned()));
        };
        if chol.is_single() != single {
            *chol = AnyCholesky::new(col_ptr.clone(), row_idx.clone(), 1, single)
                .map_err(method_error)?;
            *factored = false;
        }
        let rho = if stretched_start {
            k_lim
        } else {
            (base * self.stiffening).min(k_lim)
        };
        if self.lambda.len() != mesh.springs().len() || rho == 0.0 {
            self.lambda.clear();
            self.lambda.resize(mesh.springs().len(), 0.0);
            self.lambda_before.clear();
        }
        extrapolate_multipliers(&mut self.lambda, &mut self.lambda_before);
        let mut point_inertia = std::mem::take(&mut self.point_inertia);
        predict(
            mesh,
            colliders,
            params,
            state,
            mass,
            &mut self.y,
            &mut point_inertia,
            &mut self.contacts,
        );
        let keep = |rho: f64| if rho > 0.0 { 1.0 - rho / k_lim } else { 0.0 };
        let mut problem = Problem {
            mesh,
            topo,
            laws: mesh
                .springs()
                .iter()
                .zip(&self.lambda)
                .map(|(s, &lambda)| SpringLaw {
                    k: params.stiffness(s.kind),
                    rest: s.rest,
                    rho,
                    offset: lambda * keep(rho),
                })
                .collect(),
            inertia,
            point_inertia,
            weight: params.gravity * mass,
            lengths: Vec::new(),
        };

        self.x.clone_from(&self.y);
        let n = 3 * topo.free();
        self.grad.resize(n, 0.0);
        self.rhs.resize(n, 0.0);
        for v in &mut self.cg {
            v.resize(n, 0.0);
        }
        let mut linear = Linear {
            chol,
            col_ptr,
            row_idx,
            factored,
            extra,
            values: &mut self.values,
            grad: &mut self.grad,
            dx: &mut self.rhs,
            cg: &mut self.cg,
        };

        let tolerance = self.tolerance / f64::from(params.steps_per_frame);
        let limit_tolerance = LIMIT_TOLERANCE / f64::from(params.steps_per_frame);
        let mut iterations = 0;
        let mut residual;
        let mut unconverged = false;
        let mut updates = 0;
        // Each spring's error after the last multiplier update (none yet).
        self.limit_error.clear();
        self.limit_error.resize(mesh.springs().len(), f64::INFINITY);
        loop {
            let solve = newton(
                &mut problem,
                &mut linear,
                &mut self.x,
                &self.y,
                &mut self.trial,
                tolerance,
                MAX_NEWTON_ITERATIONS,
            )?;
            iterations += solve.iterations;
            residual = solve.residual;
            if rho == 0.0 || !residual.is_finite() {
                break;
            }
            if !solve.converged {
                unconverged = true;
                break;
            }
            // The multiplier update: each becomes the limit force the solve's state carries,
            // and each penalty grows by Bertsekas' rule, spring by spring.
            let mut largest: f64 = 0.0;
            let mut soft_left = false;
            for (((s, law), lambda), before) in mesh
                .springs()
                .iter()
                .zip(problem.laws.iter_mut())
                .zip(self.lambda.iter_mut())
                .zip(self.limit_error.iter_mut())
            {
                let len = (self.x[s.b as usize] - self.x[s.a as usize]).norm();
                *lambda = law.limit_force(len);
                // A spring is off its limit's solution when it is past the limit, or when it
                // still carries limit tension while short of it (a tension the multipliers
                // overestimate, which holds the cloth up and lets it spring back), the latter
                // measured against the looser `SLACK_SHARE` of the tolerance.
                let over = law.over(len) / law.rest;
                let error = if *lambda > 0.0 {
                    over.max(-over / SLACK_SHARE)
                } else {
                    over
                };
                largest = largest.max(error);
                soft_left |= error > limit_tolerance && law.rho < k_lim;
                if error > RAISE_SHARE * limit_tolerance && error > ERROR_DECREASE * *before {
                    law.rho = (PENALTY_GROWTH * law.rho).min(k_lim);
                }
                *before = error.max(0.0);
                law.offset = *lambda * keep(law.rho);
            }
            if largest <= limit_tolerance || !soft_left || updates == MAX_LIMIT_UPDATES {
                break;
            }
            updates += 1;
        }
        if k_lim == 0.0 {
            self.stiffening = 1.0;
        } else {
            let moved = topo
                .free_points
                .iter()
                .map(|&p| (self.x[p as usize] - state.positions[p as usize]).norm())
                .fold(0.0, f64::max);
            self.stiffening = if unconverged {
                (PENALTY_GROWTH * self.stiffening).min(k_lim / base)
            } else if moved <= RESTING_SPEED * h {
                (2.0 * self.stiffening).min(k_lim / base)
            } else {
                1.0
            };
        }

        self.point_inertia = problem.point_inertia;
        commit(
            mesh,
            &self.contacts,
            params,
            state,
            &topo.free_points,
            &self.x,
            &mut self.hash,
        )?;
        Ok(StepReport {
            iterations,
            residual,
        })
    }
}

/// The Newton matrix's storage, its factor and the vectors of one linear solve.
struct Linear<'a> {
    chol: &'a mut AnyCholesky,
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
    /// Whether `chol` holds a factor (of this or an earlier matrix).
    factored: &'a mut bool,
    /// Conjugate-gradient iterations beyond the first of each solve since the last
    /// factorisation (see [`REFACTOR_BUDGET`]).
    extra: &'a mut u32,
    values: &'a mut Vec<f64>,
    grad: &'a mut Vec<f64>,
    dx: &'a mut Vec<f64>,
    cg: &'a mut [Vec<f64>; 4],
}

/// What one Newton solve did.
struct Solve {
    /// Newton iterations done.
    iterations: u32,
    /// The last iteration's largest point move, m.
    residual: f64,
    /// Whether the solve stopped within the tolerance (or where rounding leaves no descent).
    converged: bool,
}

/// Minimises `Phi` from `x` by Newton's method with a line search, for the laws of `problem`:
/// at most `max_iterations` iterations, each solving `H dx = -grad` inexactly by the conjugate
/// gradient preconditioned by the kept factor, refactoring when that fails, and stopping once
/// a step moves no point farther than `tolerance`.
///
/// # Errors
/// A factorisation or solve failed.
fn newton(
    problem: &mut Problem<'_>,
    lin: &mut Linear<'_>,
    x: &mut Vec<Vec3>,
    y: &[Vec3],
    trial: &mut Vec<Vec3>,
    tolerance: f64,
    max_iterations: u32,
) -> Result<Solve, SolveError> {
    let free_points = &problem.topo.free_points;
    let mut converged = false;
    let mut iterations = 0;
    // Phi at x when the line search has just computed it.
    let mut phi_x = None;
    let mut residual = 0.0;
    while iterations < max_iterations {
        iterations += 1;
        problem.assemble(x, y, lin.col_ptr, lin.grad, Some(lin.values));
        let matrix = Matrix {
            col_ptr: lin.col_ptr,
            row_idx: lin.row_idx,
            values: lin.values,
        };
        let solved = if *lin.factored && *lin.extra < REFACTOR_BUDGET {
            pcg(
                &matrix,
                lin.chol,
                lin.grad,
                lin.dx,
                lin.cg,
                MAX_PCG_ITERATIONS,
            )?
        } else {
            None
        };
        if let Some(its) = solved {
            *lin.extra += its - 1;
        } else {
            *lin.factored = false;
            lin.chol
                .factorize(lin.values, problem.inertia)
                .map_err(method_error)?;
            *lin.factored = true;
            *lin.extra = 0;
            for (r, g) in lin.dx.iter_mut().zip(lin.grad.iter()) {
                *r = -g;
            }
            lin.chol.solve_in_place(lin.dx).map_err(method_error)?;
        }
        let dx = &*lin.dx;
        residual = max_point_norm(dx);
        if !residual.is_finite() {
            break;
        }
        if residual <= tolerance {
            apply_step(free_points, x, dx, 1.0);
            converged = true;
            break;
        }
        // Armijo backtracking on Phi along dx; the slope grad . dx = -dx^T H dx is < 0.
        let phi0 = phi_x.unwrap_or_else(|| problem.potential(x, y));
        let slope: f64 = lin.grad.iter().zip(dx).map(|(g, d)| g * d).sum();
        let mut alpha = 1.0;
        phi_x = None;
        for _ in 0..=MAX_HALVINGS {
            trial.clone_from(x);
            apply_step(free_points, trial, dx, alpha);
            let phi = problem.potential(trial, y);
            if phi <= phi0 + ARMIJO * alpha * slope {
                phi_x = Some(phi);
                break;
            }
            alpha *= 0.5;
        }
        if phi_x.is_none() {
            // No decrease left that rounding can see: the iterate is as good as it gets.
            converged = true;
            break;
        }
        std::mem::swap(x, trial);
        if alpha * residual <= tolerance {
            converged = true;
            break;
        }
    }
    Ok(Solve {
        iterations,
        residual,
        converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::{GridSpec, SplitMix64};

    /// A 5 x 4 cloth pinned at both ends of row 0, its points moved to `scale` times their
    /// start positions (x by `sx`, z by `sz`) plus a deterministic jitter of up to `jitter` m
    /// on every axis.
    fn deformed(sx: f64, sz: f64, jitter: f64) -> (ClothMesh, Vec<Vec3>) {
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 5,
            num_height_points: 4,
            pinned: vec![(0, 0), (4, 0)],
            ..GridSpec::default()
        })
        .unwrap();
        let mut rng = SplitMix64::new(5);
        let x = mesh
            .start_positions()
            .iter()
            .map(|p| {
                let mut j = || rng.uniform(-jitter, jitter);
                Vec3::new(p.x * sx + j(), p.y + j(), p.z * sz + j())
            })
            .collect();
        (mesh, x)
    }

    fn problem<'a>(mesh: &'a ClothMesh, topo: &'a Topology, params: &StepParams) -> Problem<'a> {
        let h = params.dt();
        let mass = mesh.point_mass(params.density);
        let k_lim = limiter_stiffness(mesh, params);
        Problem {
            mesh,
            topo,
            laws: mesh
                .springs()
                .iter()
                .map(|s| SpringLaw {
                    k: params.stiffness(s.kind),
                    rest: s.rest,
                    rho: k_lim,
                    offset: 0.0,
                })
                .collect(),
            inertia: mass * (1.0 + params.drag_rate() * h) / (h * h),
            point_inertia: vec![mass * (1.0 + params.drag_rate() * h) / (h * h); mesh.len()],
            weight: params.gravity * mass,
            lengths: Vec::new(),
        }
    }

    #[test]
    fn the_assembled_hessian_is_the_derivative_of_the_gradient() {
        // Stretched 15 % along x (limiter active on those springs), 5 % along z (in tension,
        // limiter off), diagonals at ~8.7 %: every spring is in tension, so the clamp is
        // inactive and the assembled matrix must be the exact Hessian.
        let (mesh, x) = deformed(1.15, 1.05, 5e-4);
        let params = StepParams::default();
        let topo = Topology::new(&mesh);
        let mut p = problem(&mesh, &topo, &params);
        for (s, law) in mesh.springs().iter().zip(&p.laws) {
            let len = (x[s.b as usize] - x[s.a as usize]).norm();
            assert!(len > s.rest, "{s:?} is compressed");
            // Central differences must not straddle the kink at 1.1 rest.
            assert!((len - 1.1 * law.rest).abs() > 1e-4, "{s:?} is at the kink");
        }
        let (col_ptr, _) = topo.block_pattern();
        let n = 3 * topo.free();
        let y = mesh.start_positions().to_vec();
        let mut values = vec![0.0; *col_ptr.last().unwrap()];
        let mut grad = vec![0.0; n];
        p.assemble(&x, &y, &col_ptr, &mut grad, Some(&mut values));
        let mut dense = vec![vec![0.0; n]; n];
        let (cp, ri) = topo.block_pattern();
        for j in 0..n {
            for e in cp[j]..cp[j + 1] {
                dense[ri[e]][j] = values[e];
                dense[j][ri[e]] = values[e];
            }
        }
        let scale = dense.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
        // Step 1e-7 m. The gradient is a piecewise-smooth function of the positions; its
        // third derivatives are ~k_lim / L^2 ~ 1e9, so truncation is ~1e-14 * 1e9 = 1e-5 N/m;
        // rounding of gradients of ~1e6 N is ~2e-10 / 2e-7 = 1e-3 N/m. Against a largest
        // entry of ~1e8 N/m, a relative 1e-9 (~0.1 N/m) passes only a correct Hessian: the
        // smallest true terms (mass 515 N/m, bending tension terms ~50 N/m) are far above it.
        let step = 1e-7;
        let mut plus = vec![0.0; n];
        let mut minus = vec![0.0; n];
        for j in 0..n {
            let point = topo.free_points[j / 3] as usize;
            let mut xp = x.clone();
            xp[point][j % 3] += step;
            p.assemble(&xp, &y, &col_ptr, &mut plus, None);
            let mut xm = x.clone();
            xm[point][j % 3] -= step;
            p.assemble(&xm, &y, &col_ptr, &mut minus, None);
            for i in 0..n {
                let fd = (plus[i] - minus[i]) / (2.0 * step);
                let err = (fd - dense[i][j]).abs();
                assert!(
                    err <= 1e-9 * scale,
                    "H[{i}][{j}] = {} but finite differences give {fd}",
                    dense[i][j]
                );
            }
        }
    }

    #[test]
    fn cholesky_succeeds_on_a_compressed_cloth_at_a_huge_step() {
        // Every spring compressed to ~70 %: the exact Hessian's transverse terms are
        // k (1 - L/l) ~ -0.43 k, and at h = 100 s the mass term (6e-6 N/m) cannot make up for
        // them: moving one point out of the cloth's plane is transverse to all its springs, so
        // the exact Hessian is indefinite and only the clamp keeps the matrix definite.
        let (mesh, x) = deformed(0.7, 0.7, 1e-3);
        let params = StepParams {
            steps_per_frame: 1,
            frames_per_sec: 0.01,
            ..StepParams::default()
        };
        let topo = Topology::new(&mesh);
        let mut p = problem(&mesh, &topo, &params);
        let (col_ptr, row_idx) = topo.block_pattern();
        let mut values = vec![0.0; row_idx.len()];
        let mut grad = vec![0.0; 3 * topo.free()];
        p.assemble(&x, &x, &col_ptr, &mut grad, Some(&mut values));
        let mut chol = AnyCholesky::new(col_ptr, row_idx, 1, true).unwrap();
        chol.factorize(&values, p.inertia).unwrap();
        // And the solution is a descent direction: grad . H^-1 grad > 0.
        let mut dx = grad.clone();
        chol.solve_in_place(&mut dx).unwrap();
        let slope: f64 = grad.iter().zip(&dx).map(|(g, d)| g * d).sum();
        assert!(slope > 0.0);
    }

    #[test]
    fn pinned_points_never_move_and_velocity_is_committed_to_last() {
        let (mesh, _) = deformed(1.0, 1.0, 0.0);
        let mut state = ClothState::new(&mesh);
        let params = StepParams {
            steps_per_frame: 1,
            ..StepParams::default()
        };
        let mut solver = ImplicitEuler::new();
        solver.step(&mesh, &[], &params, &mut state).unwrap();
        let before = state.positions.clone();
        solver.step(&mesh, &[], &params, &mut state).unwrap();
        for (i, &pin) in mesh.pinned().iter().enumerate() {
            if pin {
                assert_eq!(state.positions[i], mesh.start_positions()[i]);
            } else {
                // last holds the start-of-step positions: (x - last) / h is the new velocity.
                assert_eq!(state.last[i], before[i]);
            }
        }
    }
}
