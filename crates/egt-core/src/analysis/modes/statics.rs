//! The static deflection of the torsional model under a steady load, and its
//! check against the rigid model: `K x = f` with the rigid elements as
//! constraints and the rigid-body motion held by gauge rows; each mesh's
//! force along its line of action is its stiffness times its deflection, and
//! under a balanced load those forces are eq. (11)'s meshing forces
//! (docs/vibration.md, "One model at two resolutions").

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use super::eigen::null_space;
use super::model::{ElasticKind, TorsionalModel};
use crate::analysis::dynamics::DynamicsRequest;
use crate::analysis::transmission::element_constraint;
use crate::error::{AnalysisError, Error, Result, TransmissionError};
use crate::model::train::Train;

/// The share of the load that may fall on the rigid-body motion (it would
/// accelerate the train) before the load is refused as unbalanced.
pub const BALANCE_TOLERANCE: f64 = 1e-9;

/// One spring of the model under the static load.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpringLoad {
    /// The spring's name, as in [`TorsionalModel::elastic`].
    pub name: String,
    /// Mesh, spring or element.
    pub kind: ElasticKind,
    /// Its deflection: along the line of action (m) for a mesh, a twist (rad)
    /// otherwise.
    pub deflection: f64,
    /// Stiffness times deflection: the force along the line of action (N)
    /// for a mesh, a torque (N m) otherwise.
    pub force: f64,
}

/// The compliant model's answer to a steady load.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticDeflection {
    /// The rotation of each coordinate (rad), with no rigid-body part.
    pub rotation: Vec<f64>,
    /// Each spring's deflection and force, in the model's order.
    pub springs: Vec<SpringLoad>,
    /// The torque each rigid element carries (N m), in the order of
    /// [`TorsionalModel::constraint_names`], signed as the rigid model's
    /// element multipliers (the torque its first link spends on it).
    pub element_torques: Vec<f64>,
}

/// One gear pair under the steady load, both models side by side.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshCheck {
    /// The gear pair.
    pub gear: String,
    /// The torque gear i spends on the mesh in the rigid model (eq. 11's
    /// `lambda_m psi_w[m, i]`), all planet copies together (N m).
    pub rigid_torque: f64,
    /// The same from the springs: force times base radius, summed over the
    /// copies (N m).
    pub compliant_torque: f64,
    /// The force along the line of action of one copy's mesh (N).
    pub force: f64,
    /// One copy's deflection along the line of action (m).
    pub deflection: f64,
}

/// The static check: the compliant model under the loads the rigid inverse
/// dynamics balanced, mesh by mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticCheck {
    /// The compliant model's deflection.
    pub deflection: StaticDeflection,
    /// The meshes, in gear-pair order.
    pub meshes: Vec<MeshCheck>,
    /// The torque on every link the load consists of, by link index (the
    /// request's torques and the solved driving torques).
    pub torque: Vec<f64>,
}

impl TorsionalModel {
    /// The static deflection under the generalised forces `f` (one per
    /// coordinate, N m): `K x + C^T mu = f`, `C x = 0`, with `x` free of
    /// rigid-body motion.
    ///
    /// # Errors
    /// [`Error::invalid`] (`torques`) when more than [`BALANCE_TOLERANCE`] of
    /// `f` drives a rigid-body mode (the train would accelerate);
    /// [`AnalysisError::Singular`] when the rigid elements are redundant.
    pub fn static_deflection(&self, f: &[f64]) -> Result<StaticDeflection> {
        let n = self.coordinates.len();
        let c = self.constraints.nrows();
        let springs = DMatrix::from_fn(self.elastic.len(), n, |r, k| self.elastic[r].row[k]);
        let mut stacked = springs.clone();
        stacked = stacked.resize_vertically(self.elastic.len() + c, 0.0);
        stacked
            .view_mut((self.elastic.len(), 0), (c, n))
            .copy_from(&self.constraints);
        let (rigid, _) = null_space(&stacked, n)?;
        let f = DVector::from_column_slice(f);
        let scale = f.amax().max(f64::MIN_POSITIVE);
        let drive = (rigid.transpose() * &f).amax();
        if drive > BALANCE_TOLERANCE * scale {
            return Err(Error::invalid(
                "torques",
                format!(
                    "the load is not balanced: {:.3e} of it drives the rigid-body motion, so the train would accelerate (balance it, e.g. by `Train::static_check`'s driving torques)",
                    drive / scale
                ),
            ));
        }
        // The bordered system, its constraint and gauge rows scaled to the
        // stiffness so that one pivoting LU sees one size of number.
        let k = self.stiffness();
        let s = k.diagonal().amax().max(1.0);
        let r = rigid.ncols();
        let size = n + c + r;
        let mut a = DMatrix::zeros(size, size);
        a.view_mut((0, 0), (n, n)).copy_from(&k);
        let cs = &self.constraints * s;
        let rs = rigid.transpose() * s;
        a.view_mut((n, 0), (c, n)).copy_from(&cs);
        a.view_mut((0, n), (n, c)).copy_from(&cs.transpose());
        a.view_mut((n + c, 0), (r, n)).copy_from(&rs);
        a.view_mut((0, n + c), (n, r)).copy_from(&rs.transpose());
        let mut b = DVector::zeros(size);
        b.rows_mut(0, n).copy_from(&f);
        let x = a.full_piv_lu().solve(&b).ok_or_else(|| {
            Error::from(AnalysisError::Singular {
                what: "the static deflection".into(),
                detail: format!(
                    "the rigid elements {:?} hold the same motion twice",
                    self.constraint_names
                ),
            })
        })?;
        let rotation: Vec<f64> = x.rows(0, n).iter().copied().collect();
        let springs = self
            .elastic
            .iter()
            .map(|e| {
                let deflection: f64 = e.row.iter().zip(&rotation).map(|(a, b)| a * b).sum();
                SpringLoad {
                    name: e.name.clone(),
                    kind: e.kind,
                    deflection,
                    force: e.stiffness * deflection,
                }
            })
            .collect();
        // K x = f - C^T mu: an element applies -mu to its first link, which
        // so spends mu on it (the rigid model's sign); mu was solved scaled by 1/s.
        let element_torques = x.rows(n, c).iter().map(|m| m * s).collect();
        Ok(StaticDeflection {
            rotation,
            springs,
            element_torques,
        })
    }
}

impl Train {
    /// The compliant model of gear state `state` (or the bare train) under
    /// the steady load of `req`: the rigid static inverse dynamics first
    /// (no acceleration; the driving torques balance the torques), then that
    /// whole load on the springs, mesh by mesh beside eq. (11).
    ///
    /// # Errors
    /// As [`Train::torsional_model`] and [`Train::inverse_dynamics`]; a
    /// request that prescribes accelerations (this is a steady state).
    pub fn static_check(&self, state: Option<&str>, req: &DynamicsRequest) -> Result<StaticCheck> {
        if !req.accelerations.is_empty() {
            return Err(Error::invalid(
                "accelerations",
                "the static check is a steady state: prescribe no acceleration",
            ));
        }
        let model = self.torsional_model(state)?;
        let mut rigid_req = req.clone();
        if let Some(state) = state {
            let t = self
                .transmission()
                .ok_or(Error::Transmission(TransmissionError::NoStates))?;
            let s = &t.states[crate::analysis::transmission::state_index(&t.states, state)?];
            rigid_req.extras.extend(
                s.engaged
                    .iter()
                    .map(|&e| element_constraint(&self.elements()[e.index()])),
            );
        }
        let rigid = self.inverse_dynamics(&rigid_req, None)?;
        let mut f = vec![0.0; model.coordinates.len()];
        for (k, c) in model.coordinates.iter().enumerate() {
            let copies = self.link(c.link).copies.max(1);
            f[k] = rigid.torque[c.link.index()] / f64::from(copies);
        }
        let deflection = model.static_deflection(&f)?;
        let meshes = self
            .gears()
            .iter()
            .zip(&rigid.meshes)
            .map(|(g, m)| {
                let own: Vec<(f64, &SpringLoad)> = model
                    .elastic
                    .iter()
                    .zip(&deflection.springs)
                    .filter_map(|(e, s)| match e.mesh {
                        Some((gear, rb)) if gear == m.gear => Some((rb, s)),
                        _ => None,
                    })
                    .collect();
                MeshCheck {
                    gear: g.name.clone(),
                    rigid_torque: m.torque_i,
                    compliant_torque: own.iter().map(|(rb, s)| s.force * rb).sum(),
                    force: own.first().map_or(0.0, |s| s.1.force),
                    deflection: own.first().map_or(0.0, |s| s.1.deflection),
                }
            })
            .collect();
        Ok(StaticCheck {
            deflection,
            meshes,
            torque: rigid.torque,
        })
    }

    /// [`Train::static_check`] in gear state `state` under `input_torque`
    /// (N m) on the transmission input, the output reacting it: what
    /// `egt modes --static` and Python's `Train.modes(static_torque=)` ask.
    ///
    /// # Errors
    /// A non-finite torque (`input_torque`); no `[transmission]`; as
    /// [`Train::static_check`].
    pub fn static_check_in_gear(&self, state: &str, input_torque: f64) -> Result<StaticCheck> {
        if !input_torque.is_finite() {
            return Err(Error::invalid(
                "input_torque",
                format!("the input torque must be finite, not {input_torque}"),
            ));
        }
        let t = self
            .transmission()
            .ok_or(Error::Transmission(TransmissionError::NoStates))?;
        let req = DynamicsRequest {
            torques: vec![(t.input, input_torque)],
            driving: vec![t.output],
            ..DynamicsRequest::default()
        };
        self.static_check(Some(state), &req)
    }
}
