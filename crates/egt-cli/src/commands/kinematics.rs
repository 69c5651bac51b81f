//! `egt kinematics SPEC --input LINK=SPEED ...`: every link's absolute speed
//! from as many input speeds as the train has DOF (Willis equations, eq. 2),
//! exactly when the ratios come from teeth or fractions; for 1-DOF trains the
//! ratio input/link of every link; each floating link's speed relative to its
//! carrier; the Willis residual and the condition number.

use std::io::Write;

use anyhow::Context;
use egt_core::numerics::exact;
use egt_core::{LinkId, SpeedInput, Speeds, Train};
use num_traits::Zero;
use serde::Serialize;

use crate::args::{InputArg, parse_input, speed_inputs};
use crate::cli::{OutputFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};

/// Arguments of `egt kinematics`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
    /// An input speed, `LINK=SPEED` (rad/s or any unit; SPEED may be a fraction
    /// `p/q` or a decimal, read exactly). Repeat once per DOF. Default: the
    /// spec's `[analysis] speeds`.
    #[arg(short, long = "input", value_name = "LINK=SPEED", value_parser = parse_input)]
    pub inputs: Vec<InputArg>,
}

#[derive(Debug, Serialize)]
struct InputRow {
    link: String,
    speed: f64,
    exact: String,
}

#[derive(Debug, Serialize)]
struct LinkRow {
    name: String,
    frame: bool,
    input: bool,
    /// False for a planet without tooth count: its speed is unknown.
    known: bool,
    speed: Option<f64>,
    exact: Option<String>,
    /// 1-DOF trains: input speed / link speed (None where the link is at rest or unknown).
    ratio: Option<f64>,
    ratio_exact: Option<String>,
}

#[derive(Debug, Serialize)]
struct RelativeRow {
    link: String,
    carrier: String,
    speed: f64,
    exact: Option<String>,
}

#[derive(Debug, Serialize)]
pub(crate) struct Report {
    source: String,
    name: Option<String>,
    dof: usize,
    inputs: Vec<InputRow>,
    links: Vec<LinkRow>,
    relative: Vec<RelativeRow>,
    residual: f64,
    condition: f64,
    warnings: Vec<String>,
}

/// Run `egt kinematics`.
///
/// # Errors
/// Reading or validating the spec; unknown input links (spec errors, exit 2);
/// inputs that do not determine the train, singular or ill-conditioned
/// systems (analysis errors, exit 1); I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let inputs = speed_inputs(train, &args.inputs)?;
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
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => write_table(out, train, &loaded.source, &report),
    }
}

pub(crate) fn build(train: &Train, source: &str, inputs: &[SpeedInput], s: &Speeds) -> Report {
    let one_dof = inputs.len() == 1;
    let is_input = |l: LinkId| inputs.iter().any(|i| i.link == l);
    let exact_of = |l: LinkId| s.exact.as_ref().map(|e| &e[l.index()]);
    let links = train
        .links()
        .iter()
        .enumerate()
        .map(|(i, link)| {
            let id = LinkId::from_index(i);
            let known = s.known[i];
            let speed = known.then_some(s.speed[i]);
            let ex = exact_of(id).filter(|_| known);
            let (ratio, ratio_exact) = if one_dof && known && id != train.frame() {
                let inp = &inputs[0];
                let ratio = (s.speed[i] != 0.0).then(|| inp.speed / s.speed[i]);
                let ratio_exact = match (&inp.exact, ex) {
                    (Some(a), Some(b)) if !b.is_zero() => Some(report::exact(&(a / b))),
                    _ => None,
                };
                (ratio, ratio_exact)
            } else {
                (None, None)
            };
            LinkRow {
                name: link.name.clone(),
                frame: id == train.frame(),
                input: is_input(id),
                known,
                speed,
                exact: ex.map(report::exact),
                ratio,
                ratio_exact,
            }
        })
        .collect();
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        dof: train.dof(),
        inputs: inputs
            .iter()
            .map(|i| InputRow {
                link: train.link_name(i.link).to_string(),
                speed: i.speed,
                exact: i
                    .exact
                    .as_ref()
                    .map_or_else(|| report::float(i.speed), report::exact),
            })
            .collect(),
        links,
        relative: s
            .relative
            .iter()
            .map(|r| RelativeRow {
                link: train.link_name(r.link).to_string(),
                carrier: train.link_name(r.carrier).to_string(),
                speed: r.speed,
                exact: r.exact.as_ref().map(report::exact),
            })
            .collect(),
        residual: s.residual,
        condition: s.condition,
        warnings: s.warnings.clone(),
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
