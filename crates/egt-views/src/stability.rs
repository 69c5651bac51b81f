//! The stability document (`egt stability --format json`): the reduced
//! matrices of eq. (19)-(27), the eigenvalues, modes and the verdict.

use egt_core::numerics::linalg::matrix_rows;
use egt_core::{LinkId, StabilityReport, Train};
use serde::Serialize;

#[derive(Debug, Serialize)]
pub struct LinkValue {
    pub link: String,
    pub value: f64,
}

#[derive(Debug, Serialize)]
pub struct ModeOut {
    pub eigenvalue: f64,
    pub time_constant: Option<f64>,
    /// The mode in the driving coordinates (largest link speed 1).
    pub coordinates: Vec<LinkValue>,
    /// Every link's speed in the mode.
    pub speeds: Vec<LinkValue>,
}

#[derive(Debug, Serialize)]
pub struct MasslessOut {
    pub links: Vec<String>,
    pub slope: f64,
    pub speeds: Vec<LinkValue>,
}

#[derive(Debug, Serialize)]
pub struct OperatingOut {
    pub source: egt_core::analysis::stability::OperatingSource,
    pub speeds: Vec<LinkValue>,
    pub torques: Vec<LinkValue>,
    /// V^T T per driving link: zero at a steady state.
    pub reduced_torque: Vec<LinkValue>,
    pub residual: f64,
    pub steady: bool,
    pub equilibrium: Option<Vec<LinkValue>>,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub source: String,
    pub name: Option<String>,
    pub dof: usize,
    pub coordinates: Vec<String>,
    pub coordinate_source: egt_core::CoordinateSource,
    pub gamma_condition: f64,
    pub orthogonality: f64,
    /// [V] (eq. 23): one row per link (the frame's is zero), one column per driving link.
    pub velocity: Vec<Vec<f64>>,
    pub links: Vec<String>,
    /// V^T M V (eq. 25).
    pub mass: Vec<Vec<f64>>,
    /// V^T diag(K) V (eq. 26-27).
    pub slope: Vec<Vec<f64>>,
    pub operating: OperatingOut,
    pub eigenvalues: Vec<f64>,
    pub modes: Vec<ModeOut>,
    pub massless: Vec<MasslessOut>,
    pub verdict: egt_core::Verdict,
    pub reason: String,
    pub margin: f64,
    pub tolerance: f64,
    pub rk4_step_limit: Option<f64>,
    pub stiffness: Option<f64>,
    pub eigen_residual: f64,
    pub warnings: Vec<String>,
}

fn values(train: &Train, v: &[f64], skip_frame: bool) -> Vec<LinkValue> {
    v.iter()
        .enumerate()
        .filter(|(l, _)| !(skip_frame && LinkId::from_index(*l) == train.frame()))
        .map(|(l, &value)| LinkValue {
            link: train.link_name(LinkId::from_index(l)).to_string(),
            value,
        })
        .collect()
}

pub fn build(train: &Train, source: &str, rep: &StabilityReport) -> Report {
    let m = &rep.model;
    let st = &rep.stability;
    let op = &rep.operating;
    let names: Vec<String> = m
        .coordinates
        .iter()
        .map(|&l| train.link_name(l).to_string())
        .collect();
    let per_coord = |v: &[f64]| -> Vec<LinkValue> {
        names
            .iter()
            .zip(v)
            .map(|(n, &value)| LinkValue {
                link: n.clone(),
                value,
            })
            .collect()
    };
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        dof: m.dof(),
        coordinates: names.clone(),
        coordinate_source: m.source,
        gamma_condition: m.gamma_condition,
        orthogonality: m.orthogonality,
        velocity: matrix_rows(&m.velocity),
        links: train.links().iter().map(|l| l.name.clone()).collect(),
        mass: matrix_rows(&m.mass),
        slope: matrix_rows(&m.slope),
        operating: OperatingOut {
            source: op.source,
            speeds: values(train, &op.speed, true),
            torques: values(train, &op.torque, true),
            reduced_torque: per_coord(&op.reduced_torque),
            residual: op.residual,
            steady: op.steady,
            equilibrium: op.equilibrium.as_ref().map(|e| values(train, e, true)),
        },
        eigenvalues: st.eigenvalues.clone(),
        modes: st
            .modes
            .iter()
            .map(|md| ModeOut {
                eigenvalue: md.eigenvalue,
                time_constant: md.time_constant,
                coordinates: per_coord(&md.coordinates),
                speeds: values(train, &md.speeds, true),
            })
            .collect(),
        massless: st
            .massless
            .iter()
            .map(|d| MasslessOut {
                links: d
                    .links
                    .iter()
                    .map(|&l| train.link_name(l).to_string())
                    .collect(),
                slope: d.slope,
                speeds: values(train, &d.speeds, true),
            })
            .collect(),
        verdict: st.verdict,
        reason: st.reason.clone(),
        margin: st.margin,
        tolerance: st.tolerance,
        rk4_step_limit: st.rk4_step_limit,
        stiffness: st.stiffness,
        eigen_residual: st.residual,
        warnings: rep.warnings.clone(),
    }
}
