//! `egt shift SPEC`: the gear table of an automatic transmission. For every
//! gear state: engaged elements, the ratio input/output (exact and float), the
//! step to the next forward gear, the efficiency with the meshes' basic
//! efficiencies and the most loaded element; then the spread and the elements
//! swapped at each shift. `--state NAME` adds one state's details (speeds,
//! slips, element torques, meshes); `--format json` gives everything for every
//! state; `--plot FILE.svg` draws the speed chart and the element torques.

mod chart;

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use egt_core::spec::ElementKind;
use egt_core::{Driver, Freewheel, GearAnalysis, ShiftKind, ShiftTable, Train};
use serde::Serialize;

use crate::cli::{OutputFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};

/// Arguments of `egt shift`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
    /// Also print the details of this gear state (speeds, slips, element
    /// torques, meshes); repeat for several. Table format only: JSON always has them.
    #[arg(long = "state", value_name = "NAME")]
    pub states: Vec<String>,
    /// Write an SVG chart: every shaft's speed across the gears (a speed
    /// ladder), and the engaged elements' torques per gear.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
}

/// The whole report, by names.
#[derive(Debug, Serialize)]
pub struct Report {
    pub(crate) source: String,
    pub(crate) name: Option<String>,
    pub(crate) input: String,
    pub(crate) output: String,
    /// True when every gear ratio is exact (then every `*_exact` field is filled).
    exact: bool,
    pub(crate) elements: Vec<ElementDef>,
    pub(crate) gears: Vec<GearRow>,
    steps: Vec<StepRow>,
    spread: Option<SpreadRow>,
    shifts: Vec<ShiftRow>,
    warnings: Vec<String>,
}

#[derive(Debug, Serialize)]
pub(crate) struct ElementDef {
    pub(crate) name: String,
    kind: ElementKind,
    links: Vec<String>,
}

#[derive(Debug, Serialize)]
pub(crate) struct GearRow {
    pub(crate) state: String,
    engaged: Vec<String>,
    pub(crate) ratio: f64,
    ratio_exact: Option<String>,
    /// A forward gear: its ratio has the sign most states share.
    forward: bool,
    /// Every link's speed per unit input speed (`null` for a planet without teeth).
    pub(crate) speeds: Vec<SpeedRow>,
    /// Planets' speeds relative to their carriers.
    relative: Vec<RelativeRow>,
    /// Slip across every open element, per unit input speed.
    slips: Vec<SlipRow>,
    /// Torque delivered at the output per unit input torque (ideal meshes).
    output_torque: f64,
    /// Torque the housing applies through meshes with the frame.
    housing_torque: f64,
    /// Engaged elements: torque on the first link per unit input torque.
    pub(crate) elements: Vec<ElementRow>,
    largest_element: Option<ElementRow>,
    meshes: Vec<MeshRow>,
    efficiency: Option<f64>,
    output_torque_with_losses: Option<f64>,
    loss: Option<f64>,
    circulation_ratio: Option<f64>,
    circulating: Option<Circulating>,
    power_balance: f64,
    torque_balance: f64,
    warnings: Vec<String>,
    notes: Vec<String>,
}

#[derive(Debug, Serialize)]
pub(crate) struct SpeedRow {
    pub(crate) link: String,
    /// A shaft turning about the main axis (tree parent is the frame).
    pub(crate) shaft: bool,
    pub(crate) speed: Option<f64>,
    exact: Option<String>,
}

#[derive(Debug, Serialize)]
struct RelativeRow {
    planet: String,
    carrier: String,
    speed: f64,
    exact: Option<String>,
}

#[derive(Debug, Serialize)]
struct SlipRow {
    element: String,
    slip: f64,
    exact: Option<String>,
    /// One-way elements: `overruns`, `idle` or `locks`.
    freewheel: Option<Freewheel>,
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct ElementRow {
    pub(crate) element: String,
    pub(crate) torque: f64,
    /// One-way elements: whether the torque has the direction it can hold.
    holds: Option<bool>,
    parallel: bool,
}

#[derive(Debug, Serialize)]
struct MeshRow {
    gear_pair: String,
    gear_i: String,
    gear_j: String,
    carrier: String,
    torque_i: f64,
    torque_j: f64,
    torque_carrier: f64,
    /// Tangential forces on gear i and gear j (eq. 11), when radii are known.
    force: Option<[f64; 2]>,
    /// Power sent into the mesh by gear i, gear j and the carrier, with losses.
    power: Option<[f64; 3]>,
    rolling_power: Option<f64>,
    driver: Option<Driver>,
    efficiency: Option<f64>,
    loss: Option<f64>,
}

#[derive(Debug, Serialize)]
struct Circulating {
    gear_pairs: Vec<String>,
    links: Vec<String>,
}

#[derive(Debug, Serialize)]
struct StepRow {
    from: String,
    to: String,
    step: f64,
    exact: Option<String>,
}

#[derive(Debug, Serialize)]
struct SpreadRow {
    lowest: String,
    highest: String,
    spread: f64,
    exact: Option<String>,
}

#[derive(Debug, Serialize)]
struct ShiftRow {
    from: String,
    to: String,
    kind: ShiftKind,
    off: Vec<String>,
    on: Vec<String>,
    kept: Vec<String>,
    single_swap: bool,
}

/// Run `egt shift`.
///
/// # Errors
/// Reading or validating the spec; a gear state that does not leave exactly
/// one DOF (naming the state and the elements or links); an unknown `--state`;
/// writing the plot; I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let table = train
        .shift_table()
        .with_context(|| format!("{}: gear table", loaded.source))?;
    let report = build(train, &loaded.source, &table);
    let mut details = Vec::new();
    for s in &args.states {
        let g = report.gears.iter().find(|g| &g.state == s).ok_or_else(|| {
            egt_core::Error::from(egt_core::TransmissionError::UnknownState {
                state: s.clone(),
                suggestion: egt_core::error::suggest(
                    s,
                    report.gears.iter().map(|g| g.state.as_str()),
                ),
            })
        })?;
        details.push(g);
    }
    if let Some(path) = &args.plot {
        let svg = chart::svg(&report);
        std::fs::write(path, svg).with_context(|| format!("writing {}", path.display()))?;
    }
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => {
            write_table(out, train, &loaded.source, &report)?;
            for g in details {
                write_details(out, g)?;
            }
            Ok(())
        }
    }
}

fn exact_str(q: Option<&egt_core::numerics::exact::Q>) -> Option<String> {
    q.map(report::exact)
}

pub(crate) fn build(train: &Train, source: &str, table: &ShiftTable) -> Report {
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

pub(crate) fn gear_row(train: &Train, g: &GearAnalysis, forward: bool) -> GearRow {
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
            .links()
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let id = egt_core::LinkId::from_index(i);
                SpeedRow {
                    link: l.name.clone(),
                    shaft: shaft(id),
                    speed: g.speed[i],
                    exact: g
                        .speed_exact
                        .as_ref()
                        .and_then(|e| exact_str(e[i].as_ref())),
                }
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

fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    writeln!(
        out,
        "{}: gear table; input `{}`, output `{}`",
        report::title(train, source),
        r.input,
        r.output
    )?;
    let dash = || "-".to_string();
    let mut t = Table::new(&[
        "gear",
        "engaged",
        "ratio",
        "exact",
        "step",
        "efficiency",
        "largest element torque",
    ])
    .right(&[2, 3, 4, 5]);
    for g in &r.gears {
        let step = r
            .steps
            .iter()
            .find(|s| s.from == g.state)
            .map_or_else(dash, |s| format!("{:.3}", s.step));
        t.row(vec![
            g.state.clone(),
            g.engaged.join(" "),
            format!("{:.4}", g.ratio),
            g.ratio_exact.clone().unwrap_or_else(dash),
            step,
            g.efficiency.map_or_else(dash, |e| format!("{e:.4}")),
            g.largest_element
                .as_ref()
                .map_or_else(dash, |e| format!("{} {:+.3}", e.element, e.torque)),
        ]);
    }
    t.write(out, 2)?;
    writeln!(
        out,
        "  (ratio = input speed / output speed; step = ratio / next forward ratio; element torque on its first link per unit input torque)"
    )?;
    if let Some(s) = &r.spread {
        write!(
            out,
            "spread ({} / {}): {:.3}",
            s.lowest, s.highest, s.spread
        )?;
        match &s.exact {
            Some(e) => writeln!(out, " (= {e})")?,
            None => writeln!(out)?,
        }
    }
    if !r.shifts.is_empty() {
        writeln!(out, "shifts:")?;
        let mut t = Table::new(&["shift", "off", "on", "kept", "single swap"]);
        for s in &r.shifts {
            let garage = if s.kind == ShiftKind::Garage {
                " (garage)"
            } else {
                ""
            };
            t.row(vec![
                format!("{} -> {}{garage}", s.from, s.to),
                s.off.join(" "),
                s.on.join(" "),
                s.kept.join(" "),
                if s.single_swap { "yes" } else { "NO" }.to_string(),
            ]);
        }
        t.write(out, 2)?;
    }
    for w in &r.warnings {
        writeln!(out, "warning: {w}")?;
    }
    for g in &r.gears {
        for w in &g.warnings {
            writeln!(out, "warning: gear {}: {w}", g.state)?;
        }
    }
    Ok(())
}

fn write_details(out: &mut dyn Write, g: &GearRow) -> anyhow::Result<()> {
    let dash = || "-".to_string();
    writeln!(out)?;
    writeln!(
        out,
        "gear {}: engaged {}; ratio {} ({})",
        g.state,
        g.engaged.join(" "),
        report::float(g.ratio),
        g.ratio_exact.clone().unwrap_or_else(dash)
    )?;
    writeln!(out, "speeds per unit input speed:")?;
    let mut t = Table::new(&["link", "speed", "exact"]).right(&[1, 2]);
    for s in &g.speeds {
        t.row(vec![
            s.link.clone(),
            s.speed.map_or_else(|| "unknown".into(), report::float),
            s.exact.clone().unwrap_or_else(dash),
        ]);
    }
    t.write(out, 2)?;
    if !g.relative.is_empty() {
        writeln!(out, "planets relative to their carriers:")?;
        let mut t = Table::new(&["planet", "carrier", "speed", "exact"]).right(&[2, 3]);
        for x in &g.relative {
            t.row(vec![
                x.planet.clone(),
                x.carrier.clone(),
                report::float(x.speed),
                x.exact.clone().unwrap_or_else(dash),
            ]);
        }
        t.write(out, 2)?;
    }
    if !g.slips.is_empty() {
        writeln!(out, "slip across open elements:")?;
        let mut t = Table::new(&["element", "slip", "exact", "one-way"]).right(&[1, 2]);
        for s in &g.slips {
            t.row(vec![
                s.element.clone(),
                report::float(s.slip),
                s.exact.clone().unwrap_or_else(dash),
                s.freewheel.map_or_else(String::new, |f| {
                    match f {
                        Freewheel::Overruns => "overruns",
                        Freewheel::Idle => "idle",
                        Freewheel::Locks => "LOCKS",
                    }
                    .to_string()
                }),
            ]);
        }
        t.write(out, 2)?;
    }
    writeln!(out, "torques per unit input torque:")?;
    let mut t = Table::new(&["element", "torque on first link", "one-way holds"]).right(&[1]);
    for e in &g.elements {
        t.row(vec![
            e.element.clone(),
            report::float(e.torque),
            match (e.holds, e.parallel) {
                (_, true) => "parallel (idle)".to_string(),
                (Some(true), _) => "yes".to_string(),
                (Some(false), _) => "NO".to_string(),
                (None, _) => String::new(),
            },
        ]);
    }
    t.write(out, 2)?;
    writeln!(
        out,
        "  output torque {}; housing torque {}; balances: power {:.1e}, torque {:.1e}",
        report::float(g.output_torque),
        report::float(g.housing_torque),
        g.power_balance,
        g.torque_balance
    )?;
    writeln!(out, "meshes (per unit input torque and power):")?;
    let mut t = Table::new(&[
        "gear pair",
        "torque i",
        "torque j",
        "force i",
        "force j",
        "rolling power",
        "loss",
    ])
    .right(&[1, 2, 3, 4, 5, 6]);
    for m in &g.meshes {
        t.row(vec![
            m.gear_pair.clone(),
            report::float(m.torque_i),
            report::float(m.torque_j),
            m.force.map_or_else(dash, |f| report::float(f[0])),
            m.force.map_or_else(dash, |f| report::float(f[1])),
            m.rolling_power.map_or_else(dash, report::float),
            m.loss.map_or_else(dash, report::float),
        ]);
    }
    t.write(out, 2)?;
    if let (Some(e), Some(c)) = (g.efficiency, g.circulation_ratio) {
        write!(
            out,
            "  efficiency {e:.4}; circulating-power ratio {}",
            report::float(c)
        )?;
        match &g.circulating {
            Some(c) => writeln!(
                out,
                " (power circulates through {} via {})",
                c.gear_pairs.join(", "),
                c.links.join(", ")
            )?,
            None => writeln!(out)?,
        }
    }
    for n in &g.notes {
        writeln!(out, "  note: {n}")?;
    }
    Ok(())
}
