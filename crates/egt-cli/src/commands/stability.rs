//! `egt stability SPEC`: the reduced model of a train with any number of
//! degrees of freedom (paper section 5, eq. 19-27): [V] for the driving
//! links, the orthogonality check (eq. 24), the reduced mass and slope
//! matrices (eq. 25-27, with [K] = V^T diag(K) V), the operating point and
//! whether it is a steady state, and the eigenvalues and modes of
//! (lambda [M] - [K]) X = 0 with the verdict (stable, unstable, marginal).

use std::io::Write;

use anyhow::Context;
use egt_core::{StabilityRequest, Train};
use egt_views::stability::{Report, build};

use crate::args::{ModelArgs, curves, parse_pair, resolve_pairs};
use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};

/// Arguments of `egt stability`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
    #[command(flatten)]
    pub model: ModelArgs,
    /// The F driving links (the columns of [V]), comma-separated or repeated.
    /// Default: the links of `[analysis] speeds`, else a well-conditioned choice.
    #[arg(long = "coords", value_name = "LINK", value_delimiter = ',')]
    pub coords: Vec<String>,
    /// An operating speed, `LINK=SPEED`, one per DOF. Default: `[analysis]
    /// speeds`, else the equilibrium of the curves.
    #[arg(short, long = "input", value_name = "LINK=SPEED", value_parser = parse_pair)]
    pub inputs: Vec<(String, f64)>,
}
/// Run `egt stability`.
///
/// # Errors
/// Reading or validating the spec; unknown links (exit 2); no curves, driving
/// links that do not determine the train, ill-conditioned [Gamma_w], a
/// massless direction without slope (exit 1); I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let coords = args
        .coords
        .iter()
        .map(|n| train.resolve(n, &format!("--coords {n}")))
        .collect::<Result<Vec<_>, _>>()?;
    let req = StabilityRequest {
        coordinates: (!coords.is_empty()).then_some(coords),
        curves: Some(curves(train, &args.model)?),
        speeds: (!args.inputs.is_empty())
            .then(|| resolve_pairs(train, &args.inputs, "input"))
            .transpose()?,
    };
    let rep = train
        .stability(&req)
        .with_context(|| format!("{}: stability", loaded.source))?;
    let report = build(train, &loaded.source, &rep);
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => write_table(out, train, &loaded.source, &report),
    }
}
fn square(
    out: &mut dyn Write,
    label: &str,
    names: &[String],
    m: &[Vec<f64>],
) -> anyhow::Result<()> {
    writeln!(out, "{label}")?;
    let mut headers = vec![""];
    headers.extend(names.iter().map(String::as_str));
    let cols: Vec<usize> = (1..=names.len()).collect();
    let mut t = Table::new(&headers).right(&cols);
    for (n, row) in names.iter().zip(m) {
        let mut cells = vec![n.clone()];
        cells.extend(row.iter().map(|&v| report::sci(v)));
        t.row(cells);
    }
    t.write(out, 2)?;
    Ok(())
}

fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    writeln!(out, "{}: stability", report::title(train, source))?;
    let from = match r.coordinate_source {
        egt_core::CoordinateSource::Given => "given",
        egt_core::CoordinateSource::SpecSpeeds => "the links of [analysis] speeds",
        egt_core::CoordinateSource::Automatic => "chosen for conditioning",
    };
    writeln!(
        out,
        "degree of freedom: {}; driving links: {} ({from})",
        r.dof,
        r.coordinates.join(", ")
    )?;
    writeln!(
        out,
        "[Gamma_w] condition number: {}; orthogonality |psi_w V| (eq. 24): {}",
        report::sci(r.gamma_condition),
        report::sci(r.orthogonality)
    )?;
    writeln!(out, "[V] (eq. 23): link speeds per unit driving speed")?;
    let mut headers = vec!["link"];
    headers.extend(r.coordinates.iter().map(String::as_str));
    let cols: Vec<usize> = (1..=r.dof).collect();
    let mut t = Table::new(&headers).right(&cols);
    for (l, row) in r.links.iter().zip(&r.velocity) {
        if train.link_id(l) == Some(train.frame()) {
            continue;
        }
        let mut cells = vec![l.clone()];
        cells.extend(row.iter().map(|&v| report::sci(v)));
        t.row(cells);
    }
    t.write(out, 2)?;
    square(
        out,
        "reduced mass matrix [M] = V^T M V (eq. 25):",
        &r.coordinates,
        &r.mass,
    )?;
    square(
        out,
        "reduced slope matrix [K] = V^T diag(dT/dw) V (eq. 26-27, corrected):",
        &r.coordinates,
        &r.slope,
    )?;
    let op = &r.operating;
    let src = match op.source {
        egt_core::analysis::stability::OperatingSource::Speeds => "from the input speeds",
        egt_core::analysis::stability::OperatingSource::Equilibrium => {
            "the equilibrium of the curves"
        }
    };
    writeln!(out, "operating point ({src}):")?;
    let mut t = Table::new(&["link", "speed", "torque", "equilibrium"]).right(&[1, 2, 3]);
    for (k, s) in op.speeds.iter().enumerate() {
        t.row(vec![
            s.link.clone(),
            report::float(s.value),
            report::sci(op.torques[k].value),
            op.equilibrium
                .as_ref()
                .map_or_else(|| "-".into(), |e| report::float(e[k].value)),
        ]);
    }
    t.write(out, 2)?;
    let rt: Vec<String> = op
        .reduced_torque
        .iter()
        .map(|v| format!("{} {}", v.link, report::sci(v.value)))
        .collect();
    writeln!(
        out,
        "reduced torque V^T T: {} (relative {:.2e}): {}",
        rt.join(", "),
        op.residual,
        if op.steady {
            "a steady state"
        } else {
            "NOT a steady state"
        }
    )?;
    writeln!(
        out,
        "eigenvalues of (lambda [M] - [K]) X = 0; modes as link speeds (largest 1):"
    )?;
    let link_names: Vec<&str> = op.speeds.iter().map(|s| s.link.as_str()).collect();
    let mut headers = vec!["lambda [1/s]", "time constant [s]"];
    headers.extend(link_names.iter().copied());
    let cols: Vec<usize> = (0..headers.len()).collect();
    let mut t = Table::new(&headers).right(&cols);
    for md in &r.modes {
        let mut cells = vec![
            report::sci(md.eigenvalue),
            md.time_constant.map_or_else(|| "-".into(), report::sci),
        ];
        cells.extend(md.speeds.iter().map(|v| report::float(v.value)));
        t.row(cells);
    }
    t.write(out, 2)?;
    for d in &r.massless {
        writeln!(
            out,
            "massless direction (links {}): torque slope {} -> eliminated as an algebraic torque balance",
            d.links.join(", "),
            report::sci(d.slope)
        )?;
    }
    let verdict = match r.verdict {
        egt_core::Verdict::Stable => "STABLE",
        egt_core::Verdict::Unstable => "UNSTABLE",
        egt_core::Verdict::Marginal => "MARGINAL",
    };
    writeln!(out, "verdict: {verdict}: {}", r.reason)?;
    writeln!(
        out,
        "margin (largest eigenvalue): {}; RK4 step limit 2.785/|lambda_min|: {}; stiffness: {}",
        report::sci(r.margin),
        r.rk4_step_limit.map_or_else(|| "none".into(), report::sci),
        r.stiffness.map_or_else(|| "-".into(), report::sci),
    )?;
    for w in &r.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}
