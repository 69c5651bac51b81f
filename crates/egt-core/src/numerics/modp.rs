//! Linear algebra over the prime field GF(p), p = 2^61 - 1, for structural
//! (generic) decisions: the rank of the Willis equations and which turning
//! pairs can move, for ratios that are "generic".
//!
//! With ratios drawn at random from GF(p), a rank deficiency or an immobile
//! turning pair that the field shows is structural unless the draw hit a root
//! of a minor, which by the Schwartz-Zippel lemma happens with probability at
//! most (degree / p) ~ 30 / 2.3e18 per decision. The draws are deterministic
//! (splitmix64), so every run decides the same. Compared with generic rational
//! ratios and exact `BigRational` elimination the decision is the same and
//! costs machine-word arithmetic instead of growing fractions.

use super::field;

/// The Mersenne prime 2^61 - 1.
pub const P: u64 = (1 << 61) - 1;

/// a * b mod P.
#[inline]
pub fn mul(a: u64, b: u64) -> u64 {
    let x = u128::from(a) * u128::from(b);
    // x = hi * 2^61 + lo and 2^61 = 1 (mod P).
    let lo = (x as u64) & P;
    let hi = (x >> 61) as u64;
    add(lo, hi)
}

/// a + b mod P (a, b < P).
#[inline]
pub fn add(a: u64, b: u64) -> u64 {
    let s = a + b;
    if s >= P { s - P } else { s }
}

/// a - b mod P (a, b < P).
#[inline]
pub fn sub(a: u64, b: u64) -> u64 {
    if a >= b { a - b } else { a + P - b }
}

/// -a mod P.
#[inline]
pub fn neg(a: u64) -> u64 {
    if a == 0 { 0 } else { P - a }
}

/// The inverse of a non-zero a (Fermat: a^(P-2)).
pub fn inv(a: u64) -> u64 {
    debug_assert!(a != 0);
    let (mut base, mut e, mut r) = (a, P - 2, 1);
    while e > 0 {
        if e & 1 == 1 {
            r = mul(r, base);
        }
        base = mul(base, base);
        e >>= 1;
    }
    r
}

/// The k-th deterministic pseudo-random field element in [2, P) (splitmix64).
pub fn generic(k: u64) -> u64 {
    let mut z = k
        .wrapping_add(0x9E37_79B9_7F4A_7C15)
        .wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    2 + z % (P - 2)
}

/// Reduce to reduced row-echelon form in place; return the pivot columns.
pub fn rref(m: &mut [Vec<u64>]) -> Vec<usize> {
    field::rref(m)
}

/// A residue in [0, P) as an element of GF(P).
impl field::Field for u64 {
    fn is_zero(&self) -> bool {
        *self == 0
    }
    fn inverse(&self) -> Self {
        inv(*self)
    }
    fn scale(&mut self, by: &Self) {
        *self = mul(*self, *by);
    }
    fn sub_mul(&mut self, f: &Self, y: &Self) {
        *self = sub(*self, mul(*f, *y));
    }
}

/// A basis of the right null space of `m` (`cols` wide), and the rank.
pub fn nullspace(m: &[Vec<u64>], cols: usize) -> (Vec<Vec<u64>>, usize) {
    let mut w = m.to_vec();
    let pivots = rref(&mut w);
    let basis = (0..cols)
        .filter(|c| !pivots.contains(c))
        .map(|f| {
            let mut v = vec![0; cols];
            v[f] = 1;
            for (r, &pc) in pivots.iter().enumerate() {
                v[pc] = neg(w[r][f]);
            }
            v
        })
        .collect();
    (basis, pivots.len())
}

/// A sparse row: (column, non-zero value) pairs, columns distinct.
pub type SparseRow = Vec<(usize, u64)>;

/// [`nullspace`] for sparse rows (the Willis rows have three entries):
/// a basis of the right null space of `m` (`cols` wide, dense vectors) and
/// the rank, in time about linear in the entries for tree-like trains
/// where the dense elimination is cubic.
///
/// Each row is reduced against the pivot rows found so far, in the order
/// they were found (a pivot row holds no earlier pivot column, so the
/// reduction only moves forward), with a dense accumulator; a non-zero
/// remainder becomes a pivot row, its pivot the column that appears in the
/// fewest rows of `m` (to limit fill). The null vectors follow by
/// substitution through the pivot rows in reverse order, one per free
/// column.
pub fn nullspace_sparse(m: &[SparseRow], cols: usize) -> (Vec<Vec<u64>>, usize) {
    let e = Echelon::new(m, cols);
    let basis = (0..cols)
        .filter(|&c| e.pivot_of[c].is_none())
        .map(|f| {
            let mut v = vec![0; cols];
            v[f] = 1;
            e.back_substitute(&mut v);
            v
        })
        .collect();
    (basis, e.pivots.len())
}

/// `count` generic vectors of the right null space of `m` (`cols` wide) and
/// the rank: each is the combination of [`nullspace_sparse`]'s basis with
/// weights drawn by [`generic`] (seeds `seed + count * column + k`), found by
/// one substitution through the pivot rows. Where a question is "does a
/// coordinate vanish (or two coincide) on the whole null space", a generic
/// vector answers it as the basis does but for a draw of probability 1 / P
/// (Schwartz-Zippel, degree 1), with `count` vectors instead of one per free
/// column: memory and time stay about linear in the entries when the
/// train has thousands of degrees of freedom, where the basis is quadratic.
pub fn null_combinations(
    m: &[SparseRow],
    cols: usize,
    count: usize,
    seed: u64,
) -> (Vec<Vec<u64>>, usize) {
    let e = Echelon::new(m, cols);
    let vectors = (0..count)
        .map(|k| {
            let mut v = vec![0; cols];
            for (c, x) in v.iter_mut().enumerate() {
                if e.pivot_of[c].is_none() {
                    *x = generic(seed + (count * c + k) as u64);
                }
            }
            e.back_substitute(&mut v);
            v
        })
        .collect();
    (vectors, e.pivots.len())
}

/// The pivot rows of a sparse elimination (see [`nullspace_sparse`]).
struct Echelon {
    /// pivot_of[c]: the pivot row whose pivot column is c.
    pivot_of: Vec<Option<usize>>,
    /// (pivot column, row scaled to 1 there), in the order found.
    pivots: Vec<(usize, SparseRow)>,
}

impl Echelon {
    /// Given the free coordinates of `v` (the others are overwritten), the
    /// null vector they determine: each pivot coordinate from its row, in
    /// reverse order.
    fn back_substitute(&self, v: &mut [u64]) {
        for (pc, prow) in self.pivots.iter().rev() {
            let s = prow
                .iter()
                .filter(|&&(c, _)| c != *pc)
                .fold(0, |s, &(c, x)| add(s, mul(x, v[c])));
            v[*pc] = neg(s);
        }
    }

    fn new(m: &[SparseRow], cols: usize) -> Self {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let mut degree = vec![0usize; cols];
        for row in m {
            for &(c, _) in row {
                degree[c] += 1;
            }
        }
        // pivot_of[c]: the pivot row whose pivot column is c.
        let mut pivot_of: Vec<Option<usize>> = vec![None; cols];
        let mut pivots: Vec<(usize, SparseRow)> = Vec::new();
        let mut acc = vec![0u64; cols];
        let mut touched: Vec<usize> = Vec::new();
        let mut seen = vec![false; cols];
        let mut heap = BinaryHeap::new();
        for row in m {
            for &(c, v) in row {
                if !seen[c] {
                    seen[c] = true;
                    touched.push(c);
                }
                acc[c] = add(acc[c], v);
                if let Some(k) = pivot_of[c] {
                    heap.push(Reverse(k));
                }
            }
            while let Some(Reverse(k)) = heap.pop() {
                // A pivot row may be queued more than once.
                while heap.peek() == Some(&Reverse(k)) {
                    heap.pop();
                }
                let (pc, ref prow) = pivots[k];
                let f = acc[pc];
                if f == 0 {
                    continue;
                }
                for &(c, v) in prow {
                    if !seen[c] {
                        seen[c] = true;
                        touched.push(c);
                    }
                    let was = acc[c];
                    acc[c] = sub(acc[c], mul(f, v));
                    if let (0, Some(j)) = (was, pivot_of[c].filter(|_| c != pc)) {
                        heap.push(Reverse(j));
                    }
                }
            }
            let mut rest: SparseRow = Vec::new();
            for &c in &touched {
                if acc[c] != 0 {
                    rest.push((c, acc[c]));
                }
                acc[c] = 0;
                seen[c] = false;
            }
            touched.clear();
            let Some(&(pc, pv)) = rest.iter().min_by_key(|&&(c, _)| (degree[c], c)) else {
                continue;
            };
            let iv = inv(pv);
            for e in &mut rest {
                e.1 = mul(e.1, iv);
            }
            pivot_of[pc] = Some(pivots.len());
            pivots.push((pc, rest));
        }
        Echelon { pivot_of, pivots }
    }
}

/// Indices with a non-zero entry in some vector of `basis`.
pub fn support(basis: &[Vec<u64>], n: usize) -> Vec<usize> {
    (0..n)
        .filter(|&i| basis.iter().any(|v| v[i] != 0))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_arithmetic_round_trips() {
        for k in 0..200 {
            let a = generic(k);
            let b = generic(k + 1000);
            assert!((2..P).contains(&a));
            assert_eq!(mul(a, inv(a)), 1);
            assert_eq!(add(sub(a, b), b), a);
            assert_eq!(add(a, neg(a)), 0);
            // mul agrees with a u128 reference.
            assert_eq!(
                u128::from(mul(a, b)),
                u128::from(a) * u128::from(b) % u128::from(P)
            );
        }
    }

    #[test]
    fn nullspace_is_annihilated_and_rank_is_right() {
        // Row 2 = row 0 + 3 row 1: rank 2 of 3.
        let r0 = vec![1, generic(1), 0, generic(2)];
        let r1 = vec![0, generic(3), 5, 1];
        let r2: Vec<u64> = r0
            .iter()
            .zip(&r1)
            .map(|(&a, &b)| add(a, mul(3, b)))
            .collect();
        let m = vec![r0, r1, r2];
        let (basis, rank) = nullspace(&m, 4);
        assert_eq!(rank, 2);
        assert_eq!(basis.len(), 2);
        for v in &basis {
            for row in &m {
                let s = row
                    .iter()
                    .zip(v)
                    .fold(0, |acc, (&x, &y)| add(acc, mul(x, y)));
                assert_eq!(s, 0);
            }
        }
    }

    /// The sparse rows of a dense matrix.
    fn sparse(m: &[Vec<u64>]) -> Vec<SparseRow> {
        m.iter()
            .map(|r| {
                r.iter()
                    .enumerate()
                    .filter(|e| *e.1 != 0)
                    .map(|(c, &v)| (c, v))
                    .collect()
            })
            .collect()
    }

    /// `basis` is a basis of the null space of `m`: annihilated, as many
    /// vectors as `cols - rank`, and independent (each is 1 on its own free
    /// column where the others are 0, as both routines build them).
    fn assert_null_basis(m: &[Vec<u64>], cols: usize, basis: &[Vec<u64>], rank: usize) {
        assert_eq!(basis.len(), cols - rank);
        for v in basis {
            for row in m {
                let s = row
                    .iter()
                    .zip(v)
                    .fold(0, |acc, (&x, &y)| add(acc, mul(x, y)));
                assert_eq!(s, 0, "not annihilated");
            }
        }
        let mut b = basis.to_vec();
        assert_eq!(rref(&mut b).len(), basis.len(), "dependent basis");
    }

    #[test]
    fn sparse_nullspace_of_a_long_chain_is_the_dense_one() {
        // A chain of Willis-like rows, three entries each, some dependent.
        let cols = 300;
        let mut m: Vec<Vec<u64>> = Vec::new();
        for k in 0..cols - 3 {
            let mut r = vec![0; cols];
            r[k] = 1;
            r[k + 1] = neg(generic(k as u64));
            r[k + 3] = sub(generic(k as u64), 1);
            m.push(r);
            if k % 50 == 7 {
                let last = m.len() - 1;
                let dep: Vec<u64> = m[last]
                    .iter()
                    .zip(&m[last - 1])
                    .map(|(&a, &b)| add(a, mul(5, b)))
                    .collect();
                m.push(dep);
            }
        }
        let (dense, drank) = nullspace(&m, cols);
        let (sp, srank) = nullspace_sparse(&sparse(&m), cols);
        assert_eq!(srank, drank);
        assert_null_basis(&m, cols, &sp, srank);
        assert_eq!(support(&sp, cols), support(&dense, cols));
    }

    proptest::proptest! {
        /// On random sparse matrices the sparse routine finds the dense rank
        /// and a basis of the same null space.
        #[test]
        fn sparse_nullspace_agrees_with_the_dense_one(
            entries in proptest::collection::vec(
                proptest::collection::vec((0usize..12, -3i64..4), 0..4), 1..14),
            dependent in proptest::collection::vec((0usize..14, 0usize..14, -2i64..3), 0..4),
        ) {
            let field = |x: i64| if x >= 0 { x as u64 % P } else { neg((-x) as u64 % P) };
            let cols = 12;
            let mut m: Vec<Vec<u64>> = entries.iter().map(|row| {
                let mut r = vec![0; cols];
                for &(c, v) in row {
                    r[c] = add(r[c], field(v));
                }
                r
            }).collect();
            for &(a, b, k) in &dependent {
                let n = m.len();
                let r: Vec<u64> = m[a % n].iter().zip(&m[b % n]).map(|(&x, &y)| add(x, mul(field(k), y))).collect();
                m.push(r);
            }
            let (dense, drank) = nullspace(&m, cols);
            let (sp, srank) = nullspace_sparse(&sparse(&m), cols);
            proptest::prop_assert_eq!(srank, drank);
            assert_null_basis(&m, cols, &sp, srank);
            proptest::prop_assert_eq!(support(&sp, cols), support(&dense, cols));
            // Two generic vectors answer what the basis does: which
            // coordinates vanish on the null space, which pairs coincide.
            let (probes, prank) = null_combinations(&sparse(&m), cols, 2, 7);
            proptest::prop_assert_eq!(prank, drank);
            for v in &probes {
                for row in &m {
                    let s = row.iter().zip(v).fold(0, |acc, (&x, &y)| add(acc, mul(x, y)));
                    proptest::prop_assert_eq!(s, 0, "not annihilated");
                }
            }
            proptest::prop_assert_eq!(support(&probes, cols), support(&dense, cols));
            for a in 0..cols {
                for b in 0..cols {
                    let basis = dense.iter().all(|v| v[a] == v[b]);
                    let generic = probes.iter().all(|v| v[a] == v[b]);
                    proptest::prop_assert_eq!(basis, generic, "columns {} and {}", a, b);
                }
            }
        }
    }

    proptest::proptest! {
        /// For small integer matrices (minors far below P) the rank over GF(P)
        /// is the rank over the rationals, and so is the null-space support.
        #[test]
        fn rank_and_support_agree_with_exact_rationals(
            rows in proptest::collection::vec(proptest::collection::vec(-4i64..5, 6), 1..6),
            combo in proptest::collection::vec(-2i64..3, 5),
        ) {
            let mut rows = rows;
            // Add a dependent row now and then.
            let dep: Vec<i64> = (0..6).map(|c| rows.iter().zip(&combo).map(|(r, k)| r[c] * k).sum()).collect();
            rows.push(dep);
            let field = |x: i64| if x >= 0 { x as u64 % P } else { neg((-x) as u64 % P) };
            let fm: Vec<Vec<u64>> = rows.iter().map(|r| r.iter().map(|&x| field(x)).collect()).collect();
            let qm: crate::numerics::exact::QMatrix = rows.iter().map(|r| r.iter().map(|&x| crate::numerics::exact::q(x)).collect()).collect();
            let (fnull, frank) = nullspace(&fm, 6);
            proptest::prop_assert_eq!(frank, crate::numerics::exact::rank(&qm));
            proptest::prop_assert_eq!(support(&fnull, 6), crate::numerics::exact::support(&crate::numerics::exact::nullspace(&qm, 6)));
        }
    }
}
