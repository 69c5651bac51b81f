//! The modes document (`egt modes --format json`): the lumped torsional
//! model's coordinates and springs, and per mode its frequency,
//! multiplicity, mass-normalised shape and energy shares (docs/vibration.md).

use egt_core::analysis::modes::ElasticKind;
use egt_core::{NaturalModes, Train};
use serde::Serialize;

#[derive(Debug, Serialize)]
pub struct CoordinateOut {
    /// `link` or `link#c`.
    pub name: String,
    pub link: String,
    /// The planet copy, from 1 (None for a link without copies).
    pub copy: Option<u32>,
    /// A copy's angular position \[degrees\].
    pub angle: Option<f64>,
    /// Its entry of the diagonal \[M\] \[kg m^2\].
    pub inertia: f64,
}

#[derive(Debug, Serialize)]
pub struct SpringOut {
    pub name: String,
    pub kind: ElasticKind,
    /// N/m for a mesh, N m/rad otherwise.
    pub stiffness: f64,
    pub damping: f64,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub source: String,
    pub name: Option<String>,
    pub state: Option<String>,
    /// The rigid-body modes' count.
    pub dof: usize,
    pub coordinates: Vec<CoordinateOut>,
    pub springs: Vec<SpringOut>,
    /// Engaged elements held rigid.
    pub constraints: Vec<String>,
    /// The core's modes as they are (their fields are the document's).
    pub modes: Vec<egt_core::analysis::modes::NaturalMode>,
    /// Mesh orders and Campbell crossings (one rigid-body mode only).
    pub meshing: Option<MeshingOut>,
    /// The damped modes (complex eigenvalues), by rising |lambda|; empty
    /// without damping.
    pub damped: Vec<egt_core::analysis::modes::DampedMode>,
    /// The static deflection under a steady input torque (`--static`),
    /// beside the rigid model's eq. (11); absent unless asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_load: Option<StaticOut>,
}

#[derive(Debug, Serialize)]
pub struct ElementTorqueOut {
    pub name: String,
    /// The torque its first link spends on it \[N m\] (as `egt dynamics`).
    pub torque: f64,
}

#[derive(Debug, Serialize)]
pub struct StaticOut {
    /// The torque on the transmission input \[N m\].
    pub input_torque: f64,
    /// The output's reaction that balances it \[N m\].
    pub output_torque: f64,
    /// Per gear pair: eq. (11)'s mesh torque on gear i, the springs' (force
    /// times base radius, over the copies), one copy's force along the line
    /// of action \[N\] and deflection \[m\].
    pub meshes: Vec<egt_core::MeshCheck>,
    /// Every spring's deflection and force.
    pub springs: Vec<egt_core::SpringLoad>,
    /// The torques of the elements held rigidly.
    pub elements: Vec<ElementTorqueOut>,
}

/// The static part of the document: `check` under `input_torque` on the
/// transmission input, the output reacting.
pub fn statics(
    train: &Train,
    m: &NaturalModes,
    check: &egt_core::StaticCheck,
    input_torque: f64,
) -> StaticOut {
    let output = train.transmission().map(|t| t.output);
    StaticOut {
        input_torque,
        output_torque: output.map_or(0.0, |o| check.torque[o.index()]),
        meshes: check.meshes.clone(),
        springs: check.deflection.springs.clone(),
        elements: m
            .model
            .constraint_names
            .iter()
            .zip(&check.deflection.element_torques)
            .map(|(name, &torque)| ElementTorqueOut {
                name: name.clone(),
                torque,
            })
            .collect(),
    }
}

#[derive(Debug, Serialize)]
pub struct MeshingOut {
    pub input: String,
    /// Per gear pair: tooth passes per input revolution, and Hz per rpm.
    pub orders: Vec<egt_core::analysis::modes::MeshOrder>,
    /// Input speed range \[rpm\] of the crossings, when asked for.
    pub range: Option<[f64; 2]>,
    /// Input speeds \[rpm\] where a tooth-pass frequency meets a natural
    /// frequency; `mode` indexes `modes`.
    pub crossings: Vec<egt_core::analysis::modes::Crossing>,
}

pub fn build(train: &Train, source: &str, m: &NaturalModes) -> Report {
    let model = &m.model;
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        state: m.state.clone(),
        dof: m.dof,
        coordinates: model
            .coordinates
            .iter()
            .zip(&model.mass)
            .map(|(c, &inertia)| CoordinateOut {
                name: c.name.clone(),
                link: train.link_name(c.link).to_string(),
                copy: (train.link(c.link).copies > 1).then_some(c.copy + 1),
                angle: c.angle,
                inertia,
            })
            .collect(),
        springs: model
            .elastic
            .iter()
            .map(|e| SpringOut {
                name: e.name.clone(),
                kind: e.kind,
                stiffness: e.stiffness,
                damping: e.damping,
            })
            .collect(),
        constraints: model.constraint_names.clone(),
        modes: m.modes.clone(),
        meshing: m.meshing.as_ref().map(|x| MeshingOut {
            input: train.link_name(x.input).to_string(),
            orders: x.orders.clone(),
            range: x.range,
            crossings: x.crossings.clone(),
        }),
        damped: m.damped.clone(),
        static_load: None,
    }
}
