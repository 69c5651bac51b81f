//! The damped modes of the torsional model: the complex eigenvalues of
//! `M x'' + C x' + K x = 0`, C from the meshes' and springs' damping along the
//! same rows as their stiffness, in the undamped elastic modes' coordinates
//! (exact: the rigid-body motion has neither stiffness nor damping). Each
//! underdamped pair is reported once (positive imaginary part) with its
//! damped frequency and damping ratio, an overdamped motion by its real
//! rates. nalgebra's real Schur form gives the eigenvalues.

use nalgebra::{DMatrix, DVector, Schur};
use serde::Serialize;

use super::model::TorsionalModel;
use crate::error::{AnalysisError, Result};

/// One damped mode: the eigenvalue `sigma + i omega_d`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DampedMode {
    /// Real part of the eigenvalue (1/s, negative: decay).
    pub sigma: f64,
    /// Damped angular frequency, the imaginary part (rad/s; 0 when overdamped).
    pub omega_d: f64,
    /// Damped frequency (Hz).
    pub hertz_d: f64,
    /// The undamped frequency of the pair, |lambda| (rad/s).
    pub omega_n: f64,
    /// -sigma / |lambda|: the pair's damping ratio zeta for an underdamped
    /// mode; exactly 1 for each real root of an overdamped motion.
    pub damping_ratio: f64,
}

/// The damped modes from the undamped elastic modes: with them
/// mass-normalised, `q'' + Phi^T C Phi q' + Lambda q = 0` is the whole
/// elastic motion exactly (every damper acts along a spring's row, so C, like
/// K, vanishes on the rigid-body modes, which stay apart). `deflections` is
/// the springs' deflection per mode (springs x modes), `lambda` omega^2 per
/// mode. By rising |lambda|; empty when nothing is damped.
///
/// # Errors
/// [`AnalysisError::NotConverged`] when the Schur iteration does not settle.
pub(crate) fn damped_modes(
    model: &TorsionalModel,
    deflections: &DMatrix<f64>,
    lambda: &[f64],
) -> Result<Vec<DampedMode>> {
    if model.elastic.iter().all(|e| e.damping == 0.0) {
        return Ok(Vec::new());
    }
    let r = lambda.len();
    let c = DVector::from_iterator(model.elastic.len(), model.elastic.iter().map(|e| e.damping));
    let modal = deflections.transpose() * DMatrix::from_diagonal(&c) * deflections;
    // In the balanced state (Omega q, q'), Omega = diag(omega): every block
    // of the size of the frequencies, [[0, Omega], [-Omega, -Phi^T C Phi]],
    // the same eigenvalues as [[0, I], [-Lambda, -Phi^T C Phi]] without its
    // spread of scales (Lambda ~ omega^2 beside 1).
    let mut a = DMatrix::zeros(2 * r, 2 * r);
    for (k, &l) in lambda.iter().enumerate() {
        let w = l.max(0.0).sqrt();
        a[(k, r + k)] = w;
        a[(r + k, k)] = -w;
    }
    a.view_mut((r, r), (r, r)).copy_from(&(-modal));
    let schur = Schur::try_new(a, f64::EPSILON, 100 * 2 * r.max(1)).ok_or_else(|| {
        AnalysisError::NotConverged {
            what: "the damped modes' Schur iteration".into(),
            t: 0.0,
        }
    })?;
    let mut modes: Vec<DampedMode> = schur
        .complex_eigenvalues()
        .iter()
        .filter(|l| l.im >= 0.0)
        .map(|l| {
            let omega_n = l.norm();
            DampedMode {
                sigma: l.re,
                omega_d: l.im,
                hertz_d: l.im / std::f64::consts::TAU,
                omega_n,
                damping_ratio: -l.re / omega_n,
            }
        })
        .collect();
    modes.sort_by(|x, y| x.omega_n.total_cmp(&y.omega_n));
    Ok(modes)
}
