//! The equations of the method, each written once: the Willis row of a
//! fundamental circuit (eq. 2), in floating point and in exact rationals.
//! Every solver, residual and Jacobian builds its rows from here.

use crate::numerics::exact::{self, Q};

/// The Willis row of eq. (2), the coefficients of (w_i, w_j, w_k) in
/// psi_m = w_i - tau w_j + (tau - 1) w_k for gear i, gear j and the carrier.
/// With a force ratio tau' in place of tau it is also a lossy mesh's force row.
pub fn willis_row(tau: f64) -> [f64; 3] {
    [1.0, -tau, tau - 1.0]
}

/// [`willis_row`] in exact rationals.
pub fn willis_row_exact(tau: &Q) -> [Q; 3] {
    [exact::q(1), -tau.clone(), tau - exact::q(1)]
}

/// psi_m (eq. 2) at the speeds of gear i, gear j and the carrier.
pub fn willis_residual(tau: f64, [wi, wj, wk]: [f64; 3]) -> f64 {
    let [a, b, c] = willis_row(tau);
    a * wi + b * wj + c * wk
}
