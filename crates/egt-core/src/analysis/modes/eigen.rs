//! The undamped generalised eigenproblem K phi = omega^2 M phi of the
//! torsional model, on the coordinates its rigid constraints leave: the
//! rigid-body modes (the null space of the springs' rows, which is the
//! kinematics) apart, the elastic modes on the rest by a Cholesky reduction
//! of M and faer's symmetric eigensolver (blocked, a divide-and-conquer
//! tridiagonal stage: at 1000 coordinates several times nalgebra's).

use nalgebra::{DMatrix, DVector};

use crate::error::{AnalysisError, Result};

/// Eigenvalues of `A^T A` (rows scaled to unit length) below this fraction
/// of the largest span a null space.
pub const NULL_TOLERANCE: f64 = 1e-12;

/// The modes of one model, every shape over the model's coordinates and
/// normalised to phi^T M phi = 1.
pub(crate) struct Eigen {
    /// Rigid-body shapes, coordinates x DOF.
    pub rigid: DMatrix<f64>,
    /// omega^2 of the elastic modes, ascending.
    pub lambda: Vec<f64>,
    /// Elastic shapes, one column per eigenvalue.
    pub elastic: DMatrix<f64>,
}

/// Eigenvalues (ascending) and orthonormal eigenvectors of the symmetric
/// matrix `a`, by faer.
///
/// # Errors
/// [`AnalysisError::NotConverged`] when faer's iteration does not settle.
fn sym_eigen(a: &DMatrix<f64>) -> Result<(DVector<f64>, DMatrix<f64>)> {
    let n = a.nrows();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let e = m
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|_| AnalysisError::NotConverged {
            what: "the symmetric eigensolver of the torsional modes".into(),
            t: 0.0,
        })?;
    let (s, u) = (e.S(), e.U());
    Ok((
        DVector::from_fn(n, |i, _| s[i]),
        DMatrix::from_fn(n, n, |i, j| u[(i, j)]),
    ))
}

/// An orthonormal basis of the null space of `rows` (n columns): each row
/// scaled to unit length first, so that the springs' sizes do not matter.
/// The second matrix spans the row space (the orthogonal complement).
pub(crate) fn null_space(rows: &DMatrix<f64>, n: usize) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let mut a = rows.clone();
    for mut r in a.row_iter_mut() {
        let norm = r.norm();
        if norm > 0.0 {
            r /= norm;
        }
    }
    // A^T A row by row over each row's non-zeros (a spring's row has two or
    // three): about linear in the rows, where a dense product is cubic.
    let mut ata = DMatrix::zeros(n, n);
    for row in a.row_iter() {
        let nz: Vec<(usize, f64)> = row
            .iter()
            .enumerate()
            .filter(|x| *x.1 != 0.0)
            .map(|(c, v)| (c, *v))
            .collect();
        for &(i, x) in &nz {
            for &(j, y) in &nz {
                ata[(i, j)] += x * y;
            }
        }
    }
    let (values, vectors) = sym_eigen(&ata)?;
    let top = values.amax().max(1.0);
    let (free, bound): (Vec<usize>, Vec<usize>) =
        (0..n).partition(|&k| values[k] <= NULL_TOLERANCE * top);
    let pick = |ks: &[usize]| {
        let mut m = DMatrix::zeros(n, ks.len());
        for (c, &k) in ks.iter().enumerate() {
            m.set_column(c, &vectors.column(k));
        }
        m
    };
    Ok((pick(&free), pick(&bound)))
}

fn singular_mass() -> crate::Error {
    AnalysisError::IndefiniteMass { low: 0.0, top: 0.0 }.into()
}

fn cholesky_l(m: DMatrix<f64>) -> Result<DMatrix<f64>> {
    let sym = (&m + m.transpose()) * 0.5;
    let low = sym.diagonal().min();
    let top = sym.diagonal().max();
    sym.cholesky()
        .map(|c| c.l())
        .ok_or_else(|| AnalysisError::IndefiniteMass { low, top }.into())
}

/// Solve the model: `t` is a basis of the coordinates the constraints leave
/// (n x r), `springs` the springs' rows (m x n), `k` and `m` the n x n
/// stiffness and (diagonal) mass matrices.
///
/// With M_z = L L^T (L = sqrt(M) when no element is held), the modes are
/// phi = L^-T v for the eigenvectors v of A = L^-1 K_z L^-T: the rigid-body
/// modes those of the zero eigenvalues (checked against the springs, else
/// found as the springs' null space and deflated, [`deflated`]).
pub(crate) fn solve(
    t: &DMatrix<f64>,
    springs: &DMatrix<f64>,
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
) -> Result<Eigen> {
    let r = t.ncols();
    // No rigid element: t is the identity, the projections are copies and
    // M_z is diagonal.
    let whole = t.is_square() && t.is_identity(0.0);
    let (kz, mz, sz) = if whole {
        (k.clone(), m.clone(), springs.clone())
    } else {
        (t.transpose() * k * t, t.transpose() * m * t, springs * t)
    };
    // M_z = L L^T and A = L^-1 K_z L^-T.
    let l = if whole {
        if let Some(low) = mz
            .diagonal()
            .iter()
            .copied()
            .find(|v| v.is_nan() || *v <= 0.0)
        {
            return Err(AnalysisError::IndefiniteMass {
                low,
                top: mz.diagonal().max(),
            }
            .into());
        }
        None
    } else {
        Some(cholesky_l(mz.clone())?)
    };
    let a = match &l {
        None => DMatrix::from_fn(r, r, |i, j| kz[(i, j)] / (mz[(i, i)] * mz[(j, j)]).sqrt()),
        Some(l) => {
            let y = l.solve_lower_triangular(&kz).ok_or_else(singular_mass)?;
            l.solve_lower_triangular(&y.transpose())
                .ok_or_else(singular_mass)?
        }
    };
    let a = (&a + a.transpose()) * 0.5;
    // phi_z = L^-T v.
    let back = |v: &DMatrix<f64>| -> Result<DMatrix<f64>> {
        let z = match &l {
            None => DMatrix::from_fn(r, v.ncols(), |i, j| v[(i, j)] / mz[(i, i)].sqrt()),
            Some(l) => l
                .transpose()
                .solve_upper_triangular(v)
                .ok_or_else(singular_mass)?,
        };
        Ok(if whole { z } else { t * z })
    };
    // One eigenproblem of A: its lowest eigenvectors are the rigid-body
    // modes when they are plainly so (below 1e-12 of the largest eigenvalue,
    // every spring's normalised row annihilating them, and a gap of four
    // orders to the next, which deflects some spring). Otherwise the
    // springs' null space decides, and its directions are deflated exactly.
    let (values, vectors) = sym_eigen(&a)?;
    let top = values
        .iter()
        .fold(0.0_f64, |x, v| x.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let dof = values.iter().take_while(|v| **v <= 1e-12 * top).count();
    if dof == r || values[dof] > 1e-8 * top {
        let z = back(&vectors)?;
        let rigid = z.columns(0, dof).into_owned();
        let first = z.columns(dof, (r - dof).min(1)).into_owned();
        if moves_no_spring(springs, &rigid, 1e-8)
            && (dof == r || !moves_no_spring(springs, &first, 1e-6))
        {
            return Ok(Eigen {
                rigid,
                lambda: values.iter().skip(dof).map(|v| v.max(0.0)).collect(),
                elastic: z.columns(dof, r - dof).into_owned(),
            });
        }
    }
    deflated(&a, &sz, &mz, l.as_ref(), &back)
}

/// Every column of `shapes` leaves each spring undeflected: |row . phi|
/// within `tol` of |row| |phi| (the springs' scales do not matter).
fn moves_no_spring(springs: &DMatrix<f64>, shapes: &DMatrix<f64>, tol: f64) -> bool {
    shapes.column_iter().all(|phi| {
        let size = phi.amax();
        springs.row_iter().all(|row| {
            let norm = row.norm();
            norm == 0.0 || (row * phi)[0].abs() <= tol * norm * size
        })
    })
}

/// The robust route: the springs' null space R (the rigid-body motion),
/// its directions Q = orth(L^T R) deflated from A exactly, A' = P A P - s Q
/// Q^T (P = I - Q Q^T, s above every eigenvalue of A), so that they sort
/// first with eigenvalue -s, and one more eigenproblem for the rest.
fn deflated(
    a: &DMatrix<f64>,
    sz: &DMatrix<f64>,
    mz: &DMatrix<f64>,
    l: Option<&DMatrix<f64>>,
    back: &dyn Fn(&DMatrix<f64>) -> Result<DMatrix<f64>>,
) -> Result<Eigen> {
    let r = a.nrows();
    let (rb, _) = null_space(sz, r)?;
    let dof = rb.ncols();
    let deflated = if dof == 0 {
        a.clone()
    } else {
        let lt_r = match l {
            None => DMatrix::from_fn(r, dof, |i, j| mz[(i, i)].sqrt() * rb[(i, j)]),
            Some(l) => l.transpose() * &rb,
        };
        let q = lt_r.qr().q();
        let shift = 1.0 + a.norm();
        let aq = a * &q;
        let qaq = q.transpose() * &aq;
        a - &aq * q.transpose() - &q * aq.transpose()
            + &q * (qaq - DMatrix::identity(dof, dof) * shift) * q.transpose()
    };
    let (values, vectors) = sym_eigen(&deflated)?;
    let lambda: Vec<f64> = values.iter().skip(dof).map(|v| v.max(0.0)).collect();
    let elastic = back(&vectors.columns(dof, r - dof).into_owned())?;
    // The rigid shapes, M-orthonormal: R (R^T M R)^(-1/2) by Cholesky.
    let rigid = if dof == 0 {
        back(&DMatrix::zeros(r, 0))?
    } else {
        let lr = cholesky_l(rb.transpose() * mz * &rb)?;
        let inv = lr.try_inverse().ok_or_else(singular_mass)?;
        let z = &rb * inv.transpose();
        // back() maps L^T-coordinates; the rigid shapes are in z already.
        match l {
            None => {
                let lt = DMatrix::from_fn(r, dof, |i, j| mz[(i, i)].sqrt() * z[(i, j)]);
                back(&lt)?
            }
            Some(l) => back(&(l.transpose() * z))?,
        }
    };
    Ok(Eigen {
        rigid,
        lambda,
        elastic,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn null_space_ignores_the_rows_scale() {
        // x - y = 0 at 1e9 and y - z = 0 at 1e-3: the null space is (1, 1, 1).
        let rows = DMatrix::from_row_slice(2, 3, &[1e9, -1e9, 0.0, 0.0, 1e-3, -1e-3]);
        let Ok((free, bound)) = null_space(&rows, 3) else {
            panic!("the eigensolver converges on a 3 x 3 matrix");
        };
        assert_eq!((free.ncols(), bound.ncols()), (1, 2));
        let v = free.column(0);
        assert!((v.abs().sum() - 3f64.sqrt()).abs() < 1e-12);
        assert!((&rows * v).amax() < 1e-6);
    }

    #[test]
    fn a_chain_of_three_has_one_rigid_mode_and_the_textbook_frequencies() {
        // Unit inertias, unit springs 1-2 and 2-3: omega^2 = 0, 1, 3.
        let springs = DMatrix::from_row_slice(2, 3, &[1.0, -1.0, 0.0, 0.0, 1.0, -1.0]);
        let k = springs.transpose() * &springs;
        let m = DMatrix::identity(3, 3);
        let e = solve(&DMatrix::identity(3, 3), &springs, &k, &m).expect("a positive mass");
        assert_eq!(e.rigid.ncols(), 1);
        assert!((e.lambda[0] - 1.0).abs() < 1e-12 && (e.lambda[1] - 3.0).abs() < 1e-12);
        // K phi = lambda M phi for each elastic mode.
        for (c, &l) in e.lambda.iter().enumerate() {
            let phi = e.elastic.column(c);
            assert!((&k * phi - l * (&m * phi)).amax() < 1e-12);
        }
    }

    /// Unit inertias on a chain, springs 1-2 stiff and 2-3 soft by 14
    /// orders: the soft mode's eigenvalue is below 1e-12 of the largest, so
    /// the one eigenproblem cannot tell it from a rigid-body mode; the check
    /// against the springs sends it to the null-space route, which counts
    /// one rigid-body mode, not two.
    #[test]
    fn a_soft_spring_is_not_taken_for_a_rigid_body_mode() {
        let (stiff, soft) = (1.0e8, 1.0e-6);
        let springs = DMatrix::from_row_slice(2, 3, &[1.0, -1.0, 0.0, 0.0, 1.0, -1.0]);
        let k = DMatrix::from_row_slice(
            3,
            3,
            &[
                stiff,
                -stiff,
                0.0,
                -stiff,
                stiff + soft,
                -soft,
                0.0,
                -soft,
                soft,
            ],
        );
        let m = DMatrix::identity(3, 3);
        let Ok(e) = solve(&DMatrix::identity(3, 3), &springs, &k, &m) else {
            panic!("a positive mass");
        };
        assert_eq!(e.rigid.ncols(), 1);
        assert_eq!(e.lambda.len(), 2);
        // The stiff pair: 2 k_stiff (unit inertias), to round-off.
        assert!((e.lambda[1] / (2.0 * stiff) - 1.0).abs() < 1e-12);
        // The soft one, k_soft (1/2 + 1), is 1e-14 of the largest: dense
        // solvers give it to about eps / 1e-14 relative, no better.
        assert!(
            (e.lambda[0] / (1.5 * soft) - 1.0).abs() < 0.1,
            "{}",
            e.lambda[0]
        );
    }

    /// The two routes (one eigenproblem; the null space deflated) give the
    /// same frequencies on a chain they both handle.
    #[test]
    fn both_routes_give_the_same_frequencies() {
        let springs = DMatrix::from_row_slice(
            3,
            4,
            &[
                1.0, -1.0, 0.0, 0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 1.0, -1.0,
            ],
        );
        let stiff = [3.0, 5.0, 7.0];
        let k = springs.transpose()
            * DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&stiff))
            * &springs;
        let m = DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&[1.0, 2.0, 0.5, 4.0]));
        let t = DMatrix::identity(4, 4);
        let Ok(fast) = solve(&t, &springs, &k, &m) else {
            panic!("a positive mass");
        };
        let a = DMatrix::from_fn(4, 4, |i, j| k[(i, j)] / (m[(i, i)] * m[(j, j)]).sqrt());
        let back = |v: &DMatrix<f64>| -> Result<DMatrix<f64>> {
            Ok(DMatrix::from_fn(4, v.ncols(), |i, j| {
                v[(i, j)] / m[(i, i)].sqrt()
            }))
        };
        let Ok(slow) = deflated(&a, &springs, &m, None, &back) else {
            panic!("a positive mass");
        };
        assert_eq!((fast.rigid.ncols(), slow.rigid.ncols()), (1, 1));
        for (x, y) in fast.lambda.iter().zip(&slow.lambda) {
            assert!((x - y).abs() < 1e-12 * y, "{x} vs {y}");
        }
        // Both rigid shapes are the uniform rotation, M-normalised.
        for e in [&fast, &slow] {
            let v = e.rigid.column(0);
            assert!(
                (v.amax() - v.amin()).abs() < 1e-12
                    && ((v.transpose() * &m * v)[0] - 1.0).abs() < 1e-12
            );
        }
    }
}
