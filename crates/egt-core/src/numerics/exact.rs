//! Exact rational linear algebra (Gauss-Jordan over `BigRational`).
//!
//! Used where a decision must not depend on round-off: the generic-rank
//! topology checks, the exact kinematics of tooth-count trains, and the
//! diagnosis of singular systems (which links are free, which equations conflict).

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};

use super::field;

/// Exact rational number.
pub type Q = BigRational;

/// A dense matrix of rationals, row-major.
pub type QMatrix = Vec<Vec<Q>>;

/// Integer to rational.
pub fn q(n: i64) -> Q {
    Q::from_integer(BigInt::from(n))
}

/// p/q as a rational (`den` must be non-zero).
pub fn frac(num: i64, den: i64) -> Q {
    Q::new(BigInt::from(num), BigInt::from(den))
}

/// Nearest f64 of a rational (exact for values that fit in f64).
pub fn to_f64(x: &Q) -> f64 {
    x.to_f64().unwrap_or(f64::NAN)
}

/// The exact rational value of a finite f64 (every finite double is a dyadic rational).
pub fn from_f64(x: f64) -> Option<Q> {
    Q::from_float(x)
}

/// Most digits accepted in an exact number: written as text (significant
/// digits), and in the numerator and the denominator of its value (so that
/// whatever is accepted prints back, by [`display`], as text that is accepted
/// too: `1e1000` is 1001 digits).
pub const MAX_DIGITS: usize = 1024;
/// Largest decimal exponent (in absolute value) accepted in an exact number
/// written as text: far past double precision, and small enough that the
/// exact value is built in microseconds (1e1000000 would take seconds and
/// megabytes).
pub const MAX_EXPONENT: i64 = 1000;

/// Why text is not an exact number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RationalError {
    /// Not an integer, a decimal or a fraction of two of them.
    #[error("not a number: write an integer, a decimal (2.5, 1e-3) or a fraction p/q")]
    Invalid,
    /// `p/0`.
    #[error("a fraction with a zero denominator")]
    ZeroDenominator,
    /// Too many digits or too large an exponent.
    #[error(
        "more than {MAX_DIGITS} digits (written, or in the numerator or denominator of the value) or an exponent beyond +-{MAX_EXPONENT}"
    )]
    TooLarge,
    /// Exact, but beyond the range of double precision.
    #[error("beyond the range of double precision (about 1.8e308)")]
    OutOfRange,
}

/// Parse `"p/q"`, `"-3"` or a decimal like `"2.5"` / `"1e-3"` exactly; p and
/// q of a fraction are integers or decimals themselves (`1/3/4` is refused).
///
/// # Errors
/// [`RationalError`]: not a number, a zero denominator, or past
/// [`MAX_DIGITS`] / [`MAX_EXPONENT`].
pub fn parse_rational(s: &str) -> Result<Q, RationalError> {
    let s = s.trim();
    let q = if let Some((n, d)) = s.split_once('/') {
        let n = parse_decimal(n.trim())?;
        let d = parse_decimal(d.trim())?;
        if d.is_zero() {
            return Err(RationalError::ZeroDenominator);
        }
        n / d
    } else {
        parse_decimal(s)?
    };
    if !within_digits(q.numer()) || !within_digits(q.denom()) {
        return Err(RationalError::TooLarge);
    }
    Ok(q)
}

/// Serde helpers that write exact values as their text (`"p/q"`, see
/// [`display`]): `#[serde(serialize_with = "exact::text::option")]`.
pub mod text {
    use super::{Q, display};
    use serde::Serializer;

    /// An optional exact value as text, or null.
    ///
    /// # Errors
    /// The serializer's.
    pub fn option<S: Serializer>(q: &Option<Q>, s: S) -> Result<S::Ok, S::Error> {
        match q {
            Some(q) => s.serialize_some(&display(q)),
            None => s.serialize_none(),
        }
    }

    /// An optional list of exact values as texts, or null.
    ///
    /// # Errors
    /// The serializer's.
    pub fn option_vec<S: Serializer>(v: &Option<Vec<Q>>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(v) => s.collect_seq(v.iter().map(display)),
            None => s.serialize_none(),
        }
    }

    /// An optional list of optional exact values as texts or nulls, or null.
    ///
    /// # Errors
    /// The serializer's.
    pub fn option_vec_option<S: Serializer>(
        v: &Option<Vec<Option<Q>>>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        match v {
            Some(v) => s.collect_seq(v.iter().map(|q| q.as_ref().map(display))),
            None => s.serialize_none(),
        }
    }
}

/// Whether |n| has at most [`MAX_DIGITS`] decimal digits: decided from its
/// bit length away from the limit (a digit of margin), by printing near it.
fn within_digits(n: &BigInt) -> bool {
    // 2^(bits-1) <= |n| < 2^bits, so its digits lie in
    // [(bits-1) log10 2, bits log10 2 + 1].
    let bits = n.bits() as f64;
    let log2 = std::f64::consts::LOG10_2;
    if bits * log2 + 2.0 <= MAX_DIGITS as f64 {
        true
    } else if (bits - 1.0) * log2 > MAX_DIGITS as f64 + 1.0 {
        false
    } else {
        n.magnitude().to_string().len() <= MAX_DIGITS
    }
}

/// [`parse_rational`] for a value that must also be a finite double: the
/// exact value and its nearest double.
///
/// # Errors
/// As [`parse_rational`]; [`RationalError::OutOfRange`] past about 1.8e308.
pub fn parse_finite(s: &str) -> Result<(Q, f64), RationalError> {
    let q = parse_rational(s)?;
    let v = to_f64(&q);
    if v.is_finite() {
        Ok((q, v))
    } else {
        Err(RationalError::OutOfRange)
    }
}

/// An integer or a decimal with an optional exponent, exactly.
fn parse_decimal(s: &str) -> Result<Q, RationalError> {
    let (mantissa, exp) = match s.find(['e', 'E']) {
        Some(i) => {
            let e = &s[i + 1..];
            let digits = e.trim_start_matches(['+', '-']);
            if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
                return Err(RationalError::Invalid);
            }
            let v = e.parse::<i64>().map_err(|_| RationalError::TooLarge)?;
            // unsigned_abs: `-9223372036854775808` parses, and its abs() would
            // overflow (wrapping to itself, below the limit, in release builds:
            // a fuzz finding that hung on 10^(2^63)).
            if v.unsigned_abs() > MAX_EXPONENT.unsigned_abs() {
                return Err(RationalError::TooLarge);
            }
            (&s[..i], v)
        }
        None => (s, 0),
    };
    let (neg, digits) = match mantissa.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, mantissa.strip_prefix('+').unwrap_or(mantissa)),
    };
    let (int, fracp) = digits.split_once('.').unwrap_or((digits, ""));
    if int.is_empty() && fracp.is_empty() {
        return Err(RationalError::Invalid);
    }
    if !int.chars().chain(fracp.chars()).all(|c| c.is_ascii_digit()) {
        return Err(RationalError::Invalid);
    }
    let significant = format!("{int}{fracp}");
    if significant.trim_start_matches('0').len() > MAX_DIGITS || fracp.len() > MAX_DIGITS {
        return Err(RationalError::TooLarge);
    }
    let all: BigInt = significant.parse().map_err(|_| RationalError::Invalid)?;
    // |scale| <= MAX_EXPONENT + MAX_DIGITS by the checks above.
    let scale = exp - i64::try_from(fracp.len()).map_err(|_| RationalError::TooLarge)?;
    let ten = BigInt::from(10);
    let power = Q::from_integer(num_traits::pow(ten, scale.unsigned_abs() as usize));
    let mut v = Q::from_integer(all);
    if scale >= 0 {
        v *= power;
    } else {
        v /= power;
    }
    Ok(if neg { -v } else { v })
}

/// The simplest fraction (smallest denominator, by continued fractions)
/// within `rel` of `x` relatively, or the exact value of `x` when none with a
/// denominator up to 1e9 is that close.
pub fn simplest_near(x: f64, rel: f64) -> Q {
    let exact = from_f64(x).unwrap_or_else(Q::zero);
    if !x.is_finite() || x == 0.0 {
        return exact;
    }
    let (mut h0, mut h1, mut k0, mut k1) = (0i128, 1i128, 1i128, 0i128);
    let mut r = x.abs();
    for _ in 0..40 {
        let a = r.floor();
        if a > 1e12 {
            break;
        }
        let a = a as i128;
        (h0, h1) = (h1, a * h1 + h0);
        (k0, k1) = (k1, a * k1 + k0);
        if k1 > 1_000_000_000 {
            break;
        }
        let approx = h1 as f64 / k1 as f64;
        if (approx - x.abs()).abs() <= rel * x.abs() {
            let q = Q::new(BigInt::from(h1), BigInt::from(k1));
            return if x < 0.0 { -q } else { q };
        }
        let frac = r - r.floor();
        if frac == 0.0 {
            break;
        }
        r = 1.0 / frac;
    }
    exact
}

/// Display as `p/q` (or `p` when the denominator is 1).
pub fn display(x: &Q) -> String {
    if x.denom().is_one() {
        x.numer().to_string()
    } else {
        format!("{}/{}", x.numer(), x.denom())
    }
}

/// Reduce `m` to reduced row-echelon form in place; return the pivot columns.
pub fn rref(m: &mut QMatrix) -> Vec<usize> {
    field::rref(m)
}

impl field::Field for Q {
    fn is_zero(&self) -> bool {
        Zero::is_zero(self)
    }
    fn inverse(&self) -> Self {
        self.recip()
    }
    fn scale(&mut self, by: &Self) {
        *self *= by;
    }
    fn sub_mul(&mut self, f: &Self, y: &Self) {
        *self -= f * y;
    }
}

/// Rank of a matrix.
pub fn rank(m: &QMatrix) -> usize {
    let mut w = m.clone();
    rref(&mut w).len()
}

/// A basis of the right null space {x : m x = 0}, `cols` wide.
pub fn nullspace(m: &QMatrix, cols: usize) -> Vec<Vec<Q>> {
    let mut w = m.clone();
    let pivots = rref(&mut w);
    let free: Vec<usize> = (0..cols).filter(|c| !pivots.contains(c)).collect();
    free.iter()
        .map(|&f| {
            let mut v = vec![Q::zero(); cols];
            v[f] = Q::one();
            for (r, &pc) in pivots.iter().enumerate() {
                v[pc] = -w[r][f].clone();
            }
            v
        })
        .collect()
}

/// Why an exact solve failed.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveFailure {
    /// Unknowns (columns) not fixed by the equations.
    pub free_columns: Vec<usize>,
    /// Rows that belong to an inconsistent dependent set (empty when consistent).
    pub conflicting_rows: Vec<usize>,
}

/// Solve the square or rectangular system `a x = b` exactly, requiring a unique solution.
///
/// # Errors
/// The free columns (null space support) and the rows of any inconsistent dependency.
pub fn solve(a: &QMatrix, b: &[Q]) -> Result<Vec<Q>, SolveFailure> {
    let cols = a.first().map_or(0, Vec::len);
    let mut aug: QMatrix = a
        .iter()
        .zip(b)
        .map(|(row, bi)| row.iter().cloned().chain([bi.clone()]).collect())
        .collect();
    let pivots = rref(&mut aug);
    let inconsistent = pivots.contains(&cols);
    let rank_a = pivots.iter().filter(|&&c| c < cols).count();
    if rank_a == cols && !inconsistent {
        let mut x = vec![Q::zero(); cols];
        for (r, &pc) in pivots.iter().enumerate() {
            x[pc] = aug[r][cols].clone();
        }
        return Ok(x);
    }
    let free_columns = support(&nullspace(a, cols));
    let conflicting_rows = if inconsistent {
        conflicting_rows(a, b)
    } else {
        Vec::new()
    };
    Err(SolveFailure {
        free_columns,
        conflicting_rows,
    })
}

/// Indices with a non-zero entry in some vector of `basis`.
pub fn support(basis: &[Vec<Q>]) -> Vec<usize> {
    let n = basis.first().map_or(0, Vec::len);
    (0..n)
        .filter(|&i| basis.iter().any(|v| !v[i].is_zero()))
        .collect()
}

/// Rows involved in an inconsistency: those with a non-zero weight in a left
/// null vector y (y^T a = 0) with y^T b != 0.
fn conflicting_rows(a: &QMatrix, b: &[Q]) -> Vec<usize> {
    let rows = a.len();
    let cols = a.first().map_or(0, Vec::len);
    let at: QMatrix = (0..cols)
        .map(|c| (0..rows).map(|r| a[r][c].clone()).collect())
        .collect();
    let left = nullspace(&at, rows);
    let mut out = Vec::new();
    for y in &left {
        let yb: Q = y.iter().zip(b).map(|(yi, bi)| yi * bi).sum();
        if !yb.is_zero() {
            out.extend((0..rows).filter(|&i| !y[i].is_zero()));
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Absolute value helper for callers that only import this module.
pub fn abs(x: &Q) -> Q {
    x.abs()
}

/// The inertia of a symmetric matrix: how many eigenvalues are positive,
/// zero and negative (Sylvester's law: invariant under congruence).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Inertia {
    /// Positive eigenvalues.
    pub positive: usize,
    /// Zero eigenvalues.
    pub zero: usize,
    /// Negative eigenvalues.
    pub negative: usize,
}

/// The exact inertia of the symmetric matrix `a`, by congruence to a
/// diagonal matrix (symmetric elimination; where every remaining diagonal
/// entry is zero, row and column j are added to row and column i, which
/// puts 2 a_ij on the diagonal).
pub fn symmetric_inertia(a: &QMatrix) -> Inertia {
    let mut a = a.clone();
    let mut left: Vec<usize> = (0..a.len()).collect();
    let mut inertia = Inertia::default();
    while !left.is_empty() {
        let pivot = match left.iter().position(|&p| !a[p][p].is_zero()) {
            Some(k) => k,
            None => {
                let pair = left.iter().enumerate().find_map(|(ki, &i)| {
                    left.iter()
                        .find(|&&j| !a[i][j].is_zero())
                        .map(|&j| (ki, i, j))
                });
                let Some((ki, i, j)) = pair else {
                    inertia.zero += left.len();
                    break;
                };
                let row_j = a[j].clone();
                for (x, v) in a[i].iter_mut().zip(row_j) {
                    *x += v;
                }
                for row in &mut a {
                    let v = row[j].clone();
                    row[i] += v;
                }
                ki
            }
        };
        let p = left.swap_remove(pivot);
        let d = a[p][p].clone();
        if d.is_positive() {
            inertia.positive += 1;
        } else {
            inertia.negative += 1;
        }
        for &r in &left {
            let f = &a[r][p] / &d;
            for &c in &left {
                let v = &f * &a[p][c];
                a[r][c] -= v;
            }
        }
    }
    inertia
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_fractions_and_decimals_exactly() {
        assert_eq!(parse_rational("-162/77"), Ok(frac(-162, 77)));
        assert_eq!(parse_rational("2.5"), Ok(frac(5, 2)));
        assert_eq!(parse_rational("1e-3"), Ok(frac(1, 1000)));
        assert_eq!(parse_rational("0.1"), Ok(frac(1, 10)));
        assert_eq!(parse_rational("1.5/0.5"), Ok(q(3)));
        assert_eq!(parse_rational("abc"), Err(RationalError::Invalid));
        assert_eq!(parse_rational("1/0"), Err(RationalError::ZeroDenominator));
        // One fraction bar only: 1/3/4 is not (1/3)/4 nor 1/(3/4).
        assert_eq!(parse_rational("1/3/4"), Err(RationalError::Invalid));
        assert_eq!(parse_rational("1e"), Err(RationalError::Invalid));
    }

    #[test]
    fn huge_exponents_and_digit_strings_are_refused_at_once() {
        for text in [
            "1e1000000",
            "1e-1000000",
            "1e999999",
            "5e99999999999999999999",
        ] {
            assert_eq!(parse_rational(text), Err(RationalError::TooLarge), "{text}");
        }
        let digits = "7".repeat(MAX_DIGITS + 1);
        assert_eq!(parse_rational(&digits), Err(RationalError::TooLarge));
        // The limits themselves are accepted, and leading zeros do not count.
        assert!(parse_rational("1e1000").is_ok() && parse_rational("1e-1000").is_ok());
        // The most negative i64 exponent is refused, not wrapped (a fuzz timeout).
        assert_eq!(
            parse_rational("1e-9223372036854775808"),
            Err(RationalError::TooLarge)
        );
        assert_eq!(
            parse_rational("5e-0009223372036854775808"),
            Err(RationalError::TooLarge)
        );
        // The value's size counts too, so that what is accepted prints back
        // as text that is accepted (a fuzz finding: 1e1000 printed 1001 digits).
        for text in [
            "1e1000",
            "1e-1000",
            "7e1000/3",
            "1e1000/1e-1000",
            "-1/3e1000",
        ] {
            match parse_rational(text) {
                Ok(q) => assert_eq!(parse_rational(&display(&q)), Ok(q), "{text}"),
                Err(e) => assert_eq!(e, RationalError::TooLarge, "{text}"),
            }
        }
        assert_eq!(
            parse_rational("1e1000/1e-1000"),
            Err(RationalError::TooLarge)
        );
        assert_eq!(
            parse_rational(&"9".repeat(MAX_DIGITS)).map(|q| display(&q).len()),
            Ok(MAX_DIGITS)
        );
        assert_eq!(
            parse_rational(&format!("1{}", "0".repeat(MAX_DIGITS))),
            Err(RationalError::TooLarge)
        );
        assert!(parse_rational(&format!("000{}", "7".repeat(MAX_DIGITS))).is_ok());
        // Exact but not a double.
        assert_eq!(
            parse_finite("1e400").map(|x| x.1),
            Err(RationalError::OutOfRange)
        );
        assert_eq!(parse_finite("1e-400").map(|x| x.1), Ok(0.0));
    }

    #[test]
    fn solve_reconstructs_and_diagnoses() {
        let a = vec![vec![q(2), q(1)], vec![q(1), q(3)]];
        let b = vec![q(3), q(5)];
        let x = solve(&a, &b).expect("regular");
        for (row, bi) in a.iter().zip(&b) {
            let ax: Q = row.iter().zip(&x).map(|(p, y)| p * y).sum();
            assert_eq!(&ax, bi);
        }
        let sing = vec![vec![q(1), q(1)], vec![q(2), q(2)]];
        let fail = solve(&sing, &[q(1), q(3)]).expect_err("singular");
        assert_eq!(fail.free_columns, vec![0, 1]);
        assert_eq!(fail.conflicting_rows, vec![0, 1]);
        let fail = solve(&sing, &[q(1), q(2)]).expect_err("singular");
        assert!(fail.conflicting_rows.is_empty());
    }

    #[test]
    fn nullspace_vectors_are_annihilated() {
        let a = vec![vec![q(1), q(-2), q(1)], vec![q(2), q(-4), q(2)]];
        let ns = nullspace(&a, 3);
        assert_eq!(ns.len(), 2);
        for v in &ns {
            for row in &a {
                let s: Q = row.iter().zip(v).map(|(p, y)| p * y).sum();
                assert!(s.is_zero());
            }
        }
    }

    #[test]
    fn inertia_by_congruence_matches_known_spectra() {
        let m = |rows: &[&[i64]]| -> QMatrix {
            rows.iter()
                .map(|r| r.iter().map(|&v| q(v)).collect())
                .collect()
        };
        let count = |p, z, n| Inertia {
            positive: p,
            zero: z,
            negative: n,
        };
        // Eigenvalues 3 and -1.
        assert_eq!(symmetric_inertia(&m(&[&[1, 2], &[2, 1]])), count(1, 0, 1));
        // A zero diagonal: eigenvalues +-1 (needs the row-addition step).
        assert_eq!(symmetric_inertia(&m(&[&[0, 1], &[1, 0]])), count(1, 0, 1));
        // Rank one: eigenvalues 0, 0, 3.
        assert_eq!(
            symmetric_inertia(&m(&[&[1, 1, 1], &[1, 1, 1], &[1, 1, 1]])),
            count(1, 2, 0)
        );
        // Negative definite (eigenvalues -1, -3).
        assert_eq!(symmetric_inertia(&m(&[&[-2, 1], &[1, -2]])), count(0, 0, 2));
        // Negative semidefinite, singular (eigenvalues 0, -2).
        assert_eq!(symmetric_inertia(&m(&[&[-1, 1], &[1, -1]])), count(0, 1, 1));
    }

    #[test]
    fn simplest_fractions_near_floats() {
        assert_eq!(simplest_near(1.0 / 3.0, 1e-12), frac(1, 3));
        assert_eq!(simplest_near(10.0 / 3.0, 1e-12), frac(10, 3));
        assert_eq!(simplest_near(0.1, 1e-12), frac(1, 10));
        assert_eq!(simplest_near(-2.5, 1e-12), frac(-5, 2));
        // No simple fraction that close: the exact value of the double.
        let x = std::f64::consts::PI;
        let q = simplest_near(x, 1e-12);
        assert!((to_f64(&q) - x).abs() <= 1e-12 * x);
    }
}
