//! Errors a step can report.

/// Why a step failed. The state may hold the offending values; reset or stop.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// A position became NaN or infinite: the run diverged.
    #[error("the simulation diverged: point {point} (column {x}, row {y}) is no longer finite")]
    NonFinite {
        /// Index of the first bad point.
        point: usize,
        /// Its column.
        x: usize,
        /// Its row.
        y: usize,
    },
    /// The parameters are outside what the solver accepts.
    #[error("invalid parameter: {0}")]
    Params(#[from] crate::ParamError),
    /// The solver's own method failed (a factorisation, a line search...).
    #[error("the {solver} solver failed: {reason}")]
    Method {
        /// Solver name.
        solver: &'static str,
        /// What went wrong.
        reason: String,
    },
}

impl SolveError {
    /// A [`SolveError::NonFinite`] for point `index` of `mesh`.
    #[must_use]
    pub fn non_finite(mesh: &cloth_mesh::ClothMesh, index: usize) -> Self {
        Self::NonFinite {
            point: index,
            x: index % mesh.nw(),
            y: index / mesh.nw(),
        }
    }
}
