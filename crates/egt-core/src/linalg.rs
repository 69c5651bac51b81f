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

/// LU factorisation P A = L U of a square matrix, in place, row-major.
#[derive(Debug, Clone)]
pub struct Lu {
    n: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
    anorm: f64,
    work: Vec<f64>,
    work2: Vec<f64>,
}

/// A zero pivot: the matrix is singular at this column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ZeroPivot(pub usize);

impl Lu {
    /// Buffers for an `n x n` system.
    pub fn new(n: usize) -> Self {
        Lu {
            n,
            a: vec![0.0; n * n],
            piv: vec![0; n],
            anorm: 0.0,
            work: vec![0.0; n],
            work2: vec![0.0; n],
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
        let n = self.n;
        let a = &mut self.a;
        self.anorm = (0..n)
            .map(|j| (0..n).map(|i| a[i * n + j].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        for k in 0..n {
            let (mut p, mut best) = (k, a[k * n + k].abs());
            for i in k + 1..n {
                let v = a[i * n + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            self.piv[k] = p;
            if best == 0.0 || !best.is_finite() {
                return Err(ZeroPivot(k));
            }
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
            }
            let inv = 1.0 / a[k * n + k];
            for i in k + 1..n {
                let f = a[i * n + k] * inv;
                a[i * n + k] = f;
                if f != 0.0 {
                    for j in k + 1..n {
                        a[i * n + j] -= f * a[k * n + j];
                    }
                }
            }
        }
        Ok(())
    }

    /// Solve A x = b in place (after [`Lu::factor`]).
    pub fn solve(&self, b: &mut [f64]) {
        let n = self.n;
        let a = &self.a;
        for k in 0..n {
            b.swap(k, self.piv[k]);
        }
        for i in 0..n {
            let mut s = b[i];
            for j in 0..i {
                s -= a[i * n + j] * b[j];
            }
            b[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for j in i + 1..n {
                s -= a[i * n + j] * b[j];
            }
            b[i] = s / a[i * n + i];
        }
    }

    /// Solve A^T x = b in place (after [`Lu::factor`]).
    pub fn solve_transpose(&self, b: &mut [f64]) {
        let n = self.n;
        let a = &self.a;
        // A^T = U^T L^T P: solve U^T y = b, L^T z = y, x = P^T z.
        for i in 0..n {
            let mut s = b[i];
            for j in 0..i {
                s -= a[j * n + i] * b[j];
            }
            b[i] = s / a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for j in i + 1..n {
                s -= a[j * n + i] * b[j];
            }
            b[i] = s;
        }
        for k in (0..n).rev() {
            b.swap(k, self.piv[k]);
        }
    }

    /// Estimate of the 1-norm condition number ||A||_1 ||A^-1||_1 (Hager's
    /// method with Higham's extra test vector), after [`Lu::factor`]. Allocates nothing.
    pub fn condition(&mut self) -> f64 {
        let n = self.n;
        if n == 0 {
            return 1.0;
        }
        let mut x = std::mem::take(&mut self.work);
        let mut z = std::mem::take(&mut self.work2);
        x.iter_mut().for_each(|v| *v = 1.0 / n as f64);
        let mut est = 0.0;
        let mut last_j = usize::MAX;
        for _ in 0..5 {
            self.solve(&mut x);
            est = x.iter().map(|v| v.abs()).sum::<f64>();
            for (zi, xi) in z.iter_mut().zip(x.iter()) {
                *zi = if *xi >= 0.0 { 1.0 } else { -1.0 };
            }
            self.solve_transpose(&mut z);
            let (mut j, mut zmax) = (0, 0.0);
            for (i, v) in z.iter().enumerate() {
                if v.abs() > zmax {
                    zmax = v.abs();
                    j = i;
                }
            }
            // Stop when the gradient no longer points to a new unit vector.
            if j == last_j {
                break;
            }
            last_j = j;
            x.iter_mut().for_each(|v| *v = 0.0);
            x[j] = 1.0;
        }
        // Higham's alternating test vector guards against bad local maxima.
        for (i, v) in x.iter_mut().enumerate() {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            *v = sign * (1.0 + i as f64 / (n.max(2) - 1) as f64);
        }
        self.solve(&mut x);
        let alt = 2.0 * x.iter().map(|v| v.abs()).sum::<f64>() / (3.0 * n as f64);
        self.work = x;
        self.work2 = z;
        let c = self.anorm * est.max(alt);
        if c.is_finite() { c } else { f64::INFINITY }
    }
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
