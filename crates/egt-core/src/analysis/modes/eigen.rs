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
/// With M_z = L L^T (L = sqrt(M) when no element is held), the elastic modes
/// are the eigenvectors v of A = L^-1 K_z L^-T off the rigid directions
/// Q = orth(L^T R) (R: the springs' null space, the rigid-body motion), and
/// phi = L^-T v. The rigid directions are deflated exactly, A' = P A P - s Q
/// Q^T (P = I - Q Q^T, s above every eigenvalue of A), so that they sort
/// first with eigenvalue -s and one symmetric eigenproblem gives the rest.
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
    let (rb, _) = null_space(&sz, r)?;
    let dof = rb.ncols();
    // A = L^-1 K_z L^-T, and the rigid directions L^T R.
    let (a, lt_r, l) = if whole {
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
        let root: Vec<f64> = (0..r).map(|i| mz[(i, i)].sqrt()).collect();
        let a = DMatrix::from_fn(r, r, |i, j| kz[(i, j)] / (root[i] * root[j]));
        let lt_r = DMatrix::from_fn(r, dof, |i, j| root[i] * rb[(i, j)]);
        (a, lt_r, None)
    } else {
        let l = cholesky_l(mz.clone())?;
        let y = l.solve_lower_triangular(&kz).ok_or_else(singular_mass)?;
        let a = l
            .solve_lower_triangular(&y.transpose())
            .ok_or_else(singular_mass)?;
        let lt_r = l.transpose() * &rb;
        (a, lt_r, Some(l))
    };
    let a = (&a + a.transpose()) * 0.5;
    let deflated = if dof == 0 {
        a
    } else {
        let q = lt_r.qr().q();
        let shift = 1.0 + a.norm();
        let aq = &a * &q;
        let qaq = q.transpose() * &aq;
        &a - &aq * q.transpose() - &q * aq.transpose()
            + &q * (qaq - DMatrix::identity(dof, dof) * shift) * q.transpose()
    };
    let (values, vectors) = sym_eigen(&deflated)?;
    let lambda: Vec<f64> = values.iter().skip(dof).map(|v| v.max(0.0)).collect();
    let v = vectors.columns(dof, r - dof).into_owned();
    // phi_z = L^-T v.
    let z_elastic = match &l {
        None => DMatrix::from_fn(r, r - dof, |i, j| v[(i, j)] / mz[(i, i)].sqrt()),
        Some(l) => l
            .transpose()
            .solve_upper_triangular(&v)
            .ok_or_else(singular_mass)?,
    };
    // The rigid shapes, M-orthonormal: R (R^T M R)^(-1/2) by Cholesky.
    let rigid = if dof == 0 {
        DMatrix::zeros(t.nrows(), 0)
    } else {
        let lr = cholesky_l(rb.transpose() * &mz * &rb)?;
        let inv = lr.try_inverse().ok_or_else(singular_mass)?;
        let z = &rb * inv.transpose();
        if whole { z } else { t * z }
    };
    Ok(Eigen {
        rigid,
        lambda,
        elastic: if whole { z_elastic } else { t * z_elastic },
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
}
