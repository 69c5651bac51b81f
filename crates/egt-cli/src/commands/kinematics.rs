//! `egt kinematics SPEC --input LINK=SPEED ...`: every link's absolute speed
//! from as many input speeds as the train has DOF (Willis equations, eq. 2),
//! exactly when the ratios come from teeth or fractions; for 1-DOF trains the
//! ratio input/link of every link; each floating link's speed relative to its
//! carrier; the Willis residual and the condition number.

use std::io::Write;

use anyhow::Context;
use egt_core::Train;
use egt_core::numerics::exact;
use egt_views::kinematics::{Report, build};

use crate::args::{OutputFormat, SpeedArgs};
use crate::input;
use crate::report::{self, Table};

/// Arguments of `egt kinematics`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub point: SpeedArgs,
}
/// Run `egt kinematics`.
///
/// # Errors
/// Reading or validating the spec; unknown input links (spec errors, exit 2);
/// inputs that do not determine the train, singular or ill-conditioned
/// systems (analysis errors, exit 1); I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let (loaded, inputs) = input::load_speeds(&args.point)?;
    let train = &loaded.train;
    let speeds = train.kinematics(&inputs).with_context(|| {
        let given: Vec<String> = inputs
            .iter()
            .map(|i| train.link_name(i.link).to_string())
            .collect();
        format!(
            "{}: kinematics with inputs [{}]",
            loaded.source,
            given.join(", ")
        )
    })?;
    let report = build(train, &loaded.source, &inputs, &speeds);
    match args.point.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => write_table(out, train, &loaded.source, &report),
    }
}
fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    let given: Vec<String> = r
        .inputs
        .iter()
        .map(|i| {
            // Show the decimal the user wrote, and the fraction only when the decimal is not exact.
            let shown = report::float(i.speed);
            if exact::parse_rational(&shown)
                .ok()
                .map(|q| report::exact(&q))
                .as_deref()
                == Some(i.exact.as_str())
            {
                format!("{} = {shown}", i.link)
            } else {
                format!("{} = {shown} (= {})", i.link, i.exact)
            }
        })
        .collect();
    writeln!(out, "{}: kinematics", report::title(train, source))?;
    writeln!(
        out,
        "degree of freedom: {}; inputs: {}",
        r.dof,
        given.join(", ")
    )?;
    let one_dof = r.inputs.len() == 1;
    let mut headers = vec!["link", "role", "speed", "exact"];
    if one_dof {
        headers.extend(["input/link", "exact ratio"]);
    }
    let mut t = Table::new(&headers).right(&[2, 3, 4, 5]);
    let dash = || "-".to_string();
    for l in &r.links {
        let role = if l.frame {
            "frame"
        } else if l.input {
            "input"
        } else {
            ""
        };
        let mut row = vec![l.name.clone(), role.to_string()];
        if l.known {
            row.push(l.speed.map_or_else(dash, report::float));
            row.push(l.exact.clone().unwrap_or_else(dash));
        } else {
            row.extend(["unknown".to_string(), "unknown".to_string()]);
        }
        if one_dof {
            if l.known {
                row.push(l.ratio.map_or_else(dash, report::float));
                row.push(l.ratio_exact.clone().unwrap_or_else(dash));
            } else {
                row.extend(["unknown".to_string(), "unknown".to_string()]);
            }
        }
        t.row(row);
    }
    writeln!(out, "absolute speeds:")?;
    t.write(out, 2)?;
    if !r.relative.is_empty() {
        let mut t = Table::new(&["link", "carrier", "relative speed", "exact"]).right(&[2, 3]);
        for x in &r.relative {
            t.row(vec![
                x.link.clone(),
                x.carrier.clone(),
                report::float(x.speed),
                x.exact.clone().unwrap_or_else(dash),
            ]);
        }
        writeln!(out, "speeds relative to the carrier (w_link - w_carrier):")?;
        t.write(out, 2)?;
    }
    if r.links.iter().any(|l| !l.known) {
        writeln!(
            out,
            "note: `unknown` marks planets given without a tooth count; the other speeds do not depend on it"
        )?;
    }
    writeln!(
        out,
        "Willis residual: {:.3e}; condition number: {}",
        r.residual,
        report::float(r.condition)
    )?;
    for w in &r.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}
