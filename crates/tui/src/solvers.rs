//! The closed menu of solvers: [`SolverKind`] to a boxed [`Solver`].

use cloth_solver::{Solver, SolverKind, Verlet};

/// Builds the solver for `kind`.
///
/// # Errors
/// When `kind` is not compiled into this binary (the `implicit` cargo feature is off).
#[cfg_attr(
    feature = "implicit",
    allow(
        clippy::unnecessary_wraps,
        reason = "it fails when the implicit feature is off"
    )
)]
pub fn build(kind: SolverKind) -> anyhow::Result<Box<dyn Solver>> {
    match kind {
        SolverKind::Verlet => Ok(Box::new(Verlet::new())),
        #[cfg(feature = "implicit")]
        SolverKind::Implicit => Ok(Box::new(cloth_implicit::ImplicitEuler::new())),
        #[cfg(feature = "implicit")]
        SolverKind::FastImplicit => Ok(Box::new(cloth_implicit::FastImplicit::new())),
        #[cfg(not(feature = "implicit"))]
        SolverKind::Implicit | SolverKind::FastImplicit => anyhow::bail!(
            "the {kind} solver is not built into this clothsim; rebuild with `--features implicit`"
        ),
    }
}
