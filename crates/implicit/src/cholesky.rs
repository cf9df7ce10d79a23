//! A faer sparse Cholesky (`L L^T`) whose symbolic analysis is done once per sparsity pattern.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side, Spec};

use crate::memory::{Allocation, check_available, try_filled};

/// The outcome of [`Cholesky::analyse`]: the symbolic factor and the workspace it needs.
pub(crate) struct Analysis {
    symbolic: SymbolicCholesky<usize>,
    scratch: StackReq,
}

impl Analysis {
    /// Entries of the factor `L`.
    pub(crate) fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Bytes the numeric factor and its workspace take: its values plus the workspace (the
    /// symbolic factor itself is already allocated).
    pub(crate) fn bytes(&self) -> u64 {
        8 * self.factor_len() as u64 + self.scratch.unaligned_bytes_required() as u64
    }
}

/// A symmetric positive-definite matrix with a fixed lower-triangular pattern and its Cholesky
/// factor.
///
/// The fill-reducing ordering (AMD) and the symbolic factor are computed in [`Cholesky::new`];
/// [`Cholesky::factorize`] then only redoes the numeric factor, which is what a Newton iteration
/// or a change of stiffness needs.
///
/// NOTE: everything runs with [`Par::Seq`]: results must be bit-identical from run to run and
/// the machine's cores are better spent elsewhere (the TUI, other cloths) than on a
/// 10^4-unknown factorisation.
pub(crate) struct Cholesky {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    factored: bool,
    scratch: MemBuffer,
    /// Right-hand sides the scratch was sized for.
    rhs_cols: usize,
}

impl std::fmt::Debug for Cholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cholesky")
            .field("n", &self.n())
            .field("nnz_a", &self.row_idx.len())
            .field("nnz_l", &self.l_values.len())
            .field("factored", &self.factored)
            .finish_non_exhaustive()
    }
}

impl Cholesky {
    /// Analyses the pattern of an `n x n` matrix given by its lower triangle in compressed
    /// columns (`col_ptr` of length `n + 1`, sorted `row_idx` with every row `>=` its column),
    /// for solves with up to `rhs_cols` right-hand sides at once, and allocates the factor.
    ///
    /// # Errors
    /// A message when the analysis fails or the factor does not fit in memory.
    pub(crate) fn new(
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        rhs_cols: usize,
    ) -> Result<Self, String> {
        let analysis = Self::analyse(&col_ptr, &row_idx, rhs_cols)?;
        check_available(analysis.bytes(), "the Cholesky factor").map_err(|e| e.to_string())?;
        let l_values = try_filled(analysis.symbolic.len_val(), 0.0, "the Cholesky factor")
            .map_err(|e| e.to_string())?;
        let scratch = MemBuffer::try_new(analysis.scratch).map_err(|_| {
            Allocation {
                what: "the Cholesky workspace",
                bytes: analysis.scratch.unaligned_bytes_required() as u64,
            }
            .to_string()
        })?;
        Ok(Self {
            col_ptr,
            row_idx,
            symbolic: analysis.symbolic,
            l_values,
            factored: false,
            scratch,
            rhs_cols,
        })
    }

    /// The symbolic analysis alone (fill-reducing ordering and the factor's pattern), which
    /// tells the memory the factor will need before any of it is allocated.
    ///
    /// # Errors
    /// A message when faer's analysis fails (it reports running out of memory as an error).
    pub(crate) fn analyse(
        col_ptr: &[usize],
        row_idx: &[usize],
        rhs_cols: usize,
    ) -> Result<Analysis, String> {
        let n = col_ptr.len() - 1;
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern,
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| format!("symbolic Cholesky analysis failed: {e:?}"))?;
        let factor_req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Spec::default());
        let solve_req = symbolic.solve_in_place_scratch::<f64>(rhs_cols, Par::Seq);
        Ok(Analysis {
            symbolic,
            scratch: StackReq::any_of(&[factor_req, solve_req]),
        })
    }

    /// Order of the matrix.
    pub(crate) fn n(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Number of stored entries of the lower triangle (the length `values` must have).
    pub(crate) fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Numerically factors the matrix whose lower-triangle entries are `values` (in the
    /// pattern's order).
    ///
    /// # Errors
    /// A message when the matrix is not numerically positive definite.
    pub(crate) fn factorize(&mut self, values: &[f64]) -> Result<(), String> {
        self.factored = false;
        let n = self.n();
        let pattern =
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(pattern, values);
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Spec::default(),
            )
            .map_err(|e| format!("the matrix is not positive definite ({e})"))?;
        self.factored = true;
        Ok(())
    }

    /// Overwrites `rhs` (column-major, `n` rows, at most `rhs_cols` columns) with the solution
    /// of `A x = rhs` for the last factored `A`.
    ///
    /// # Errors
    /// A message when nothing has been factored yet or the shape is wrong.
    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), String> {
        let n = self.n();
        if !self.factored {
            return Err("solve before a successful factorisation".to_owned());
        }
        if n == 0 {
            return Ok(());
        }
        let cols = rhs.len() / n;
        if cols * n != rhs.len() || cols > self.rhs_cols {
            return Err(format!(
                "right-hand side of length {} does not fit {n} rows x at most {} columns",
                rhs.len(),
                self.rhs_cols
            ));
        }
        let rhs = MatMut::from_column_major_slice_mut(rhs, n, cols);
        LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.scratch),
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_spd_system_exactly() {
        // [[4, 1, 0], [1, 3, 1], [0, 1, 2]] x = [1, 2, 3]; lower triangle by columns.
        let mut c = Cholesky::new(vec![0, 2, 4, 5], vec![0, 1, 1, 2, 2], 1).unwrap();
        c.factorize(&[4.0, 1.0, 3.0, 1.0, 2.0]).unwrap();
        let mut x = vec![1.0, 2.0, 3.0];
        c.solve_in_place(&mut x).unwrap();
        let a = [[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]];
        for (row, b) in a.iter().zip([1.0, 2.0, 3.0]) {
            let ax: f64 = row.iter().zip(&x).map(|(a, x)| a * x).sum();
            // A well-conditioned 3x3 (condition number < 10): rounding only.
            assert!((ax - b).abs() < 1e-14);
        }
    }

    #[test]
    fn an_indefinite_matrix_is_an_error_not_a_panic() {
        let mut c = Cholesky::new(vec![0, 2, 3], vec![0, 1, 1], 1).unwrap();
        assert!(c.factorize(&[1.0, 2.0, 1.0]).is_err());
        let mut x = vec![1.0, 1.0];
        assert!(c.solve_in_place(&mut x).is_err());
    }
}
