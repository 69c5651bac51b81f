//! Dense linear algebra for the per-scenario hot path: an in-place LU with
//! partial pivoting on buffers sized once, and a 1-norm condition estimate
//! (Hager-Higham), so every solve carries its conditioning without allocating.
//!
//! The accuracy harness compares this against nalgebra, faer, QR/SVD and exact
//! rationals; see `docs/accuracy.md`.

/// Above this 1-norm condition estimate a result is flagged with a warning.
pub const COND_WARN: f64 = 1e8;
/// Above this 1-norm condition estimate egt refuses to return a result: with
/// double precision fewer than ~4 significant digits would be trustworthy.
pub const COND_REFUSE: f64 = 1e12;

use crate::error::{AnalysisError, Error, Result};

/// LU factorisation P A = L U of a square matrix, in place, row-major.
#[derive(Debug, Clone)]
pub struct Lu {
    n: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
    /// Reciprocals of U's diagonal: the solves multiply instead of dividing
    /// (a division's latency dominates a small triangular solve).
    dinv: Vec<f64>,
    /// Envelope of the factors: the first non-zero column of each row of L
    /// and one past the last non-zero column of each row of U. Systems too
    /// large for the unrolled kernels skip the zeros outside it (Willis rows
    /// have three non-zeros, and chains of planetary sets stay banded).
    lo: Vec<usize>,
    hi: Vec<usize>,
    anorm: f64,
    norm1: Norm1Work,
}

/// A zero pivot: the matrix is singular at this column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ZeroPivot(pub usize);

/// A singular system, in words.
pub(crate) fn singular(what: &str, detail: &str) -> Error {
    AnalysisError::Singular {
        what: what.into(),
        detail: detail.into(),
    }
    .into()
}

/// Refuse a result whose condition estimate is past [`COND_REFUSE`].
pub(crate) fn refuse(cond: f64, what: &str) -> Result<()> {
    if cond > COND_REFUSE {
        return Err(AnalysisError::IllConditioned {
            what: what.into(),
            condition: cond,
            threshold: COND_REFUSE,
        }
        .into());
    }
    Ok(())
}

impl Lu {
    /// Buffers for an `n x n` system.
    pub fn new(n: usize) -> Self {
        Lu {
            n,
            a: vec![0.0; n * n],
            piv: vec![0; n],
            dinv: vec![0.0; n],
            lo: (0..n).collect(),
            hi: (1..=n).collect(),
            anorm: 0.0,
            norm1: Norm1Work::new(n),
        }
    }

    /// Order of the system.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The matrix to fill before [`Lu::factor`] (row-major, `a[i * n + j]`).
    pub fn matrix_mut(&mut self) -> &mut [f64] {
        &mut self.a
    }

    /// Factor in place.
    ///
    /// # Errors
    /// [`ZeroPivot`] when a whole pivot column is zero.
    pub fn factor(&mut self) -> Result<(), ZeroPivot> {
        let (a, piv, dinv) = (&mut self.a[..], &mut self.piv[..], &mut self.dinv[..]);
        let env = Envelope {
            lo: &mut self.lo,
            hi: &mut self.hi,
        };
        self.anorm = dispatch!(self.n, d => factor(d, a, piv, dinv, env))?;
        Ok(())
    }

    /// Factor and estimate the condition: the one checked factorisation of
    /// egt. `what` names the system and `detail` says what a zero pivot
    /// means for it.
    ///
    /// # Errors
    /// [`AnalysisError::Singular`] on a zero pivot; [`AnalysisError::IllConditioned`]
    /// past [`COND_REFUSE`].
    pub(crate) fn factor_checked(&mut self, what: &str, detail: &str) -> Result<f64> {
        self.factor().map_err(|_| singular(what, detail))?;
        let cond = self.condition();
        refuse(cond, what)?;
        Ok(cond)
    }

    /// Solve A x = b in place (after [`Lu::factor`]).
    pub fn solve(&self, b: &mut [f64]) {
        let (a, piv, dinv, env) = (&self.a[..], &self.piv[..], &self.dinv[..], self.env());
        dispatch!(self.n, d => solve(d, a, piv, dinv, env, b));
    }

    /// Solve A x = b and A y = c in place at once (after [`Lu::factor`]): the
    /// two substitutions interleave, which hides their latency on small systems.
    pub fn solve2(&self, b: &mut [f64], c: &mut [f64]) {
        let (a, piv, dinv, env) = (&self.a[..], &self.piv[..], &self.dinv[..], self.env());
        dispatch!(self.n, d => solve2(d, a, piv, dinv, env, b, c));
    }

    /// Solve A^T x = b in place (after [`Lu::factor`]).
    pub fn solve_transpose(&self, b: &mut [f64]) {
        let (a, piv, dinv, env) = (&self.a[..], &self.piv[..], &self.dinv[..], self.env());
        dispatch!(self.n, d => solve_transpose(d, a, piv, dinv, env, b));
    }

    fn env(&self) -> (&[usize], &[usize]) {
        (&self.lo, &self.hi)
    }

    /// Estimate of the 1-norm condition number ||A||_1 ||A^-1||_1, after
    /// [`Lu::factor`]: Hager's method with Higham's stopping rules and extra test
    /// vector (LAPACK's `dlacn2`), a lower bound in practice within a factor
    /// of 3 of the true value. Allocates nothing.
    pub fn condition(&mut self) -> f64 {
        let mut work = std::mem::take(&mut self.norm1);
        let c = condition(&mut &*self, self.anorm, &mut work);
        self.norm1 = work;
        c
    }
}

/// The work vectors of the condition estimate, of the system's order.
#[derive(Debug, Clone, Default)]
pub(crate) struct Norm1Work {
    x: Vec<f64>,
    alt: Vec<f64>,
    sign: Vec<f64>,
}

impl Norm1Work {
    /// Work vectors for a system of order `n`.
    pub(crate) fn new(n: usize) -> Self {
        Norm1Work {
            x: vec![0.0; n],
            alt: vec![0.0; n],
            sign: vec![0.0; n],
        }
    }
}

/// The 1-norm condition estimate ||A||_1 ||A^-1||_1 of a factored A whose
/// 1-norm is `anorm`, with work vectors of its order: `1` for an empty
/// system, infinite when the product is not finite.
pub(crate) fn condition(a: &mut impl Factored, anorm: f64, work: &mut Norm1Work) -> f64 {
    if work.x.is_empty() {
        return 1.0;
    }
    let est = inverse_norm1(a, &mut work.x, &mut work.alt, &mut work.sign);
    let c = anorm * est;
    if c.is_finite() { c } else { f64::INFINITY }
}

/// A factored square system, as the condition estimate sees it.
pub(crate) trait Factored {
    /// Solve A x = b and A y = c in place.
    fn solve_pair(&mut self, b: &mut [f64], c: &mut [f64]);
    /// Solve A x = b in place.
    fn solve_one(&mut self, b: &mut [f64]);
    /// Solve A^T x = b in place.
    fn solve_transposed(&mut self, b: &mut [f64]);
}

impl Factored for &Lu {
    #[inline]
    fn solve_pair(&mut self, b: &mut [f64], c: &mut [f64]) {
        self.solve2(b, c);
    }
    #[inline]
    fn solve_one(&mut self, b: &mut [f64]) {
        self.solve(b);
    }
    #[inline]
    fn solve_transposed(&mut self, b: &mut [f64]) {
        self.solve_transpose(b);
    }
}

/// Estimate of ||A^-1||_1 for a factored A of order `x.len()`: Hager's
/// method with Higham's stopping rules and extra test vector (LAPACK's
/// `dlacn2`). A lower bound, in practice within a factor of 3 of the true
/// value. `x`, `alt` and `sign` are work vectors of the system's order.
#[inline]
pub(crate) fn inverse_norm1(
    a: &mut impl Factored,
    x: &mut [f64],
    alt: &mut [f64],
    sign: &mut [f64],
) -> f64 {
    let n = x.len();
    if n == 0 {
        return 1.0;
    }
    // Start from x = (1/n, ..) and, alongside, Higham's alternating vector.
    x.iter_mut().for_each(|v| *v = 1.0 / n as f64);
    for (i, v) in alt.iter_mut().enumerate() {
        let s = if i % 2 == 0 { 1.0 } else { -1.0 };
        *v = s * (1.0 + i as f64 / (n.max(2) - 1) as f64);
    }
    a.solve_pair(x, alt);
    let alt_est = 2.0 * norm1(alt) / (3.0 * n as f64);
    let mut est = norm1(x);
    if n > 1 {
        signs_of(x, sign);
        for _ in 0..4 {
            // The gradient z = A^-T sign(x) points to the next unit vector.
            alt.copy_from_slice(sign);
            a.solve_transposed(alt);
            let j = argmax_abs(alt);
            x.iter_mut().for_each(|v| *v = 0.0);
            x[j] = 1.0;
            a.solve_one(x);
            let previous = est;
            est = norm1(x);
            // Stop when the signs repeat (a local maximum) or the estimate stalls.
            if est <= previous || same_signs(x, sign) {
                est = est.max(previous);
                break;
            }
            signs_of(x, sign);
        }
    }
    est.max(alt_est)
}

/// The order of a system: a compile-time constant for the small systems
/// (most trains: up to 12 coordinates), where the loops then unroll and the
/// bounds checks fold away, or a run-time value for the rest.
pub(crate) trait Dim: Copy {
    /// Track and use the envelope of the factors (run-time sizes only: the
    /// unrolled kernels are faster without the bookkeeping).
    const ENVELOPE: bool;
    fn n(self) -> usize;
}

/// The envelope being written by a factorisation.
struct Envelope<'a> {
    lo: &'a mut [usize],
    hi: &'a mut [usize],
}

#[derive(Clone, Copy)]
pub(crate) struct Fixed<const N: usize>;

impl<const N: usize> Dim for Fixed<N> {
    const ENVELOPE: bool = false;
    #[inline(always)]
    fn n(self) -> usize {
        N
    }
}

#[derive(Clone, Copy)]
pub(crate) struct Dynamic(pub(crate) usize);

impl Dim for Dynamic {
    const ENVELOPE: bool = true;
    #[inline(always)]
    fn n(self) -> usize {
        self.0
    }
}

/// Call `$f` with the order as a [`Fixed`] dimension when it is small, else [`Dynamic`].
macro_rules! dispatch {
    ($n:expr, $d:ident => $call:expr) => {
        match $n {
            1 => {
                let $d = Fixed::<1>;
                $call
            }
            2 => {
                let $d = Fixed::<2>;
                $call
            }
            3 => {
                let $d = Fixed::<3>;
                $call
            }
            4 => {
                let $d = Fixed::<4>;
                $call
            }
            5 => {
                let $d = Fixed::<5>;
                $call
            }
            6 => {
                let $d = Fixed::<6>;
                $call
            }
            7 => {
                let $d = Fixed::<7>;
                $call
            }
            8 => {
                let $d = Fixed::<8>;
                $call
            }
            9 => {
                let $d = Fixed::<9>;
                $call
            }
            10 => {
                let $d = Fixed::<10>;
                $call
            }
            11 => {
                let $d = Fixed::<11>;
                $call
            }
            12 => {
                let $d = Fixed::<12>;
                $call
            }
            n => {
                let $d = Dynamic(n);
                $call
            }
        }
    };
}
pub(crate) use dispatch;

/// LU with partial pivoting in place; returns ||A||_1.
// Index loops on purpose: with a constant order they unroll completely.
#[allow(clippy::needless_range_loop)]
#[inline]
fn factor<D: Dim>(
    d: D,
    a: &mut [f64],
    piv: &mut [usize],
    dinv: &mut [f64],
    env: Envelope<'_>,
) -> Result<f64, ZeroPivot> {
    let n = d.n();
    let (a, piv, dinv) = (&mut a[..n * n], &mut piv[..n], &mut dinv[..n]);
    let mut anorm = 0.0_f64;
    for j in 0..n {
        let mut s = 0.0;
        for i in 0..n {
            s += a[i * n + j].abs();
        }
        anorm = anorm.max(s);
    }
    for k in 0..n {
        let (mut p, mut best) = (k, a[k * n + k].abs());
        for i in k + 1..n {
            let v = a[i * n + k].abs();
            if v > best {
                best = v;
                p = i;
            }
        }
        piv[k] = p;
        if best == 0.0 || !best.is_finite() {
            return Err(ZeroPivot(k));
        }
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
        }
        let inv = 1.0 / a[k * n + k];
        dinv[k] = inv;
        // Row k of U is final now: its last non-zero bounds the updates.
        let hk = if D::ENVELOPE {
            (k + 1..n)
                .rev()
                .find(|&j| a[k * n + j] != 0.0)
                .map_or(k + 1, |j| j + 1)
        } else {
            n
        };
        if D::ENVELOPE {
            env.hi[k] = hk;
        }
        // Eliminate below the pivot (the Willis rows are sparse: most multipliers are zero).
        for i in k + 1..n {
            let f = a[i * n + k] * inv;
            a[i * n + k] = f;
            if f != 0.0 {
                for j in k + 1..hk {
                    a[i * n + j] -= f * a[k * n + j];
                }
            }
        }
    }
    if D::ENVELOPE {
        for i in 0..n {
            env.lo[i] = (0..i).find(|&j| a[i * n + j] != 0.0).unwrap_or(i);
        }
    }
    Ok(anorm)
}

/// Solve A x = b in place from the factors.
// Index loops on purpose: with a constant order they unroll completely.
#[allow(clippy::needless_range_loop)]
#[inline]
fn solve<D: Dim>(
    d: D,
    a: &[f64],
    piv: &[usize],
    dinv: &[f64],
    env: (&[usize], &[usize]),
    b: &mut [f64],
) {
    let n = d.n();
    let (a, piv, dinv, b) = (&a[..n * n], &piv[..n], &dinv[..n], &mut b[..n]);
    for k in 0..n {
        b.swap(k, piv[k]);
    }
    // L y = P b (unit lower).
    for i in 1..n {
        let mut s = b[i];
        for j in lo::<D>(env, i)..i {
            s -= a[i * n + j] * b[j];
        }
        b[i] = s;
    }
    // U x = y, multiplying by the stored reciprocal pivots.
    for i in (0..n).rev() {
        let mut s = b[i];
        for j in i + 1..hi::<D>(env, i, n) {
            s -= a[i * n + j] * b[j];
        }
        b[i] = s * dinv[i];
    }
}

/// Solve A x = b and A y = c in place, interleaved.
// Index loops on purpose: with a constant order they unroll completely.
#[allow(clippy::needless_range_loop)]
#[inline]
fn solve2<D: Dim>(
    d: D,
    a: &[f64],
    piv: &[usize],
    dinv: &[f64],
    env: (&[usize], &[usize]),
    b: &mut [f64],
    c: &mut [f64],
) {
    let n = d.n();
    let (a, piv, dinv) = (&a[..n * n], &piv[..n], &dinv[..n]);
    let (b, c) = (&mut b[..n], &mut c[..n]);
    for k in 0..n {
        b.swap(k, piv[k]);
        c.swap(k, piv[k]);
    }
    for i in 1..n {
        let (mut s, mut t) = (b[i], c[i]);
        for j in lo::<D>(env, i)..i {
            s -= a[i * n + j] * b[j];
            t -= a[i * n + j] * c[j];
        }
        b[i] = s;
        c[i] = t;
    }
    for i in (0..n).rev() {
        let (mut s, mut t) = (b[i], c[i]);
        for j in i + 1..hi::<D>(env, i, n) {
            s -= a[i * n + j] * b[j];
            t -= a[i * n + j] * c[j];
        }
        b[i] = s * dinv[i];
        c[i] = t * dinv[i];
    }
}

/// Solve A^T x = b in place: A^T = U^T L^T P, so U^T y = b, L^T z = y,
/// x = P^T z, each as updates by rows of U and L (contiguous).
// Index loops on purpose: with a constant order they unroll completely.
#[allow(clippy::needless_range_loop)]
#[inline]
fn solve_transpose<D: Dim>(
    d: D,
    a: &[f64],
    piv: &[usize],
    dinv: &[f64],
    env: (&[usize], &[usize]),
    b: &mut [f64],
) {
    let n = d.n();
    let (a, piv, dinv, b) = (&a[..n * n], &piv[..n], &dinv[..n], &mut b[..n]);
    for i in 0..n {
        let y = b[i] * dinv[i];
        b[i] = y;
        for j in i + 1..hi::<D>(env, i, n) {
            b[j] -= a[i * n + j] * y;
        }
    }
    for i in (1..n).rev() {
        let z = b[i];
        for j in lo::<D>(env, i)..i {
            b[j] -= a[i * n + j] * z;
        }
    }
    for k in (0..n).rev() {
        b.swap(k, piv[k]);
    }
}

/// First column of row i of L to visit.
#[inline(always)]
fn lo<D: Dim>(env: (&[usize], &[usize]), i: usize) -> usize {
    if D::ENVELOPE { env.0[i] } else { 0 }
}

/// One past the last column of row i of U to visit.
#[inline(always)]
fn hi<D: Dim>(env: (&[usize], &[usize]), i: usize, n: usize) -> usize {
    if D::ENVELOPE { env.1[i] } else { n }
}

fn norm1(v: &[f64]) -> f64 {
    v.iter().map(|x| x.abs()).sum()
}

fn signs_of(v: &[f64], out: &mut [f64]) {
    for (o, x) in out.iter_mut().zip(v) {
        *o = if *x >= 0.0 { 1.0 } else { -1.0 };
    }
}

fn same_signs(v: &[f64], signs: &[f64]) -> bool {
    v.iter()
        .zip(signs)
        .all(|(x, s)| (if *x >= 0.0 { 1.0 } else { -1.0 }) == *s)
}

fn argmax_abs(v: &[f64]) -> usize {
    let (mut j, mut best) = (0, -1.0);
    for (i, x) in v.iter().enumerate() {
        if x.abs() > best {
            best = x.abs();
            j = i;
        }
    }
    j
}

/// A matrix as a list of rows (for reports).
pub fn matrix_rows(m: &nalgebra::DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

/// Serialize a matrix as a list of rows:
/// `#[serde(serialize_with = "crate::numerics::linalg::serde_rows")]`.
///
/// # Errors
/// The serializer's.
pub fn serde_rows<S: serde::Serializer>(
    m: &nalgebra::DMatrix<f64>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&matrix_rows(m), s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fill(lu: &mut Lu, m: &[f64]) {
        lu.matrix_mut().copy_from_slice(m);
    }

    #[test]
    fn solves_and_transposes_by_residual() {
        let m = [4.0, -2.0, 1.0, 3.0, 6.0, -4.0, 2.0, 1.0, 8.0];
        let mut lu = Lu::new(3);
        fill(&mut lu, &m);
        lu.factor().expect("regular");
        let b = [1.0, 2.0, 3.0];
        let mut x = b;
        lu.solve(&mut x);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| m[i * 3 + j] * x[j]).sum::<f64>() - b[i];
            assert!(r.abs() < 1e-14);
        }
        let mut y = b;
        lu.solve_transpose(&mut y);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| m[j * 3 + i] * y[j]).sum::<f64>() - b[i];
            assert!(r.abs() < 1e-14);
        }
    }

    /// Larger systems take the run-time path with the envelope: banded,
    /// sparse-with-fill and dense matrices, checked by residuals both ways.
    #[test]
    fn envelope_path_solves_banded_sparse_and_dense_systems() {
        let n = 20;
        let mut seed = 7u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64) - 0.5
        };
        for kind in 0..3 {
            let mut m = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    let keep = match kind {
                        0 => i.abs_diff(j) <= 2,
                        1 => i == j || (i * 7 + j * 3) % 5 == 0,
                        _ => true,
                    };
                    if keep {
                        m[i * n + j] = rand();
                    }
                }
                m[i * n + i] += if kind == 1 { 0.3 } else { 0.0 };
            }
            let mut lu = Lu::new(n);
            fill(&mut lu, &m);
            lu.factor().expect("regular");
            let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
            let (mut x, mut y, mut z) = (b.clone(), b.clone(), b.clone());
            let mut w = b.iter().map(|v| 2.0 * v).collect::<Vec<_>>();
            lu.solve(&mut x);
            lu.solve_transpose(&mut y);
            lu.solve2(&mut z, &mut w);
            let scale = m.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
            for i in 0..n {
                let r: f64 = (0..n).map(|j| m[i * n + j] * x[j]).sum::<f64>() - b[i];
                let rt: f64 = (0..n).map(|j| m[j * n + i] * y[j]).sum::<f64>() - b[i];
                let xs = x.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                let ys = y.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                assert!(
                    r.abs() <= 1e-12 * scale * xs.max(1.0),
                    "kind {kind} row {i}: {r}"
                );
                assert!(
                    rt.abs() <= 1e-12 * scale * ys.max(1.0),
                    "kind {kind} col {i}: {rt}"
                );
                assert_eq!(z[i], x[i]);
                assert!((w[i] - 2.0 * x[i]).abs() <= 1e-12 * xs.max(1.0));
            }
        }
    }

    #[test]
    fn condition_matches_exact_for_diagonal_and_flags_near_singular() {
        let mut lu = Lu::new(2);
        fill(&mut lu, &[1.0, 0.0, 0.0, 1e-9]);
        lu.factor().expect("regular");
        let c = lu.condition();
        assert!((c / 1e9 - 1.0).abs() < 1e-12, "{c}");
        fill(&mut lu, &[1.0, 1.0, 1.0, 1.0 + 1e-14]);
        lu.factor().expect("regular");
        assert!(lu.condition() > COND_REFUSE);
        fill(&mut lu, &[1.0, 1.0, 2.0, 2.0]);
        assert_eq!(lu.factor(), Err(ZeroPivot(1)));
    }
}
