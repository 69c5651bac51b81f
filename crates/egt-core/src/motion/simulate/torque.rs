//! Applied torques as a [`TorqueModel`]: the spec's linearised curves
//! ([`LinearCurves`]) or any law ([`TorqueFn`]).

use super::*;

/// Applied torques on the links as functions of time and link speeds.
pub trait TorqueModel {
    /// The applied torque on every link (by link index) at time `t` and link
    /// speeds `speed`, written into `torque`.
    fn torques(&self, t: f64, speed: &[f64], torque: &mut [f64]);

    /// dT_i/dw_j (links x links). The default differentiates
    /// [`TorqueModel::torques`] by central differences.
    fn jacobian(&self, t: f64, speed: &[f64], jac: &mut DMatrix<f64>) {
        let n = speed.len();
        let mut w = speed.to_vec();
        let (mut tp, mut tm) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let h = 1e-6 * speed[j].abs().max(1.0);
            w[j] = speed[j] + h;
            self.torques(t, &w, &mut tp);
            w[j] = speed[j] - h;
            self.torques(t, &w, &mut tm);
            w[j] = speed[j];
            for i in 0..n {
                jac[(i, j)] = (tp[i] - tm[i]) / (2.0 * h);
            }
        }
    }
}

/// The linearised torque-speed curves T_l = T0_l + K_l (w_l - w0_l) (eq. 13-15).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearCurves {
    slope: Vec<f64>,
    offset: Vec<f64>,
    active: Vec<bool>,
}

impl LinearCurves {
    /// From the reduced model's per-link slopes and offsets.
    pub fn from_model(model: &ReducedModel) -> Self {
        LinearCurves {
            slope: model.link_slope.clone(),
            offset: model.link_offset.clone(),
            active: model.has_curve.clone(),
        }
    }

    /// From curves on a train's links (several on one link add up; a curve on the frame does nothing).
    ///
    /// # Errors
    /// A non-finite number in a curve.
    pub fn new(train: &Train, curves: &[Curve]) -> Result<Self> {
        let n = train.links().len();
        let mut c = LinearCurves {
            slope: vec![0.0; n],
            offset: vec![0.0; n],
            active: vec![false; n],
        };
        for k in curves {
            for v in [k.torque, k.slope, k.speed] {
                if !v.is_finite() {
                    return Err(Error::spec(
                        format!("curve on `{}`", train.link_name(k.link)),
                        SpecErrorKind::NonFinite { value: v },
                    ));
                }
            }
            if k.link == train.frame() {
                continue;
            }
            let l = k.link.index();
            c.slope[l] += k.slope;
            c.offset[l] += k.torque - k.slope * k.speed;
            c.active[l] = true;
        }
        Ok(c)
    }
}

impl TorqueModel for LinearCurves {
    fn torques(&self, _t: f64, speed: &[f64], torque: &mut [f64]) {
        for (l, t) in torque.iter_mut().enumerate() {
            *t = if self.active[l] {
                self.offset[l] + self.slope[l] * speed[l]
            } else {
                0.0
            };
        }
    }

    fn jacobian(&self, _t: f64, _speed: &[f64], jac: &mut DMatrix<f64>) {
        jac.fill(0.0);
        for (l, &k) in self.slope.iter().enumerate() {
            jac[(l, l)] = k;
        }
    }
}

/// Any closure `|t, speeds, torques|` as a torque model (Jacobian by differences).
pub struct TorqueFn<F>(pub F);

impl<F> std::fmt::Debug for TorqueFn<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("TorqueFn(..)")
    }
}

impl<F: Fn(f64, &[f64], &mut [f64])> TorqueModel for TorqueFn<F> {
    fn torques(&self, t: f64, speed: &[f64], torque: &mut [f64]) {
        (self.0)(t, speed, torque);
    }
}
