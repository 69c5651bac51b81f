//! Stability of a train with any number F of degrees of freedom (paper
//! section 5, eq. 12-27, which stops at F = 2).
//!
//! The reduced model. Choose F independent driving links; \[V\] of eq. (23)
//! gives every link speed from theirs, w = V w_d, and \[psi_w\]\[V\] = 0 (eq. 24)
//! removes the Willis multipliers from eq. (6) when it is premultiplied by
//! V^T:
//!
//!   V^T M V w_d' = V^T T(V w_d)                                  (eq. 12, 25)
//!
//! With the linearised torque-speed curves T_l = T0_l + K_l (w_l - w0_l) on
//! any links (eq. 13-15, K_l = dT_l/dw_l of the *applied* torque),
//!
//!   \[M\] dw_d' = \[K\] dw_d,   \[M\] = V^T M V,   \[K\] = V^T diag(K_l) V.
//!
//! The paper's eq. (26), \[K\] = \[V\]^T {T}, is the reduced torque vector
//! \[K\] dw_d (eq. 27 already holds the speed deviations), not the matrix; and
//! its eq. (16)-(18) carry the opposite sign: dw_d = X e^(lambda t) gives
//! (lambda \[M\] - \[K\]) X = 0, so a motor whose torque falls as it speeds up
//! (K_l < 0) is stabilising. `docs/stability.md` and `docs/errata.md` give the
//! argument, and `crates/egt-core/tests/analyses/stability.rs` proves it by simulation.
//!
//! \[M\] is symmetric positive semi-definite and \[K\] is symmetric (each curve
//! acts on one link's own speed), so every eigenvalue is real: a rigid train
//! under speed-dependent torques creeps or runs away, it never oscillates.
//! The pencil is solved as a symmetric eigenproblem: \[M\] = Q diag(mu) Q^T;
//! directions with zero inertia are algebraic (their torques balance at every
//! instant) and are eliminated by a Schur complement before scaling by
//! mu^(-1/2).
//!
//! ```
//! use egt_core::{Format, StabilityRequest, Train, Verdict};
//!
//! // A motor (inertia 0.5) geared 2:1 to a flywheel (0.3); its torque falls
//! // as it speeds up (slope -0.8 N m s): lambda = K / I_reflected < 0.
//! let spec = r#"
//!     frame = "0"
//!     links = [{ name = "m", inertia = 0.5 }, { name = "o", inertia = 0.3 }]
//!     revolutes = [{ links = ["0", "m"], level = "a" }, { links = ["0", "o"], level = "b" }]
//!     gears = [{ links = ["m", "o"], ratio = -2.0 }]
//!     [analysis]
//!     speeds = { m = 100 }
//!     curves = [{ link = "m", torque = 1.0, slope = -0.8, speed = 100.0 }]
//! "#;
//! let train = Train::from_str(spec, Format::Toml, "example").unwrap();
//! let report = train.stability(&StabilityRequest::default()).unwrap();
//! let lambda = report.stability.eigenvalues[0];
//! assert!((lambda - (-0.8 / (0.5 + 0.3 / 4.0))).abs() < 1e-12);
//! assert_eq!(report.stability.verdict, Verdict::Stable);
//! ```

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::Serialize;

use crate::error::{AnalysisError, Result};
use crate::model::train::{Curve, LinkId, Train};
use crate::numerics::exact;
pub use crate::solve::reduced::{CoordinateSource, ReducedModel};
use crate::solve::reduced::{InertiaSplit, num, sym};

/// A massless direction whose torque slope is within this fraction of the
/// largest slope of zero has neither inertia nor a slope: its speed is
/// undetermined.
pub const MARGINAL_REL: f64 = 1e-10;
/// The operating point is steady when |V^T T| is below this fraction of the
/// torques that enter it.
pub const STEADY_REL: f64 = 1e-9;
/// The classical RK4 is stable on the negative real axis for |lambda| dt up to
/// this value (the real root of 1 + z + z^2/2 + z^3/6 + z^4/24 = 1 besides 0).
pub const RK4_REAL_LIMIT: f64 = 2.785_293_563_405_282;
/// Entries of [K] beyond this would overflow once scaled by the inertias.
const OVERFLOW_GUARD: f64 = 1e150;
/// Resolution of the scaled eigenproblem: eigenvalues within this multiple of
/// machine epsilon times the order and the norm of the scaled matrix are
/// indistinguishable from zero in double precision.
const EIGEN_RESOLUTION: f64 = 64.0 * f64::EPSILON;
/// Relative eigen residual of the modes past which a warning says their rates are approximate.
pub const MODE_RESIDUAL_WARN: f64 = 1e-8;

/// Where the operating point came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OperatingSource {
    /// Input speeds (the spec's `[analysis] speeds`, or given).
    Speeds,
    /// The equilibrium of the linearised curves, V^T T(w) = 0.
    Equilibrium,
}

/// The operating point and whether it is a steady state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OperatingPoint {
    /// Where it came from.
    pub source: OperatingSource,
    /// Every link's speed (by link index).
    pub speed: Vec<f64>,
    /// The applied torque of the curves on every link at these speeds.
    pub torque: Vec<f64>,
    /// V^T T: the reduced torque that accelerates the driving links (the
    /// right-hand side of eq. 16); zero at a steady state.
    pub reduced_torque: Vec<f64>,
    /// |V^T T| relative to the torques entering it.
    pub residual: f64,
    /// True when `residual` <= [`STEADY_REL`].
    pub steady: bool,
    /// The equilibrium of the linearised curves (link speeds), when \[K\] is regular.
    pub equilibrium: Option<Vec<f64>>,
    /// Condition estimate of \[K\] for the equilibrium solve.
    pub equilibrium_condition: Option<f64>,
}

/// Stable, unstable or marginal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Every eigenvalue is negative: perturbations decay.
    Stable,
    /// An eigenvalue is positive (or a massless direction runs away).
    Unstable,
    /// The largest eigenvalue is zero within the resolution: perturbations neither grow nor decay.
    Marginal,
}

/// One eigenvalue of (lambda \[M\] - \[K\]) X = 0 and its mode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mode {
    /// lambda [1/s]: the perturbation grows as e^(lambda t).
    pub eigenvalue: f64,
    /// 1/|lambda| \[s\], when lambda is not zero.
    pub time_constant: Option<f64>,
    /// X in the driving coordinates, scaled so that the largest link speed is 1.
    pub coordinates: Vec<f64>,
    /// V X: every link's speed in the mode (by link index).
    pub speeds: Vec<f64>,
}

/// A direction of the driving coordinates with no inertia.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MasslessDirection {
    /// The direction in the driving coordinates (largest link speed 1).
    pub coordinates: Vec<f64>,
    /// The link speeds along it (by link index).
    pub speeds: Vec<f64>,
    /// Links that move along it.
    pub links: Vec<LinkId>,
    /// The torque slope along it (eigenvalue of the massless block of \[K\]):
    /// negative, it is an attracting algebraic equilibrium; positive, any
    /// parasitic inertia makes it run away infinitely fast.
    pub slope: f64,
}

/// Eigenvalues, modes and the verdict.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stability {
    /// Eigenvalues, largest first.
    pub eigenvalues: Vec<f64>,
    /// Modes, in the order of `eigenvalues`.
    pub modes: Vec<Mode>,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in words.
    pub reason: String,
    /// The largest eigenvalue (positive: unstable, by how much).
    pub margin: f64,
    /// Eigenvalues with |lambda| below this count as zero.
    pub tolerance: f64,
    /// Directions without inertia, eliminated as algebraic equations.
    pub massless: Vec<MasslessDirection>,
    /// Largest fixed step for which RK4 is stable on this model
    /// ([`RK4_REAL_LIMIT`] / |most negative eigenvalue|).
    pub rk4_step_limit: Option<f64>,
    /// max |lambda| / min |lambda| over the non-zero eigenvalues.
    pub stiffness: Option<f64>,
    /// Largest relative residual ||K X - lambda M X|| of the modes.
    pub residual: f64,
}

/// What a stability analysis asks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StabilityRequest {
    /// Driving links; default: the spec's speeds, else chosen automatically.
    pub coordinates: Option<Vec<LinkId>>,
    /// Curves; default: the spec's `[analysis] curves`.
    pub curves: Option<Vec<Curve>>,
    /// Operating speeds (F links); default: the spec's speeds, else the equilibrium.
    pub speeds: Option<Vec<(LinkId, f64)>>,
}

/// Everything `egt stability` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StabilityReport {
    /// The reduced model.
    pub model: ReducedModel,
    /// The operating point.
    pub operating: OperatingPoint,
    /// Eigenvalues and the verdict.
    pub stability: Stability,
    /// Warnings gathered on the way.
    pub warnings: Vec<String>,
}

/// Symmetric eigen-decomposition of a small matrix, eigenvalues largest first.
fn sorted_eigen(a: DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let n = a.nrows();
    if n == 0 {
        return (Vec::new(), a);
    }
    let e = SymmetricEigen::new(a);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| e.eigenvalues[y].total_cmp(&e.eigenvalues[x]));
    let mut vecs = DMatrix::zeros(n, n);
    for (c, &i) in order.iter().enumerate() {
        vecs.set_column(c, &e.eigenvectors.column(i));
    }
    (order.iter().map(|&i| e.eigenvalues[i]).collect(), vecs)
}

impl Train {
    /// The operating point: every link's speed from `speeds` (F input speeds),
    /// else the equilibrium of the linearised curves; the reduced torque
    /// V^T T there, and the equilibrium.
    ///
    /// # Errors
    /// As [`Train::kinematics`]; without speeds, a singular \[K\] (no equilibrium).
    pub fn operating_point(
        &self,
        model: &ReducedModel,
        speeds: Option<&[(LinkId, f64)]>,
    ) -> Result<OperatingPoint> {
        let equilibrium = model.equilibrium();
        let (source, speed) = match speeds {
            Some(s) => (OperatingSource::Speeds, self.speeds_from(s)?),
            None => match &equilibrium {
                Ok((e, _)) => (OperatingSource::Equilibrium, e.clone()),
                Err(e) => {
                    return Err(AnalysisError::MissingData {
                        what: "operating speeds".into(),
                        analysis: format!("the operating point ({e})"),
                        hint: "give `[analysis] speeds`, one per degree of freedom".into(),
                    }
                    .into());
                }
            },
        };
        let torque = model.torques(&speed);
        let reduced_torque: Vec<f64> = model
            .velocity
            .tr_mul(&DVector::from_vec(torque.clone()))
            .iter()
            .copied()
            .collect();
        let scale = (0..model.coordinates.len())
            .map(|k| {
                (0..speed.len())
                    .map(|l| (model.velocity[(l, k)] * torque[l]).abs())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        let big = reduced_torque.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let residual = if scale > 0.0 { big / scale } else { 0.0 };
        let (equilibrium, equilibrium_condition) = match equilibrium {
            Ok((e, c)) => (Some(e), Some(c)),
            Err(_) => (None, None),
        };
        Ok(OperatingPoint {
            source,
            speed,
            torque,
            reduced_torque,
            residual,
            steady: residual <= STEADY_REL,
            equilibrium,
            equilibrium_condition,
        })
    }

    /// The whole stability analysis for a request (defaults from the spec).
    ///
    /// # Errors
    /// As [`Train::driving_coordinates`], [`Train::reduced_model`],
    /// [`Train::operating_point`] and [`ReducedModel::stability`].
    pub fn stability(&self, req: &StabilityRequest) -> Result<StabilityReport> {
        let (coords, source) = self.driving_coordinates(req.coordinates.as_deref())?;
        let curves = req
            .curves
            .clone()
            .unwrap_or_else(|| self.analysis().curves.clone());
        if curves.is_empty() {
            return Err(AnalysisError::MissingData {
                what: "a torque-speed curve".into(),
                analysis: "the stability analysis".into(),
                hint: "give [[analysis.curves]] with link, torque, slope and speed".into(),
            }
            .into());
        }
        let model = self.reduced_model_from(&coords, source, &curves)?;
        let spec_speeds: Vec<(LinkId, f64)> =
            self.analysis().speeds.iter().map(|s| (s.0, s.1)).collect();
        let speeds = match &req.speeds {
            Some(s) => Some(s.as_slice()),
            None if !spec_speeds.is_empty() => Some(spec_speeds.as_slice()),
            None => None,
        };
        let operating = self.operating_point(&model, speeds)?;
        let stability = model.stability()?;
        let mut warnings = model.warnings.clone();
        if stability.residual > MODE_RESIDUAL_WARN {
            warnings.push(format!(
                "the modes satisfy (lambda [M] - [K]) X = 0 only to {:.1e} relative: the inertias span too many decades for double precision to keep every mode's rate exact; the verdict (decided exactly) is not affected",
                stability.residual
            ));
        }
        if !operating.steady {
            let r: Vec<String> = operating
                .reduced_torque
                .iter()
                .map(|v| format!("{v:.4e}"))
                .collect();
            warnings.push(format!(
                "the operating point is not a steady state: V^T T = [{}] (relative {:.2e}) accelerates it; the eigenvalues describe deviations from the motion, which are independent of the point for linear curves",
                r.join(", "),
                operating.residual
            ));
        }
        if !stability.massless.is_empty() {
            warnings.push(format!(
                "{} massless direction(s) eliminated as algebraic torque balances (links {})",
                stability.massless.len(),
                stability
                    .massless
                    .iter()
                    .map(|m| self.names(&m.links))
                    .collect::<Vec<_>>()
                    .join("; ")
            ));
        }
        Ok(StabilityReport {
            model,
            operating,
            stability,
            warnings,
        })
    }
}

impl ReducedModel {
    /// Eigenvalues, modes and verdict of (lambda \[M\] - \[K\]) X = 0.
    ///
    /// Solved in the orthonormal basis N (the same eigenvalues: \[V\] = N N_S^-1
    /// is a congruence of the pencil), so the answer does not degrade when
    /// the driving links make \[Gamma_w\] ill-conditioned.
    ///
    /// # Errors
    /// No inertia at all; an indefinite \[M\]; a massless direction without a
    /// torque slope (its speed is undetermined).
    pub fn stability(&self) -> Result<Stability> {
        let f = self.dof();
        if self
            .basis_slope
            .iter()
            .any(|v| !v.is_finite() || v.abs() > OVERFLOW_GUARD)
        {
            return Err(AnalysisError::NonFinite {
                what: "the reduced slope matrix".into(),
                detail: "the torque slopes are too large to represent".into(),
            }
            .into());
        }
        let split = InertiaSplit::new(&self.basis_mass)?;
        let r = split.r;
        let kq = sym(&(split.q.transpose() * &self.basis_slope * &split.q));
        let k11 = kq.view((0, 0), (r, r)).into_owned();
        let k10 = kq.view((0, r), (r, f - r)).into_owned();
        let k00 = kq.view((r, r), (f - r, f - r)).into_owned();
        // Massless block: K00 = P diag(kappa) P^T must be regular.
        let (kappa, p) = sorted_eigen(k00);
        let kscale = self.basis_slope.amax();
        let mut massless = Vec::new();
        let q0 = split.q0();
        for (i, &kp) in kappa.iter().enumerate() {
            let dir: DVector<f64> = &q0 * p.column(i);
            let (speeds, coordinates) = self.normalised(self.basis_speeds(&dir));
            let links: Vec<LinkId> = speeds
                .iter()
                .enumerate()
                .filter(|(_, v)| v.abs() > 1e-9)
                .map(|(l, _)| LinkId::from_index(l))
                .collect();
            if kscale == 0.0 || kp.abs() <= MARGINAL_REL * kscale {
                let names: Vec<String> = links
                    .iter()
                    .map(|&l| format!("`{}`", self.link_names[l.index()]))
                    .collect();
                return Err(AnalysisError::Singular {
                    what: "the reduced model".into(),
                    detail: format!(
                        "a motion of links {} has neither inertia nor a torque slope, so its speed is undetermined; give one of them an inertia or a curve",
                        names.join(", ")
                    ),
                }
                .into());
            }
            massless.push(MasslessDirection {
                coordinates,
                speeds,
                links,
                slope: kp,
            });
        }
        // Schur complement: the massless coordinates z = -K00^-1 K01 y follow the others.
        let k00_inv =
            &p * DMatrix::from_diagonal(&DVector::from_iterator(
                f - r,
                kappa.iter().map(|k| 1.0 / k),
            )) * p.transpose();
        let ks = sym(&(&k11 - &k10 * &k00_inv * k10.transpose()));
        let d = DVector::from_iterator(r, split.mu.iter().map(|m| 1.0 / m.sqrt()));
        let a = sym(&DMatrix::from_fn(r, r, |i, j| d[i] * ks[(i, j)] * d[j]));
        if a.iter().any(|v| !v.is_finite()) {
            return Err(AnalysisError::NonFinite {
                what: "the scaled eigenproblem".into(),
                detail: "the torque slopes are too large for the inertias to represent".into(),
            }
            .into());
        }
        let (lambda, evec) = sorted_eigen(a.clone());
        let q1 = split.q1();
        let mut modes = Vec::with_capacity(r);
        let mut residual: f64 = 0.0;
        let (mm, kk) = (&self.basis_mass, &self.basis_slope);
        for (c, &lam) in lambda.iter().enumerate() {
            let y = DVector::from_iterator(r, (0..r).map(|i| d[i] * evec[(i, c)]));
            let z = -&k00_inv * k10.transpose() * &y;
            let u: DVector<f64> = &q1 * &y + &q0 * &z;
            let res = (kk * &u - mm * &u * lam).amax()
                / ((kk.amax() + mm.amax() * lam.abs()) * u.amax()).max(f64::MIN_POSITIVE);
            residual = residual.max(res);
            let (speeds, coordinates) = self.normalised(self.basis_speeds(&u));
            modes.push(Mode {
                eigenvalue: lam,
                time_constant: (lam != 0.0).then(|| 1.0 / lam.abs()),
                coordinates,
                speeds,
            });
        }
        let tolerance = a.norm() * EIGEN_RESOLUTION * r.max(1) as f64;
        let margin = lambda.first().copied().unwrap_or(f64::NEG_INFINITY);
        let runaway: Vec<&MasslessDirection> = massless.iter().filter(|m| m.slope > 0.0).collect();
        let (verdict, reason) = if !runaway.is_empty() {
            (
                Verdict::Unstable,
                format!(
                    "a massless direction has a rising torque (slope {} > 0): with any parasitic inertia it runs away infinitely fast",
                    num(runaway[0].slope)
                ),
            )
        } else if r == 0 {
            (
                Verdict::Stable,
                "every direction is massless with a falling torque: the train sits at the torque balance".into(),
            )
        } else if let Some(inertia) = self.slope_inertia {
            exact_verdict(inertia, margin, tolerance)
        } else if margin > tolerance {
            (
                Verdict::Unstable,
                format!(
                    "eigenvalue {} > 0: a perturbation grows as e^({} t)",
                    num(margin),
                    num(margin)
                ),
            )
        } else if margin < -tolerance {
            (
                Verdict::Stable,
                format!(
                    "every eigenvalue is negative (largest {}): perturbations decay at least as e^({} t)",
                    num(margin),
                    num(margin)
                ),
            )
        } else {
            (
                Verdict::Marginal,
                format!(
                    "the largest eigenvalue {margin:.3e} is zero within its resolution {tolerance:.1e} and its sign could not be decided exactly: perturbations along its mode may neither grow nor decay"
                ),
            )
        };
        let most_negative = lambda.last().copied().unwrap_or(0.0);
        let rk4_step_limit = (most_negative < -tolerance).then(|| RK4_REAL_LIMIT / -most_negative);
        let nonzero: Vec<f64> = lambda
            .iter()
            .map(|l| l.abs())
            .filter(|&l| l > tolerance)
            .collect();
        let stiffness = (!nonzero.is_empty()).then(|| {
            nonzero.iter().fold(0.0_f64, |m, &v| m.max(v))
                / nonzero.iter().fold(f64::INFINITY, |m, &v| m.min(v))
        });
        crate::error::finite_results("the eigenvalues", &lambda)?;
        Ok(Stability {
            eigenvalues: lambda,
            modes,
            verdict,
            reason,
            margin,
            tolerance,
            massless,
            rk4_step_limit,
            stiffness,
            residual,
        })
    }
}

/// The verdict from the exact signs of the eigenvalues (Sylvester's law of
/// inertia), with the computed largest eigenvalue for the words.
fn exact_verdict(inertia: exact::Inertia, margin: f64, tolerance: f64) -> (Verdict, String) {
    let resolved = margin.abs() > tolerance;
    let note = if resolved {
        String::new()
    } else {
        format!(
            " (the computed eigenvalue {} is below the double-precision resolution {tolerance:.1e} of the scaled problem; its sign is decided exactly from [K] by Sylvester's law of inertia)",
            num(margin)
        )
    };
    if inertia.positive > 0 {
        (
            Verdict::Unstable,
            format!(
                "{} eigenvalue(s) > 0 (largest {}): a perturbation grows as e^({} t){note}",
                inertia.positive,
                num(margin),
                num(margin)
            ),
        )
    } else if inertia.zero > 0 {
        (
            Verdict::Marginal,
            format!(
                "{} eigenvalue(s) are exactly zero ([K] is singular: a motion meets no torque slope): perturbations along it neither grow nor decay",
                inertia.zero
            ),
        )
    } else {
        (
            Verdict::Stable,
            format!(
                "every eigenvalue is negative (largest {}): perturbations decay at least as e^({} t){note}",
                num(margin),
                num(margin)
            ),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rk4_limit_is_the_real_stability_boundary() {
        let r = |z: f64| 1.0 + z + z * z / 2.0 + z * z * z / 6.0 + z.powi(4) / 24.0;
        assert!((r(-RK4_REAL_LIMIT) - 1.0).abs() < 1e-14);
        assert!(r(-RK4_REAL_LIMIT + 1e-6) < 1.0);
        assert!(r(-RK4_REAL_LIMIT - 1e-6) > 1.0);
    }

    #[test]
    fn inertia_split_separates_massless_and_rejects_indefinite() {
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let s = InertiaSplit::new(&m).expect("psd");
        assert_eq!(s.r, 1);
        assert!((s.mu[0] - 2.0).abs() < 1e-14);
        let q0 = s.q0();
        assert!((&m * &q0).amax() < 1e-14);
        let bad = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
        assert!(InertiaSplit::new(&bad).is_err());
        assert!(InertiaSplit::new(&DMatrix::zeros(2, 2)).is_err());
    }
}
