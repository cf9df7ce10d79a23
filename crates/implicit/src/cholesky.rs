//! A faer sparse Cholesky (`L L^T`) whose symbolic analysis is done once per sparsity pattern.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par, Side, Spec};

use crate::memory::{Allocation, try_filled};

/// The outcome of [`Cholesky::analyse`]: the symbolic factor and the workspace it needs.
pub(crate) struct Analysis<T> {
    symbolic: SymbolicCholesky<usize>,
    scratch: StackReq,
    precision: std::marker::PhantomData<T>,
}

impl<T> Analysis<T> {
    /// Entries of the factor `L`.
    pub(crate) fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Bytes the factorisation holds: the symbolic factor (kept for every refactorisation),
    /// the numeric factor's values and the workspace.
    pub(crate) fn bytes(&self) -> u64 {
        symbolic_bytes(&self.symbolic)
            + (size_of::<T>() * self.factor_len() + self.scratch.unaligned_bytes_required()) as u64
    }
}

/// Bytes of `symbolic`'s arrays: the fill-reducing permutation and its inverse, and the
/// factor's structure (simplicial: column pointers and row indices; supernodal: the supernodes'
/// bounds, pointers and row indices, and faer's row-major copy of their pattern, as long again).
fn symbolic_bytes(symbolic: &SymbolicCholesky<usize>) -> u64 {
    let perm = if symbolic.perm().is_some() {
        2 * symbolic.nrows()
    } else {
        0
    };
    let structure = match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr().len() + s.row_idx().len(),
        SymbolicCholeskyRaw::Supernodal(s) => {
            let supernodes = s.n_supernodes() + 1;
            5 * supernodes + 2 * s.row_idx().len()
        }
    };
    (size_of::<usize>() * (perm + structure)) as u64
}

/// The floating-point type a [`Cholesky`] factor is stored and computed in.
pub(crate) trait Precision: ComplexField + Copy + Default {
    /// `v` rounded to this precision.
    fn narrow_one(v: f64) -> Self::Real;
    /// `values` in this precision: `values` itself for `f64`, else a rounded copy in `buf`.
    fn narrow<'a>(values: &'a [f64], buf: &'a mut Vec<Self>) -> &'a [Self];
    /// Runs `f` on `rhs` in this precision and writes its result back (in place for `f64`,
    /// through `buf` otherwise).
    fn in_place(rhs: &mut [f64], buf: &mut Vec<Self>, f: impl FnOnce(&mut [Self]));
}

impl Precision for f64 {
    fn narrow_one(v: f64) -> Self {
        v
    }
    fn narrow<'a>(values: &'a [f64], _: &'a mut Vec<Self>) -> &'a [Self] {
        values
    }
    fn in_place(rhs: &mut [f64], _: &mut Vec<Self>, f: impl FnOnce(&mut [Self])) {
        f(rhs);
    }
}

impl Precision for f32 {
    #[allow(clippy::cast_possible_truncation)]
    fn narrow_one(v: f64) -> Self {
        v as f32
    }
    #[allow(clippy::cast_possible_truncation)]
    fn narrow<'a>(values: &'a [f64], buf: &'a mut Vec<Self>) -> &'a [Self] {
        buf.clear();
        buf.extend(values.iter().map(|&v| v as f32));
        buf
    }
    fn in_place(rhs: &mut [f64], buf: &mut Vec<Self>, f: impl FnOnce(&mut [Self])) {
        Self::narrow(rhs, buf);
        f(buf);
        for (r, &b) in rhs.iter_mut().zip(buf.iter()) {
            *r = f64::from(b);
        }
    }
}

/// A symmetric positive-definite matrix with a fixed lower-triangular pattern and its Cholesky
/// factor, computed and stored in precision `T` from `f64` values (`f32` halves the memory the
/// factorisation and the triangular solves stream through, for a factor used only as a
/// preconditioner).
///
/// The fill-reducing ordering (AMD) and the symbolic factor are computed in [`Cholesky::new`];
/// [`Cholesky::factorize`] then only redoes the numeric factor, which is what a Newton iteration
/// or a change of stiffness needs.
///
/// NOTE: everything runs with [`Par::Seq`]: results must be bit-identical from run to run and
/// the machine's cores are better spent elsewhere (the TUI, other cloths) than on a
/// 10^4-unknown factorisation.
pub(crate) struct Cholesky<T: Precision = f64> {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<T>,
    /// The matrix's values, then the right-hand sides, rounded to `T` (unused for `f64`).
    rounded: Vec<T>,
    factored: bool,
    scratch: MemBuffer,
    /// Right-hand sides the scratch was sized for.
    rhs_cols: usize,
}

impl<T: Precision> std::fmt::Debug for Cholesky<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cholesky")
            .field("n", &self.n())
            .field("nnz_a", &self.row_idx.len())
            .field("nnz_l", &self.l_values.len())
            .field("factored", &self.factored)
            .finish_non_exhaustive()
    }
}

impl<T: Precision> Cholesky<T> {
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
        let l_values = try_filled(
            analysis.symbolic.len_val(),
            T::default(),
            "the Cholesky factor",
        )
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
            rounded: Vec::new(),
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
    ) -> Result<Analysis<T>, String> {
        let n = col_ptr.len() - 1;
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern,
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|_| "the analysis of its system's sparsity pattern failed".to_owned())?;
        let factor_req = symbolic.factorize_numeric_llt_scratch::<T>(Par::Seq, Spec::default());
        let solve_req = symbolic.solve_in_place_scratch::<T>(rhs_cols, Par::Seq);
        Ok(Analysis {
            symbolic,
            scratch: StackReq::any_of(&[factor_req, solve_req]),
            precision: std::marker::PhantomData,
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
    /// `least_pivot`, when positive, is a lower bound on the matrix's least eigenvalue, which
    /// bounds every pivot of an exact factorisation from below: a pivot that rounding takes
    /// under half of it is replaced by `least_pivot`, so that a factor computed in a low
    /// precision stays that of a positive-definite matrix close to this one (which is all a
    /// preconditioner needs) instead of failing.
    ///
    /// # Errors
    /// A message when the matrix is not numerically positive definite.
    pub(crate) fn factorize(&mut self, values: &[f64], least_pivot: f64) -> Result<(), String> {
        self.factored = false;
        let n = self.n();
        let pattern =
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(pattern, T::narrow(values, &mut self.rounded));
        self.symbolic
            .factorize_numeric_llt::<T>(
                &mut self.l_values,
                a,
                Side::Lower,
                if least_pivot > 0.0 {
                    LltRegularization {
                        dynamic_regularization_delta: T::narrow_one(least_pivot),
                        dynamic_regularization_epsilon: T::narrow_one(0.5 * least_pivot),
                    }
                } else {
                    LltRegularization::default()
                },
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Spec::default(),
            )
            // NOTE: faer's error names its own types; what the user can act on is the
            // matrix and its cause, which the caller words from the scene.
            .map_err(|_| {
                "its system matrix is not positive definite (the springs' stiffness \
                 overwhelms the points' mass, or positions are beyond what a 64-bit float \
                 resolves)"
                    .to_owned()
            })?;
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
        let (symbolic, l_values, scratch) = (&self.symbolic, &self.l_values, &mut self.scratch);
        T::in_place(rhs, &mut self.rounded, |rhs| {
            let rhs = MatMut::from_column_major_slice_mut(rhs, n, cols);
            LltRef::new(symbolic, l_values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                Par::Seq,
                MemStack::new(scratch),
            );
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_spd_system_to_its_precision() {
        // [[4, 1, 0], [1, 3, 1], [0, 1, 2]] x = [1, 2, 3]; lower triangle by columns. A
        // condition number under 10, so the solution is within a few roundings of the exact
        // one: 1e-14 in double; in single (6e-8 each), 1e-5 leaves a factor of a hundred and
        // still fails on any wrong value.
        for (single, tolerance) in [(false, 1e-14), (true, 1e-5)] {
            let (col_ptr, row_idx) = (vec![0, 2, 4, 5], vec![0, 1, 1, 2, 2]);
            let values = [4.0, 1.0, 3.0, 1.0, 2.0];
            let mut x = vec![1.0, 2.0, 3.0];
            if single {
                let mut c = Cholesky::<f32>::new(col_ptr, row_idx, 1).unwrap();
                c.factorize(&values, 0.0).unwrap();
                c.solve_in_place(&mut x).unwrap();
            } else {
                let mut c = Cholesky::<f64>::new(col_ptr, row_idx, 1).unwrap();
                c.factorize(&values, 0.0).unwrap();
                c.solve_in_place(&mut x).unwrap();
            }
            let a = [[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]];
            for (row, b) in a.iter().zip([1.0, 2.0, 3.0]) {
                let ax: f64 = row.iter().zip(&x).map(|(a, x)| a * x).sum();
                assert!(
                    (ax - b).abs() < tolerance,
                    "single {single}: {ax} against {b}"
                );
            }
        }
    }

    #[test]
    fn a_pivot_under_the_least_pivot_is_replaced_and_the_factor_stays_definite() {
        // [[1, 2], [2, 1]] is indefinite: its second pivot is 1 - 4 = -3. With a least pivot of
        // 1 it becomes 1, the factor is that of [[1, 2], [2, 5]], positive definite, and a
        // solve with it is a descent direction: b . x > 0 for any b.
        for single in [false, true] {
            let b = [1.0, -1.0];
            let mut x = b.to_vec();
            if single {
                let mut c = Cholesky::<f32>::new(vec![0, 2, 3], vec![0, 1, 1], 1).unwrap();
                c.factorize(&[1.0, 2.0, 1.0], 1.0).unwrap();
                c.solve_in_place(&mut x).unwrap();
            } else {
                let mut c = Cholesky::<f64>::new(vec![0, 2, 3], vec![0, 1, 1], 1).unwrap();
                c.factorize(&[1.0, 2.0, 1.0], 1.0).unwrap();
                c.solve_in_place(&mut x).unwrap();
            }
            // The factor's matrix is [[1, 2], [2, 5]]: x = [7, -3] exactly (to f32 rounding).
            assert!(
                (x[0] - 7.0).abs() < 1e-5 && (x[1] + 3.0).abs() < 1e-5,
                "{x:?}"
            );
            assert!(b[0] * x[0] + b[1] * x[1] > 0.0);
        }
    }

    #[test]
    fn an_indefinite_matrix_is_an_error_not_a_panic() {
        let mut c = Cholesky::<f64>::new(vec![0, 2, 3], vec![0, 1, 1], 1).unwrap();
        assert!(c.factorize(&[1.0, 2.0, 1.0], 0.0).is_err());
        let mut x = vec![1.0, 1.0];
        assert!(c.solve_in_place(&mut x).is_err());
    }
}
