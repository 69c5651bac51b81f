//! `egt circuits SPEC`: the fundamental-circuit table (the paper's Table 1):
//! for each gear pair m, gear i, gear j, transfer vertex k, the Willis ratio
//! tau_m = (w_i - w_k)/(w_j - w_k) (exact when known) and the levels i/j.

use std::io::Write;

use serde::Serialize;

use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::report;
use egt_views::circuits::{CircuitRow, rows};

/// Arguments of `egt circuits`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
}

#[derive(Debug, Serialize)]
struct Report {
    source: String,
    name: Option<String>,
    circuits: Vec<CircuitRow>,
}

/// Run `egt circuits`.
///
/// # Errors
/// Reading or validating the spec; I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let report = Report {
        source: loaded.source.clone(),
        name: train.name().map(str::to_string),
        circuits: rows(train),
    };
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => {
            writeln!(
                out,
                "{}: fundamental circuits",
                report::title(train, &loaded.source)
            )?;
            report::circuit_table(out, &report.circuits, 0)?;
            writeln!(
                out,
                "tau_m = (w_i - w_k)/(w_j - w_k); Willis eq. (2): w_i - tau_m w_j + (tau_m - 1) w_k = 0"
            )?;
            Ok(())
        }
    }
}
