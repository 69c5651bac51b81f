//! `egt batch`: many scenarios at full speed, in parallel (rayon), streamed
//! as JSON Lines, CSV, Parquet or Arrow IPC (blocks solved and encoded in
//! parallel tasks, written in order). Scenarios come from one spec whose parameters vary
//! (`--vary` arrays, zipped; `--grid` axes, crossed; `--rows` a JSON Lines
//! file of parameter objects; `--state` gear states of a transmission), or
//! from a JSON Lines file of whole specs (`--specs`, one train per line, each
//! with its `[analysis]`). A bad row (a parameter out of range, a singular or
//! ill-conditioned system, an unreadable line) is reported in its own output
//! row and on stderr; the rest go on, and the exit code is 1 when any failed.
//! A progress line shows on stderr when it is a terminal (or with
//! `--progress`). Ctrl-C stops the batch after the last block written: the
//! output then holds the first rows, whole (CSV and JSON Lines lines, a
//! Parquet or Arrow file closed with its footer, readable), stderr says how
//! many, and the exit code is 130.

use std::io::Write;
use std::path::PathBuf;

use egt_core::batch::BatchPlan;
use egt_core::numerics::linalg::COND_WARN;
use egt_core::solve::prepared::Compute;
use egt_core::{Error, SpecErrorKind};

use crate::args::SpecFormat;
use design::{parse_set, parse_values};
use specs::run_specs;
use sweep::run_one_spec;

mod block;
mod columnar;
#[cfg(test)]
mod columnar_tests;
mod design;
mod order;
mod rows;
mod specs;
mod sweep;
#[cfg(test)]
mod tests;
mod text;

/// Scenarios solved and written per block (bounds memory; output streams per block).
const BLOCK: usize = 1 << 14;

/// Scenarios a block of Parquet or Arrow IPC output: a Parquet row group.
/// Larger than a text block: what a block costs besides its rows (a row
/// group's metadata and its place in the footer, the page writers, a task)
/// was a tenth of a 10^7-row batch to Parquet at 16 384 rows (10^7 rows, 2
/// threads: 34.3 -> 31.0 ms; docs/performance.md (history: git log -p -- docs/benchmarks.md)). Text stays at [`BLOCK`]:
/// at this size CSV ran 5 % slower and JSON Lines 40 %.
const COLUMNAR_BLOCK: usize = 1 << 16;

/// Bytes of parameter and result rows one block may hold: the rows of a
/// large train are wide (a 10 000-link chain has 35 000 parameters and
/// 40 000 outputs a row, 600 kB), so its blocks hold fewer rows.
const BLOCK_BYTES: usize = 64 << 20;

/// Rows per block for rows of `width` doubles (parameters and outputs):
/// `most` ([`BLOCK`] or [`COLUMNAR_BLOCK`]), or fewer so that a block holds
/// at most [`BLOCK_BYTES`].
fn block_rows(width: usize, most: usize) -> usize {
    (BLOCK_BYTES / 8usize.saturating_mul(width.max(1))).clamp(1, most)
}

/// What each scenario computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ComputeArg {
    /// Speeds (eq. 2).
    Kinematics,
    /// Speeds, accelerations, multipliers, driving torques, meshing forces (eq. 2, 8, 10, 11).
    Dynamics,
    /// Dynamics with mesh losses and the power balance.
    Power,
}

/// Output format of `egt batch`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BatchOutput {
    /// One JSON object per line.
    Jsonl,
    /// Comma-separated values with a header.
    Csv,
    /// Apache Parquet (binary; redirect to a file): the CSV's columns, typed,
    /// empty cells as nulls, one row group per block of 65 536 scenarios
    /// (fewer for a large train, whose rows are wide: a block holds at most
    /// 64 MiB of them; with `--specs`, the CSV's long form: row, name,
    /// quantity, value, error).
    Parquet,
    /// Apache Arrow IPC file (binary; redirect to a file), columns as for Parquet.
    Arrow,
}

/// Arguments of `egt batch`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// The spec (TOML or JSON, `-` for stdin) whose scenarios vary. Omit with `--specs`.
    #[arg(value_name = "SPEC", required_unless_present = "specs")]
    pub spec: Option<PathBuf>,
    /// Spec format; by default from the extension, or sniffed on stdin.
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub spec_format: Option<SpecFormat>,
    /// A JSON Lines file of whole specs (`-` for stdin): one scenario per line, from its `[analysis]`.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["spec", "vary", "grid", "rows", "state"])]
    pub specs: Option<PathBuf>,
    /// What each scenario computes.
    #[arg(long, value_enum, default_value_t = ComputeArg::Dynamics)]
    pub compute: ComputeArg,
    /// Fix a parameter: `NAME=VALUE` (see `--list`). Repeatable.
    #[arg(long, value_name = "NAME=VALUE", value_parser = parse_set)]
    pub set: Vec<(String, f64)>,
    /// Vary a parameter over an array: `NAME=V1,V2,...` or `NAME=START:STOP:COUNT`.
    /// Several `--vary` arrays are zipped (equal lengths).
    #[arg(long, value_name = "NAME=VALUES", value_parser = parse_values)]
    pub vary: Vec<(String, Vec<f64>)>,
    /// A grid axis, as `--vary`; the scenarios are the cartesian product of the
    /// axes (and of the zipped `--vary` block).
    #[arg(long, value_name = "NAME=VALUES", value_parser = parse_values)]
    pub grid: Vec<(String, Vec<f64>)>,
    /// A JSON Lines file of parameter objects (`{"NAME": VALUE, ...}`), one scenario per line.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["vary", "grid", "set"])]
    pub rows: Option<PathBuf>,
    /// The most scenarios a `--vary`/`--grid` design may make (checked
    /// before any is solved; one array or axis holds at most 10^7 values).
    #[arg(long, value_name = "N", default_value_t = design::DEFAULT_MAX_ROWS)]
    pub max_rows: u64,
    /// A gear state of the spec's transmission (repeatable), or `all` for the shift table.
    #[arg(long, value_name = "STATE")]
    pub state: Vec<String>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = BatchOutput::Jsonl)]
    pub output: BatchOutput,
    /// Worker threads (default, 0 and anything above the core count: all cores).
    #[arg(short = 'j', long, value_name = "N")]
    pub threads: Option<usize>,
    /// Write only these output columns (comma-separated names; see `--list`). Default: all.
    /// Only those are computed (and the conditions, for the warnings).
    /// Without a `cond.*` column among them, rows solved eight at a time
    /// estimate a condition only where a bound cannot show it small (the
    /// same warnings and errors, 10 to 30 % faster on ratio sweeps).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub columns: Vec<String>,
    /// Print the parameters (with the spec's values) and the output columns, then exit.
    #[arg(long)]
    pub list: bool,
    /// Show a progress line on stderr (scenarios written / all, rate) even
    /// when stderr is not a terminal (on a terminal it shows anyway). Ctrl-C
    /// stops the batch after the last whole block: the output holds the
    /// first rows (a Parquet or Arrow file is closed, readable) and the exit
    /// code is 130.
    #[arg(long)]
    pub progress: bool,
}

/// Run `egt batch`.
///
/// # Errors
/// Reading the spec or files; unknown parameter names or states (exit 2);
/// I/O; and, after every row is written, a summary error when rows failed (exit 1).
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    // (The machine's parallelism is read from cgroup files, so only when
    // there is a request to compare with it.)
    if args.threads.is_some()
        && let (_, Some(note)) = egt_core::batch::worker_threads(args.threads)
    {
        eprintln!("note: {note}");
    }
    let compute = match args.compute {
        ComputeArg::Kinematics => Compute::Kinematics,
        ComputeArg::Dynamics => Compute::Dynamics,
        ComputeArg::Power => Compute::Power,
    };
    let (total, failed, first) = match &args.specs {
        Some(path) => run_specs(args, path, compute, out)?,
        None => run_one_spec(args, compute, out)?,
    };
    if failed > 0 {
        anyhow::bail!(
            "{failed} of {total} scenarios failed (each is reported in its output row); first: {}",
            first.unwrap_or_default()
        );
    }
    Ok(())
}

/// Parquet and Arrow are binary: refused when stdout is a terminal.
///
/// # Errors
/// A spec error naming `--output`, when the batch would write Parquet or
/// Arrow (not for `--list`).
pub fn refuse_binary_to_terminal(args: &Args) -> anyhow::Result<()> {
    let format = match args.output {
        BatchOutput::Parquet => "parquet",
        BatchOutput::Arrow => "arrow",
        BatchOutput::Jsonl | BatchOutput::Csv => return Ok(()),
    };
    if args.list {
        return Ok(());
    }
    Err(Error::spec(
        "--output",
        SpecErrorKind::Invalid {
            message: format!(
                "{format} is binary and stdout is a terminal: redirect it to a file \
                 (`egt batch ... --output {format} > batch.{format}`)"
            ),
        },
    )
    .into())
}

/// Scenarios (or `--specs` lines) written, of them failed, the first failure.
type Outcome = (usize, usize, Option<String>);

/// What a batch that Ctrl-C stopped wrote: `written` of `total` rows
/// (None: not known, `--specs`), `failed` of them failed.
fn interrupted(written: usize, total: Option<usize>, failed: usize, what: &str) -> anyhow::Error {
    let of = total.map_or(String::new(), |t| format!(" of {t}"));
    let failed = if failed > 0 {
        format!(" ({failed} of them failed, each in its row)")
    } else {
        String::new()
    };
    crate::interrupt::Interrupted(format!(
        "{written}{of} {what} written{failed}: the output holds them whole, in order; the rest were not run"
    ))
    .into()
}

/// A block's output, ready to be written.
enum Encoded {
    /// JSON Lines or CSV text.
    Text(Vec<String>),
    /// Parquet column chunks of one row group, in the schema's order.
    Parquet(Vec<parquet::arrow::arrow_writer::ArrowColumnChunk>),
    /// One Arrow record batch.
    Arrow(arrow_array::RecordBatch),
}

/// The output columns to write: those named (that the plan has), or all.
fn select(names: &[String], plan: &BatchPlan) -> Vec<usize> {
    if names.is_empty() {
        (0..plan.outputs().len()).collect()
    } else {
        names.iter().filter_map(|n| plan.output(n)).collect()
    }
}

/// The warning of a row whose condition estimate exceeds COND_WARN.
fn warning(plan: &BatchPlan, o: &[f64]) -> Option<String> {
    warning_at(plan, |c| o[c])
}

/// [`warning`] of the row whose output `c` is `output(c)`.
fn warning_at(plan: &BatchPlan, output: impl Fn(usize) -> f64) -> Option<String> {
    let worst = (plan.condition_columns().iter())
        .map(|&c| output(c))
        .fold(0.0, f64::max);
    (worst > COND_WARN).then(|| {
        format!(
            "ill-conditioned (condition {worst:.2e}): expect about {:.0} correct digits",
            (16.0 - worst.log10()).max(0.0)
        )
    })
}
