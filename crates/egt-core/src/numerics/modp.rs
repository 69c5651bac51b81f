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
    let rows = m.len();
    let cols = m.first().map_or(0, Vec::len);
    let mut pivots = Vec::new();
    let mut r = 0;
    for c in 0..cols {
        if r == rows {
            break;
        }
        let Some(p) = (r..rows).find(|&i| m[i][c] != 0) else {
            continue;
        };
        m.swap(r, p);
        let iv = inv(m[r][c]);
        for x in m[r].iter_mut() {
            *x = mul(*x, iv);
        }
        let pivot_row = m[r].clone();
        for (i, row) in m.iter_mut().enumerate() {
            let f = row[c];
            if i != r && f != 0 {
                for (x, &y) in row.iter_mut().zip(&pivot_row) {
                    if y != 0 {
                        *x = sub(*x, mul(f, y));
                    }
                }
            }
        }
        pivots.push(c);
        r += 1;
    }
    pivots
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
