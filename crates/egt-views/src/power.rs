//! The power-flow document (`egt power --format json`): power per link and
//! per mesh, losses, efficiency and circulating power.

use egt_core::analysis::power::{Driver, PowerFlow, PowerTotals};
use egt_core::{LinkId, Train};
use serde::Serialize;

#[derive(Debug, Serialize)]
pub struct LinkRow {
    pub name: String,
    pub speed: f64,
    pub torque: f64,
    pub external_power: f64,
    pub inertial_power: f64,
}

#[derive(Debug, Serialize)]
pub struct MeshRow {
    pub pair: String,
    pub carrier: String,
    /// Power sent into the mesh by gear i, gear j and the carrier (absolute frame).
    pub absolute: [f64; 3],
    /// Rolling power in the carrier's frame.
    pub rolling: f64,
    pub driver: Option<String>,
    pub efficiency: f64,
    pub loss: f64,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub source: String,
    pub name: Option<String>,
    pub losses: bool,
    pub links: Vec<LinkRow>,
    pub meshes: Vec<MeshRow>,
    /// The core's totals, field by field.
    #[serde(flatten)]
    pub totals: PowerTotals,
    pub circulating_meshes: Vec<String>,
    pub circulating_shafts: Vec<String>,
    pub warnings: Vec<String>,
}

pub fn build(train: &Train, source: &str, pf: &PowerFlow, losses: bool) -> Report {
    let name = |l: LinkId| train.link_name(l).to_string();
    let links = pf
        .links
        .iter()
        .map(|l| LinkRow {
            name: name(l.link),
            speed: pf.speeds.speed[l.link.index()],
            torque: pf.dynamics.torque[l.link.index()],
            external_power: l.external,
            inertial_power: l.inertial,
        })
        .collect();
    let meshes = pf
        .meshes
        .iter()
        .map(|m| {
            let c = &train.circuits()[m.gear.index()];
            MeshRow {
                pair: train.gears()[m.gear.index()].name.clone(),
                carrier: name(c.carrier),
                absolute: m.absolute,
                rolling: m.rolling,
                driver: match m.driver {
                    Driver::GearI => Some(name(c.gear_i)),
                    Driver::GearJ => Some(name(c.gear_j)),
                    Driver::None => None,
                },
                efficiency: m.efficiency,
                loss: m.loss,
            }
        })
        .collect();
    let (cm, cs) = pf.circulating.clone().unwrap_or_default();
    let mut warnings = pf.notes.clone();
    warnings.extend(pf.dynamics.warnings.iter().cloned());
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        losses,
        links,
        meshes,
        totals: pf.totals,
        circulating_meshes: cm
            .iter()
            .map(|g| train.gears()[g.index()].name.clone())
            .collect(),
        circulating_shafts: cs.iter().map(|&l| name(l)).collect(),
        warnings,
    }
}
