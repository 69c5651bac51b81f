//! Lock-up as a momentum-consistent projection. When a friction element locks
//! (or a one-way element engages), the speeds jump onto the new constraint
//! `A v = 0` through an impulse along the constraint directions only:
//!
//! `v+ = v - M^-1 A^T λ`, `λ = (A M^-1 A^T)^-1 A v`.
//!
//! This is the `M`-orthogonal projection of `v` onto the null space of `A`, so
//! the generalised momentum in every direction the constraint leaves free is
//! unchanged, and the kinetic energy lost is `½ (v - v+)^T M (v - v+) >= 0`:
//! a lock-up never raises kinetic energy. With a clutch that slips to zero
//! relative speed the jump is zero (the lock is smooth); the projection matters
//! for a one-way element or a dog clutch meeting a non-zero relative speed and
//! it removes the round-off drift of a locate-then-lock step.

use nalgebra::{DMatrix, DVector};

use crate::error::{AnalysisError, Error, Result};

/// Smallest squared pivot ratio of `A M^-1 A^T` taken as full rank.
pub const RANK_TOLERANCE: f64 = 1e-12;

/// Result of one lock-up projection.
#[derive(Debug, Clone, PartialEq)]
pub struct LockUp {
    /// Speeds after the lock (`A v+ = 0`).
    pub speed: DVector<f64>,
    /// Constraint impulses `λ`, one per row of `A` (N·m·s).
    pub impulse: DVector<f64>,
    /// Kinetic energy removed by the lock, `½ Δv^T M Δv` (J), never negative.
    pub energy_lost: f64,
}

/// Projects `speed` onto `A v = 0` in the metric of the mass matrix `mass`.
///
/// # Errors
/// `Analysis` error when `mass` is not positive definite or the rows of `A`
/// are dependent in that metric (`A M^-1 A^T` singular), or the sizes disagree.
pub fn lock_projection(
    mass: &DMatrix<f64>,
    rows: &DMatrix<f64>,
    speed: &DVector<f64>,
) -> Result<LockUp> {
    let n = speed.len();
    if mass.nrows() != n || mass.ncols() != n || rows.ncols() != n {
        return Err(refuse(format!(
            "mass matrix {}x{}, constraint rows {}x{} and {} speeds do not agree",
            mass.nrows(),
            mass.ncols(),
            rows.nrows(),
            rows.ncols(),
            n
        )));
    }
    let chol = mass
        .clone()
        .cholesky()
        .ok_or_else(|| refuse("mass matrix is not positive definite".into()))?;
    let m_inv_at = chol.solve(&rows.transpose());
    let schur = rows * &m_inv_at;
    let schur_chol = schur
        .cholesky()
        .ok_or_else(|| refuse("locked-element rows are dependent in the mass metric".into()))?;
    // Cholesky succeeds on a semi-definite matrix spoiled by round-off: judge
    // the rank from the pivots instead.
    let l = schur_chol.l_dirty();
    let pivots = (0..l.nrows()).map(|i| l[(i, i)].abs());
    let (lo, hi) = pivots.fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    if l.nrows() > 0 && (lo * lo <= RANK_TOLERANCE * hi * hi || lo.is_nan()) {
        return Err(refuse(
            "locked-element rows are dependent in the mass metric".into(),
        ));
    }
    let impulse = schur_chol.solve(&(rows * speed));
    let jump = &m_inv_at * &impulse;
    let after = speed - &jump;
    let energy_lost = 0.5 * jump.dot(&(mass * &jump));
    Ok(LockUp {
        speed: after,
        impulse,
        energy_lost,
    })
}

fn refuse(detail: String) -> Error {
    Error::Analysis(AnalysisError::Singular {
        what: "lock-up projection".into(),
        detail,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ke(m: &DMatrix<f64>, v: &DVector<f64>) -> f64 {
        0.5 * v.dot(&(m * v))
    }

    #[test]
    fn two_inertias_lock_at_the_momentum_average() {
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![0.2, 0.6]));
        let a = DMatrix::from_row_slice(1, 2, &[1.0, -1.0]);
        let v = DVector::from_vec(vec![300.0, 100.0]);
        let lock = lock_projection(&m, &a, &v).expect("test case is valid");
        let w = (0.2 * 300.0 + 0.6 * 100.0) / 0.8;
        assert!((lock.speed[0] - w).abs() < 1e-12 * w);
        assert!((lock.speed[1] - w).abs() < 1e-12 * w);
        // Closed form of the loss: ½ J1 J2 / (J1 + J2) Δω².
        let loss = 0.5 * 0.2 * 0.6 / 0.8 * 200.0f64.powi(2);
        assert!((lock.energy_lost - loss).abs() < 1e-12 * loss);
        assert!((ke(&m, &v) - ke(&m, &lock.speed) - loss).abs() < 1e-9 * loss);
    }

    #[test]
    fn random_locks_never_raise_energy_and_keep_free_momentum() {
        // A small deterministic LCG instead of a dependency: 200 random cases.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..200 {
            let n = 4;
            let b = DMatrix::from_fn(n, n, |_, _| next());
            let m = &b * b.transpose() + DMatrix::identity(n, n) * 0.1;
            let a = DMatrix::from_fn(2, n, |_, _| next());
            let v = DVector::from_fn(n, |_, _| 100.0 * next());
            let lock = lock_projection(&m, &a, &v).expect("test case is valid");
            assert!((&a * &lock.speed).amax() < 1e-9 * v.amax().max(1.0));
            assert!(lock.energy_lost >= 0.0);
            assert!(ke(&m, &lock.speed) <= ke(&m, &v) * (1.0 + 1e-12));
            // Momentum along any free direction u (A u = 0) is unchanged.
            let null = nalgebra::linalg::SVD::new(a.transpose() * &a, true, true);
            let u = null.u.expect("test case is valid");
            for k in 0..n {
                if null.singular_values[k] < 1e-10 {
                    let dir = u.column(k);
                    let p0 = dir.dot(&(&m * &v));
                    let p1 = dir.dot(&(&m * &lock.speed));
                    assert!((p0 - p1).abs() < 1e-9 * (1.0 + p0.abs()));
                }
            }
        }
    }

    #[test]
    fn dependent_rows_are_refused() {
        let m = DMatrix::identity(2, 2);
        let a = DMatrix::from_row_slice(2, 2, &[1.0, -1.0, 2.0, -2.0]);
        let v = DVector::from_vec(vec![1.0, 0.0]);
        assert!(lock_projection(&m, &a, &v).is_err());
    }
}
