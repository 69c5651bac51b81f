//! `egt check SPEC`: validate a spec and say what was checked: the degree of
//! freedom, every topology check that passed (paper section 2) and the
//! fundamental-circuit table.

use std::io::Write;

use serde::Serialize;

use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::report;
use egt_views::circuits::{self, CircuitRow};

/// Arguments of `egt check`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
}

#[derive(Debug, Serialize)]
struct Report {
    source: String,
    name: Option<String>,
    frame: String,
    links: Vec<String>,
    turning_pairs: usize,
    gear_pairs: usize,
    dof: usize,
    checks: Vec<String>,
    circuits: Vec<CircuitRow>,
    warnings: Vec<String>,
}

/// Run `egt check`.
///
/// # Errors
/// Reading or validating the spec (exit 2 in `main`); I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let report = Report {
        source: loaded.source.clone(),
        name: train.name().map(str::to_string),
        frame: train.link_name(train.frame()).to_string(),
        links: train.links().iter().map(|l| l.name.clone()).collect(),
        turning_pairs: train.revolutes().len(),
        gear_pairs: train.gears().len(),
        dof: train.dof(),
        checks: train.checks().to_vec(),
        circuits: circuits::rows(train),
        warnings: train.design_warnings().to_vec(),
    };
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => {
            writeln!(
                out,
                "{}: valid geared kinematic chain",
                report::title(train, &loaded.source)
            )?;
            writeln!(
                out,
                "links: {} (frame `{}`), turning pairs: {}, gear pairs: {}",
                report.links.len(),
                report.frame,
                report.turning_pairs,
                report.gear_pairs
            )?;
            writeln!(out, "degree of freedom: {}", report.dof)?;
            writeln!(out, "checks passed:")?;
            for c in &report.checks {
                writeln!(out, "  ok  {c}")?;
            }
            writeln!(out, "fundamental circuits:")?;
            report::circuit_table(out, &report.circuits, 2)?;
            for w in &report.warnings {
                writeln!(out, "warning: {w}")?;
            }
            Ok(())
        }
    }
}
