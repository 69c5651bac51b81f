//! The shift-table document (`egt shift --format json`, `ShiftTable.to_dict()`):
//! every gear state's ratio, step, efficiency, speeds, slips, element and mesh
//! loads, then the spread and the elements swapped at each shift.

use egt_core::spec::ElementKind;
use egt_core::{Driver, Freewheel, GearAnalysis, ShiftKind, ShiftTable, Train};
use serde::Serialize;

use crate::format;

/// The whole report, by names.
#[derive(Debug, Serialize)]
pub struct Report {
    pub source: String,
    pub name: Option<String>,
    pub input: String,
    pub output: String,
    /// True when every gear ratio is exact (then every `*_exact` field is filled).
    pub exact: bool,
    pub elements: Vec<ElementDef>,
    pub gears: Vec<GearRow>,
    pub steps: Vec<StepRow>,
    pub spread: Option<SpreadRow>,
    pub shifts: Vec<ShiftRow>,
    pub warnings: Vec<String>,
}

#[derive(Debug, Serialize)]
pub struct ElementDef {
    pub name: String,
    pub kind: ElementKind,
    pub links: Vec<String>,
}

#[derive(Debug, Serialize)]
pub struct GearRow {
    pub state: String,
    pub engaged: Vec<String>,
    pub ratio: f64,
    pub ratio_exact: Option<String>,
    /// A forward gear: its ratio has the sign most states share.
    pub forward: bool,
    /// Every link's speed per unit input speed (`null` for a planet without teeth).
    pub speeds: Vec<SpeedRow>,
    /// Planets' speeds relative to their carriers.
    pub relative: Vec<RelativeRow>,
    /// Slip across every open element, per unit input speed.
    pub slips: Vec<SlipRow>,
    /// Torque delivered at the output per unit input torque (ideal meshes).
    pub output_torque: f64,
    /// Torque the housing applies through meshes with the frame.
    pub housing_torque: f64,
    /// Engaged elements: torque on the first link per unit input torque.
    pub elements: Vec<ElementRow>,
    pub largest_element: Option<ElementRow>,
    pub meshes: Vec<MeshRow>,
    pub efficiency: Option<f64>,
    pub output_torque_with_losses: Option<f64>,
    pub loss: Option<f64>,
    pub circulation_ratio: Option<f64>,
    pub circulating: Option<Circulating>,
    pub power_balance: f64,
    pub torque_balance: f64,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
}

#[derive(Debug, Serialize)]
pub struct SpeedRow {
    pub link: String,
    /// A shaft turning about the main axis (tree parent is the frame).
    pub shaft: bool,
    pub speed: Option<f64>,
    pub exact: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct RelativeRow {
    pub planet: String,
    pub carrier: String,
    pub speed: f64,
    pub exact: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct SlipRow {
    pub element: String,
    pub slip: f64,
    pub exact: Option<String>,
    /// One-way elements: `overruns`, `idle` or `locks`.
    pub freewheel: Option<Freewheel>,
}

#[derive(Debug, Clone, Serialize)]
pub struct ElementRow {
    pub element: String,
    pub torque: f64,
    /// One-way elements: whether the torque has the direction it can hold.
    pub holds: Option<bool>,
    pub parallel: bool,
}

#[derive(Debug, Serialize)]
pub struct MeshRow {
    pub gear_pair: String,
    pub gear_i: String,
    pub gear_j: String,
    pub carrier: String,
    pub torque_i: f64,
    pub torque_j: f64,
    pub torque_carrier: f64,
    /// Tangential forces on gear i and gear j (eq. 11), when radii are known.
    pub force: Option<[f64; 2]>,
    /// Power sent into the mesh by gear i, gear j and the carrier, with losses.
    pub power: Option<[f64; 3]>,
    pub rolling_power: Option<f64>,
    pub driver: Option<Driver>,
    pub efficiency: Option<f64>,
    pub loss: Option<f64>,
}

#[derive(Debug, Serialize)]
pub struct Circulating {
    pub gear_pairs: Vec<String>,
    pub links: Vec<String>,
}

#[derive(Debug, Serialize)]
pub struct StepRow {
    pub from: String,
    pub to: String,
    pub step: f64,
    pub exact: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct SpreadRow {
    pub lowest: String,
    pub highest: String,
    pub spread: f64,
    pub exact: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct ShiftRow {
    pub from: String,
    pub to: String,
    pub kind: ShiftKind,
    pub off: Vec<String>,
    pub on: Vec<String>,
    pub kept: Vec<String>,
    pub single_swap: bool,
}

fn exact_str(q: Option<&egt_core::numerics::exact::Q>) -> Option<String> {
    q.map(format::exact)
}

pub fn build(train: &Train, source: &str, table: &ShiftTable) -> Report {
    let name = |l: egt_core::LinkId| train.link_name(l).to_string();
    let element_name = |e: egt_core::ElementId| train.elements()[e.index()].name.clone();
    let state = |k: usize| table.gears[k].state.clone();
    let gears = table
        .gears
        .iter()
        .zip(&table.forward)
        .map(|(g, &forward)| gear_row(train, g, forward))
        .collect::<Vec<_>>();
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        input: name(table.input),
        output: name(table.output),
        exact: train.has_exact_ratios(),
        elements: train
            .elements()
            .iter()
            .map(|e| ElementDef {
                name: e.name.clone(),
                kind: e.kind,
                links: e.links.iter().map(|&l| name(l)).collect(),
            })
            .collect(),
        gears,
        steps: table
            .steps
            .iter()
            .map(|s| StepRow {
                from: state(s.from),
                to: state(s.to),
                step: s.value,
                exact: exact_str(s.exact.as_ref()),
            })
            .collect(),
        spread: table.spread.as_ref().map(|s| SpreadRow {
            lowest: state(s.lowest),
            highest: state(s.highest),
            spread: s.value,
            exact: exact_str(s.exact.as_ref()),
        }),
        shifts: table
            .shifts
            .iter()
            .map(|s| ShiftRow {
                from: state(s.from),
                to: state(s.to),
                kind: s.kind,
                off: s.off.iter().map(|&e| element_name(e)).collect(),
                on: s.on.iter().map(|&e| element_name(e)).collect(),
                kept: s.kept.iter().map(|&e| element_name(e)).collect(),
                single_swap: s.single_swap,
            })
            .collect(),
        warnings: table.warnings.clone(),
    }
}

pub fn gear_row(train: &Train, g: &GearAnalysis, forward: bool) -> GearRow {
    let name = |l: egt_core::LinkId| train.link_name(l).to_string();
    let element_name = |e: egt_core::ElementId| train.elements()[e.index()].name.clone();
    let shaft = |l: egt_core::LinkId| {
        l != train.frame()
            && train
                .tree()
                .parent(l)
                .is_some_and(|(p, _)| p == train.frame())
    };
    let elements: Vec<ElementRow> = g
        .elements
        .iter()
        .map(|e| ElementRow {
            element: element_name(e.element),
            torque: e.torque,
            holds: e.holds,
            parallel: e.parallel,
        })
        .collect();
    let largest_element = g
        .largest_element_torque()
        .and_then(|(e, _)| elements.iter().find(|r| r.element == element_name(e)))
        .cloned();
    let power = g.power.as_ref();
    GearRow {
        state: g.state.clone(),
        engaged: g.engaged.iter().map(|&e| element_name(e)).collect(),
        ratio: g.ratio,
        ratio_exact: exact_str(g.ratio_exact.as_ref()),
        forward,
        speeds: train
            .links_with_ids()
            .map(|(id, l)| SpeedRow {
                link: l.name.clone(),
                shaft: shaft(id),
                speed: g.speed[id.index()],
                exact: g
                    .speed_exact
                    .as_ref()
                    .and_then(|e| exact_str(e[id.index()].as_ref())),
            })
            .collect(),
        relative: g
            .relative
            .iter()
            .map(|r| RelativeRow {
                planet: name(r.link),
                carrier: name(r.carrier),
                speed: r.speed,
                exact: exact_str(r.exact.as_ref()),
            })
            .collect(),
        slips: g
            .slips
            .iter()
            .map(|s| SlipRow {
                element: element_name(s.element),
                slip: s.speed,
                exact: exact_str(s.exact.as_ref()),
                freewheel: s.freewheel,
            })
            .collect(),
        output_torque: g.output_torque,
        housing_torque: g.housing_torque,
        elements,
        largest_element,
        meshes: g
            .meshes
            .iter()
            .map(|m| {
                let c = &train.circuits()[m.gear.index()];
                let p = power.and_then(|p| p.meshes.get(m.gear.index()));
                MeshRow {
                    gear_pair: train.gears()[m.gear.index()].name.clone(),
                    gear_i: name(c.gear_i),
                    gear_j: name(c.gear_j),
                    carrier: name(c.carrier),
                    torque_i: m.torque_i,
                    torque_j: m.torque_j,
                    torque_carrier: m.torque_carrier,
                    force: m.force,
                    power: p.map(|p| p.absolute),
                    rolling_power: p.map(|p| p.rolling),
                    driver: p.map(|p| p.driver),
                    efficiency: p.map(|p| p.efficiency),
                    loss: p.map(|p| p.loss),
                }
            })
            .collect(),
        efficiency: power.map(|p| p.efficiency),
        output_torque_with_losses: power.map(|p| p.output_torque),
        loss: power.map(|p| p.loss),
        circulation_ratio: power.map(|p| p.circulation_ratio),
        circulating: power
            .and_then(|p| p.circulating.as_ref())
            .map(|(gs, ls)| Circulating {
                gear_pairs: gs
                    .iter()
                    .map(|g| train.gears()[g.index()].name.clone())
                    .collect(),
                links: ls.iter().map(|&l| name(l)).collect(),
            }),
        power_balance: g.power_balance,
        torque_balance: g.torque_balance,
        warnings: g.warnings.clone(),
        notes: g.notes.clone(),
    }
}
