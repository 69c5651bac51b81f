//! `egt power SPEC`: power flow at an operating point: the power each link
//! receives, the power through every mesh in the absolute frame and in its
//! carrier's frame (the rolling power that causes mesh loss), the loss in each
//! mesh with its basic efficiency, overall efficiency, and circulating power.

use std::io::Write;

use anyhow::Context;
use egt_core::Train;
use egt_core::analysis::power::PowerRequest;
use egt_views::power::{Report, build};

use crate::args::{LoadArgs, OutputFormat, SpeedArgs, load_request, mass_if_needed};
use crate::input;
use crate::report::{self, Table};

/// Arguments of `egt power`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub point: SpeedArgs,
    #[command(flatten)]
    pub loads: LoadArgs,
    /// Ignore the gear pairs' efficiencies (ideal meshes).
    #[arg(long)]
    pub ideal: bool,
}
/// Run `egt power`.
///
/// # Errors
/// Spec errors (exit 2); missing data, singular systems, self-locking (exit 1).
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let (loaded, speeds) = input::load_speeds(&args.point)?;
    let train = &loaded.train;
    let dynamics = load_request(train, &args.loads)?;
    let mass = mass_if_needed(train, &dynamics)?;
    let req = PowerRequest {
        speeds,
        dynamics,
        losses: !args.ideal,
    };
    let pf = train
        .power_flow(&req, mass.as_ref())
        .with_context(|| format!("{}: power flow", loaded.source))?;
    let report = build(train, &loaded.source, &pf, req.losses);
    match args.point.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => write_table(out, train, &loaded.source, &report),
    }
}
fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    let f = report::float;
    let kind = if r.losses {
        "with mesh losses"
    } else {
        "ideal meshes"
    };
    writeln!(out, "{}: power flow ({kind})", report::title(train, source))?;
    let mut t =
        Table::new(&["link", "speed", "torque", "power in", "to inertia"]).right(&[1, 2, 3, 4]);
    for l in &r.links {
        t.row(vec![
            l.name.clone(),
            f(l.speed),
            f(l.torque),
            f(l.external_power),
            f(l.inertial_power),
        ]);
    }
    writeln!(out, "links (power in = applied torque x speed):")?;
    t.write(out, 2)?;
    let mut t = Table::new(&[
        "pair",
        "carrier",
        "P_i",
        "P_j",
        "P_carrier",
        "rolling",
        "driver",
        "eta",
        "loss",
    ])
    .right(&[2, 3, 4, 5, 7, 8]);
    for m in &r.meshes {
        t.row(vec![
            m.pair.clone(),
            m.carrier.clone(),
            f(m.absolute[0]),
            f(m.absolute[1]),
            f(m.absolute[2]),
            f(m.rolling),
            m.driver.clone().unwrap_or_else(|| "-".into()),
            f(m.efficiency),
            f(m.loss),
        ]);
    }
    writeln!(
        out,
        "meshes (power sent into the mesh by each member; rolling = power in the carrier's frame):"
    )?;
    t.write(out, 2)?;
    writeln!(
        out,
        "input power {}, output power {}, mesh losses {}, dK/dt {}",
        f(r.totals.input_power),
        f(r.totals.output_power),
        f(r.totals.loss),
        f(r.totals.kinetic_rate)
    )?;
    match r.totals.efficiency {
        Some(e) => writeln!(out, "efficiency: {}", f(e))?,
        None => writeln!(out, "efficiency: - (no input power)")?,
    }
    if r.circulating_meshes.is_empty() {
        writeln!(
            out,
            "circulating power: none (largest branch / input = {})",
            f(r.totals.circulation_ratio)
        )?;
    } else {
        writeln!(
            out,
            "circulating power: largest branch / input = {} through shafts [{}] and meshes [{}]",
            f(r.totals.circulation_ratio),
            r.circulating_shafts.join(", "),
            r.circulating_meshes.join(", ")
        )?;
    }
    for w in &r.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}
