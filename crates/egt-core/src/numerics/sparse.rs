//! Sparse LU for large systems of fixed pattern (faer's sparse LU: a
//! fill-reducing column order, partial pivoting by rows), with the same
//! 1-norm condition estimate as the dense [`Lu`](super::linalg::Lu).
//!
//! The pattern is analysed once ([`SparseLu::new`]); each factorisation then
//! reuses the symbolic analysis, the numeric storage and one scratch buffer,
//! so refactoring for new values and solving allocate nothing. A Willis row
//! has three entries, so a train of n links factors in time and memory about
//! linear in n where the dense LU takes n^2 memory.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::prelude::Reborrow;
use faer::sparse::linalg::lu::{
    LuRef, LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};

use super::linalg::{Factored, Norm1Work, condition, refuse, singular};
use crate::error::AnalysisError;

/// The pattern could not be analysed (faer ran out of memory or index room).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the sparse LU could not be set up: {0}")]
pub struct SetupError(pub String);

/// Why a factorisation failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FactorError {
    /// No non-zero pivot is left in the pattern at this column (of the
    /// fill-reducing order): the matrix is structurally singular.
    #[error("structurally singular at pivot {0}")]
    Singular(usize),
    /// faer could not allocate its working memory.
    #[error("the sparse LU could not allocate: {0}")]
    Failed(String),
}

/// LU factorisation of a square sparse matrix of fixed pattern.
pub struct SparseLu {
    n: usize,
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    /// Values in the pattern's column-major order.
    values: Vec<f64>,
    stack: MemBuffer,
    factored: bool,
    anorm: f64,
    norm1: Norm1Work,
}

impl std::fmt::Debug for SparseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu")
            .field("n", &self.n)
            .field("nnz", &self.values.len())
            .field("factored", &self.factored)
            .finish_non_exhaustive()
    }
}

impl Clone for SparseLu {
    fn clone(&self) -> Self {
        // The factors are not kept across a clone: refill and factor again.
        let stack = MemBuffer::new(scratch(&self.symbolic));
        SparseLu {
            n: self.n,
            pattern: self.pattern.clone(),
            symbolic: self.symbolic.clone(),
            numeric: NumericLu::new(),
            values: self.values.clone(),
            stack,
            factored: false,
            anorm: 0.0,
            norm1: self.norm1.clone(),
        }
    }
}

fn scratch(symbolic: &SymbolicLu<usize>) -> StackReq {
    StackReq::any_of(&[
        symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
        symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        symbolic.solve_transpose_in_place_scratch::<f64>(1, Par::Seq),
    ])
}

impl SparseLu {
    /// Analyse the pattern of an `n x n` matrix whose non-zeros may sit at
    /// `entries` (row, column); repeated entries share one slot. Returns the
    /// solver and, for each entry, its slot in [`SparseLu::values_mut`].
    ///
    /// # Errors
    /// [`SetupError`] when faer cannot allocate the analysis.
    ///
    /// # Panics
    /// An entry outside the matrix (a bug of the caller).
    pub fn new(n: usize, entries: &[(usize, usize)]) -> Result<(Self, Vec<usize>), SetupError> {
        let mut sorted: Vec<(usize, usize)> = entries.iter().map(|&(r, c)| (c, r)).collect();
        sorted.sort_unstable();
        sorted.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::with_capacity(sorted.len());
        for &(c, r) in &sorted {
            assert!(
                r < n && c < n,
                "entry ({r}, {c}) outside a {n} x {n} matrix"
            );
            col_ptr[c + 1] += 1;
            row_idx.push(r);
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let slots = entries
            .iter()
            .map(|&(r, c)| {
                let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
                col_ptr[c] + rows.binary_search(&r).unwrap_or_else(|_| unreachable!())
            })
            .collect();
        let nnz = row_idx.len();
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_lu(pattern.rb(), LuSymbolicParams::default())
            .map_err(|e| SetupError(format!("{e:?}")))?;
        let stack =
            MemBuffer::try_new(scratch(&symbolic)).map_err(|e| SetupError(format!("{e:?}")))?;
        Ok((
            SparseLu {
                n,
                pattern,
                symbolic,
                numeric: NumericLu::new(),
                values: vec![0.0; nnz],
                stack,
                factored: false,
                anorm: 0.0,
                norm1: Norm1Work::new(n),
            },
            slots,
        ))
    }

    /// Order of the system.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The values to fill before [`SparseLu::factor`], at the slots
    /// [`SparseLu::new`] returned (zero the ones not set).
    pub fn values_mut(&mut self) -> &mut [f64] {
        self.factored = false;
        &mut self.values
    }

    /// Factor.
    ///
    /// # Errors
    /// [`FactorError::Singular`] when the pattern is structurally singular
    /// (a pivot that is zero by its value shows as an infinite
    /// [`SparseLu::condition`] instead); [`FactorError::Failed`] when faer
    /// cannot allocate.
    pub fn factor(&mut self) -> Result<(), FactorError> {
        self.factored = false;
        let pattern = self.pattern.rb();
        self.anorm = (0..self.n)
            .map(|c| {
                let (a, b) = (pattern.col_ptr()[c], pattern.col_ptr()[c + 1]);
                self.values[a..b].iter().map(|v| v.abs()).sum::<f64>()
            })
            .fold(0.0, f64::max);
        let mat = SparseColMatRef::new(pattern, &self.values);
        self.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                mat,
                Par::Seq,
                MemStack::new(&mut self.stack),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::sparse::linalg::LuError::SymbolicSingular { index } => {
                    FactorError::Singular(index)
                }
                faer::sparse::linalg::LuError::Generic(e) => FactorError::Failed(format!("{e:?}")),
            })?;
        self.factored = true;
        Ok(())
    }

    /// Factor and estimate the condition, as [`Lu`](super::linalg::Lu)'s
    /// checked factorisation: `what` names the system and `detail` says what
    /// a zero pivot means for it.
    ///
    /// # Errors
    /// [`AnalysisError::Singular`] on a structurally or numerically zero
    /// pivot; [`AnalysisError::IllConditioned`] past
    /// [`COND_REFUSE`](super::linalg::COND_REFUSE);
    /// [`AnalysisError::OutOfMemory`] when faer cannot allocate.
    pub(crate) fn factor_checked(&mut self, what: &str, detail: &str) -> crate::error::Result<f64> {
        self.factor().map_err(|e| match e {
            FactorError::Singular(_) => singular(what, detail),
            FactorError::Failed(d) => AnalysisError::OutOfMemory {
                what: what.into(),
                detail: d,
            }
            .into(),
        })?;
        let cond = self.condition();
        if cond.is_infinite() {
            return Err(singular(what, "a pivot is zero"));
        }
        refuse(cond, what)?;
        Ok(cond)
    }

    /// Solve A x = b in place (after [`SparseLu::factor`]).
    ///
    /// # Panics
    /// Before a successful [`SparseLu::factor`], or with `b` of another length.
    pub fn solve(&mut self, b: &mut [f64]) {
        assert!(self.factored, "solve before factor");
        let n = self.n;
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(b, n, 1),
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
    }

    /// Solve A^T x = b in place (after [`SparseLu::factor`]).
    ///
    /// # Panics
    /// As [`SparseLu::solve`].
    pub fn solve_transpose(&mut self, b: &mut [f64]) {
        assert!(self.factored, "solve before factor");
        let n = self.n;
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_transpose_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(b, n, 1),
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
    }

    /// Estimate of the 1-norm condition number, after [`SparseLu::factor`]
    /// (the estimate of the dense LU: a few solves with A and A^T). Infinite
    /// when a pivot was zero.
    pub fn condition(&mut self) -> f64 {
        let mut work = std::mem::take(&mut self.norm1);
        let c = condition(self, self.anorm, &mut work);
        self.norm1 = work;
        c
    }
}

impl Factored for SparseLu {
    fn solve_pair(&mut self, b: &mut [f64], c: &mut [f64]) {
        self.solve(b);
        self.solve(c);
    }
    fn solve_one(&mut self, b: &mut [f64]) {
        self.solve(b);
    }
    fn solve_transposed(&mut self, b: &mut [f64]) {
        self.solve_transpose(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::linalg::Lu;

    /// Entries (row, column, value) of a test matrix.
    type Entries = Vec<(usize, usize, f64)>;

    /// A random-ish sparse matrix with a heavy diagonal, and the same in a dense LU.
    fn pair(n: usize, seed: u64) -> (Entries, SparseLu, Vec<usize>, Lu) {
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (s >> 33) as usize
        };
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push((i, i, 4.0 + (next() % 7) as f64));
            for _ in 0..2 {
                let j = next() % n;
                entries.push((i, j, (next() % 11) as f64 - 5.0));
            }
        }
        let pat: Vec<(usize, usize)> = entries.iter().map(|&(r, c, _)| (r, c)).collect();
        let (sp, slots) = SparseLu::new(n, &pat).unwrap_or_else(|e| panic!("{e}"));
        let mut lu = Lu::new(n);
        for &(r, c, v) in &entries {
            lu.matrix_mut()[r * n + c] += v;
        }
        (entries, sp, slots, lu)
    }

    #[test]
    fn solves_and_conditions_agree_with_the_dense_lu() {
        for (n, seed) in [(1, 1), (7, 2), (60, 3), (300, 4)] {
            let (entries, mut sp, slots, mut lu) = pair(n, seed);
            let v = sp.values_mut();
            v.iter_mut().for_each(|x| *x = 0.0);
            for (&(_, _, a), &k) in entries.iter().zip(&slots) {
                v[k] += a;
            }
            sp.factor().unwrap_or_else(|e| panic!("{e:?}"));
            lu.factor().unwrap_or_else(|e| panic!("{e:?}"));
            let b: Vec<f64> = (0..n).map(|i| (i as f64).sin() + 1.0).collect();
            let (mut x, mut y) = (b.clone(), b.clone());
            sp.solve(&mut x);
            lu.solve(&mut y);
            let (mut xt, mut yt) = (b.clone(), b.clone());
            sp.solve_transpose(&mut xt);
            lu.solve_transpose(&mut yt);
            // Residual of the sparse solve, against A built from the entries.
            let mut r = b.clone();
            for &(i, j, a) in &entries {
                r[i] -= a * x[j];
            }
            let scale = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            assert!(
                r.iter().all(|v| v.abs() <= 1e-12 * scale),
                "n = {n}: residual {r:?}"
            );
            for (p, q) in x.iter().zip(&y).chain(xt.iter().zip(&yt)) {
                assert!(
                    (p - q).abs() <= 1e-10 * (1.0 + q.abs()),
                    "n = {n}: {p} vs {q}"
                );
            }
            let (cs, cd) = (sp.condition(), lu.condition());
            // Both are lower bounds of the same number, from different factors.
            assert!(cs <= 3.0 * cd && cd <= 3.0 * cs, "n = {n}: {cs} vs {cd}");
        }
    }

    #[test]
    fn a_structurally_singular_pattern_and_a_zero_pivot_are_caught() {
        // Column 1 has no entry.
        let (mut sp, _) = SparseLu::new(2, &[(0, 0), (1, 0)]).unwrap_or_else(|e| panic!("{e}"));
        sp.values_mut().iter_mut().for_each(|v| *v = 1.0);
        assert!(sp.factor().is_err());
        // A full pattern whose values are singular: [[1, 2], [2, 4]].
        let pat = [(0, 0), (0, 1), (1, 0), (1, 1)];
        let (mut sp, slots) = SparseLu::new(2, &pat).unwrap_or_else(|e| panic!("{e}"));
        for (k, v) in slots.iter().zip([1.0, 2.0, 2.0, 4.0]) {
            sp.values_mut()[*k] = v;
        }
        let c = match sp.factor() {
            Ok(()) => sp.condition(),
            Err(_) => f64::INFINITY,
        };
        assert!(c > 1e15, "condition {c}");
    }
}
