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
use egt_core::{Freewheel, ShiftKind, Train};
use egt_views::shift::{GearRow, Report, build};

use crate::args::{OutputFormat, SpecArgs};
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
