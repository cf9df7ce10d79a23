//! Backward Euler on one constant, prefactored matrix: the projective-dynamics matrix of Liu et
//! al. 2013, "Fast Simulation of Mass-Spring Systems", as the initial Hessian of an L-BFGS
//! minimisation with a line search (Liu, Bouaziz and Kavan 2017, "Quasi-Newton methods for
//! real-time simulation of hyperelastic materials").
//!
//! The same solver with Newton directions, each a conjugate gradient on the clamped Hessian
//! preconditioned by the same factor, is [`ImplicitEuler`] (`implicit`).
//!
//! # Method
//!
//! The step minimises the incremental potential
//!
//! ```text
//! Phi(x) = sum_i m_i (1 + (c + c_f,i) h) / (2 h^2) |x_i - y_i|^2 - sum_i m g . x_i
//!        + sum_s k_s/2 (|d_s| - L_s)^2 + (the stretch limit's term, below)
//!        + (the contact terms, below)
//! ```
//!
//! with `y_i` the damped prediction, `d_s = x_b - x_a` a spring's vector and `c_f,i` the drag of
//! the friction a point rests on (see [Collisions](#collisions)). The matrix
//!
//! ```text
//! A = M (1 + c h) / h^2 + sum_s (k_s + w_s) A_s^T A_s          (A_s x = x_b - x_a)
//! ```
//!
//! is the Hessian of Liu et al.'s local/global form of the springs' part, the same for the
//! three coordinates and independent of `x`: it is factored (faer sparse Cholesky, one scalar
//! unknown per free point) only when `ks`, the density, the step, the drag, a spring toggle, the
//! stretch limit's switch or level, the set of points in contact with a collision object (whose
//! friction's drag is on the diagonal, see [Collisions](#collisions)) or the topology changes. Each iteration takes the L-BFGS
//! direction (five curvature pairs, two-loop recursion, `A^-1` as the initial inverse Hessian:
//! two triangular solves with three right-hand sides) and halves the step along it until `Phi`
//! falls by the Armijo share of the slope. With no curvature pair the direction is `-A^-1 grad
//! Phi`, which is exactly Liu et al.'s local/global iteration; the pairs correct it for what
//! `A` does not describe (the springs' true curvature, the contact terms).
//! Pinned points are not unknowns. The iterations stop once a full step (not halved) moves no
//! point farther than the tolerance ([`FAST_TOLERANCE`] by default) with the stretch limit met
//! within 0.2 % of rest, or after the iteration count (the solver's `iterations` option,
//! [`DEFAULT_ITERATIONS`] by default), whichever comes first.
//!
//! # The stretch limit
//!
//! The course keeps every spring at most 10 % over its rest length by a sweep after each step
//! (Provot's correction): it moves the ends of each over-long spring back to `1.1 L`, one
//! spring after the other, so a later correction can stretch an earlier spring again, and a
//! falling cloth keeps springs up to about 1.17 L. Here the limit is part of the minimisation
//! instead: the constraint `|d_s| <= 1.1 L_s` on the step's positions, by the augmented term
//! `w_s/2 dist(d_s + u_s, B_s)^2` in `Phi`, `B_s` the allowed ball `|q| <= 1.1 L_s`, with a
//! scaled multiplier `u_s` per spring, a vector (ADMM, Overby et al. 2017), that turns the
//! penalty into the exact constraint as the iterations converge. After every iteration:
//!
//! ```text
//! v_s  = d_s + u_s
//! z_s  = v_s min(1, 1.1 L_s / |v_s|)                      (projection onto the ball)
//! u_s <- v_s - z_s                                        (the tension over w_s)
//! ```
//!
//! For fixed multipliers the term is convex and continuously differentiable in `d_s`, with the
//! gradient `w_s (v_s - z_s)`. A slack spring gets `u_s = 0` and a zero term.
//! A spring already beyond the limit (a state left by the course's sweep, a swap from Verlet,
//! an edit of `ks`) is pulled towards its projection, weighted against the mass and the other
//! springs in the same convex solve. `w_s` is [`limit_weight`]: the spring's own stiffness plus
//! the inertia, which makes the ADMM iteration converge at about the rate of the springs' own
//! local/global iteration. The multipliers are warm-started from the previous step (a cache:
//! [`Solver::reset`] and a solver swap drop it, costing a few steps of convergence).
//!
//! That weight serves a moving cloth, but not one at rest on a long taut chain of binding
//! springs (the hammock's width, a hanging corner at many steps per frame): there the
//! multipliers converge at about the rate at which the mass term lets the chain's longest mode
//! move, slower than the iterations of a step can follow, and the step velocity keeps a jitter
//! of centimetres per second that the drag never removes. A stiffer weight converges the chain
//! quickly but holds every slack spring to its last iterate, which on a moving cloth damps its
//! deformation. The weight is therefore raised only once the cloth is still: the solver watches the
//! free points' root-mean-square speed over windows of 0.25 s, and their jitter (the
//! root-mean-square of their step speeds, which sees the back-and-forth that a window's net
//! displacement averages away). A window below 2 cm/s in which most steps ran out of iterations
//! before the tolerance (a cloth whose steps converge needs no raise) and whose jitter has stalled
//! (above 1 mm/s and above 0.6 of the window's before: a jitter that falls faster settles at the
//! weight it has, where the slack springs converge freely), with no spring more than 1 % over the
//! limit and no point within [`CONTACT_DISTANCE`](crate::CONTACT_DISTANCE) of a collision object
//! (its friction's drag lets a resting point follow only a small share of what pulls it, so a
//! stiffer limit would fight the friction rather than converge a chain), raises the weight tenfold,
//! at most three times (one refactorisation each); the multipliers are rescaled so that the
//! tensions they stand for are kept. Each level is measured for two windows before it is raised
//! again or judged: a raise after which the second window's jitter exceeds the jitter of the window
//! before it is undone, and the level held until the cloth moves again. A window faster than 6
//! cm/s, a step that starts with a point faster than 0.5 m/s, the limit switched off or
//! [`Solver::reset`] return the weight to its least value (the cache, like the multipliers, is the
//! solver's own: a swap starts afresh). While a raise is being judged only the windows count: the
//! raise itself moves a few points fast for a step or two as the tensions it converges
//! redistribute; a window faster than 6 cm/s then returns the weight to its least value and holds
//! it there until a later window moves again.
//!
//! The multipliers converge at about the rate of the springs' own iteration, which a cloth caught
//! by its pins outruns: at the bottom of a fall a frame's iterations can leave springs well past
//! the limit. So after the minimisation the course's correction is swept over the step's positions
//! until no spring is over the limit by more than 0.2 % of its rest length (the tolerance the
//! multipliers' updates stop at), or 30 sweeps: as many as the course's Verlet makes in a frame,
//! one a step, so a long taut chain the sweeps converge slowly on costs no more than the course's
//! own limit does. A state so stretched would otherwise be snapped back by the first short step of
//! a solver that takes over from this one (Verlet's sweep moves a point by the excess in a
//! thirtieth of the step, a velocity thirty times what the same move over this step would make).
//! Each correction is the projection onto the positions where its one spring is within the limit
//! (its pinned ends held), a convex set that holds the step's start whenever the start is within
//! the limit; a projection onto a convex set moves no point set farther from a point of the set, so
//! no sweep lengthens `x - x0`, and the step's velocity `(x - x0) / h` and kinetic energy do not
//! grow. What a correction changes in the potential is its spring's excess stretch, which it
//! removes.
//!
//! NOTE: the multiplier is a vector fixed in space, not a length along the spring's current
//! direction. A binding spring's tension is `w_s |u_s|`; where it exceeds `w_s 1.1 L_s` the
//! target `q_s` points against the spring. pinned4's corner springs hang in that state at
//! rest, and the more so the finer the grid: its springs carry the same cloth's weight while
//! `w_s L_s` halves with each halving of the spacing, so `|u_s| / L_s` doubles. Read along
//! `d_s / |d_s|`, such a target would turn with a spring that the global step swings through
//! zero, and each swing would add `|d_s| - 1.1 L_s` to the multiplier where the vector update
//! `u_s <- u_s + d_s - z_s` takes about `|d_s| + 1.1 L_s` off it: the swings would grow without
//! bound, while the vector form is the standard scaled ADMM, whose multiplier the swing shrinks.
//!
//! # Stability
//!
//! Every accepted iteration lowers `Phi` (the line search takes no step that does not), and the
//! minimisation starts from whichever of the prediction `y` and the step's start `x0` has the
//! lower `Phi`. So even a step cut off by the iteration count ends with `Phi` no higher than at
//! `x0`: the start's potential energy (springs, gravity, contact terms) plus the kinetic energy
//! the prediction carries, reduced by the drag. The step creates no energy whatever its size and
//! stiffness; the matrix is positive definite, so every direction is a descent direction or the
//! iterations restart from `-A^-1 grad Phi`, which is. The one exception is the stretch limit's
//! multiplier update, which changes the limit's term between iterations (ADMM): for a convex
//! energy and a convex constraint its standard form converges at any weight, but the springs'
//! energy is not convex (a compressed spring), so this is an argument rather than a proof, and a
//! run that diverges all the same is stopped by the front ends' divergence guard. With few
//! iterations the solver under-resolves stiff springs, which makes the cloth look softer and
//! more damped. At convergence the step equals [`ImplicitEuler`]'s, which minimises the same
//! potential by Newton directions over the same factor.
//!
//! # Collisions
//!
//! Contact is part of the minimised potential, as one-sided penalties on the contacts found at
//! the step's start (in the manner of Vertex Block Descent, Chen et al. 2024), not a push after
//! the solve:
//!
//! - a collision object adds `k_i/2 min(0, s_i(x_i) - delta)^2` for each free point, `s_i` its
//!   signed distance to the surface on the side the point starts the step on (so a plane's side
//!   is fixed for the step), `delta` the course's surface offset (0.1 mm) and `k_i` half the
//!   point's own diagonal of `A` (about as stiff as everything else that holds it, yet not so
//!   much stiffer than `A` that the L-BFGS steps overshoot it), and at least the stiffness at
//!   which the point's own weight sinks it a tenth of `delta` (a point of the course's cloth
//!   pressed with a newton sinks about 20 um into the 0.1 mm margin);
//! - self-collision adds `k/2 min(0, |x_j - x_i| - 2 t)^2` for each pair of points closer than
//!   twice the thickness `t` at the step's start or at their predictions, with `k = ks + m (1
//!   + c h) / h^2`: both points are pushed apart, with equal and opposite forces.
//!
//! Each term is a potential that depends on the positions alone and is zero away from contact,
//! so it is conservative: the minimisation lowers `Phi` with it as with the springs, and what it
//! stores while a point presses on an object it gives back as the point leaves, never more. A
//! position push after a frame-long step (the course's collision response, applied after the
//! solve) would move points by up to the overlap without moving their previous positions: a
//! velocity of overlap over step, made from nothing. After the solve, a point that the penalty still left inside an object (only under a
//! force of many newtons) is put onto its surface with its velocity into the object removed and
//! its previous position moved with it: that only takes kinetic energy out.
//!
//! The friction of a collision object is a drag on the points in contact with it, inside the
//! step: such a point's mass term in `Phi` is `m (1 + (c + c_f) h) / h^2`, with its own
//! prediction. A point is in contact for the step when its prediction ends within
//! [`CONTACT_DISTANCE`](crate::CONTACT_DISTANCE) of (or inside) the object, whether it rests
//! on it or arrives during the step, as the course applies its friction to the whole
//! displacement of the step in which a point crosses a surface. The crate's documentation
//! ([Friction](crate#friction)) gives the drag rate `c_f` that stands for the course's per-step
//! friction, and why the course's friction after a large step cannot.
//!
//! # Damping
//!
//! The course's damping becomes the drag rate [`StepParams::drag_rate`]. At 100 % that rate is
//! infinite: the step keeps the cloth where it is with no velocity (the limit of the damped
//! step as the drag grows), and only the collisions act.
//!
//! [`ImplicitEuler`]: crate::ImplicitEuler

use cloth_mesh::{ClothMesh, ClothState, SURFACE_OFFSET, SpringKind, Vec3};
use cloth_solver::{
    Collider, MAX_STRETCH, SolveError, Solver, SpatialHash, StepParams, StepReport,
    max_stretch_ratio,
};

use crate::cholesky::Cholesky;
use crate::commit::{hold_still, predict};
use crate::contact::{Contacts, touches};
use crate::lbfgs::{Lbfgs, Problem};
use crate::memory::{Allocation, try_filled};
use crate::newton::NewtonScratch;
use crate::objective::{
    CONTACT_GAP, LIMIT_OVERSHOOT_TOLERANCE, Objective, StepProblem, surface_distance,
};
use crate::self_contact::SelfContacts;
use crate::topology::{NONE, Topology};

/// By default the iterations of a step stop once a full iteration moves no point
/// farther than this, metres (0.1 um: a two-hundredth of the 0.1 % stretch of a 2 cm spring).
pub const FAST_TOLERANCE: f64 = 1e-7;

/// A point's contact term is stiff enough that the point's own weight sinks it at most this
/// share of the contact margin into it.
const CONTACT_SINK: f64 = 0.1;

/// The factor between successive levels of the stretch limit's penalty.
const PENALTY_GROWTH: f64 = 10.0;

/// The highest level of the stretch limit's penalty: at most `PENALTY_GROWTH^3` times
/// [`limit_weight`].
const MAX_PENALTY_LEVEL: u32 = 3;

/// The span, s, over which the cloth's motion is measured to raise the limit's penalty.
const QUIET_WINDOW: f64 = 0.25;

/// A window over which the free points' root-mean-square speed stays below this, m/s, raises
/// the limit's penalty a level.
const QUIET_SPEED: f64 = 0.02;

/// A window over which the free points' root-mean-square speed exceeds this, m/s, or a step
/// that starts with a point faster than [`MOVING_SPEED`], returns the limit's penalty to its
/// least level.
const MOVING_WINDOW_SPEED: f64 = 0.06;

/// The limit's penalty is raised only while no spring is over the limit by more than this
/// share of it: a spring far past it is one the solve cannot bring back (held by friction on a
/// collision object), and a stiffer limit would only pull it harder.
const RAISE_OVERSHOOT: f64 = 0.01;

/// A window whose jitter (root-mean-square step speed) stays above this share of the window's
/// before has stalled: converging at that rate, a jitter of centimetres per second would
/// still be millimetres per second seconds later. Only a stalled window raises the limit's
/// penalty; a cloth whose jitter falls faster settles at the weight it has, where its slack
/// springs converge freely.
const STALL_RATIO: f64 = 0.6;

/// Nor does a window whose jitter is below this, m/s, a tenth of the speed a settled cloth
/// may keep: it is at rest for every purpose, and a stiffer weight would only slow its slack
/// springs' convergence.
const STALLED_JITTER: f64 = 1e-3;

/// The windows measured at a level before it is judged (after a raise) or raised again.
const JUDGED_AFTER: u32 = 2;

/// See [`MOVING_WINDOW_SPEED`], m/s.
const MOVING_SPEED: f64 = 0.5;

/// The stretch limit's weight at penalty `level`, as a multiple of [`limit_weight`].
fn penalty_scale(level: u32) -> f64 {
    PENALTY_GROWTH.powi(level as i32)
}

/// Iterations per step of [`FastImplicit::new`], at most.
pub const DEFAULT_ITERATIONS: u32 = 10;

/// The weight of the stretch limit's projection term of a spring of stiffness `k`, N/m, for a
/// step whose mass term per point is `inertia = m (1 + c h) / h^2`: `k + inertia`.
///
/// It is also the ADMM penalty. Any positive value converges to the same constrained step; this
/// one is as stiff as the stiffest thing the constraint competes with, so the multiplier and the
/// positions converge together (a much smaller weight leaves the multiplier to do all the work,
/// a much larger one holds every slack spring to its previous iterate).
#[must_use]
pub fn limit_weight(k: f64, inertia: f64) -> f64 {
    k + inertia
}

/// The fast implicit solver. Owns caches (topology, factored matrix, multiplier
/// warm start) and scratch memory only.
#[derive(Debug)]
pub struct FastImplicit {
    system: Option<System>,
    /// Iterations per step, at most (at least 1).
    iterations: u32,
    tolerance: f64,
    /// Scaled multipliers of the stretch limit, m, one vector per spring (warm start).
    mu: Vec<Vec3>,
    rhs: Vec<f64>,
    y: Vec<Vec3>,
    x: Vec<Vec3>,
    /// The stretch limit's penalty level: its weight is [`limit_weight`] times
    /// `PENALTY_GROWTH` to this power (see the module doc).
    level: u32,
    /// The free points' positions at the start of the current quiet window, and the time
    /// since, s.
    checkpoint: Vec<Vec3>,
    since: f64,
    /// Steps in the current window, and those that ran out of iterations before the tolerance.
    steps: u32,
    unconverged: u32,
    /// The sum over the window's steps of the free points' mean squared step speed, m^2/s^2.
    jitter: f64,
    /// The jitter (root-mean-square step speed, m/s) of the last window measured.
    last_jitter: f64,
    /// The jitter (root-mean-square step speed, m/s) of the window before the last raise of
    /// the level, until the raise has been judged.
    raised_from: Option<f64>,
    /// Windows measured since the level last changed.
    windows_at_level: u32,
    /// Whether a raise was undone, which holds the level until the cloth moves again.
    held: bool,
    /// The points resting on collision objects, and the colliders that finish a step.
    contacts: Contacts,
    /// Per point, its mass term `m (1 + (c + c_f) h) / h^2`, N/m, with the drag of the friction
    /// it rests on.
    point_inertia: Vec<f64>,
    hash: SpatialHash,
    /// The pairs of points self-collision acts on in the current step.
    self_contacts: SelfContacts,
    lbfgs: Lbfgs,
    /// How each iteration's direction is found.
    method: Method,
    /// Newton's Hessian blocks and conjugate-gradient vectors (empty for L-BFGS).
    newton: NewtonScratch,
}

/// How an iteration of the step's minimisation finds its direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Method {
    /// L-BFGS over the prefactored matrix (`fast-implicit`).
    Lbfgs,
    /// Newton: the conjugate gradient on the clamped Hessian, preconditioned by the
    /// prefactored matrix, at most this many iterations per direction (`implicit`).
    Newton(u32),
}

impl Default for FastImplicit {
    fn default() -> Self {
        Self::new()
    }
}

/// What the factored matrix depends on besides the topology, as bit patterns so that any
/// change (even to a NaN-free equal value with another sign) refactors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct MatrixKey {
    inertia: u64,
    stiffness: [u64; 3],
    limit: bool,
    level: u32,
}

#[derive(Debug)]
struct System {
    topo: Topology,
    chol: Cholesky,
    col_ptr: Vec<usize>,
    values: Vec<f64>,
    key: Option<MatrixKey>,
    /// The free points' mass terms the factor was computed with.
    inertia: Vec<f64>,
    /// The matrix's diagonal, per free point, N/m: the stiffness of a point's contact term.
    diag: Vec<f64>,
}

const KINDS: [SpringKind; 3] = [
    SpringKind::Structural,
    SpringKind::Shearing,
    SpringKind::Bending,
];

impl FastImplicit {
    /// A new solver with the default [`FAST_TOLERANCE`] and at most [`DEFAULT_ITERATIONS`]
    /// iterations per step; its caches are built on the first step.
    #[must_use]
    pub fn new() -> Self {
        Self::with_iterations(DEFAULT_ITERATIONS)
    }

    /// A new solver doing at most `iterations` iterations per step (0 counts as
    /// 1), stopping earlier on the tolerance.
    #[must_use]
    pub fn with_iterations(iterations: u32) -> Self {
        Self {
            system: None,
            iterations: iterations.max(1),
            tolerance: FAST_TOLERANCE,
            mu: Vec::new(),
            rhs: Vec::new(),
            y: Vec::new(),
            x: Vec::new(),
            level: 0,
            checkpoint: Vec::new(),
            since: 0.0,
            steps: 0,
            unconverged: 0,
            jitter: 0.0,
            last_jitter: f64::INFINITY,
            raised_from: None,
            windows_at_level: 0,
            held: false,
            contacts: Contacts::approaching(),
            point_inertia: Vec::new(),
            hash: SpatialHash::default(),
            self_contacts: SelfContacts::default(),
            lbfgs: Lbfgs::default(),
            method: Method::Lbfgs,
            newton: NewtonScratch::default(),
        }
    }

    /// This solver with each iteration's direction found by `method`.
    #[must_use]
    pub(crate) fn with_method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    /// The tolerance, m: iterations stop once a full step moves no point farther.
    pub(crate) fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Iterations per step, at most.
    #[must_use]
    pub fn iterations(&self) -> u32 {
        self.iterations
    }

    /// Sets the tolerance, metres: a step's iterations stop once a global step moves no point
    /// farther than this (non-finite or negative values mean [`FAST_TOLERANCE`]; 0 runs every
    /// iteration).
    #[must_use]
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = if tolerance.is_finite() && tolerance >= 0.0 {
            tolerance
        } else {
            FAST_TOLERANCE
        };
        self
    }

    /// Bytes this solver allocates for `mesh`: the topology, the matrix's pattern and values,
    /// its Cholesky factor and the factorisation's workspace (from faer's symbolic analysis of
    /// the pattern, so the fill is counted exactly), and the per-point and per-spring scratch.
    /// The self-collision hash, the same as Verlet's, is not counted.
    ///
    /// The analysis itself takes memory in proportion to the pattern (about a tenth of the
    /// total); when even that fails, the estimate is `u64::MAX`.
    #[must_use]
    pub fn memory_estimate(mesh: &ClothMesh) -> u64 {
        let topo = Topology::new(mesh);
        let (col_ptr, row_idx) = topo.scalar_pattern();
        let Ok(factor) = Cholesky::<f64>::analyse(&col_ptr, &row_idx, 3) else {
            return u64::MAX;
        };
        let n = topo.free() as u64;
        let pattern = 8 * 2 * col_ptr.len() as u64 + 8 * row_idx.len() as u64;
        let values = 8 * row_idx.len() as u64;
        // rhs (3 per free point), y, x and the quiet window's checkpoint (3 per point each),
        // the multipliers (3 per spring); the L-BFGS curvature pairs and vectors (3 per free
        // point each) and a trial configuration (3 per point); the self-collision cells (2
        // per point) and pairs (about 4 per point in a folded cloth).
        let lbfgs = 3 * n * (2 * Lbfgs::HISTORY as u64 + 3) + 3 * mesh.len() as u64;
        let points = mesh.len() as u64;
        let scratch = 8 * (3 * n + 9 * points + 3 * mesh.springs().len() as u64 + lbfgs)
            + 16 * points
            + 8 * 4 * points;
        topo.bytes() + pattern + values + factor.bytes() + scratch
    }

    /// Moves the stretch limit's penalty to `level`, rescaling the scaled multipliers so that
    /// the tensions they stand for (penalty times multiplier) are kept.
    fn set_level(&mut self, level: u32) {
        if level != self.level {
            let scale = penalty_scale(self.level) / penalty_scale(level);
            for mu in &mut self.mu {
                *mu *= scale;
            }
            self.level = level;
            self.windows_at_level = 0;
        }
    }

    /// Returns the limit's penalty to its least level and starts watching the motion afresh.
    /// Motion that sets in while a raise is being judged counts against the raise: the level
    /// is then held at its least.
    fn release(&mut self) {
        self.set_level(0);
        self.checkpoint.clear();
        self.held = self.raised_from.take().is_some();
        self.windows_at_level = 0;
    }

    /// Measures the cloth's motion over [`QUIET_WINDOW`] and raises or drops the limit's
    /// penalty level by it.
    fn watch(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        state: &ClothState,
        h: f64,
        converged: bool,
    ) {
        if self.checkpoint.len() != mesh.len() {
            self.checkpoint.clone_from(&state.positions);
            self.since = 0.0;
            self.unconverged = 0;
            self.steps = 0;
            self.jitter = 0.0;
            return;
        }
        self.since += h;
        self.steps += 1;
        if !converged {
            self.unconverged += 1;
        }
        let (mut step_sum, mut count) = (0.0, 0_usize);
        for ((x, l), &pinned) in state.positions.iter().zip(&state.last).zip(mesh.pinned()) {
            if !pinned {
                step_sum += (x - l).norm_squared();
                count += 1;
            }
        }
        self.jitter += step_sum / (count.max(1) as f64 * h * h);
        if self.since < QUIET_WINDOW {
            return;
        }
        let mut sum = 0.0;
        for ((x, c), &pinned) in state
            .positions
            .iter()
            .zip(&self.checkpoint)
            .zip(mesh.pinned())
        {
            if !pinned {
                sum += (x - c).norm_squared();
            }
        }
        let speed = (sum / count.max(1) as f64).sqrt() / self.since;
        let jitter = (self.jitter / f64::from(self.steps)).sqrt();
        if speed > MOVING_WINDOW_SPEED {
            self.release();
        } else {
            self.windows_at_level += 1;
            if let Some(before) = self.raised_from {
                // NOTE: a stiffer limit settles a cloth whose binding chain was converging too
                // slowly, but one whose slack springs the stiffer weight holds back converges
                // more slowly still. A raise is judged on the second window after it (the
                // first still carries the change): if the cloth jitters more than before it,
                // the raise is undone and the level held until the cloth moves again.
                if self.windows_at_level >= JUDGED_AFTER {
                    self.raised_from = None;
                    if jitter > before {
                        self.set_level(self.level.saturating_sub(1));
                        self.held = true;
                    }
                }
            } else if self.windows_at_level >= JUDGED_AFTER
                && speed < QUIET_SPEED
                && jitter >= STALLED_JITTER
                && jitter > STALL_RATIO * self.last_jitter
                && 2 * self.unconverged > self.steps
                && !self.held
                && self.level < MAX_PENALTY_LEVEL
                && max_stretch_ratio(mesh, state) <= MAX_STRETCH * (1.0 + RAISE_OVERSHOOT)
                && !touches(mesh, colliders, state)
            {
                self.set_level(self.level + 1);
                self.raised_from = Some(jitter);
            }
        }
        self.checkpoint.clone_from(&state.positions);
        self.since = 0.0;
        self.unconverged = 0;
        self.steps = 0;
        self.jitter = 0.0;
        self.last_jitter = jitter;
    }

    /// Makes sure the topology, the symbolic factor and the numeric factor describe `mesh` and
    /// the current parameters. `inertia` is the mass term of a point that rests on nothing,
    /// which the limit's weight is set by; each point's own, with the drag of the friction it
    /// rests on, is in `point_inertia` and on the matrix's diagonal, so that the solve of a
    /// resting point's slide is exact in the first iteration.
    fn prepare(
        &mut self,
        mesh: &ClothMesh,
        params: &StepParams,
        inertia: f64,
    ) -> Result<(), SolveError> {
        let name = self.name();
        if !self.system.as_ref().is_some_and(|s| s.topo.matches(mesh)) {
            self.system = None;
            self.mu = Vec::new();
            let topo = Topology::new(mesh);
            let (col_ptr, row_idx) = topo.scalar_pattern();
            let chol =
                Cholesky::<f64>::new(col_ptr.clone(), row_idx, 3).map_err(method_error(name))?;
            let values = try_filled(chol.nnz(), 0.0, "the fast-implicit matrix")
                .map_err(alloc_error(name))?;
            self.system = Some(System {
                topo,
                chol,
                col_ptr,
                values,
                key: None,
                inertia: Vec::new(),
                diag: Vec::new(),
            });
        }
        if self.mu.len() != mesh.springs().len() {
            self.mu = try_filled(
                mesh.springs().len(),
                Vec3::zeros(),
                "the stretch-limit multipliers",
            )
            .map_err(alloc_error(name))?;
        }
        let Some(sys) = self.system.as_mut() else {
            return Err(method_error(name)("no linear system was built".to_owned()));
        };
        let key = MatrixKey {
            inertia: inertia.to_bits(),
            stiffness: KINDS.map(|k| params.stiffness(k).to_bits()),
            limit: params.stretch_limit,
            level: self.level,
        };
        let topo = &sys.topo;
        let point_inertia = &self.point_inertia;
        // NOTE: compared by value: the points resting on a collision object change the
        // diagonal, and a cloth at rest keeps the same ones from step to step.
        if sys.key == Some(key)
            && sys.inertia.len() == topo.free()
            && topo
                .free_points
                .iter()
                .zip(&sys.inertia)
                .all(|(&p, &m)| point_inertia[p as usize].to_bits() == m.to_bits())
        {
            return Ok(());
        }
        sys.key = None;
        sys.inertia.clear();
        sys.inertia
            .extend(topo.free_points.iter().map(|&p| point_inertia[p as usize]));
        let v = &mut sys.values;
        v.fill(0.0);
        for (f, &m) in sys.inertia.iter().enumerate() {
            v[sys.col_ptr[f]] = m;
        }
        for (s, &slot) in mesh.springs().iter().zip(&topo.spring_slot) {
            let k = spring_weight(params, s.kind, inertia, self.level);
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
        sys.chol
            .factorize(&sys.values, 0.0)
            .map_err(method_error(name))?;
        sys.diag.clear();
        sys.diag
            .extend(sys.col_ptr[..topo.free()].iter().map(|&c| sys.values[c]));
        sys.key = Some(key);
        Ok(())
    }
}

/// The total weight a spring of `kind` puts into the matrix: its stiffness, plus the stretch
/// limit's weight when the limit is on.
fn spring_weight(params: &StepParams, kind: SpringKind, inertia: f64, level: u32) -> f64 {
    let k = params.stiffness(kind);
    if params.stretch_limit {
        k + limit_weight(k, inertia) * penalty_scale(level)
    } else {
        k
    }
}

fn method_error(solver: &'static str) -> impl Fn(String) -> SolveError {
    move |reason| SolveError::Method { solver, reason }
}

fn alloc_error(solver: &'static str) -> impl Fn(Allocation) -> SolveError {
    move |a| method_error(solver)(a.to_string())
}

impl Solver for FastImplicit {
    fn name(&self) -> &'static str {
        match self.method {
            Method::Lbfgs => "fast-implicit",
            Method::Newton(_) => "implicit",
        }
    }

    fn reset(&mut self) {
        self.mu.fill(Vec3::zeros());
        self.raised_from = None;
        self.release();
    }

    fn step(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &mut ClothState,
    ) -> Result<StepReport, SolveError> {
        params.validate()?;
        let name = self.name();
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
        if !params.stretch_limit {
            self.raised_from = None;
            self.release();
        } else if self.level > 0
            // A raise under judgement moves a few points fast while the tensions it converges
            // redistribute; only its window speaks against it.
            && self.raised_from.is_none()
            && fastest_point(mesh, state) > MOVING_SPEED * h
        {
            self.release();
        }
        predict(
            mesh,
            colliders,
            params,
            state,
            mass,
            &mut self.y,
            &mut self.point_inertia,
            &mut self.contacts,
        );
        self.prepare(mesh, params, inertia)?;
        let max_iterations = self.iterations;
        // Newton's tolerance is per frame, so that its velocity error does not grow with the
        // steps per frame.
        let tolerance = match self.method {
            Method::Lbfgs => self.tolerance,
            Method::Newton(_) => self.tolerance / f64::from(params.steps_per_frame),
        };
        let Some(sys) = self.system.as_mut() else {
            return Err(method_error(name)("no linear system was built".to_owned()));
        };
        let weight = params.gravity * mass;
        if !params.stretch_limit {
            self.mu.fill(Vec3::zeros());
        }
        let limits = KINDS.map(|kind| {
            if params.stretch_limit {
                limit_weight(params.stiffness(kind), inertia) * penalty_scale(self.level)
            } else {
                0.0
            }
        });

        let pair_stiffness = params.stiffness(SpringKind::Structural) + inertia;
        let weight_floor = mass * params.gravity.norm() / (CONTACT_SINK * CONTACT_GAP);
        let reach = 2.0 * mesh.spec().thickness;
        if params.self_collision {
            // NOTE: pairs closer than the reach at the predictions are closer than the reach
            // plus twice the largest prediction's move at the start: while that move is small
            // (a cloth at or near rest) one search at the start with the reach so widened
            // finds them, at half the cost of a search in each configuration.
            let moved = state
                .positions
                .iter()
                .zip(&self.y)
                .map(|(a, b)| (a - b).norm_squared())
                .fold(0.0, f64::max)
                .sqrt();
            if moved < 0.25 * reach {
                self.self_contacts
                    .find(mesh, &[&state.positions], reach + 2.0 * moved);
            } else {
                self.self_contacts
                    .find(mesh, &[&state.positions, &self.y], reach);
            }
        } else {
            self.self_contacts.clear();
        }
        let System {
            topo, chol, diag, ..
        } = sys;
        let free = &topo.free_points;
        let mut problem = StepProblem {
            objective: Objective {
                mesh,
                topo,
                params,
                colliders,
                inertia: &self.point_inertia,
                y: &self.y,
                x0: &state.positions,
                weight,
                limits,
                mu: &mut self.mu,
                contact_stiffness: diag,
                contact_floor: weight_floor,
                pairs: self.self_contacts.pairs(),
                pair_stiffness,
                reach,
            },
            chol,
            rhs: &mut self.rhs,
            newton: match self.method {
                Method::Lbfgs => None,
                Method::Newton(cg) => Some((&mut self.newton, cg, tolerance)),
            },
        };
        // NOTE: the minimisation only ever lowers the incremental potential from its start, so
        // it starts from whichever of the prediction and the step's start has the lower one:
        // then even a truncated step ends with a potential no higher than the start's (see the
        // module doc).
        let at_start = problem.evaluate(&state.positions, None);
        let at_prediction = problem.evaluate(&self.y, None);
        if at_start < at_prediction {
            self.x.clone_from(&state.positions);
        } else {
            self.x.clone_from(&self.y);
        }
        let outcome = self
            .lbfgs
            .minimise(&mut self.x, free, max_iterations, tolerance, &mut problem)
            .map_err(method_error(name))?;
        let iterations = outcome.iterations;
        if params.stretch_limit {
            project_to_limit(mesh, &mut self.x);
        }

        commit_in_step(mesh, colliders, state, free, &self.x, h)?;
        if params.stretch_limit {
            self.watch(mesh, colliders, state, h, outcome.converged);
        }
        Ok(StepReport {
            iterations,
            residual: outcome.residual,
        })
    }
}

/// Moves the free points to `x` with `last` at their start-of-step positions, so that `(x -
/// last) / h` is the step's velocity, then puts back outside a collision object any point that
/// its contact term left inside: onto the surface (a plane's at the course's offset), with
/// `last` moved so that the point keeps its velocity but for the part into the object, which
/// is removed. That correction takes kinetic energy out and moves a point by no more than
/// the term let it in (micrometres); it gives no point a velocity it did not have.
///
/// # Errors
/// [`SolveError::NonFinite`] for the first non-finite point.
fn commit_in_step(
    mesh: &ClothMesh,
    colliders: &[Collider],
    state: &mut ClothState,
    free: &[u32],
    x: &[Vec3],
    h: f64,
) -> Result<(), SolveError> {
    for &p in free {
        let p = p as usize;
        let x0 = state.positions[p];
        let mut new = x[p];
        let mut velocity = (new - x0) / h;
        let mut corrected = false;
        for c in colliders {
            let Some((dist, n)) = surface_distance(c, &x0, &new) else {
                continue;
            };
            if dist >= 0.0 {
                continue;
            }
            let lift = match c {
                Collider::Sphere(_) => -dist,
                Collider::Plane(_) => SURFACE_OFFSET - dist,
            };
            new += n * lift;
            corrected = true;
            let into = velocity.dot(&n);
            if into < 0.0 {
                velocity -= n * into;
            }
        }
        state.positions[p] = new;
        state.last[p] = if corrected { new - velocity * h } else { x0 };
    }
    match state.first_non_finite() {
        Some(i) => Err(SolveError::non_finite(mesh, i)),
        None => Ok(()),
    }
}

/// Sweeps the course's correction over `x` until no spring is longer than the limit by more
/// than [`LIMIT_OVERSHOOT_TOLERANCE`] of its rest length, or [`MAX_PROJECTION_SWEEPS`] sweeps.
/// See the module documentation for why it adds no kinetic energy.
fn project_to_limit(mesh: &ClothMesh, x: &mut [Vec3]) {
    let springs = mesh.springs();
    let pinned = mesh.pinned();
    let ratio = MAX_STRETCH + LIMIT_OVERSHOOT_TOLERANCE;
    for _ in 0..MAX_PROJECTION_SWEEPS {
        let over = springs
            .iter()
            .any(|s| (x[s.b as usize] - x[s.a as usize]).norm_squared() > (ratio * s.rest).powi(2));
        if !over {
            return;
        }
        cloth_solver::limit_stretch(springs, pinned, x, MAX_STRETCH);
    }
}

/// At most this many sweeps of the course's correction end a step with the limit on (see
/// [`project_to_limit`]).
const MAX_PROJECTION_SWEEPS: u32 = 30;

/// The largest distance, m, a free point moved over the last step (`positions - last`).
fn fastest_point(mesh: &ClothMesh, state: &ClothState) -> f64 {
    state
        .positions
        .iter()
        .zip(&state.last)
        .zip(mesh.pinned())
        .filter(|(_, pinned)| !**pinned)
        .map(|((x, l), _)| (x - l).norm())
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_of_the_limit_penalty_keeps_the_limit_tensions() {
        // The scaled multiplier is the tension over the penalty: raising the penalty a
        // hundredfold must divide it by a hundred, or the limit's pull would jump.
        let mut solver = FastImplicit::new();
        solver.mu = vec![Vec3::new(0.3, -0.2, 0.1), Vec3::zeros()];
        let before = solver.mu.clone();
        solver.set_level(MAX_PENALTY_LEVEL);
        let scale = penalty_scale(MAX_PENALTY_LEVEL);
        for (b, a) in before.iter().zip(&solver.mu) {
            assert!(
                (b - a * scale).norm() <= 1e-15 * b.norm(),
                "{b} against {a}"
            );
        }
        solver.reset();
        assert_eq!(solver.level, 0);
        assert!(solver.mu.iter().all(|m| *m == Vec3::zeros()));
    }
}
