//! The undamped generalised eigenproblem K phi = omega^2 M phi of the
//! torsional model, on the coordinates its rigid constraints leave: the
//! rigid-body modes (the null space of the springs' rows, which is the
//! kinematics) apart, the elastic modes on the rest by a Cholesky reduction
//! of M and nalgebra's symmetric eigensolver.

use nalgebra::{DMatrix, SymmetricEigen};

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

/// An orthonormal basis of the null space of `rows` (n columns): each row
/// scaled to unit length first, so that the springs' sizes do not matter.
/// The second matrix spans the row space (the orthogonal complement).
pub(crate) fn null_space(rows: &DMatrix<f64>, n: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut a = rows.clone();
    for mut r in a.row_iter_mut() {
        let norm = r.norm();
        if norm > 0.0 {
            r /= norm;
        }
    }
    let eig = SymmetricEigen::new(a.transpose() * &a);
    let top = eig.eigenvalues.amax().max(1.0);
    let (free, bound): (Vec<usize>, Vec<usize>) =
        (0..n).partition(|&k| eig.eigenvalues[k] <= NULL_TOLERANCE * top);
    let pick = |ks: &[usize]| {
        let mut m = DMatrix::zeros(n, ks.len());
        for (c, &k) in ks.iter().enumerate() {
            m.set_column(c, &eig.eigenvectors.column(k));
        }
        m
    };
    (pick(&free), pick(&bound))
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
/// stiffness and mass matrices.
pub(crate) fn solve(
    t: &DMatrix<f64>,
    springs: &DMatrix<f64>,
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
) -> Result<Eigen> {
    let r = t.ncols();
    let kz = t.transpose() * k * t;
    let mz = t.transpose() * m * t;
    // z = R a + E b: R spans the springs' null space (rigid motion), E its
    // complement; K R = 0, so the elastic modes solve E^T K E b = lambda S b
    // with S the Schur complement of R^T M R in M (the rigid coordinates
    // condensed out, exactly).
    let (rb, eb) = null_space(&(springs * t), r);
    let mrr = rb.transpose() * &mz * &rb;
    let mre = rb.transpose() * &mz * &eb;
    let mee = eb.transpose() * &mz * &eb;
    let kee = eb.transpose() * &kz * &eb;
    let (schur, a_of_b) = if rb.ncols() == 0 {
        (mee, DMatrix::zeros(0, eb.ncols()))
    } else {
        let lr = cholesky_l(mrr)?;
        let y = lr.solve_lower_triangular(&mre).ok_or_else(singular_mass)?;
        let a_of_b = -lr
            .transpose()
            .solve_upper_triangular(&y)
            .ok_or_else(singular_mass)?;
        (&mee + mre.transpose() * &a_of_b, a_of_b)
    };
    let l = cholesky_l(schur)?;
    let linv = l.try_inverse().ok_or_else(singular_mass)?;
    let a = &linv * &kee * linv.transpose();
    let eig = SymmetricEigen::new((&a + a.transpose()) * 0.5);
    let mut order: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    order.sort_by(|&x, &y| eig.eigenvalues[x].total_cmp(&eig.eigenvalues[y]));
    let lambda = order.iter().map(|&i| eig.eigenvalues[i].max(0.0)).collect();
    let mut b = DMatrix::zeros(eb.ncols(), order.len());
    for (c, &i) in order.iter().enumerate() {
        b.set_column(c, &(linv.transpose() * eig.eigenvectors.column(i)));
    }
    let z_elastic = &eb * &b + &rb * (&a_of_b * &b);
    // The rigid shapes, M-orthonormal: R (R^T M R)^(-1/2) by Cholesky.
    let rigid = if rb.ncols() == 0 {
        DMatrix::zeros(t.nrows(), 0)
    } else {
        let lr = cholesky_l(rb.transpose() * &mz * &rb)?;
        let inv = lr.try_inverse().ok_or_else(singular_mass)?;
        t * (&rb * inv.transpose())
    };
    Ok(Eigen {
        rigid,
        lambda,
        elastic: t * z_elastic,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn null_space_ignores_the_rows_scale() {
        // x - y = 0 at 1e9 and y - z = 0 at 1e-3: the null space is (1, 1, 1).
        let rows = DMatrix::from_row_slice(2, 3, &[1e9, -1e9, 0.0, 0.0, 1e-3, -1e-3]);
        let (free, bound) = null_space(&rows, 3);
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
