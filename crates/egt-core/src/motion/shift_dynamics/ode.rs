//! The explicit integrator the shift simulations share: one Bogacki–Shampine
//! 3(2) step with its embedded error, the cubic Hermite dense output of a
//! step, and Illinois false position for locating an event on it.

/// One Bogacki–Shampine 3(2) step from `(t, y)` with `k1 = f(t, y)`: the new
/// state, its derivative (first same as last) and the embedded error estimate.
pub fn bs23(
    f: &mut dyn FnMut(f64, &[f64]) -> Vec<f64>,
    t: f64,
    y: &[f64],
    k1: &[f64],
    h: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let add = |parts: &[(f64, &[f64])]| -> Vec<f64> {
        let mut r = y.to_vec();
        for (c, k) in parts {
            for (ri, ki) in r.iter_mut().zip(k.iter()) {
                *ri += h * c * ki;
            }
        }
        r
    };
    let k2 = f(t + 0.5 * h, &add(&[(0.5, k1)]));
    let k3 = f(t + 0.75 * h, &add(&[(0.75, &k2)]));
    let y1 = add(&[(2.0 / 9.0, k1), (1.0 / 3.0, &k2), (4.0 / 9.0, &k3)]);
    let k4 = f(t + h, &y1);
    let err = (0..y.len())
        .map(|i| {
            h * ((2.0 / 9.0 - 7.0 / 24.0) * k1[i]
                + (1.0 / 3.0 - 0.25) * k2[i]
                + (4.0 / 9.0 - 1.0 / 3.0) * k3[i]
                - 0.125 * k4[i])
        })
        .collect();
    (y1, k4, err)
}

/// The weighted RMS norm of a step's error, `<= 1` to accept.
pub fn error_norm(err: &[f64], y0: &[f64], y1: &[f64], rtol: f64, atol: f64) -> f64 {
    let sum: f64 = (0..err.len())
        .map(|i| (err[i] / (atol + rtol * y0[i].abs().max(y1[i].abs()))).powi(2))
        .sum();
    (sum / err.len().max(1) as f64).sqrt()
}

/// Cubic Hermite interpolant through `(t0, y0, f0)` and `(t1, y1, f1)` at `s`:
/// the third-order dense output of Bogacki–Shampine.
pub fn hermite(
    t0: f64,
    y0: &[f64],
    f0: &[f64],
    t1: f64,
    y1: &[f64],
    f1: &[f64],
    s: f64,
) -> Vec<f64> {
    let h = t1 - t0;
    let th = (s - t0) / h;
    let h00 = (1.0 + 2.0 * th) * (1.0 - th) * (1.0 - th);
    let h10 = th * (1.0 - th) * (1.0 - th);
    let h01 = th * th * (3.0 - 2.0 * th);
    let h11 = th * th * (th - 1.0);
    (0..y0.len())
        .map(|i| h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i])
        .collect()
}

/// Illinois false position for the root of `g` in `[a, b]` with `g(a) > 0 >= g(b)`.
pub fn locate(
    mut g: impl FnMut(f64) -> f64,
    mut a: f64,
    mut b: f64,
    mut ga: f64,
    mut gb: f64,
) -> f64 {
    let mut side = 0;
    for _ in 0..200 {
        if gb == 0.0 || (b - a).abs() <= 4.0 * f64::EPSILON * b.abs().max(1e-300) {
            return b;
        }
        let c = (a * gb - b * ga) / (gb - ga);
        let gc = g(c);
        if gc > 0.0 {
            a = c;
            ga = gc;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        } else {
            b = c;
            gb = gc;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        }
    }
    b
}

/// One step of the linearly implicit Euler method extrapolated over the
/// step-number sequence 1, 2, 3 (a fixed-order SEULEX): third order and
/// stable for stiff modes. The Jacobian `df/dy` and `df/dt` are taken once, by
/// finite differences at `(t, y)`; each substep solves
/// `(I - h J) dy = h f(t_k, y_k) + h^2 df/dt`. Returns the new state, its
/// derivative and the error estimate (the difference between the third- and
/// second-order table entries), or `None` when a matrix `I - h J` is singular.
pub fn implicit_step(
    f: &mut dyn FnMut(f64, &[f64]) -> Vec<f64>,
    t: f64,
    y: &[f64],
    h: f64,
) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    use nalgebra::{DMatrix, DVector};
    let n = y.len();
    let f0 = f(t, y);
    let mut jac = DMatrix::<f64>::zeros(n, n);
    for j in 0..n {
        let d = 1e-7 * (1.0 + y[j].abs());
        let mut yp = y.to_vec();
        yp[j] += d;
        let fp = f(t, &yp);
        for i in 0..n {
            jac[(i, j)] = (fp[i] - f0[i]) / d;
        }
    }
    let dt = 1e-7 * (1.0 + t.abs()).max(h);
    let ft: Vec<f64> = f(t + dt, y)
        .iter()
        .zip(&f0)
        .map(|(a, b)| (a - b) / dt)
        .collect();
    // T_m1: m linearly implicit Euler substeps of h / m.
    let mut table: Vec<Vec<f64>> = Vec::with_capacity(3);
    for m in 1..=3usize {
        let hs = h / m as f64;
        let lu = (DMatrix::<f64>::identity(n, n) - &jac * hs).lu();
        let mut yk = y.to_vec();
        for k in 0..m {
            let fk = if k == 0 {
                f0.clone()
            } else {
                f(t + k as f64 * hs, &yk)
            };
            let rhs = DVector::from_iterator(n, (0..n).map(|i| hs * fk[i] + hs * hs * ft[i]));
            let d = lu.solve(&rhs)?;
            for i in 0..n {
                yk[i] += d[i];
            }
        }
        table.push(yk);
    }
    // Aitken-Neville for an h-expansion: T22 = 2 T21 - T11,
    // T32 = 3 T31 - 2 T21, T33 = T32 + (T32 - T22) / 2.
    let t22: Vec<f64> = (0..n).map(|i| 2.0 * table[1][i] - table[0][i]).collect();
    let t32: Vec<f64> = (0..n)
        .map(|i| 3.0 * table[2][i] - 2.0 * table[1][i])
        .collect();
    let t33: Vec<f64> = (0..n).map(|i| t32[i] + 0.5 * (t32[i] - t22[i])).collect();
    let err: Vec<f64> = (0..n).map(|i| t33[i] - t32[i]).collect();
    if !t33.iter().all(|v| v.is_finite()) {
        return None;
    }
    let f1 = f(t + h, &t33);
    Some((t33, f1, err))
}
