//! Inverse dynamics (paper section 4, eq. 6-11) for any number of DOF.
//!
//! Equations of motion, eq. (6): \[M\]{w'} + [psi~_w]^T {lambda} = {Q}, with the
//! kinematic constraints \[psi_w\]{w'} = 0 (eq. 2 differentiated). The F
//! prescribed accelerations complete \[psi_w\] to the square \[Psi_w\] of eq. (8);
//! the F unknown driving torques join the multipliers in the transposed system
//! of eq. (10). [psi~_w] equals \[psi_w\] for ideal meshes; with mesh losses its
//! rows carry the efficiency (see `power.rs`).
//!
//! Constraint rows beyond the Willis equations (brakes holding a link, clutches
//! joining two) are supported, so gear states of a transmission use the same
//! solver; their multipliers are the element reaction torques.
//!
//! Sign convention: Q_l is the external torque applied to link l (positive
//! along positive rotation). (psi_w^T lambda)_l is the torque link l spends on
//! its constraints (eq. 7); the torque the frame or a held element applies to
//! the train is the corresponding sum over the frame's column.

use nalgebra::DMatrix;
use serde::Serialize;

use crate::error::{AnalysisError, Error, Result};
use crate::model::equations::willis_row;
use crate::model::mass::MassMatrix;
use crate::model::train::MAX_DENSE_BYTES;
use crate::model::train::{GearId, LinkId, Train};
use crate::numerics::linalg::COND_WARN;
use crate::solve::prepared::{Compute, PreparedTrain, Scenario, Workspace};
use crate::solve::rows::Extra;

/// What an inverse-dynamics (or static) analysis asks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DynamicsRequest {
    /// Known applied torques.
    pub torques: Vec<(LinkId, f64)>,
    /// Prescribed accelerations (F of them, or none for the static case).
    pub accelerations: Vec<(LinkId, f64)>,
    /// Links whose torque is unknown (F of them).
    pub driving: Vec<LinkId>,
    /// Brakes and clutches in force.
    pub extras: Vec<Extra>,
}

/// What a caller sets over the spec's `[analysis]` loads (the CLI's flags,
/// Python's keywords); `None` keeps the spec's value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadOverrides {
    /// Known applied torques.
    pub torques: Option<Vec<(LinkId, f64)>>,
    /// Prescribed accelerations.
    pub accelerations: Option<Vec<(LinkId, f64)>>,
    /// Links whose torque is unknown.
    pub driving: Option<Vec<LinkId>>,
    /// Brakes and clutches in force (the spec has none to default to).
    pub extras: Vec<Extra>,
}

impl DynamicsRequest {
    /// The request a caller's overrides and the spec's `[analysis]` section
    /// resolve to: each list from the override, else the spec. The one place
    /// those defaults are decided, for the CLI and Python alike.
    ///
    /// # Errors
    /// No driving links anywhere (for a train that moves).
    pub fn resolve(train: &Train, over: &LoadOverrides) -> Result<Self> {
        let spec = train.analysis();
        let pick = |o: &Option<Vec<(LinkId, f64)>>, s: &[(LinkId, f64)]| {
            o.clone().unwrap_or_else(|| s.to_vec())
        };
        let driving = over.driving.clone().unwrap_or_else(|| spec.driving.clone());
        if driving.is_empty() && train.dof() > 0 {
            return Err(AnalysisError::MissingData {
                what: format!(
                    "{} driving link(s) (whose torque is solved for)",
                    train.dof()
                ),
                analysis: "inverse dynamics".into(),
                hint: "name them in the request or give `[analysis] driving`".into(),
            }
            .into());
        }
        Ok(DynamicsRequest {
            torques: pick(&over.torques, &spec.torques),
            accelerations: pick(&over.accelerations, &spec.accelerations),
            driving,
            extras: over.extras.clone(),
        })
    }

    /// Whether the analysis needs the mass matrix: only when some prescribed
    /// acceleration is non-zero (a static analysis never demands inertia data).
    pub fn needs_mass(&self) -> bool {
        self.accelerations.iter().any(|a| a.1 != 0.0)
    }
}

/// The tangential meshing force and torques of one gear pair (eq. 11).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshLoad {
    /// The gear pair.
    pub gear: GearId,
    /// Its multiplier lambda_m.
    pub multiplier: f64,
    /// Torque gear i spends on the mesh, lambda_m psi_w[m, i].
    pub torque_i: f64,
    /// Torque gear j spends on the mesh, lambda_m psi_w[m, j].
    pub torque_j: f64,
    /// Torque the carrier spends on the mesh, lambda_m psi_w[m, k].
    pub torque_carrier: f64,
    /// F_im = torque_i / r_i and F_jm = torque_j / r_j (eq. 11), when radii are known.
    pub force: Option<[f64; 2]>,
}

/// Results of inverse dynamics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InverseDynamics {
    /// Angular acceleration of every link (by link index; frame 0).
    pub acceleration: Vec<f64>,
    /// Applied torque on every link, known and solved (by link index; the frame's
    /// entry is the torque the housing applies to hold it).
    pub torque: Vec<f64>,
    /// The solved driving torques, in request order.
    pub driving_torques: Vec<(LinkId, f64)>,
    /// Multipliers of the Willis rows then the extra rows.
    pub multipliers: Vec<f64>,
    /// Multipliers of the extra rows: the torque the first link of each brake or
    /// clutch spends on it (eq. 7). The element applies minus this to its first
    /// link (and, for a clutch, plus this to the second).
    pub element_torques: Vec<f64>,
    /// Per gear pair: multiplier, torques, tangential forces.
    pub meshes: Vec<MeshLoad>,
    /// Condition estimates of \[Psi_w\] (eq. 8) and of the force system (eq. 10).
    /// The first is 1.0 when eq. (8) was not factored: no acceleration was
    /// prescribed and no speed system with the same matrix was solved (a
    /// static analysis); a power flow, which solves the speeds, reports the
    /// estimate of that shared matrix instead.
    pub conditions: [f64; 2],
    /// The velocity-squared torques of a mass matrix that varies with the
    /// configuration ([`Train::velocity_torques`]), by link; zero otherwise.
    pub velocity_torque: Vec<f64>,
    /// Warnings.
    pub warnings: Vec<String>,
}

impl Train {
    /// The mass matrix when `req` needs it ([`DynamicsRequest::needs_mass`]),
    /// else `None`.
    ///
    /// # Errors
    /// Missing inertia data, named by field, when the mass matrix is needed.
    pub fn mass_for(&self, req: &DynamicsRequest) -> Result<Option<MassMatrix>> {
        if !req.needs_mass() {
            return Ok(None);
        }
        self.mass_matrix().map(Some)
    }

    /// The links whose accelerations a request prescribes: its
    /// `accelerations`, or the driving links for the static analysis.
    pub(crate) fn accelerated_links(req: &DynamicsRequest) -> Vec<LinkId> {
        if req.accelerations.is_empty() {
            req.driving.clone()
        } else {
            req.accelerations.iter().map(|a| a.0).collect()
        }
    }

    /// The prescribed accelerations in the order of [`Self::accelerated_links`]
    /// (zeros for the static analysis).
    ///
    /// # Errors
    /// [`AnalysisError::NonFinite`] for a non-finite acceleration.
    pub(crate) fn prescribed_accelerations(req: &DynamicsRequest) -> Result<Vec<f64>> {
        if req.accelerations.is_empty() {
            return Ok(vec![0.0; req.driving.len()]);
        }
        let alpha: Vec<f64> = req.accelerations.iter().map(|a| a.1).collect();
        if alpha.iter().any(|a| !a.is_finite()) {
            return Err(AnalysisError::NonFinite {
                what: "a prescribed acceleration".into(),
                detail: format!("{alpha:?}"),
            }
            .into());
        }
        Ok(alpha)
    }

    /// The generalized forces of eq. (6) per coordinate: the applied torques
    /// and, when [M] varies with the configuration, its velocity-squared
    /// torques (returned apart too) at `speeds` (by link), else at the spec's
    /// `[analysis] speeds`.
    ///
    /// # Errors
    /// A non-finite torque; speeds needed but not given.
    pub(crate) fn generalized_forces(
        &self,
        req: &DynamicsRequest,
        mass: Option<&MassMatrix>,
        speeds: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let n = self.coordinates().len();
        let mut q = vec![0.0; n];
        for &(l, t) in &req.torques {
            if !t.is_finite() {
                return Err(Error::spec(
                    format!("torque on `{}`", self.link_name(l)),
                    crate::SpecErrorKind::NonFinite { value: t },
                ));
            }
            if let Some(k) = self.coordinate(l) {
                q[k] += t;
            }
        }
        let velocity = match mass {
            Some(mm) if !mm.configuration.is_empty() => {
                let w = match speeds {
                    Some(w) => w.to_vec(),
                    None => self.analysis_speeds(&req.extras)?,
                };
                self.velocity_torques(mm, &w)
            }
            _ => vec![0.0; n],
        };
        for (qk, v) in q.iter_mut().zip(&velocity) {
            *qk += v;
        }
        Ok((q, velocity))
    }

    /// Solve inverse dynamics: accelerations, multipliers, driving torques,
    /// meshing forces (where pitch radii are known), the housing and element
    /// reactions. With no accelerations it is the static-force analysis. A
    /// front over the one prepared solver ([`PreparedTrain`]), which it
    /// prepares and solves once.
    ///
    /// `mass`: the mass matrix, or `None` for **no inertia at all** (every
    /// link massless: the torques balance the constraints and the applied
    /// loads only). [`Train::mass_for`] gives the train's own \[M\] exactly
    /// when the request accelerates something, which is what the CLI and
    /// Python do.
    ///
    /// # Errors
    /// Missing ratios or data for the mass matrix, wrong counts, singular or
    /// ill-conditioned systems.
    pub fn inverse_dynamics(
        &self,
        req: &DynamicsRequest,
        mass: Option<&MassMatrix>,
    ) -> Result<InverseDynamics> {
        let ratios = self.ratios()?;
        let accelerated = Self::accelerated_links(req);
        let plan = PreparedTrain::for_analysis(
            self,
            &accelerated,
            &accelerated,
            &req.driving,
            &req.extras,
        )?;
        let alpha = Self::prescribed_accelerations(req)?;
        let (q, velocity) = self.generalized_forces(req, mass, None)?;
        let mut ws = plan.workspace();
        let scenario = Scenario {
            ratios: &ratios,
            speeds: &vec![0.0; accelerated.len()],
            accelerations: &alpha,
            torques: &q,
            inertia: &[],
            mass: &[],
            efficiency: &vec![1.0; ratios.len()],
            mass_matrix: mass,
        };
        plan.solve(&mut ws, &scenario, Compute::Forces)?;
        let result = self.dynamics_result(req, mass, &plan, &ws, &velocity);
        crate::error::finite_results(
            "the inverse dynamics",
            result
                .torque
                .iter()
                .chain(&result.multipliers)
                .chain(&result.acceleration),
        )?;
        Ok(result)
    }

    /// The [`InverseDynamics`] of a solved workspace: per-link accelerations
    /// and torques, the housing torque, per-mesh loads and forces (eq. 11).
    pub(crate) fn dynamics_result(
        &self,
        req: &DynamicsRequest,
        mass: Option<&MassMatrix>,
        plan: &PreparedTrain,
        ws: &Workspace,
        velocity: &[f64],
    ) -> InverseDynamics {
        let nl = self.links().len();
        let mut acceleration = vec![0.0; nl];
        let mut velocity_torque = vec![0.0; nl];
        for (k, l) in self.coordinates().iter().enumerate() {
            acceleration[l.index()] = ws.accelerations()[k];
            velocity_torque[l.index()] = velocity[k];
        }
        let lambda = ws.multipliers(plan).to_vec();
        let mut torque = vec![0.0; nl];
        for &(l, t) in &req.torques {
            torque[l.index()] += t;
        }
        let driving_torques: Vec<(LinkId, f64)> = req
            .driving
            .iter()
            .zip(ws.driving_torques(plan))
            .map(|(&l, &t)| (l, t))
            .collect();
        for &(l, t) in &driving_torques {
            torque[l.index()] += t;
        }
        // The frame: the torque the housing applies = the frame's column of psi~^T lambda.
        let jg = self.circuits().len();
        let mut meshes = Vec::with_capacity(jg);
        for (m, (c, g)) in self.circuits().iter().zip(self.gears()).enumerate() {
            let lam = lambda[m];
            let [ti, tj, tk] = willis_row(ws.force_ratios()[m]).map(|v| v * lam);
            for (l, v) in [(c.gear_i, ti), (c.gear_j, tj), (c.carrier, tk)] {
                if l == self.frame() {
                    torque[l.index()] += v;
                }
            }
            let force = g.radii.map(|[ri, rj]| [ti / ri, tj / rj]);
            meshes.push(MeshLoad {
                gear: GearId::from_index(m),
                multiplier: lam,
                torque_i: ti,
                torque_j: tj,
                torque_carrier: tk,
                force,
            });
        }
        let element_torques = lambda[jg..].to_vec();
        let [_, psi, force] = ws.conditions();
        let conditions = [psi, force];
        let mut warnings = Vec::new();
        for (c, what) in conditions.iter().zip(["[Psi_w]", "the force system"]) {
            if *c > COND_WARN {
                warnings.push(format!("{what} is ill-conditioned (condition {c:.2e})"));
            }
        }
        if let Some(mm) = mass {
            warnings.extend(mm.notes.iter().cloned());
        }
        InverseDynamics {
            acceleration,
            torque,
            driving_torques,
            multipliers: lambda,
            element_torques,
            meshes,
            conditions,
            velocity_torque,
            warnings,
        }
    }

    /// \[V\] of eq. (23): the speeds of every coordinate per unit speed of each
    /// input (columns), from the Willis equations and any extra constraints.
    ///
    /// # Errors
    /// As the kinematic solve: wrong count, free links, ill-conditioning.
    pub fn velocity_matrix(&self, inputs: &[LinkId], extras: &[Extra]) -> Result<DMatrix<f64>> {
        Ok(self.velocity_matrix_cond(inputs, extras)?.0)
    }

    /// [`Train::velocity_matrix`] with the condition estimate of [Gamma_w].
    pub(crate) fn velocity_matrix_cond(
        &self,
        inputs: &[LinkId],
        extras: &[Extra],
    ) -> Result<(DMatrix<f64>, f64)> {
        let n = self.coordinates().len();
        // One dense column of n speeds per input.
        let bytes = n.saturating_mul(inputs.len()).saturating_mul(8);
        if bytes > MAX_DENSE_BYTES {
            return Err(AnalysisError::TooLarge {
                analysis: format!("[V] (eq. 23), one column per input ({})", inputs.len()),
                links: self.links().len(),
                mib: bytes >> 20,
                limit_mib: MAX_DENSE_BYTES >> 20,
                most: MAX_DENSE_BYTES / (8 * inputs.len().max(1)) + 1,
                what: "the kinematics and inverse dynamics take it".into(),
            }
            .into());
        }
        let ratios = self.ratios()?;
        let plan = PreparedTrain::for_analysis(self, inputs, inputs, inputs, extras)?;
        plan.velocity_columns(
            &ratios,
            "[Gamma_w] (eq. 23)",
            "the chosen inputs do not determine the train",
        )
    }

    /// The reduced mass matrix V^T M V (eq. 25) for the given independent inputs;
    /// for one DOF, the equivalent inertia reduced to that link.
    ///
    /// # Errors
    /// As [`Train::velocity_matrix`] and [`Train::mass_matrix`].
    pub fn reduced_mass_matrix(&self, inputs: &[LinkId], extras: &[Extra]) -> Result<DMatrix<f64>> {
        let v = self.velocity_matrix(inputs, extras)?;
        let m = self.mass_matrix()?;
        // V^T M V over M's non-zeros: linear in the links for a given DOF.
        let f = v.ncols();
        let mut r = DMatrix::zeros(f, f);
        for &(a, b, x) in m.entries() {
            for i in 0..f {
                let vai = v[(a, i)] * x;
                for j in 0..f {
                    r[(i, j)] += vai * v[(b, j)];
                }
            }
        }
        Ok(r)
    }

    /// Equivalent inertia of a 1-DOF train reduced to `link`: 2K / w_link^2.
    ///
    /// # Errors
    /// When the train does not have one DOF, or as [`Train::reduced_mass_matrix`].
    pub fn equivalent_inertia(&self, link: LinkId) -> Result<f64> {
        if self.dof() != 1 {
            return Err(AnalysisError::WrongInputCount {
                dof: self.dof(),
                given: 1,
                what: "links to reduce to (use the reduced mass matrix for several DOF)".into(),
            }
            .into());
        }
        Ok(self.reduced_mass_matrix(&[link], &[])?[(0, 0)])
    }
}

impl Train {
    /// Every link's speed at the spec's `[analysis] speeds`, under `extras`.
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] when the spec gives no speeds; the kinematics' errors.
    pub(crate) fn analysis_speeds(&self, extras: &[Extra]) -> Result<Vec<f64>> {
        let inputs: Vec<crate::solve::kinematics::SpeedInput> = self
            .analysis()
            .speeds
            .iter()
            .map(|&(link, speed, _)| crate::solve::kinematics::SpeedInput {
                link,
                speed,
                exact: None,
            })
            .collect();
        if inputs.is_empty() {
            return Err(AnalysisError::MissingData {
                what: "the link speeds".into(),
                analysis: "the velocity-squared torques of a mass matrix that varies with the carrier angles".into(),
                hint: "give [analysis] speeds".into(),
            }
            .into());
        }
        Ok(if extras.is_empty() {
            self.kinematics(&inputs)?.speed
        } else {
            self.constrained_speeds(&inputs, extras)?.speed
        })
    }
}
