//! The closed set of solvers the binary offers.

use std::fmt;
use std::str::FromStr;

/// The solvers clothsim ships, by name. The [`crate::Solver`] trait is the open extension point;
/// this enum is the closed menu shared by the command line, scene files and the UI.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum SolverKind {
    /// The course's explicit damped Verlet (the faithful reference).
    #[default]
    Verlet,
    /// Backward Euler by Newton's method on the incremental potential (`cloth-implicit`).
    Implicit,
    /// Liu et al. 2013 "Fast Simulation of Mass-Spring Systems": local/global iterations with a
    /// constant prefactored matrix (`cloth-implicit`).
    FastImplicit,
}

impl SolverKind {
    /// Every kind, in menu order.
    pub const ALL: [SolverKind; 3] = [
        SolverKind::Verlet,
        SolverKind::Implicit,
        SolverKind::FastImplicit,
    ];

    /// The name used on the command line and in scene files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Verlet => "verlet",
            SolverKind::Implicit => "implicit",
            SolverKind::FastImplicit => "fast-implicit",
        }
    }

    /// A one-line description for menus and help.
    #[must_use]
    pub fn description(self) -> &'static str {
        match self {
            SolverKind::Verlet => "explicit damped Verlet, the course's reference (faithful)",
            SolverKind::Implicit => {
                "backward Euler, Newton + line search on faer (stable at large steps)"
            }
            SolverKind::FastImplicit => {
                "Liu et al. 2013 local/global, one prefactored matrix (fast, stiff)"
            }
        }
    }
}

impl fmt::Display for SolverKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A solver name that is not one of [`SolverKind::ALL`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown solver {0:?}; expected one of: verlet, implicit, fast-implicit")]
pub struct UnknownSolver(pub String);

impl FromStr for SolverKind {
    type Err = UnknownSolver;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        SolverKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| UnknownSolver(s.to_owned()))
    }
}
