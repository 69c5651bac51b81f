//! Kinematics by the Willis equations (paper section 3, eq. 2):
//! psi_m = w_i - tau_m w_j + (tau_m - 1) w_k = 0 for every fundamental circuit m.
//!
//! [`Train::kinematics`] solves one scenario in floating point through the
//! one float solver, [`PreparedTrain`] (the Willis rows completed by the
//! input rows, dense or sparse by size); adds the exact rational solution
//! when every ratio is exact; and diagnoses singular inputs exactly (which
//! links are free, which equations conflict). Many scenarios: prepare a
//! [`PreparedTrain`] once and solve [`Compute::Kinematics`] per scenario.

use nalgebra::DMatrix;
use num_traits::Zero;
use serde::Serialize;

use crate::error::{AnalysisError, Error, Result};
use crate::model::equations::{self, willis_row};
use crate::model::train::{LinkId, Train};
use crate::numerics::exact::{self, Q, QMatrix};
use crate::numerics::linalg::COND_WARN;
use crate::solve::prepared::{Compute, PreparedTrain, Scenario, Workspace};

/// One prescribed input speed.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedInput {
    /// The link.
    pub link: LinkId,
    /// Its speed.
    pub speed: f64,
    /// The exact speed, when known (for the exact solution).
    pub exact: Option<Q>,
}

impl From<(LinkId, f64)> for SpeedInput {
    fn from((link, speed): (LinkId, f64)) -> Self {
        SpeedInput {
            link,
            speed,
            exact: exact::from_f64(speed),
        }
    }
}

/// A planet's (or any floating link's) speed relative to the link carrying it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RelativeSpeed {
    /// The floating link.
    pub link: LinkId,
    /// The carrier (its parent in the turning-pair tree).
    pub carrier: LinkId,
    /// w_link - w_carrier.
    pub speed: f64,
    /// Exact value, when known (serialized as text).
    #[serde(serialize_with = "exact::text::option")]
    pub exact: Option<Q>,
}

/// The speeds of all links for one set of inputs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Speeds {
    /// Absolute angular speed of every link (indexed by `LinkId::index()`; the frame is 0).
    pub speed: Vec<f64>,
    /// False where the speed is unknown (a planet given without a tooth count).
    pub known: Vec<bool>,
    /// Exact speeds, when every ratio and input is exact (serialized as text).
    #[serde(serialize_with = "exact::text::option_vec")]
    pub exact: Option<Vec<Q>>,
    /// Speeds of floating links relative to their carriers.
    pub relative: Vec<RelativeSpeed>,
    /// Largest Willis residual |psi_m| relative to the largest speed.
    pub residual: f64,
    /// 1-norm condition estimate of the solved system.
    pub condition: f64,
    /// Warnings (e.g. ill-conditioning below the refusal threshold).
    pub warnings: Vec<String>,
}

fn unsized_error(train: &Train, l: LinkId) -> Error {
    AnalysisError::MissingData {
        what: format!("the tooth count of planet `{}`", train.link_name(l)),
        analysis: "its speed".into(),
        hint: "give `teeth.planet` in its planetary set".into(),
    }
    .into()
}

/// The prepared solver's refusal of the speed system, named as the
/// single-scenario kinematics has always named it.
fn willis_named(e: Error) -> Error {
    match e {
        Error::Analysis(AnalysisError::Singular { detail, .. }) => AnalysisError::Singular {
            what: "the Willis system".into(),
            detail,
        }
        .into(),
        Error::Analysis(AnalysisError::IllConditioned {
            condition,
            threshold,
            ..
        }) => AnalysisError::IllConditioned {
            what: "the Willis system".into(),
            condition,
            threshold,
        }
        .into(),
        e => e,
    }
}

/// Largest |psi_m| over the circuits, relative to the largest |w| (eq. 2 residual).
pub fn willis_residual(train: &Train, ratios: &[f64], speeds: &[f64]) -> f64 {
    let scale = speeds
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    train
        .circuits()
        .iter()
        .zip(ratios)
        .map(|(c, &t)| {
            equations::willis_residual(
                t,
                [c.gear_i, c.gear_j, c.carrier].map(|l| speeds[l.index()]),
            )
            .abs()
        })
        .fold(0.0, f64::max)
        / scale
}

impl Train {
    /// The Willis Jacobian \[psi_w\] (j_G x (l - 1)): rows are circuits, columns the
    /// coordinates (every link but the frame, in link order).
    ///
    /// # Errors
    /// Missing ratio.
    pub fn willis_jacobian(&self) -> Result<DMatrix<f64>> {
        self.require_dense("the Willis Jacobian")?;
        let ratios = self.ratios()?;
        let mut j = DMatrix::zeros(self.circuits().len(), self.coordinates().len());
        for (m, (c, &t)) in self.circuits().iter().zip(&ratios).enumerate() {
            for (l, v) in [c.gear_i, c.gear_j, c.carrier]
                .into_iter()
                .zip(willis_row(t))
            {
                if let Some(k) = self.coordinate(l) {
                    j[(m, k)] += v;
                }
            }
        }
        Ok(j)
    }

    /// The exact Willis Jacobian, when every ratio is exact (and the train is
    /// within [`MAX_DENSE_BYTES`](crate::model::train::MAX_DENSE_BYTES)).
    pub fn willis_jacobian_exact(&self) -> Option<QMatrix> {
        self.require_dense("the exact Willis Jacobian").ok()?;
        let taus: Vec<Q> = self
            .gears()
            .iter()
            .map(|g| g.ratio.as_ref()?.exact.clone())
            .collect::<Option<_>>()?;
        Some(crate::model::topology::willis_exact(
            self.links().len(),
            self.frame(),
            self.circuits(),
            |m| taus[m].clone(),
        ))
    }

    /// Solve the speeds of every link for the given input speeds (one per DOF).
    /// When every ratio and input is exact, `exact` holds the rational solution.
    ///
    /// # Errors
    /// Missing ratios; wrong input count; [`AnalysisError::Underdetermined`] /
    /// [`AnalysisError::Inconsistent`] naming the free links or conflicting
    /// circuits when the inputs do not determine the train;
    /// [`AnalysisError::IllConditioned`] when nearly singular.
    pub fn kinematics(&self, inputs: &[SpeedInput]) -> Result<Speeds> {
        let links: Vec<LinkId> = inputs.iter().map(|i| i.link).collect();
        self.ratios()?;
        self.check_speed_inputs(&links)?;
        let plan = PreparedTrain::for_analysis(self, &links, &links, &links, &[])?;
        let mut ws = plan.workspace();
        self.kinematics_on(&plan, &mut ws, inputs)
    }

    /// Input links for a speed solve: one per DOF, distinct, not the frame,
    /// each of known speed (a planet needs its tooth count).
    pub(crate) fn check_speed_inputs(&self, links: &[LinkId]) -> Result<()> {
        if links.len() != self.dof() {
            return Err(AnalysisError::WrongInputCount {
                dof: self.dof(),
                given: links.len(),
                what: "input speeds".into(),
            }
            .into());
        }
        for (k, &l) in links.iter().enumerate() {
            if l == self.frame() {
                return Err(AnalysisError::FrameInput {
                    link: self.link_name(l).to_string(),
                }
                .into());
            }
            if links[..k].contains(&l) {
                return Err(AnalysisError::RepeatedLink {
                    link: self.link_name(l).to_string(),
                    role: "input links".into(),
                }
                .into());
            }
            if !self.link(l).sized {
                return Err(unsized_error(self, l));
            }
        }
        Ok(())
    }

    /// [`Train::kinematics`] with a prepared train whose input links are
    /// those of `inputs`, in order, and a workspace of it: power flow solves
    /// its speeds here and its forces in the same workspace, so the speed
    /// system is factored once.
    ///
    /// # Errors
    /// As [`Train::kinematics`].
    pub(crate) fn kinematics_on(
        &self,
        plan: &PreparedTrain,
        ws: &mut Workspace,
        inputs: &[SpeedInput],
    ) -> Result<Speeds> {
        let ratios = self.ratios()?;
        let links: Vec<LinkId> = inputs.iter().map(|i| i.link).collect();
        self.check_speed_inputs(&links)?;
        let values: Vec<f64> = inputs.iter().map(|i| i.speed).collect();
        for (k, v) in values.iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::spec(
                    format!("input speed of `{}`", self.link_name(links[k])),
                    crate::SpecErrorKind::NonFinite { value: *v },
                ));
            }
        }
        let solved = plan
            .solve(
                ws,
                &Scenario::kinematic(&ratios, &values),
                Compute::Kinematics,
            )
            .map_err(willis_named);
        let mut speed = vec![0.0; self.links().len()];
        for (&l, &w) in self.coordinates().iter().zip(ws.speeds()) {
            speed[l.index()] = w;
        }
        let exact_inputs: Option<Vec<Q>> = inputs.iter().map(|i| i.exact.clone()).collect();
        let exact_taus: Option<Vec<Q>> = self
            .gears()
            .iter()
            .map(|g| g.ratio.as_ref()?.exact.clone())
            .collect();
        // The exact solve and the exact diagnosis eliminate densely over the
        // rationals: only for trains within the dense limit.
        let exact_fits = self.require_dense("the exact kinematics");
        let condition = match solved {
            Ok(()) => ws.conditions()[0],
            Err(e) if exact_fits.is_err() => return Err(e),
            Err(e) => {
                // Diagnose exactly, on the exact ratios or on the exact values of the floats.
                let taus: Vec<Q> = match &exact_taus {
                    Some(t) => t.clone(),
                    None => ratios
                        .iter()
                        .map(|&r| exact::from_f64(r).unwrap_or_else(Q::zero))
                        .collect(),
                };
                let ins: Vec<Q> = values
                    .iter()
                    .map(|&v| exact::from_f64(v).unwrap_or_else(Q::zero))
                    .collect();
                self.solve_exact(&links, &taus, &ins)?;
                // Exactly regular but singular in floating point: name what is
                // nearly dependent by diagnosing the simplest fractions within
                // 1e-12 of the ratios (0.3333333333333333 is 1/3 meant).
                let simple: Vec<Q> = ratios
                    .iter()
                    .map(|&r| exact::simplest_near(r, 1e-12))
                    .collect();
                let zero_pivot = matches!(e, Error::Analysis(AnalysisError::Singular { .. }));
                if zero_pivot && let Err(near) = self.solve_exact(&links, &simple, &ins) {
                    return Err(AnalysisError::Singular {
                        what: "the Willis system".into(),
                        detail: format!("it is singular to round-off (with the ratios as the simplest fractions within 1e-12: {near})"),
                    }
                    .into());
                }
                return Err(e);
            }
        };
        let mut warnings = Vec::new();
        if condition > COND_WARN {
            warnings.push(format!("the Willis system is ill-conditioned (condition {condition:.2e}); expect about {:.0} correct digits", (16.0 - condition.log10()).max(0.0)));
        }
        let exact = match (exact_taus, exact_inputs, exact_fits) {
            (Some(t), Some(i), Ok(())) => Some(self.solve_exact(&links, &t, &i)?),
            (Some(_), Some(_), Err(_)) => {
                warnings.push(format!(
                    "no exact speeds: exact rationals are solved for trains of at most {} links, this one has {} (the float speeds stand, checked by their Willis residual)",
                    crate::model::train::most_dense_links(),
                    self.links().len()
                ));
                None
            }
            _ => None,
        };
        if let Some(e) = &exact {
            // The exact solution, correctly rounded, is the best float answer.
            debug_assert!(
                e.iter().zip(&speed).all(
                    |(q, f)| (exact::to_f64(q) - f).abs() <= 1e-9 * (1.0 + f.abs()) * condition
                )
            );
            for (f, q) in speed.iter_mut().zip(e) {
                *f = exact::to_f64(q);
            }
        }
        let known: Vec<bool> = self.links().iter().map(|l| l.sized).collect();
        // Speeds below the smallest normal double lose digits (subnormal) or
        // become 0: say so rather than print them as if exact.
        let underflowed: Vec<&str> = speed
            .iter()
            .enumerate()
            .filter(|&(i, w)| {
                let lost = exact.as_ref().is_some_and(|e| !e[i].is_zero());
                (*w != 0.0 && w.abs() < f64::MIN_POSITIVE) || (*w == 0.0 && lost)
            })
            .map(|(i, _)| self.link_name(LinkId::from_index(i)))
            .collect();
        if let Some(first) = underflowed.first() {
            warnings.push(format!(
                "the speeds of {} link(s), from `{first}`, are below 2.2e-308 in magnitude, where double precision keeps fewer digits; a speed smaller still prints as 0{}",
                underflowed.len(),
                if exact.is_some() { " (the exact speeds are right)" } else { "" }
            ));
        }
        let relative = self.relative_speeds(&speed, exact.as_deref(), &known);
        let residual = willis_residual(self, &ratios, &speed);
        crate::error::finite_results("the speeds", &speed)?;
        Ok(Speeds {
            speed,
            known,
            exact,
            relative,
            residual,
            condition,
            warnings,
        })
    }

    /// The exact speeds of every link: the Willis equations over the
    /// rationals with the speeds of `links` given as `inputs` (their
    /// elimination names the free links or the conflicting circuits).
    fn solve_exact(&self, links: &[LinkId], taus: &[Q], inputs: &[Q]) -> Result<Vec<Q>> {
        // Each link's place: a given speed (its input index), an unknown
        // (its column), or the frame (None in both).
        let mut given: Vec<Option<usize>> = vec![None; self.links().len()];
        for (k, &l) in links.iter().enumerate() {
            given[l.index()] = Some(k);
        }
        let unknowns: Vec<LinkId> = self
            .coordinates()
            .iter()
            .copied()
            .filter(|l| given[l.index()].is_none())
            .collect();
        let mut column: Vec<Option<usize>> = vec![None; self.links().len()];
        for (u, &l) in unknowns.iter().enumerate() {
            column[l.index()] = Some(u);
        }
        let n = unknowns.len();
        let mut a: QMatrix = vec![vec![Q::zero(); n]; self.circuits().len()];
        let mut b: Vec<Q> = vec![Q::zero(); self.circuits().len()];
        for (m, (c, tau)) in self.circuits().iter().zip(taus).enumerate() {
            let coefs = [exact::q(1), -tau.clone(), tau - exact::q(1)];
            for (l, coef) in [c.gear_i, c.gear_j, c.carrier].into_iter().zip(coefs) {
                if let Some(k) = given[l.index()] {
                    b[m] -= coef * &inputs[k];
                } else if let Some(u) = column[l.index()] {
                    a[m][u] += coef;
                }
            }
        }
        match exact::solve(&a, &b) {
            Ok(x) => {
                let mut out = vec![Q::zero(); self.links().len()];
                for (k, &l) in links.iter().enumerate() {
                    out[l.index()] = inputs[k].clone();
                }
                for (u, &l) in unknowns.iter().enumerate() {
                    out[l.index()] = x[u].clone();
                }
                Ok(out)
            }
            Err(f) if !f.conflicting_rows.is_empty() => Err(AnalysisError::Inconsistent {
                conflicting: f
                    .conflicting_rows
                    .iter()
                    .map(|&m| format!("circuit #{} (gear pair {})", m + 1, self.gears()[m].name))
                    .collect(),
            }
            .into()),
            Err(f) => Err(AnalysisError::Underdetermined {
                free: f
                    .free_columns
                    .iter()
                    .map(|&u| self.link_name(unknowns[u]).to_string())
                    .collect(),
            }
            .into()),
        }
    }

    /// Speeds of floating links relative to their carriers: every link whose
    /// turning pair to its tree parent (not the frame) is at another level than
    /// the parent's own axis.
    pub(crate) fn relative_speeds(
        &self,
        speed: &[f64],
        exact: Option<&[Q]>,
        known: &[bool],
    ) -> Vec<RelativeSpeed> {
        let mut out = Vec::new();
        for &l in self.tree().order() {
            let Some((p, r)) = self.tree().parent(l) else {
                continue;
            };
            let Some((_, rp)) = self.tree().parent(p) else {
                continue;
            };
            if self.revolutes()[r.index()].level == self.revolutes()[rp.index()].level
                || !known[l.index()]
            {
                continue;
            }
            out.push(RelativeSpeed {
                link: l,
                carrier: p,
                speed: speed[l.index()] - speed[p.index()],
                exact: exact.map(|e| &e[l.index()] - &e[p.index()]),
            });
        }
        out
    }
}
