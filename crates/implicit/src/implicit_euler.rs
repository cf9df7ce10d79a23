//! Backward Euler by Newton's method on the incremental potential, over the constant
//! prefactored matrix.
//!
//! # Method
//!
//! Each step minimises the same incremental potential `Phi` as [`FastImplicit`]: the inertia
//! of the damped prediction, gravity, the springs, the stretch limit's augmented term and the
//! one-sided contact penalties (its module documentation gives `Phi` term by term, and why
//! the contact terms cannot create energy). Only the direction of each iteration differs:
//! Newton's, `H dx = -grad Phi`, solved inexactly by the conjugate gradient on the true
//! Hessian `H` of `Phi`, each term's block clamped to be positive semi-definite (a spring's
//! `k (u u^T + max(0, 1 - L / l) (I - u u^T))`, at most `k I`: under compression its
//! transverse curvature is negative and is left out; a contact term's `k n n^T`; the stretch
//! limit's term for its fixed multiplier, at most its weight times `I`). The mass term makes
//! `H` positive definite.
//!
//! The conjugate gradient is preconditioned by the one constant matrix `M (1 + c h) / h^2 +
//! sum_s (k_s + w_s) A_s^T A_s` that [`FastImplicit`] factors: built once per topology and
//! refactored only when a parameter it holds changes (the step, `ks`, the density, the drag, a
//! spring toggle, the limit's switch or weight, the set of points resting on an object), never
//! during a run of fixed parameters because of the cloth's motion. Each spring's clamped block
//! is at most `k I`, which the factor holds, so the preconditioned spectrum is bounded above by
//! one plus the contact terms' share and the iteration needs few steps where the springs are
//! not much stiffer than the mass term. It stops once the residual falls below half the
//! gradient or after [`MAX_PCG_ITERATIONS`] iterations: a conjugate gradient started at zero
//! on a positive-definite matrix returns a descent direction at every iteration, so a direction
//! cut short (where the spectrum is wide: ks 1e6) is still one, and the iterations that follow
//! make up for it. An Armijo line search along it accepts only a step that lowers `Phi`. The
//! step stops once a full Newton step moves no point farther than the tolerance over the steps
//! per frame ([`NEWTON_TOLERANCE`] by default) with the stretch limit met, or after
//! [`MAX_NEWTON_ITERATIONS`] iterations.
//!
//! # The stretch limit
//!
//! The stiff limit penalty is not in the Hessian. The limit is held as [`FastImplicit`] holds
//! it: by the augmented term `w_s/2 dist(d_s + u_s, B_s)^2` with a scaled multiplier per
//! spring (ADMM), `w_s` the spring's own stiffness plus the mass term, updated after every
//! iteration; its weight is what the factor holds, so a spring that starts or stops binding
//! changes the Hessian by no more than the factor already describes. What the multipliers leave
//! over the limit after the iterations, the projection that [`FastImplicit`] ends its steps
//! with takes back (the course's correction swept until every spring is within 0.2 % of the
//! limit), which adds no kinetic energy.
//!
//! # Why a step adds no energy
//!
//! Every accepted iteration lowers `Phi`, and the minimisation starts from whichever of the
//! prediction and the step's start has the lower `Phi`. So the step ends with `Phi` no higher
//! than at the start: the start's potential energy (springs, gravity, contact terms) plus the
//! kinetic energy the prediction carries, less what the drag takes. The contact terms are
//! functions of the positions alone, conservative like the springs; the correction after the
//! solve that puts a point left inside an object onto its surface only removes velocity. The
//! one exception is the multiplier update of the stretch limit (see [`FastImplicit`]'s
//! documentation).
//!
//! # Velocity and solver swaps
//!
//! The velocity is `(positions - last) / h` with the current `h = params.dt()`, exactly
//! Verlet's implied velocity; besides its caches the solver keeps only the limit's multipliers
//! between steps. When `h` changes, call [`retime_velocity`](crate::retime_velocity) first to
//! keep the velocity.
//!
//! [`FastImplicit`]: crate::FastImplicit

use cloth_mesh::{ClothMesh, ClothState};
use cloth_solver::{Collider, SolveError, Solver, StepParams, StepReport};

use crate::fast_implicit::{FastImplicit, Method};
use crate::newton::NewtonScratch;
use crate::topology::Topology;

/// By default Newton stops once a full step moves no point farther than this per frame,
/// metres: at `steps_per_frame` steps a frame, this over `steps_per_frame` per step (a velocity
/// error under `NEWTON_TOLERANCE * frames_per_sec`, 0.09 mm/s at 90 frames per second, whatever
/// the step). A cloth hanging on its stretch limit leaves each step with that error in the
/// multipliers' iterate; at 10 um a frame, pinned2's the check measures a jitter that sums to
/// 2.5 J of energy rises over its last two seconds, at 1 um 0.07 J. See
/// [`ImplicitEuler::with_tolerance`].
pub const NEWTON_TOLERANCE: f64 = 1e-6;

/// At most this many Newton iterations per step; a step that has not converged by then keeps
/// its last iterate, whose potential is no higher than the start's. Where the stretch limit
/// binds, the iterations are mostly spent on its multipliers, which converge over the steps
/// that follow as well (they are kept from step to step).
pub const MAX_NEWTON_ITERATIONS: u32 = 8;

/// At most this many conjugate-gradient iterations per Newton direction.
pub const MAX_PCG_ITERATIONS: u32 = 10;

/// The implicit (backward Euler) solver: Newton's method with a line search on the incremental
/// potential, preconditioned by one constant factor. See the module documentation.
///
/// Owns only caches (the topology, the factor, the limit's multipliers) and scratch memory.
#[derive(Debug)]
pub struct ImplicitEuler {
    inner: FastImplicit,
}

impl Default for ImplicitEuler {
    fn default() -> Self {
        Self::new()
    }
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
            inner: FastImplicit::with_iterations(MAX_NEWTON_ITERATIONS)
                .with_tolerance(tolerance)
                .with_method(Method::Newton(MAX_PCG_ITERATIONS)),
        }
    }

    /// This solver with at most `newton` Newton iterations per step and `conjugate_gradient`
    /// conjugate-gradient iterations per direction (0 counts as 1): more converges a step's
    /// slowest modes (a slack edge at a step of a quarter second, whose stiffness the factor
    /// overstates a hundred thousand times) where the defaults stop early.
    #[must_use]
    pub fn with_iterations(self, newton: u32, conjugate_gradient: u32) -> Self {
        let tolerance = self.inner.tolerance();
        Self {
            inner: FastImplicit::with_iterations(newton)
                .with_tolerance(tolerance)
                .with_method(Method::Newton(conjugate_gradient.max(1))),
        }
    }

    /// The tolerance, metres per frame.
    #[must_use]
    pub fn tolerance(&self) -> f64 {
        self.inner.tolerance()
    }

    /// Bytes this solver allocates for `mesh`: what [`FastImplicit::memory_estimate`] counts
    /// (the same factor, pattern and scratch) and the Hessian's blocks and the conjugate
    /// gradient's vectors. The self-collision hash, the same as Verlet's, is not counted.
    #[must_use]
    pub fn memory_estimate(mesh: &ClothMesh) -> u64 {
        let free = Topology::new(mesh).free() as u64;
        FastImplicit::memory_estimate(mesh)
            .saturating_add(8 * NewtonScratch::doubles(free, mesh.springs().len() as u64))
    }
}

impl Solver for ImplicitEuler {
    fn name(&self) -> &'static str {
        "implicit"
    }

    fn reset(&mut self) {
        self.inner.reset();
    }

    fn step(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &mut ClothState,
    ) -> Result<StepReport, SolveError> {
        self.inner.step(mesh, colliders, params, state)
    }
}
