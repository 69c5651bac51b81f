//! Dense LU for [`LANES`] systems of one structure at once, the scenarios in
//! the lanes of each entry (structure of arrays): every scalar step of
//! [`Lu`](super::linalg::Lu) becomes one operation over `[f64; LANES]`, which
//! the compiler turns into SIMD instructions.
//!
//! The lanes share one pivot order. At each column every live lane's
//! partial-pivoting choice is computed; a lane whose choice differs from the
//! group's (the first live lane's), whose pivot column is zero or not finite,
//! or whose condition estimate is past [`COND_REFUSE`] is marked dead, and its
//! caller solves it again on its own (where the error, if any, is raised).
//! A live lane therefore goes through exactly the operations, in the same
//! order, that [`Lu`](super::linalg::Lu) would apply to it alone (the same
//! pivots, the same reciprocal pivots, the same dlacn2 estimate): its results
//! are the same numbers.

use super::linalg::{COND_REFUSE, Dim};

/// Scenarios per group: 8 doubles fill two AVX registers or four SSE2 ones.
pub const LANES: usize = 8;

/// One value per lane.
pub type Lane = [f64; LANES];

/// Which lanes of a group are still being solved together.
pub type Live = [bool; LANES];

/// `a[l] -= f[l] * b[l]` for every lane.
#[inline(always)]
pub fn sub_mul(a: &mut Lane, f: &Lane, b: &Lane) {
    for l in 0..LANES {
        a[l] -= f[l] * b[l];
    }
}

/// `a[l] *= f[l]` for every lane.
#[inline(always)]
pub fn mul(a: &mut Lane, f: &Lane) {
    for l in 0..LANES {
        a[l] *= f[l];
    }
}

/// LU factorisations P A = L U of [`LANES`] `n x n` matrices with one pivot
/// order, in place; entry `(i, j)` of every lane at `a[i * n + j]`. The
/// methods take the order as a [`Dim`] (a constant for small systems, as
/// in `linalg`), so that a caller dispatches once for a whole group.
#[derive(Debug, Clone)]
pub struct LaneLu {
    a: Vec<Lane>,
    piv: Vec<usize>,
    dinv: Vec<Lane>,
    /// Envelope of the factors over all lanes: the first non-zero column of
    /// each row of L, one past the last non-zero column of each row of U.
    /// The substitutions skip the zeros outside it (Willis rows have three
    /// non-zeros); a skipped term is an exact zero in every lane.
    lo: Vec<usize>,
    hi: Vec<usize>,
    anorm: Lane,
    x: Vec<Lane>,
    alt: Vec<Lane>,
    signs: Vec<Lane>,
}

/// Borrowed factors of a [`LaneLu`] for the substitutions.
struct Factors<'a> {
    a: &'a [Lane],
    piv: &'a [usize],
    dinv: &'a [Lane],
    lo: &'a [usize],
    hi: &'a [usize],
}

impl LaneLu {
    /// Buffers for `n x n` systems.
    pub fn new(n: usize) -> Self {
        LaneLu {
            a: vec![[0.0; LANES]; n * n],
            piv: vec![0; n],
            dinv: vec![[0.0; LANES]; n],
            lo: (0..n).collect(),
            hi: (1..=n).collect(),
            anorm: [0.0; LANES],
            x: vec![[0.0; LANES]; n],
            alt: vec![[0.0; LANES]; n],
            signs: vec![[0.0; LANES]; n],
        }
    }

    /// The matrices to fill before [`LaneLu::factor`].
    pub fn matrix_mut(&mut self) -> &mut [Lane] {
        &mut self.a
    }

    /// Factor in place with the pivot order of the first live lane; lanes
    /// that would pivot differently, or meet a zero or non-finite pivot
    /// column, are marked dead in `live` (their factors are then meaningless).
    // Index loops: the same order of operations as `linalg::factor`.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(crate) fn factor<D: Dim>(&mut self, d: D, live: &mut Live) {
        let n = d.n();
        let a = &mut self.a[..n * n];
        let (piv, dinv) = (&mut self.piv[..n], &mut self.dinv[..n]);
        let mut anorm = [0.0_f64; LANES];
        for j in 0..n {
            let mut s = [0.0; LANES];
            for i in 0..n {
                for l in 0..LANES {
                    s[l] += a[i * n + j][l].abs();
                }
            }
            for l in 0..LANES {
                anorm[l] = larger(anorm[l], s[l]);
            }
        }
        self.anorm = anorm;
        for k in 0..n {
            // Every lane's partial-pivoting choice (the first largest, as `linalg::factor`).
            let mut p = [k; LANES];
            let mut best = [0.0; LANES];
            for l in 0..LANES {
                best[l] = a[k * n + k][l].abs();
            }
            for i in k + 1..n {
                for l in 0..LANES {
                    let v = a[i * n + k][l].abs();
                    if v > best[l] {
                        best[l] = v;
                        p[l] = i;
                    }
                }
            }
            let Some(first) = live.iter().position(|&x| x) else {
                return;
            };
            let pk = p[first];
            for l in 0..LANES {
                if p[l] != pk || best[l] == 0.0 || !best[l].is_finite() {
                    live[l] = false;
                }
            }
            piv[k] = pk;
            if pk != k {
                for j in 0..n {
                    a.swap(k * n + j, pk * n + j);
                }
            }
            let mut inv = [0.0; LANES];
            for l in 0..LANES {
                inv[l] = 1.0 / a[k * n + k][l];
            }
            dinv[k] = inv;
            for i in k + 1..n {
                let mut f = a[i * n + k];
                mul(&mut f, &inv);
                a[i * n + k] = f;
                if f.iter().any(|&v| v != 0.0) {
                    for j in k + 1..n {
                        let u = a[k * n + j];
                        sub_mul(&mut a[i * n + j], &f, &u);
                    }
                }
            }
        }
        let nonzero = |e: &Lane| e.iter().any(|&v| v != 0.0);
        for i in 0..n {
            self.lo[i] = (0..i).find(|&j| nonzero(&a[i * n + j])).unwrap_or(i);
            self.hi[i] = (i + 1..n)
                .rev()
                .find(|&j| nonzero(&a[i * n + j]))
                .map_or(i + 1, |j| j + 1);
        }
    }

    /// The factors, cut to order `n` (the bounds checks then fold away).
    #[inline(always)]
    fn factors(&self, n: usize) -> Factors<'_> {
        Factors {
            a: &self.a[..n * n],
            piv: &self.piv[..n],
            dinv: &self.dinv[..n],
            lo: &self.lo[..n],
            hi: &self.hi[..n],
        }
    }

    /// Solve A x = b in place in every lane (after [`LaneLu::factor`]).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(crate) fn solve<D: Dim>(&self, d: D, b: &mut [Lane]) {
        let n = d.n();
        let Factors {
            a,
            piv,
            dinv,
            lo,
            hi,
        } = self.factors(n);
        let b = &mut b[..n];
        for k in 0..n {
            b.swap(k, piv[k]);
        }
        for i in 1..n {
            let mut s = b[i];
            for j in lo[i]..i {
                sub_mul(&mut s, &a[i * n + j], &b[j]);
            }
            b[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for j in i + 1..hi[i] {
                sub_mul(&mut s, &a[i * n + j], &b[j]);
            }
            mul(&mut s, &dinv[i]);
            b[i] = s;
        }
    }

    /// Solve A^T x = b in place in every lane (after [`LaneLu::factor`]).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(crate) fn solve_transpose<D: Dim>(&self, d: D, b: &mut [Lane]) {
        let n = d.n();
        let Factors {
            a,
            piv,
            dinv,
            lo,
            hi,
        } = self.factors(n);
        let b = &mut b[..n];
        for i in 0..n {
            let mut y = b[i];
            mul(&mut y, &dinv[i]);
            b[i] = y;
            for j in i + 1..hi[i] {
                sub_mul(&mut b[j], &a[i * n + j], &y);
            }
        }
        for i in (1..n).rev() {
            let z = b[i];
            for j in lo[i]..i {
                sub_mul(&mut b[j], &a[i * n + j], &z);
            }
        }
        for k in (0..n).rev() {
            b.swap(k, piv[k]);
        }
    }

    /// An upper bound on every lane's 1-norm condition number,
    /// `||A||_1 ||U^-1||_1 ||L^-1||_1` (after [`LaneLu::factor`]; `A = P^T L U`).
    /// The inverse of a triangular `T` is bounded entrywise by that of its
    /// comparison matrix `M(T)` (`|t_ii|` on the diagonal, `-|t_ij|` off it):
    /// `|T^-1| <= M(T)^-1` (Higham, *Accuracy and Stability of Numerical
    /// Algorithms*, 2nd ed., Thm 8.12), and `M(T)^-1 >= 0`, so `||T^-1||_1 <=
    /// max(M(T)^-T e)`: one substitution with `|U|^T` and one with `|L|^T`,
    /// each adding only non-negative terms (no cancellation: a few ulps of
    /// relative error). No sign choice and no iteration, unlike dlacn2: it
    /// costs about one substitution where the estimate costs four to ten.
    /// Not finite when a factor is not.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(crate) fn condition_bound<D: Dim>(&mut self, d: D) -> Lane {
        let n = d.n();
        if n == 0 {
            return [1.0; LANES];
        }
        let (a, dinv) = (&self.a[..n * n], &self.dinv[..n]);
        let (lo, hi) = (&self.lo[..n], &self.hi[..n]);
        let (y, z) = (&mut self.x[..n], &mut self.alt[..n]);
        // M(U)^T y = e, by columns of U: y_j = (1 + sum_{i<j} |u_ij| y_i) / |u_jj|.
        y.iter_mut().for_each(|v| *v = [1.0; LANES]);
        let mut umax = [0.0_f64; LANES];
        for j in 0..n {
            let mut yj = y[j];
            for l in 0..LANES {
                yj[l] *= dinv[j][l].abs();
                umax[l] = larger(umax[l], yj[l]);
            }
            y[j] = yj;
            for i in j + 1..hi[j] {
                let u = a[j * n + i];
                for l in 0..LANES {
                    y[i][l] += u[l].abs() * yj[l];
                }
            }
        }
        // M(L)^T z = e, L unit lower: z_k = 1 + sum_{i>k} |l_ik| z_i.
        z.iter_mut().for_each(|v| *v = [1.0; LANES]);
        let mut lmax = [0.0_f64; LANES];
        for k in (0..n).rev() {
            let zk = z[k];
            for l in 0..LANES {
                lmax[l] = larger(lmax[l], zk[l]);
            }
            for j in lo[k]..k {
                let m = a[k * n + j];
                for l in 0..LANES {
                    z[j][l] += m[l].abs() * zk[l];
                }
            }
        }
        let mut bound = [0.0; LANES];
        for l in 0..LANES {
            // NaN (a NaN factor) reads as not finite.
            let b = self.anorm[l] * umax[l] * lmax[l];
            bound[l] = if b.is_nan() { f64::INFINITY } else { b };
        }
        bound
    }

    /// [`LaneLu::condition`] where it matters: when [`LaneLu::condition_bound`]
    /// shows every live lane's condition number below `below` / 2, the bound
    /// (at most `below` / 2) is returned and no lane dies; otherwise the
    /// dlacn2 estimate of every lane, as [`LaneLu::condition`]. The estimate
    /// is a lower bound of the condition number (up to rounding, far inside
    /// the factor 2), so with `below` at most [`COND_REFUSE`] the lanes that
    /// die are exactly those `condition` kills, and every value above
    /// `below` is the estimate itself.
    #[inline(always)]
    pub(crate) fn condition_or_bound<D: Dim>(&mut self, d: D, live: &mut Live, below: f64) -> Lane {
        let bound = self.condition_bound(d);
        let small = (0..LANES).all(|l| !live[l] || bound[l] <= 0.5 * below);
        if small {
            bound
        } else {
            self.condition(d, live)
        }
    }

    /// The 1-norm condition estimate of every lane, as
    /// [`Lu::condition`](super::linalg::Lu::condition) computes it (dlacn2,
    /// each lane stopping on its own); lanes past [`COND_REFUSE`] are marked dead.
    #[inline(always)]
    pub(crate) fn condition<D: Dim>(&mut self, d: D, live: &mut Live) -> Lane {
        let n = d.n();
        let mut cond = [f64::INFINITY; LANES];
        if n == 0 {
            return [1.0; LANES];
        }
        let mut x = std::mem::take(&mut self.x);
        let mut alt = std::mem::take(&mut self.alt);
        let mut sign = std::mem::take(&mut self.signs);
        let (xs, alts, signs) = (&mut x[..n], &mut alt[..n], &mut sign[..n]);
        xs.iter_mut().for_each(|v| *v = [1.0 / n as f64; LANES]);
        for (i, v) in alts.iter_mut().enumerate() {
            let s = if i % 2 == 0 { 1.0 } else { -1.0 };
            *v = [s * (1.0 + i as f64 / (n.max(2) - 1) as f64); LANES];
        }
        self.solve(d, xs);
        self.solve(d, alts);
        let alt_norm = norm1(alts);
        let mut est = norm1(xs);
        if n > 1 {
            signs_of(xs, signs);
            // Lanes still iterating.
            let mut going = *live;
            for _ in 0..4 {
                if !going.iter().any(|&g| g) {
                    break;
                }
                alts.copy_from_slice(signs);
                self.solve_transpose(d, alts);
                let j = argmax_abs(alts);
                for (i, v) in xs.iter_mut().enumerate() {
                    for l in 0..LANES {
                        v[l] = if i == j[l] { 1.0 } else { 0.0 };
                    }
                }
                self.solve(d, xs);
                let now = norm1(xs);
                for l in 0..LANES {
                    if !going[l] {
                        continue;
                    }
                    let previous = est[l];
                    if now[l] <= previous || same_signs(xs, signs, l) {
                        est[l] = larger(now[l], previous);
                        going[l] = false;
                    } else {
                        est[l] = now[l];
                        for (s, v) in signs.iter_mut().zip(xs.iter()) {
                            s[l] = if v[l] >= 0.0 { 1.0 } else { -1.0 };
                        }
                    }
                }
            }
        }
        for l in 0..LANES {
            let alt_est = 2.0 * alt_norm[l] / (3.0 * n as f64);
            let c = self.anorm[l] * larger(est[l], alt_est);
            cond[l] = if c.is_finite() { c } else { f64::INFINITY };
            if cond[l] > COND_REFUSE {
                live[l] = false;
            }
        }
        self.x = x;
        self.alt = alt;
        self.signs = sign;
        cond
    }
}

/// `a.max(b)` (the other when one is NaN), spelled as a comparison. In
/// release builds, `f64::max` over the lanes inside the AVX-512 dispatch
/// came out wrong: the 1-norm of one lane's 7 x 7 matrix missed its largest
/// column (4.625 for 4.868; `lanes_equal_fresh_row_by_row_solves_bit_for_bit`
/// failed in release only, the debug build and the scalar code agreeing).
/// The comparison gives the scalar code's numbers in both builds.
#[inline(always)]
fn larger(a: f64, b: f64) -> f64 {
    if b > a || a.is_nan() { b } else { a }
}

#[inline(always)]
fn norm1(v: &[Lane]) -> Lane {
    let mut s = [0.0; LANES];
    for x in v {
        for l in 0..LANES {
            s[l] += x[l].abs();
        }
    }
    s
}

#[inline(always)]
fn signs_of(v: &[Lane], out: &mut [Lane]) {
    for (o, x) in out.iter_mut().zip(v) {
        for l in 0..LANES {
            o[l] = if x[l] >= 0.0 { 1.0 } else { -1.0 };
        }
    }
}

#[inline(always)]
fn same_signs(v: &[Lane], signs: &[Lane], l: usize) -> bool {
    v.iter()
        .zip(signs)
        .all(|(x, s)| (if x[l] >= 0.0 { 1.0 } else { -1.0 }) == s[l])
}

#[inline(always)]
fn argmax_abs(v: &[Lane]) -> [usize; LANES] {
    let mut j = [0; LANES];
    let mut best = [-1.0; LANES];
    for (i, x) in v.iter().enumerate() {
        for l in 0..LANES {
            if x[l].abs() > best[l] {
                best[l] = x[l].abs();
                j[l] = i;
            }
        }
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::linalg::Lu;

    /// Uniform numbers in [-0.5, 0.5) (xorshift64).
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// One random `n x n` matrix per lane (row-major), each near a common,
    /// diagonally heavy one, which keeps most lanes on one pivot order.
    fn near_one_matrix(n: usize, next: &mut impl FnMut() -> f64) -> Vec<Vec<f64>> {
        let common: Vec<f64> = (0..n * n)
            .map(|k| next() + if k % (n + 1) == 0 { 3.0 } else { 0.0 })
            .collect();
        (0..LANES)
            .map(|_| common.iter().map(|c| c + 0.3 * next()).collect())
            .collect()
    }

    /// One matrix per lane (row-major, order `d`), factored: the factors
    /// and the live lanes.
    fn factored(mats: &[Vec<f64>], d: crate::numerics::linalg::Dynamic) -> (LaneLu, Live) {
        let mut lanes = LaneLu::new(d.n());
        for (k, e) in lanes.matrix_mut().iter_mut().enumerate() {
            for l in 0..LANES {
                e[l] = mats[l][k];
            }
        }
        let mut live = [true; LANES];
        lanes.factor(d, &mut live);
        (lanes, live)
    }

    /// Lanes of random matrices, one of them singular: every live lane gives
    /// the scalar LU's solutions and condition estimate, bit for bit.
    #[test]
    fn lanes_equal_the_scalar_lu_bit_for_bit() {
        let mut next = uniform(0x2545_f491_4f6c_dd1d);
        for n in [1, 2, 3, 5, 9, 14] {
            for _ in 0..20 {
                let mut mats = near_one_matrix(n, &mut next);
                for (l, m) in mats.iter_mut().enumerate() {
                    if l == 3 {
                        // A zero column: singular.
                        for i in 0..n {
                            m[i * n] = 0.0;
                        }
                    }
                }
                let d = crate::numerics::linalg::Dynamic(n);
                let (mut lanes, mut live) = factored(&mats, d);
                let cond = lanes.condition(d, &mut live);
                assert!(!live[3], "the singular lane is dead");
                let rhs: Vec<f64> = (0..n).map(|_| next()).collect();
                let mut b: Vec<Lane> = rhs.iter().map(|&v| [v; LANES]).collect();
                let mut bt = b.clone();
                lanes.solve(d, &mut b);
                lanes.solve_transpose(d, &mut bt);
                for l in (0..LANES).filter(|&l| live[l]) {
                    let mut lu = Lu::new(n);
                    lu.matrix_mut().copy_from_slice(&mats[l]);
                    lu.factor().unwrap_or_else(|e| panic!("lane {l}: {e:?}"));
                    let c = lu.condition();
                    assert_eq!(c.to_bits(), cond[l].to_bits(), "condition, lane {l}");
                    let (mut x, mut xt) = (rhs.clone(), rhs.clone());
                    lu.solve(&mut x);
                    lu.solve_transpose(&mut xt);
                    for i in 0..n {
                        assert_eq!(x[i].to_bits(), b[i][l].to_bits(), "solve n={n} lane {l}");
                        assert_eq!(xt[i].to_bits(), bt[i][l].to_bits(), "transpose n={n}");
                    }
                }
                assert!(live.iter().filter(|&&x| x).count() >= 1);
            }
        }
    }

    /// The bound of [`LaneLu::condition_bound`] is at least the 1-norm
    /// condition number, `||A||_1` times the largest column sum of the
    /// inverse (its columns solved one by one with the scalar LU), and at
    /// least the dlacn2 estimate, on random matrices of order 1 to 14 with
    /// lanes from well- to ill-conditioned (a row nearly a copy of another,
    /// up to 1e-14 apart). `condition_or_bound` then kills the lanes
    /// `condition` kills and returns the estimate past its limit.
    #[test]
    fn the_condition_bound_is_at_least_the_condition_number() {
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut bounded, mut estimated, mut loose) = (0, 0, 0.0_f64);
        for n in [1, 2, 3, 5, 9, 14] {
            for round in 0..30 {
                let mut mats = near_one_matrix(n, &mut next);
                for (l, m) in mats.iter_mut().enumerate() {
                    if n > 1 && l > 0 {
                        // Row n-1 nearly row 0: the condition grows as 1/eps.
                        let eps = 10f64.powi(-((l as i32 * 2 + round) % 15));
                        for j in 0..n {
                            m[(n - 1) * n + j] = m[j] + eps * next();
                        }
                    }
                }
                let d = crate::numerics::linalg::Dynamic(n);
                let (mut lanes, live) = factored(&mats, d);
                let bound = lanes.condition_bound(d);
                let (mut dead, mut guarded) = (live, live);
                let cond = lanes.condition(d, &mut dead);
                let either = lanes.condition_or_bound(d, &mut guarded, COND_REFUSE);
                assert_eq!(dead, guarded, "n={n}: the same lanes die");
                for l in (0..LANES).filter(|&l| live[l]) {
                    if either[l].to_bits() != cond[l].to_bits() {
                        assert!(either[l] == bound[l] && bound[l] <= 0.5 * COND_REFUSE);
                        bounded += 1;
                    } else if cond[l] > 0.5 * COND_REFUSE {
                        estimated += 1;
                    }
                }
                for l in (0..LANES).filter(|&l| live[l]) {
                    let mut lu = Lu::new(n);
                    lu.matrix_mut().copy_from_slice(&mats[l]);
                    if lu.factor().is_err() {
                        continue;
                    }
                    let anorm = (0..n)
                        .map(|j| (0..n).map(|i| mats[l][i * n + j].abs()).sum::<f64>())
                        .fold(0.0, f64::max);
                    let mut inorm = 0.0_f64;
                    for j in 0..n {
                        let mut e = vec![0.0; n];
                        e[j] = 1.0;
                        lu.solve(&mut e);
                        inorm = inorm.max(e.iter().map(|v| v.abs()).sum());
                    }
                    let kappa = anorm * inorm;
                    // The inverse's columns are computed with relative
                    // errors near kappa * 1e-16: allow that much.
                    let slack = 1.0 - (kappa * 1e-15).min(0.5);
                    assert!(
                        bound[l] >= kappa * slack,
                        "n={n} lane {l}: bound {:e} below the condition number {kappa:e}",
                        bound[l]
                    );
                    assert!(bound[l] >= cond[l] * slack, "n={n} lane {l}: below dlacn2");
                    if kappa < 1e8 {
                        loose = loose.max(bound[l] / kappa);
                    }
                }
            }
        }
        // Both branches of `condition_or_bound` ran.
        assert!(bounded >= 50 && estimated >= 50, "{bounded} {estimated}");
        assert!(loose.is_finite(), "{loose}");
        eprintln!("bound / condition number at most {loose:.1} on these matrices");
    }
}
