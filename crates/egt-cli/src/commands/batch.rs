//! `egt batch`: many scenarios at full speed, in parallel (rayon), streamed
//! as JSON Lines, CSV, Parquet or Arrow IPC (blocks solved and encoded in
//! parallel tasks, written in order). Scenarios come from one spec whose parameters vary
//! (`--vary` arrays, zipped; `--grid` axes, crossed; `--rows` a JSON Lines
//! file of parameter objects; `--state` gear states of a transmission), or
//! from a JSON Lines file of whole specs (`--specs`, one train per line, each
//! with its `[analysis]`). A bad row (a parameter out of range, a singular or
//! ill-conditioned system, an unreadable line) is reported in its own output
//! row and on stderr; the rest go on, and the exit code is 1 when any failed.
//! A progress bar shows on stderr when it is a terminal.

use std::fmt::Write as _;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use egt_core::batch::{BatchPlan, BatchSpec, Column, Threads};
use egt_core::numerics::linalg::COND_WARN;
use egt_core::solve::prepared::Compute;
use egt_core::{Error, Format, SpecErrorKind, Train};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::cli::{OutputFormat, SpecArgs, SpecFormat};
use crate::input;

mod rows;

/// Scenarios solved and written per block (bounds memory; output streams per block).
const BLOCK: usize = 1 << 14;
/// Scenarios a block of Parquet or Arrow IPC output: a Parquet row group.
/// Larger than a text block: what a block costs besides its rows (a row
/// group's metadata and its place in the footer, the page writers, a task)
/// was a tenth of a 10^7-row batch to Parquet at 16 384 rows (10^7 rows, 2
/// threads: 34.3 -> 31.0 ms; docs/benchmarks.md). Text stays at [`BLOCK`]:
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
/// Rows formatted per parallel task.
const FORMAT_TASK: usize = 1024;

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
    #[arg(long, value_name = "FILE")]
    pub rows: Option<PathBuf>,
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
}

fn parse_set(s: &str) -> Result<(String, f64), String> {
    let (name, v) = split(s)?;
    let v: f64 = v.parse().map_err(|_| format!("`{v}` is not a number"))?;
    Ok((name, v))
}

fn split(s: &str) -> Result<(String, &str), String> {
    let (n, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, got `{s}`"))?;
    if n.trim().is_empty() {
        return Err(format!("no parameter name in `{s}`"));
    }
    Ok((n.trim().to_string(), v.trim()))
}

fn parse_values(s: &str) -> Result<(String, Vec<f64>), String> {
    let (name, v) = split(s)?;
    let num = |x: &str| -> Result<f64, String> {
        x.trim()
            .parse::<f64>()
            .map_err(|_| format!("`{}` is not a number", x.trim()))
    };
    let values = if v.contains(':') {
        let parts: Vec<&str> = v.split(':').collect();
        let [a, b, n] = parts[..] else {
            return Err(format!("expected START:STOP:COUNT, got `{v}`"));
        };
        let (a, b) = (num(a)?, num(b)?);
        let n: usize = n
            .trim()
            .parse()
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| format!("COUNT must be a positive integer, got `{n}`"))?;
        (0..n)
            .map(|i| {
                if n == 1 {
                    a
                } else {
                    a + (b - a) * i as f64 / (n - 1) as f64
                }
            })
            .collect()
    } else {
        v.split(',').map(num).collect::<Result<Vec<_>, _>>()?
    };
    if values.is_empty() {
        return Err(format!("no values for `{name}`"));
    }
    Ok((name, values))
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

fn progress(total: usize) -> ProgressBar {
    // Drawn on stderr only when it is a terminal (indicatif hides it otherwise).
    let bar = ProgressBar::new(total as u64);
    if let Ok(style) =
        ProgressStyle::with_template("{bar:30} {human_pos}/{human_len} scenarios, eta {eta}")
    {
        bar.set_style(style);
    }
    bar
}

/// Where each scenario's overrides come from.
struct Design {
    /// Parameter columns (in the plans' layout) that vary, in output order.
    varied: Vec<(String, usize)>,
    /// Per scenario: overrides (column, value), or why the row is unreadable.
    rows: Rows,
}

enum Rows {
    /// Zipped arrays times grid axes: row i by mixed radix.
    Product {
        zipped: Vec<(usize, Vec<f64>)>,
        axes: Vec<(usize, Vec<f64>)>,
        count: usize,
    },
    /// Parsed lines of a `--rows` file.
    Listed(rows::Listed),
}

impl Rows {
    fn count(&self) -> usize {
        match self {
            Rows::Product { count, .. } => *count,
            Rows::Listed(lines) => lines.len(),
        }
    }

    /// Apply row `i`'s overrides to `row`; Err for an unreadable line.
    fn apply(&self, i: usize, row: &mut [f64]) -> Result<(), String> {
        self.set(i, |c, v| row[c] = v)
    }

    /// Row `i`'s values, `set(column, value)`.
    fn set(&self, i: usize, mut set: impl FnMut(usize, f64)) -> Result<(), String> {
        match self {
            Rows::Product { zipped, axes, .. } => {
                let zl = zipped.first().map_or(1, |z| z.1.len());
                let mut r = i;
                for (c, vals) in axes.iter().rev() {
                    set(*c, vals[r % vals.len()]);
                    r /= vals.len();
                }
                for (c, vals) in zipped {
                    set(*c, vals[r % zl]);
                }
                Ok(())
            }
            Rows::Listed(lines) => match lines.line(i) {
                Ok(values) => {
                    for &(c, x) in values {
                        set(c, x);
                    }
                    Ok(())
                }
                Err(e) => Err(e.to_string()),
            },
        }
    }

    /// Rows `start..start + len` of a grid or zip into `params`, column-major
    /// (`len` rows a column) or row-major (`width` columns a row), as
    /// [`Rows::set`] gives them: each varied column is filled in runs of
    /// equal values, with no division per row (which cost about a tenth of
    /// a 10^6-row Parquet batch). False for a `--rows` file, which is set
    /// line by line.
    fn fill(&self, (start, len): (usize, usize), params: &mut [f64], by: Layout<'_>) -> bool {
        let Rows::Product { zipped, axes, .. } = self else {
            return false;
        };
        let mut fill = |c: usize, vals: &[f64], stride: usize| {
            // (Every column a product sets is a varied one.)
            let (c, by) = match by {
                Layout::Varied(slot) => match slot[c] {
                    Some(j) => (j, Layout::Columns),
                    None => return,
                },
                by => (c, by),
            };
            if vals.is_empty() || stride == 0 {
                return;
            }
            if let (1, Layout::Columns) = (stride, by) {
                // The last axis: its values in turn, copied in runs.
                let column = &mut params[c * len..][..len];
                let (mut k, mut r) = (start % vals.len(), 0);
                while r < len {
                    let n = (vals.len() - k).min(len - r);
                    column[r..r + n].copy_from_slice(&vals[k..k + n]);
                    (r, k) = (r + n, 0);
                }
                return;
            }
            let mut k = (start / stride) % vals.len();
            let mut r = 0;
            let mut run = stride - start % stride;
            while r < len {
                let end = len.min(r + run);
                match by {
                    Layout::Columns | Layout::Varied(_) => params[c * len..][r..end].fill(vals[k]),
                    Layout::Rows(width) => (params[r * width + c..end * width].iter_mut())
                        .step_by(width)
                        .for_each(|x| *x = vals[k]),
                }
                (r, run) = (end, stride);
                k = if k + 1 == vals.len() { 0 } else { k + 1 };
            }
        };
        // Row i takes the last axis's value i % L, the one before's
        // (i / L) % L', and the zipped arrays' (i / all axes) % their length.
        let mut stride = 1usize;
        for (c, vals) in axes.iter().rev() {
            fill(*c, vals, stride);
            stride = stride.saturating_mul(vals.len());
        }
        for (c, vals) in zipped {
            fill(*c, vals, stride);
        }
        true
    }
}

/// How a block's parameters are laid out ([`Rows::fill`]).
#[derive(Clone, Copy)]
enum Layout<'a> {
    /// Column-major, a column for each parameter.
    Columns,
    /// Column-major, a column for each varied parameter only: parameter
    /// `c`'s is column `slot[c]` (the others are the base row's values).
    Varied(&'a [Option<usize>]),
    /// Row-major, this many columns a row.
    Rows(usize),
}

fn unknown(plan: &BatchPlan, name: &str, flag: &str) -> Error {
    let hint = egt_core::error::suggest(name, plan.parameters().iter().map(String::as_str))
        .map(|s| format!(" (did you mean `{s}`?)"))
        .unwrap_or_default();
    Error::spec(
        flag,
        SpecErrorKind::Invalid {
            message: format!(
                "unknown parameter `{name}`{hint}; `egt batch SPEC --list` lists them"
            ),
        },
    )
}

fn design(args: &Args, plan: &BatchPlan) -> anyhow::Result<Design> {
    let col = |name: &str, flag: &str| {
        plan.parameter(name)
            .ok_or_else(|| unknown(plan, name, flag))
    };
    let mut varied: Vec<(String, usize)> = Vec::new();
    let mut note = |name: &str, c: usize| {
        if !varied.iter().any(|v| v.1 == c) {
            varied.push((name.to_string(), c));
        }
    };
    if let Some(path) = &args.rows {
        let text = read(path)?;
        let lines: Vec<(usize, &str)> = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
            .collect();
        // Parsed in parallel; the varied columns noted in line order.
        size_global_pool(args.threads);
        let rows = rows::parse(&lines, plan, &path.display().to_string());
        for &(c, _) in rows.overrides() {
            note(&plan.parameters()[c], c);
        }
        return Ok(Design {
            varied,
            rows: Rows::Listed(rows),
        });
    }
    let mut zipped = Vec::new();
    for (name, vals) in &args.vary {
        let c = col(name, "--vary")?;
        if let Some((_, first)) = zipped.first().map(|z: &(usize, Vec<f64>)| (z.0, z.1.len())) {
            anyhow::ensure!(
                first == vals.len(),
                "--vary arrays are zipped and must have equal lengths: `{name}` has {}, the first has {first}",
                vals.len()
            );
        }
        note(name, c);
        zipped.push((c, vals.clone()));
    }
    let mut axes = Vec::new();
    let mut count = zipped.first().map_or(1, |z| z.1.len());
    for (name, vals) in &args.grid {
        let c = col(name, "--grid")?;
        note(name, c);
        count = count.saturating_mul(vals.len());
        axes.push((c, vals.clone()));
    }
    Ok(Design {
        varied,
        rows: Rows::Product {
            zipped,
            axes,
            count,
        },
    })
}

fn read(path: &PathBuf) -> anyhow::Result<String> {
    if path.as_os_str() == "-" {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut std::io::stdin(), &mut s)
            .context("reading standard input")?;
        return Ok(s);
    }
    std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))
}

/// A JSON string literal.
fn quoted(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"?\"".into())
}

/// A CSV field (quoted when needed).
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number as JSON (null when not finite) or CSV (empty when not finite),
/// as `{v:?}` writes it: the shortest decimal that reads back as `v`.
fn number(buf: &mut String, v: f64, json: bool) {
    if !v.is_finite() {
        if json {
            buf.push_str("null");
        }
    } else if v == 0.0 || (1e-4..1e16).contains(&v.abs()) {
        plain_decimal(buf, v);
    } else {
        let _ = write!(buf, "{v:?}");
    }
}

/// `{v:?}` of a number it writes as a plain decimal (zero, or 1e-4 <= |v| <
/// 1e16: most of a batch's numbers), written by zmij (dtolnay's Schubfach
/// port, which serde_json uses), several times faster. (Outside that range
/// zmij spells the exponent otherwise, "1e+16" and "0.00001" for 1e-5.)
///
/// The two differ only where two shortest decimals are equally near `v`:
/// zmij writes the one with an even last digit, `{v:?}` the one greater in
/// magnitude, and so does this. That happens when the lowest set bit of `v`
/// is one binary place below its last decimal place, so that `v` times ten
/// to the decimal places is an odd number of halves. (Tested on half a
/// million numbers; a release build of the same code agreed with `{v:?}` on
/// 156 million, docs/benchmarks.md.)
fn plain_decimal(buf: &mut String, v: f64) {
    let mut digits = zmij::Buffer::new();
    let text = digits.format_finite(v);
    buf.push_str(text);
    // |v| = odd 2^exponent (normal: |v| >= 1e-4). A tie needs 1 to 21
    // decimal places (17 digits from 1e-4 on), so -22 <= exponent <= -2: a
    // computed number, with bits far below, is passed at once.
    let bits = v.abs().to_bits();
    let mantissa = (bits & ((1 << 52) - 1)) | (1 << 52);
    let shift = mantissa.trailing_zeros();
    let (odd, exponent) = (mantissa >> shift, (bits >> 52) as i32 - 1075 + shift as i32);
    if !(-22..=-2).contains(&exponent) {
        return;
    }
    let Some((_, fraction)) = text.split_once('.') else {
        return;
    };
    let places = fraction.len() as i32;
    if exponent != -(places + 1) {
        return;
    }
    // |v| 10^places = odd 5^places / 2: zmij wrote the lower of the two
    // when twice its digits fall short of that.
    let written =
        (text.bytes().filter(u8::is_ascii_digit)).fold(0u128, |n, d| n * 10 + u128::from(d - b'0'));
    if 2 * written < u128::from(odd) * 5u128.pow(places.unsigned_abs()) {
        // Its last digit is even (zmij's choice): one more carries nothing.
        if let Some(last) = buf.pop() {
            buf.push(char::from(last as u8 + 1));
        }
    }
}

/// One plan's share of the output: which of the CSV columns it fills.
struct Columns {
    /// For each output column of the plan, its CSV position.
    positions: Vec<usize>,
}

type Outcome = (usize, usize, Option<String>);

fn run_one_spec(args: &Args, compute: Compute, out: &mut dyn Write) -> anyhow::Result<Outcome> {
    let threads = batch_threads(args.threads);
    let spec = SpecArgs {
        spec: args.spec.clone().unwrap_or_else(|| PathBuf::from("-")),
        spec_format: args.spec_format,
        format: OutputFormat::Json,
    };
    let loaded = input::load(&spec)?;
    let train = &loaded.train;
    let states: Vec<String> = if args.state.iter().any(|s| s == "all") {
        train
            .checked_transmission()?
            .states
            .iter()
            .map(|s| s.name.clone())
            .collect()
    } else {
        args.state.clone()
    };
    let plans: Vec<(Option<String>, BatchPlan)> = if states.is_empty() {
        let spec = BatchSpec::from_analysis(train, compute)
            .with_context(|| format!("{}: the batch's input links", loaded.source))?;
        vec![(None, BatchPlan::new(train, &spec)?)]
    } else {
        states
            .iter()
            .map(|s| {
                let spec = BatchSpec::for_gear_state(train, s, compute)?;
                Ok((Some(s.clone()), BatchPlan::new(train, &spec)?))
            })
            .collect::<anyhow::Result<_>>()?
    };
    let first = &plans[0].1;
    if args.list {
        writeln!(out, "parameters (with the spec's values):")?;
        for (p, v) in first.parameters().iter().zip(first.base()) {
            writeln!(out, "  {p} = {v}")?;
        }
        for (state, plan) in &plans {
            match state {
                Some(s) => writeln!(out, "outputs (gear state {s}):")?,
                None => writeln!(out, "outputs:")?,
            }
            writeln!(out, "  {}", plan.outputs().join(", "))?;
        }
        return Ok((0, 0, None));
    }
    let mut design = design(args, first)?;
    for name in &args.columns {
        if !plans.iter().any(|(_, p)| p.output(name).is_some()) {
            return Err(Error::spec(
                "--columns",
                SpecErrorKind::Invalid {
                    message: format!(
                        "unknown output column `{name}`; `egt batch SPEC --list` lists them"
                    ),
                },
            )
            .into());
        }
    }
    // Each plan computes only the columns asked for (that it has), and the
    // conditions, which give the warnings. No `cond.*` column asked for:
    // estimate a condition only where a bound cannot show it below the
    // warning level (the same warnings and errors). The straight-line
    // program is compiled once, for the columns chosen (`--list` compiles
    // none).
    let bounds = BatchPlan::bounds_serve(&args.columns);
    let plans: Vec<(Option<String>, BatchPlan)> = (plans.into_iter())
        .map(|(state, plan)| {
            let plan = if args.columns.is_empty() {
                plan
            } else {
                let chosen: Vec<String> = (args.columns.iter())
                    .filter(|c| plan.output(c).is_some())
                    .chain(
                        (plan.outputs().iter())
                            .filter(|o| o.starts_with("cond.") && !args.columns.contains(o)),
                    )
                    .cloned()
                    .collect();
                plan.with_outputs(&chosen)?
            };
            Ok((state, plan.with_condition_bounds(bounds)))
        })
        .collect::<anyhow::Result<_>>()?;
    let first = &plans[0].1;
    // The output columns written, per plan.
    let selected: Vec<Vec<usize>> = plans
        .iter()
        .map(|(_, p)| select(&args.columns, p))
        .collect();
    let mut base = first.base().to_vec();
    for (name, v) in &args.set {
        let c = first
            .parameter(name)
            .ok_or_else(|| unknown(first, name, "--set"))?;
        base[c] = *v;
    }
    // The CSV header: row, state, varied parameters, the union of outputs, error.
    let json = args.output == BatchOutput::Jsonl;
    let mut header: Vec<String> = Vec::new();
    let mut columns = Vec::new();
    for ((_, plan), sel) in plans.iter().zip(&selected) {
        let positions = sel
            .iter()
            .map(|&i| &plan.outputs()[i])
            .map(|o| match header.iter().position(|h| h == o) {
                Some(k) => k,
                None => {
                    header.push(o.clone());
                    header.len() - 1
                }
            })
            .collect();
        columns.push(Columns { positions });
    }
    // A varied speed or acceleration is also an output column (the same value): write it once.
    design.varied.retain(|(name, _)| !header.contains(name));
    let (encoder, mut sink) = match args.output {
        BatchOutput::Parquet | BatchOutput::Arrow => {
            let (e, s) = columnar(args.output, plans[0].0.is_some(), &design.varied, &header)?;
            (Some(e), Some(s))
        }
        BatchOutput::Jsonl | BatchOutput::Csv => (None, None),
    };
    if !json && encoder.is_none() {
        let mut h = String::from("row");
        if plans[0].0.is_some() {
            h.push_str(",state");
        }
        for (name, _) in &design.varied {
            let _ = write!(h, ",{}", csv_field(name));
        }
        for o in &header {
            let _ = write!(h, ",{}", csv_field(o));
        }
        h.push_str(",warning,error\n");
        out.write_all(h.as_bytes())?;
    }
    let per_plan = design.rows.count();
    let total = per_plan * plans.len();
    let bar = progress(total);
    let (mut failed, mut first_error) = (0, None);
    let keys: Vec<String> = design.varied.iter().map(|v| quoted(&v.0)).collect();
    let okeys: Vec<Vec<String>> = plans
        .iter()
        .map(|(_, p)| p.outputs().iter().map(|o| quoted(o)).collect())
        .collect();
    // Rows per block: fewer for wide rows (large trains), the same for every
    // plan. Every output counts, chosen or not: the solve holds them all
    // for the rows of a task.
    let most = if encoder.is_some() {
        COLUMNAR_BLOCK
    } else {
        BLOCK
    };
    let block = plans
        .iter()
        .map(|(_, p)| block_rows(p.parameters().len() + p.all_outputs().len(), most))
        .min()
        .unwrap_or(most);
    let blocks = per_plan.div_ceil(block);
    let all = blocks * plans.len();
    // Blocks run as tasks on one thread each ([`in_order`]), which solves,
    // formats text and applies `--rows` lines itself; a lone block on a
    // machine of several threads is shared out on rayon's global pool.
    // (On one thread, `--rows` lines are still parsed on the global pool.)
    if all <= 1 || threads == 1 {
        size_global_pool(args.threads);
    }
    let within = if all <= 1 && threads > 1 {
        Threads::Pool
    } else {
        Threads::Calling
    };
    // Parameter column `c`'s place among the varied ones, if it is one.
    let mut slot = vec![None; base.len()];
    for (j, &(_, c)) in design.varied.iter().enumerate() {
        slot[c] = Some(j);
    }
    // Block `i` of the whole batch: plan `i / blocks`, its block `i % blocks`.
    let solve = |(buffers, i): (&mut Buffers, usize)| -> anyhow::Result<Done> {
        let (k, b) = (i / blocks, i % blocks);
        let ((state, plan), (cols, sel)) = (&plans[k], (&columns[k], &selected[k]));
        // Parquet and Arrow take a block column-major when the straight-line
        // program solves it: it reads and writes whole columns, and the
        // encoders copy them. Otherwise (a sweep of loads, speeds or
        // accelerations goes to the linear path) and for text, row-major,
        // as the other paths solve rows (docs/benchmarks.md has the A/B).
        let by_columns = encoder.is_some()
            && plan.has_program()
            && (design.varied.iter()).any(|&(_, c)| !plan.is_linear_parameter(c));
        let okeys = &okeys[k];
        let start = b * block;
        let len = block.min(per_plan - start);
        let (np, nq) = (plan.parameters().len(), plan.outputs().len());
        let Buffers {
            params,
            params_by_columns,
            results,
            messages,
            failed_rows,
        } = buffers;
        // Every row starts from the base row. A grid or zip sets the same
        // columns in every row, so a buffer of the same length from an
        // earlier block already holds the base everywhere else; a `--rows`
        // file sets other columns line by line, so it refills.
        let same_columns = matches!(design.rows, Rows::Product { .. });
        // A column-major block of a grid or zip holds only the varied
        // columns: the program reads the others' values from the base row
        // (`Column::Every`), and no column of repeated values is written
        // or read (at 6 links, 2 columns of 35).
        let varied_only = by_columns && same_columns;
        let width = if varied_only { design.varied.len() } else { np };
        // (A buffer filled in the other layout, for a plan without a
        // program, refills too.)
        if !(same_columns && params.len() == len * width && *params_by_columns == by_columns) {
            *params_by_columns = by_columns;
            params.clear();
            if varied_only {
                // Every row of each column is set below.
                params.resize(len * width, 0.0);
            } else if by_columns {
                for &v in &base {
                    params.extend(std::iter::repeat_n(v, len));
                }
            } else {
                for _ in 0..len {
                    params.extend_from_slice(&base);
                }
            }
        }
        let layout = if varied_only {
            Layout::Varied(&slot)
        } else if by_columns {
            Layout::Columns
        } else {
            Layout::Rows(np)
        };
        let unreadable: Vec<(usize, String)> = if design.rows.fill((start, len), params, layout) {
            Vec::new()
        } else if by_columns {
            // A few columns set per row: cheaper than a parallel task.
            let mut bad = Vec::new();
            for r in 0..len {
                if let Err(e) = design.rows.set(start + r, |c, v| params[c * len + r] = v) {
                    (0..np).for_each(|c| params[c * len + r] = f64::NAN);
                    bad.push((r, e));
                }
            }
            bad
        } else {
            let apply = |(r, row): (usize, &mut [f64])| {
                design.rows.apply(start + r, row).err().map(|e| {
                    row.iter_mut().for_each(|v| *v = f64::NAN);
                    (r, e)
                })
            };
            match within {
                Threads::Pool => params
                    .par_chunks_mut(np)
                    .enumerate()
                    .filter_map(apply)
                    .collect(),
                Threads::Calling => params
                    .chunks_mut(np)
                    .enumerate()
                    .filter_map(apply)
                    .collect(),
            }
        };
        // `run` writes every output of every row (NaN on failed rows).
        results.resize(len * nq, 0.0);
        // `bounded`: every row's condition numbers are known to be below
        // the warning's (the compiled program, with bounds, solved every
        // row), so that the block's warnings need no scan.
        let (errors, bounded) = if varied_only {
            let columns: Vec<Column<'_>> = (base.iter().zip(&slot))
                .map(|(&v, j)| match *j {
                    Some(j) => Column::Rows(&params[j * len..][..len]),
                    None => Column::Every(v),
                })
                .collect();
            plan.run_column_set_bounded(within, &columns, len, results)
        } else if by_columns {
            (plan.run_columns_with(within, params, results), false)
        } else {
            (plan.run_with(within, params, results), false)
        };
        // Most blocks have no failed row: a buffer of the same length is
        // cleared only where the last block set it (a block's 16 384
        // messages are 384 KiB to write).
        if messages.len() == len {
            for r in failed_rows.drain(..) {
                messages[r] = None;
            }
        } else {
            messages.clear();
            messages.resize(len, None);
            failed_rows.clear();
        }
        for e in errors {
            messages[e.row] = Some(e.error.to_string());
            failed_rows.push(e.row);
        }
        for (r, e) in unreadable {
            messages[r] = Some(e);
            failed_rows.push(r);
        }
        failed_rows.sort_unstable();
        failed_rows.dedup();
        let base_row = k * per_plan + start;
        // Parquet encodes a column-major block's columns where they are: the
        // buffers are lent to Arrow for the encoding (an Arrow IPC batch
        // outlives it, and takes copies).
        let lent = (by_columns && encoder.as_ref().is_some_and(Encoder::parquet)).then(|| {
            let lend = |v: &mut Vec<f64>| arrow_buffer::Buffer::from_vec(std::mem::take(v));
            (lend(params), lend(results))
        });
        let (pdata, rdata): (&[f64], &[f64]) = match &lent {
            Some((p, r)) => (p.typed_data(), r.typed_data()),
            None => (params, results),
        };
        let encoded = match &encoder {
            Some(c) => c.encode(
                plan,
                &Block {
                    index: i,
                    first_row: base_row,
                    state: state.as_deref(),
                    varied: &design.varied,
                    varied_only,
                    params: Matrix {
                        data: pdata,
                        shared: lent.as_ref().map(|l| &l.0),
                        width,
                        rows: len,
                        columns: by_columns,
                    },
                    results: Matrix {
                        data: rdata,
                        shared: lent.as_ref().map(|l| &l.1),
                        width: nq,
                        rows: len,
                        columns: by_columns,
                    },
                    positions: (&cols.positions, sel),
                    messages,
                    any_failed: !failed_rows.is_empty(),
                    bounded,
                },
            )?,
            None => Encoded::Text(format_text(
                TextBlock {
                    json,
                    base_row,
                    state: state.as_deref(),
                    design: &design,
                    keys: &keys,
                    okeys,
                    header_len: header.len(),
                    positions: (&cols.positions, sel),
                },
                plan,
                (params, np),
                (results, nq),
                messages,
                within,
            )),
        };
        // The encoded chunks hold bytes, not the arrays: the buffers come
        // back whole (a copy only if a slice were still held).
        if let Some((p, r)) = lent {
            let back = |b: arrow_buffer::Buffer| {
                b.into_vec::<f64>()
                    .unwrap_or_else(|b| b.typed_data::<f64>().to_vec())
            };
            *params = back(p);
            *results = back(r);
        }
        Ok(Done {
            len,
            encoded,
            failed: failed_rows.len(),
            first_error: (failed_rows.first())
                .and_then(|&r| Some(format!("row {}: {}", base_row + r, messages[r].as_ref()?))),
        })
    };
    // Blocks are solved and encoded in the pool's tasks, each task taking
    // the next block as soon as it has finished one, and written in order
    // on this thread, which only copies bytes (docs/benchmarks.md has the
    // history: waves of blocks left a thread idle while the other finished
    // its block and while this one wrote).
    let ahead = if block < most { 1 } else { AHEAD };
    in_order(all, ahead, threads, &solve, |d| {
        let d = d?;
        match d.encoded {
            Encoded::Text(text) => {
                for t in &text {
                    out.write_all(t.as_bytes())?;
                }
            }
            encoded => match sink.as_mut() {
                Some(sink) => sink.append(encoded, out)?,
                None => anyhow::bail!("a columnar block without its output"),
            },
        }
        failed += d.failed;
        if first_error.is_none() {
            first_error = d.first_error;
        }
        bar.inc(d.len as u64);
        Ok(())
    })?;
    bar.finish_and_clear();
    if let Some(sink) = sink {
        sink.finish(out)?;
    }
    Ok((total, failed, first_error))
}

/// What the text writers of one block share.
struct TextBlock<'a> {
    json: bool,
    base_row: usize,
    state: Option<&'a str>,
    design: &'a Design,
    keys: &'a [String],
    okeys: &'a [String],
    header_len: usize,
    /// The plan's CSV positions and its selected outputs.
    positions: (&'a [usize], &'a [usize]),
}

/// A block as JSON Lines or CSV, in pieces of [`FORMAT_TASK`] rows, in
/// order: parallel tasks on rayon's global pool (`within` a pool: a lone
/// block), or on this thread (blocks run in parallel, or one thread).
fn format_text(
    t: TextBlock<'_>,
    plan: &BatchPlan,
    (params, np): (&[f64], usize),
    (results, nq): (&[f64], usize),
    messages: &[Option<String>],
    within: Threads,
) -> Vec<String> {
    let sel = t.positions.1;
    let piece = |k: usize, res: &[f64], par: &[f64], msgs: &[Option<String>]| {
        let mut buf = String::with_capacity(res.len() * 24);
        for (r, ((o, p), m)) in res.chunks(nq).zip(par.chunks(np)).zip(msgs).enumerate() {
            let fmt = Row {
                row: t.base_row + k * FORMAT_TASK + r,
                state: t.state,
                varied: &t.design.varied,
                keys: t.keys,
                params: p,
            };
            if t.json {
                fmt.json(&mut buf, t.okeys, sel, plan, o, m.as_deref());
            } else {
                fmt.csv(&mut buf, t.header_len, t.positions, plan, o, m.as_deref());
            }
        }
        buf
    };
    match within {
        Threads::Pool => (results.par_chunks(nq * FORMAT_TASK))
            .zip(params.par_chunks(np * FORMAT_TASK))
            .zip(messages.par_chunks(FORMAT_TASK))
            .enumerate()
            .map(|(k, ((res, par), msgs))| piece(k, res, par, msgs))
            .collect(),
        Threads::Calling => (results.chunks(nq * FORMAT_TASK))
            .zip(params.chunks(np * FORMAT_TASK))
            .zip(messages.chunks(FORMAT_TASK))
            .enumerate()
            .map(|(k, ((res, par), msgs))| piece(k, res, par, msgs))
            .collect(),
    }
}

/// A task's parameters and results of one block (column-major where the
/// program solves a Parquet or Arrow block, else row-major) and its row
/// errors.
#[derive(Default)]
struct Buffers {
    params: Vec<f64>,
    /// `params` is column-major.
    params_by_columns: bool,
    results: Vec<f64>,
    messages: Vec<Option<String>>,
    /// The rows of `messages` that are set, in order.
    failed_rows: Vec<usize>,
}

/// Blocks `0..all`: `solve` on this thread and on `threads - 1` helper
/// threads (each with its own buffers, taking the next block as it finishes
/// one), and `write` on this thread, in order. A thread takes no block
/// `ahead` times `threads` past the last one written, so memory stays that
/// many blocks whatever the batch. The first error of `write` stops the
/// helpers (their blocks in progress are dropped) and is returned.
///
/// This thread writes the blocks that are ready between its own solves, and
/// waits only when the window is full. So a batch on `threads` cores runs
/// `threads` threads, not one more that wakes for every block: on a 2-core
/// KVM guest, a thread woken while both cores were busy waited up to a
/// 4 ms scheduler tick, and one started on an idle core ran 1 to 4 ms later
/// (docs/benchmarks.md, "The writer solves too").
fn in_order<T: Send>(
    all: usize,
    ahead: usize,
    threads: usize,
    solve: &(impl Fn((&mut Buffers, usize)) -> T + Sync),
    mut write: impl FnMut(T) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::sync::{Condvar, Mutex, mpsc};
    let threads = threads.max(1);
    let mut buffers = Buffers::default();
    if threads == 1 || all <= 1 {
        return (0..all).try_for_each(|i| write(solve((&mut buffers, i))));
    }
    let window = ahead.max(1) * threads;
    let next = AtomicUsize::new(0);
    // Blocks written, with the condition the helpers wait on.
    let written = (Mutex::new(0usize), Condvar::new());
    let stop = AtomicBool::new(false);
    // Stops every helper when dropped on this thread (at the end, or on an
    // error), or when a helper unwinds (this thread would wait forever for
    // its block); `.2` says which. The flag is set under the lock, so that
    // a helper between its test and its wait cannot miss the wake-up.
    struct Stop<'a>(&'a AtomicBool, &'a (Mutex<usize>, Condvar), bool);
    impl Drop for Stop<'_> {
        fn drop(&mut self) {
            if self.2 || std::thread::panicking() {
                let _lock = self.1.0.lock().unwrap_or_else(|e| e.into_inner());
                self.0.store(true, Ordering::SeqCst);
                self.1.1.notify_all();
            }
        }
    }
    let (tx, rx) = mpsc::channel::<(usize, T)>();
    std::thread::scope(|scope| {
        // No more helpers than blocks for them.
        for _ in 1..threads.min(all) {
            let (tx, next, written, stop) = (tx.clone(), &next, &written, &stop);
            scope.spawn(move || {
                let _stop = Stop(stop, written, false);
                let mut buffers = Buffers::default();
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    if i >= all {
                        break;
                    }
                    let mut done = written.0.lock().unwrap_or_else(|e| e.into_inner());
                    while i >= *done + window && !stop.load(Ordering::SeqCst) {
                        done = written.1.wait(done).unwrap_or_else(|e| e.into_inner());
                    }
                    drop(done);
                    if stop.load(Ordering::SeqCst)
                        || tx.send((i, solve((&mut buffers, i)))).is_err()
                    {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let _stop = Stop(&stop, &written, true);
        // Blocks come in the order they finish; each waits here for those before it.
        let mut pending: std::collections::BTreeMap<usize, T> = Default::default();
        let mut at = 0;
        while at < all {
            // The next block, if it is within the window: this thread's to
            // solve. (A helper that took a block past the window waits.)
            let mine = next
                .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |i| {
                    (i < all && i < at + window).then_some(i + 1)
                })
                .ok();
            match mine {
                Some(i) => {
                    pending.insert(i, solve((&mut buffers, i)));
                    pending.extend(rx.try_iter());
                }
                None => match rx.recv() {
                    Ok((i, d)) => {
                        pending.insert(i, d);
                    }
                    Err(_) => {
                        anyhow::bail!("a batch task stopped before its block {at} was written")
                    }
                },
            }
            let before = at;
            while let Some(d) = pending.remove(&at) {
                write(d)?;
                at += 1;
            }
            if at > before {
                *written.0.lock().unwrap_or_else(|e| e.into_inner()) = at;
                written.1.notify_all();
            }
        }
        Ok(())
    })
}

/// The block tasks of `egt batch` ([`in_order`]): `--threads`, else
/// rayon's own rule (`RAYON_NUM_THREADS`, else the machine's parallelism).
/// Found without starting rayon's global pool: the tasks run on pools of
/// their own, and the global pool's idle threads would spin beside them
/// (about 3.5 ms of CPU in a 17 ms run of 10^6 rows on 2 cores,
/// docs/benchmarks.md).
fn batch_threads(requested: Option<usize>) -> usize {
    let asked = requested.or_else(|| {
        std::env::var("RAYON_NUM_THREADS")
            .ok()
            .and_then(|n| n.trim().parse::<usize>().ok())
            .filter(|&n| n > 0)
    });
    egt_core::batch::worker_threads(asked).0
}

/// Size rayon's global pool to `--threads`, where the global pool is about
/// to work (parsing `--rows`, a lone block, `--specs` lines) rather than at
/// the start: built, its idle threads would spin beside the block tasks.
/// (The pool is built once a process; a second build only fails.)
fn size_global_pool(requested: Option<usize>) {
    if requested.is_some() {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(batch_threads(requested))
            .build_global();
    }
}

/// How many blocks a thread may be ahead of the writer ([`in_order`]), when
/// blocks are of [`BLOCK`] rows ([`COLUMNAR_BLOCK`] for Parquet and Arrow
/// IPC; 1 measured slower there). Blocks cut short by [`BLOCK_BYTES`] (wide
/// rows, large trains) keep one a thread, as much as the waves before held.
/// (4 and 8 measured no faster than 2, 2026-11-26.)
const AHEAD: usize = 2;

/// One block solved and encoded in a worker task, to be written in order.
struct Done {
    len: usize,
    encoded: Encoded,
    failed: usize,
    first_error: Option<String>,
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

/// A block's parameters or results, row- or column-major.
#[derive(Clone, Copy)]
struct Matrix<'a> {
    data: &'a [f64],
    /// `data` as an Arrow buffer, when the block lends it: whole columns
    /// of a column-major block are then slices of it, not copies.
    shared: Option<&'a arrow_buffer::Buffer>,
    /// Columns and rows.
    width: usize,
    rows: usize,
    /// Column-major.
    columns: bool,
}

impl Matrix<'_> {
    /// Row `r`, column `c`.
    #[inline]
    fn at(&self, r: usize, c: usize) -> f64 {
        if self.columns {
            self.data[c * self.rows + r]
        } else {
            self.data[r * self.width + c]
        }
    }

    /// Column `c`, in row order.
    fn column(&self, c: usize) -> arrow_buffer::ScalarBuffer<f64> {
        match (self.columns, self.shared) {
            (true, Some(b)) => arrow_buffer::ScalarBuffer::new(b.clone(), c * self.rows, self.rows),
            (true, None) => self.data[c * self.rows..][..self.rows].to_vec().into(),
            (false, _) => (self.data[c..].iter().step_by(self.width))
                .take(self.rows)
                .copied()
                .collect::<Vec<f64>>()
                .into(),
        }
    }

    /// Whether a row's value in column `c` is above `limit`.
    fn any_above(&self, c: usize, limit: f64) -> bool {
        if self.columns {
            self.data[c * self.rows..][..self.rows]
                .iter()
                .any(|&x| x > limit)
        } else {
            (self.data[c..].iter().step_by(self.width))
                .take(self.rows)
                .any(|&x| x > limit)
        }
    }
}

/// One block of solved rows, for the columnar writers.
struct Block<'a> {
    /// Its place among all blocks (the Parquet row group's index).
    index: usize,
    first_row: usize,
    state: Option<&'a str>,
    varied: &'a [(String, usize)],
    /// `params` holds the varied columns only, in `varied`'s order.
    varied_only: bool,
    params: Matrix<'a>,
    results: Matrix<'a>,
    /// The plan's positions among the output columns, and its selected outputs.
    positions: (&'a [usize], &'a [usize]),
    messages: &'a [Option<String>],
    /// Some of `messages` are set.
    any_failed: bool,
    /// Every row's condition numbers are below the warning's
    /// ([`egt_core::batch::BatchPlan::run_column_set_bounded`]).
    bounded: bool,
}

/// Parquet or Arrow IPC output: the CSV's columns, typed (row as an
/// unsigned integer, numbers as doubles, texts as strings), with nulls where
/// the CSV leaves a cell empty; one record batch (Parquet row group) per
/// block. Blocks are encoded in worker tasks ([`Encoder`], shared) and
/// appended in order ([`Sink`], the main thread's).
fn columnar(
    kind: BatchOutput,
    states: bool,
    varied: &[(String, usize)],
    header: &[String],
) -> anyhow::Result<(Encoder, Sink)> {
    use arrow_schema::{DataType, Field};
    let mut fields = vec![Field::new("row", DataType::UInt64, false)];
    if states {
        fields.push(Field::new("state", DataType::Utf8, false));
    }
    for (name, _) in varied {
        fields.push(Field::new(name, DataType::Float64, true));
    }
    for name in header {
        fields.push(Field::new(name, DataType::Float64, true));
    }
    fields.push(Field::new("warning", DataType::Utf8, true));
    fields.push(Field::new("error", DataType::Utf8, true));
    let parameters: Vec<&str> = varied.iter().map(|v| v.0.as_str()).collect();
    columnar_file(kind, fields, header.len(), &parameters)
}

/// The CSV's long form of `--specs` (one row per output of each line),
/// typed: row, name, quantity, value (null on a failed line) and error.
fn long_columnar(kind: BatchOutput) -> anyhow::Result<(Encoder, Sink)> {
    use arrow_schema::{DataType, Field};
    let fields = vec![
        Field::new("row", DataType::UInt64, false),
        Field::new("name", DataType::Utf8, false),
        Field::new("quantity", DataType::Utf8, false),
        Field::new("value", DataType::Float64, true),
        Field::new("error", DataType::Utf8, true),
    ];
    columnar_file(kind, fields, 0, &[])
}

/// The data page size limit of a Parquet file: a page of doubles holds
/// this many bytes of values, 8 192 values. (A block's column is 512 KiB,
/// and the writer's page buffers grow by doubling up to the page; with
/// pages smaller than the default 1 MiB they stay small: docs/benchmarks.md.)
const PAGE_BYTES: usize = 64 * 1024;

/// parquet-rs's settings for a file of the columns of `schema`, of which
/// `parameters` are a design's varied parameters (measured on a 10^6-row
/// grid of a 6-link chain, 2 threads):
/// - Snappy, but not for the solver's doubles, which it hardly shrinks
///   (a computed double's low bits are noise) and spends time on;
/// - a varied parameter's column plain, and Snappy-compressed: a grid's or
///   a zip's values repeat (in runs, or in short cycles), which Snappy
///   finds. (Dictionary-encoded, the file was 15 % smaller, but hashing
///   every value took a fifth more CPU time.)
/// - the row numbers delta-encoded (they count up by one: a few bytes a
///   page);
/// - pages of 64 KiB rather than the default 1 MiB (the writer's page
///   buffers grow by doubling up to the page; with smaller pages they stay
///   small), and at most a block's rows;
/// - the numbers' statistics the row group's, not each page's: a row group
///   is a block (65 536 rows).
fn parquet_properties(
    schema: &arrow_schema::Schema,
    parameters: &[&str],
) -> parquet::file::properties::WriterProperties {
    use arrow_schema::DataType;
    use parquet::basic::{Compression, Encoding};
    use parquet::file::properties::{EnabledStatistics, WriterProperties, WriterVersion};
    use parquet::schema::types::ColumnPath;
    let mut props = WriterProperties::builder()
        .set_writer_version(WriterVersion::PARQUET_1_0)
        .set_data_page_size_limit(PAGE_BYTES)
        .set_data_page_row_count_limit(COLUMNAR_BLOCK)
        .set_compression(Compression::SNAPPY)
        .set_dictionary_enabled(false)
        .set_column_encoding(ColumnPath::from("row"), Encoding::DELTA_BINARY_PACKED);
    for field in schema.fields() {
        let path = || ColumnPath::from(field.name().as_str());
        if let DataType::Float64 | DataType::UInt64 = field.data_type() {
            props = props.set_column_statistics_enabled(path(), EnabledStatistics::Chunk);
        }
        if field.data_type() == &DataType::Float64 && !parameters.contains(&field.name().as_str()) {
            props = props.set_column_compression(path(), Compression::UNCOMPRESSED);
        }
    }
    props.build()
}

/// An encoder and a sink for the columns `fields` (`outputs` of them the
/// solver's, `parameters` a design's varied parameters).
fn columnar_file(
    kind: BatchOutput,
    fields: Vec<arrow_schema::Field>,
    outputs: usize,
    parameters: &[&str],
) -> anyhow::Result<(Encoder, Sink)> {
    let schema = std::sync::Arc::new(arrow_schema::Schema::new(fields));
    let (factory, sink) = if kind == BatchOutput::Parquet {
        let props = parquet_properties(&schema, parameters);
        // The Arrow writer adds the Arrow schema to the file's metadata;
        // its lower half lets row groups be encoded in parallel.
        let (writer, factory) =
            parquet::arrow::ArrowWriter::try_new(Vec::new(), schema.clone(), Some(props))?
                .into_serialized_writer()?;
        (Some(factory), Sink::Parquet(Box::new(writer)))
    } else {
        let writer = arrow_ipc::writer::FileWriter::try_new(Vec::new(), &schema)?;
        (None, Sink::Arrow(Box::new(writer)))
    };
    let encoder = Encoder {
        schema,
        outputs,
        factory,
        null_arrays: std::sync::Mutex::default(),
    };
    Ok((encoder, sink))
}

/// Turns a block into Parquet column chunks or an Arrow record batch.
struct Encoder {
    schema: arrow_schema::SchemaRef,
    /// Output columns (after row, state and the varied parameters).
    outputs: usize,
    /// Parquet's column writers, for each row group. None for Arrow IPC.
    factory: Option<parquet::arrow::arrow_writer::ArrowRowGroupWriterFactory>,
    /// Arrays of nulls only, of a type and a length ([`Encoder::null_column`]).
    null_arrays: std::sync::Mutex<Vec<arrow_array::ArrayRef>>,
}

/// A column of doubles, null where a value is not finite or its row
/// `failed` (None when no row of the block did; no null buffer when there
/// are no nulls).
fn doubles(
    values: arrow_buffer::ScalarBuffer<f64>,
    failed: Option<&[Option<String>]>,
) -> arrow_array::ArrayRef {
    let missing = |r: usize| failed.is_some_and(|f| f[r].is_some()) || !values[r].is_finite();
    let nulls = (failed.is_some() || !values.iter().all(|v| v.is_finite()))
        .then(|| {
            (0..values.len())
                .map(|r| !missing(r))
                .collect::<Vec<bool>>()
        })
        .filter(|valid| valid.contains(&false))
        .map(arrow_buffer::NullBuffer::from);
    let values = match &nulls {
        // Null slots hold 0 (never a NaN or an inf a reader might take up).
        Some(n) => values
            .iter()
            .enumerate()
            .map(|(r, &v)| if n.is_valid(r) { v } else { 0.0 })
            .collect::<Vec<f64>>()
            .into(),
        None => values,
    };
    std::sync::Arc::new(arrow_array::Float64Array::new(values, nulls))
}

/// A column of optional texts: all null without building one by one when
/// `text` gives none (the usual block: no warning, no error).
fn texts<'a>(
    len: usize,
    text: impl Fn(usize) -> Option<std::borrow::Cow<'a, str>>,
) -> arrow_array::ArrayRef {
    use arrow_array::StringArray;
    let first = (0..len).find(|&r| text(r).is_some());
    std::sync::Arc::new(match first {
        None => StringArray::new_null(len),
        Some(_) => StringArray::from_iter((0..len).map(text)),
    })
}

impl Encoder {
    /// Whether blocks become Parquet column chunks (else Arrow batches).
    fn parquet(&self) -> bool {
        self.factory.is_some()
    }

    fn encode(&self, plan: &BatchPlan, b: &Block<'_>) -> anyhow::Result<Encoded> {
        use arrow_array::{ArrayRef, StringArray, UInt64Array};
        use std::sync::Arc;
        let (params, results) = (b.params, b.results);
        let len = b.messages.len();
        let mut columns: Vec<ArrayRef> = Vec::with_capacity(self.schema.fields().len());
        let first = b.first_row as u64;
        columns.push(Arc::new(UInt64Array::from_iter_values(
            first..first + len as u64,
        )));
        if let Some(s) = b.state {
            columns.push(Arc::new(StringArray::from_iter_values(
                std::iter::repeat_n(s, len),
            )));
        }
        for (j, &(_, c)) in b.varied.iter().enumerate() {
            let values = params.column(if b.varied_only { j } else { c });
            columns.push(doubles(values, None));
        }
        let failed = |r: usize| b.messages[r].is_some();
        let any_failed = b.any_failed.then_some(b.messages);
        // Which of this plan's outputs fills each output column, if any.
        let mut source = vec![None; self.outputs];
        for (&pos, &i) in b.positions.0.iter().zip(b.positions.1) {
            source[pos] = Some(i);
        }
        for src in source {
            columns.push(match src {
                Some(i) => doubles(results.column(i), any_failed),
                None => self.null_column(&arrow_schema::DataType::Float64, len),
            });
        }
        // Most blocks have no row past the warning's limit: a scan of the
        // condition columns finds so, with no test row by row.
        let warned = !b.bounded
            && (plan.condition_columns().iter()).any(|&c| results.any_above(c, COND_WARN));
        columns.push(if warned {
            texts(len, |r| {
                if failed(r) {
                    None
                } else {
                    warning_at(plan, |c| results.at(r, c)).map(std::borrow::Cow::Owned)
                }
            })
        } else {
            self.null_column(&arrow_schema::DataType::Utf8, len)
        });
        columns.push(if b.any_failed {
            texts(len, |r| {
                b.messages[r].as_deref().map(std::borrow::Cow::Borrowed)
            })
        } else {
            self.null_column(&arrow_schema::DataType::Utf8, len)
        });
        self.record_batch(columns, b.index)
    }

    /// An array of `len` nulls of type `of`, one for every block of that
    /// length (a new one was 64 KiB of offsets to clear for a text column,
    /// every block).
    fn null_column(&self, of: &arrow_schema::DataType, len: usize) -> arrow_array::ArrayRef {
        let mut kept = self.null_arrays.lock().unwrap_or_else(|e| e.into_inner());
        let found = kept.iter().find(|a| a.len() == len && a.data_type() == of);
        if let Some(array) = found {
            return array.clone();
        }
        let array = arrow_array::new_null_array(of, len);
        kept.push(array.clone());
        array
    }

    /// The columns, in the schema's order, as one Arrow record batch, or
    /// as the Parquet column chunks of row group `index` (encoded by
    /// parquet-rs's column writers).
    fn record_batch(
        &self,
        columns: Vec<arrow_array::ArrayRef>,
        index: usize,
    ) -> anyhow::Result<Encoded> {
        let batch = arrow_array::RecordBatch::try_new(self.schema.clone(), columns)?;
        let Some(factory) = &self.factory else {
            return Ok(Encoded::Arrow(batch));
        };
        let writers = factory.create_column_writers(index)?;
        // Every column is flat: one leaf, so one writer, a column.
        anyhow::ensure!(
            writers.len() == batch.num_columns(),
            "a nested Parquet column"
        );
        let mut chunks = Vec::with_capacity(writers.len());
        for ((mut writer, array), field) in
            (writers.into_iter().zip(batch.columns())).zip(self.schema.fields())
        {
            for leaf in parquet::arrow::arrow_writer::compute_leaves(field, array)? {
                writer.write(&leaf)?;
            }
            chunks.push(writer.close()?);
        }
        Ok(Encoded::Parquet(chunks))
    }
}

/// The columnar files being written: each writes into a buffer that is
/// drained to the output after every block, so memory stays one wave of
/// blocks whatever the batch.
enum Sink {
    Parquet(Box<parquet::file::writer::SerializedFileWriter<Vec<u8>>>),
    Arrow(Box<arrow_ipc::writer::FileWriter<Vec<u8>>>),
}

impl Sink {
    /// Append an encoded block and pass the bytes written so far on to `out`.
    fn append(&mut self, encoded: Encoded, out: &mut dyn Write) -> anyhow::Result<()> {
        let bytes = match (self, encoded) {
            (Sink::Parquet(w), Encoded::Parquet(chunks)) => {
                let mut group = w.next_row_group()?;
                for chunk in chunks {
                    chunk.append_to_row_group(&mut group)?;
                }
                group.close()?;
                // (The writer counts the bytes it wrote, not those its
                // buffer holds: the buffer may be drained.)
                w.flush()?;
                w.inner_mut()
            }
            (Sink::Arrow(w), Encoded::Arrow(batch)) => {
                w.write(&batch)?;
                w.get_mut()
            }
            _ => anyhow::bail!("a block encoded for another output format"),
        };
        out.write_all(bytes)?;
        bytes.clear();
        Ok(())
    }

    /// Write the footer.
    fn finish(self, out: &mut dyn Write) -> anyhow::Result<()> {
        let bytes = match self {
            Sink::Parquet(w) => w.into_inner()?,
            Sink::Arrow(mut w) => {
                w.finish()?;
                w.into_inner()?
            }
        };
        out.write_all(&bytes)?;
        Ok(())
    }
}

/// The output columns to write: those named (that the plan has), or all.
fn select(names: &[String], plan: &BatchPlan) -> Vec<usize> {
    if names.is_empty() {
        (0..plan.outputs().len()).collect()
    } else {
        names.iter().filter_map(|n| plan.output(n)).collect()
    }
}

/// One output row's identity and inputs.
struct Row<'a> {
    row: usize,
    state: Option<&'a str>,
    varied: &'a [(String, usize)],
    keys: &'a [String],
    params: &'a [f64],
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

impl Row<'_> {
    fn json(
        &self,
        buf: &mut String,
        okeys: &[String],
        sel: &[usize],
        plan: &BatchPlan,
        o: &[f64],
        error: Option<&str>,
    ) {
        let _ = write!(buf, "{{\"row\":{}", self.row);
        if let Some(s) = self.state {
            let _ = write!(buf, ",\"state\":{}", quoted(s));
        }
        for (k, (_, c)) in self.keys.iter().zip(self.varied) {
            let _ = write!(buf, ",{k}:");
            number(buf, self.params[*c], true);
        }
        match error {
            Some(e) => {
                let _ = write!(buf, ",\"error\":{}", quoted(e));
            }
            None => {
                for &i in sel {
                    let _ = write!(buf, ",{}:", okeys[i]);
                    number(buf, o[i], true);
                }
                if let Some(w) = warning(plan, o) {
                    let _ = write!(buf, ",\"warning\":{}", quoted(&w));
                }
            }
        }
        buf.push_str("}\n");
    }

    fn csv(
        &self,
        buf: &mut String,
        width: usize,
        cols: (&[usize], &[usize]),
        plan: &BatchPlan,
        o: &[f64],
        error: Option<&str>,
    ) {
        let (positions, sel) = cols;
        let _ = write!(buf, "{}", self.row);
        if let Some(s) = self.state {
            let _ = write!(buf, ",{}", csv_field(s));
        }
        for (_, c) in self.varied {
            buf.push(',');
            number(buf, self.params[*c], false);
        }
        let mut cells = vec![f64::NAN; width];
        if error.is_none() {
            for (&p, &i) in positions.iter().zip(sel) {
                cells[p] = o[i];
            }
        }
        for v in cells {
            buf.push(',');
            number(buf, v, false);
        }
        let w = if error.is_none() {
            warning(plan, o)
        } else {
            None
        };
        let _ = writeln!(
            buf,
            ",{},{}",
            csv_field(w.as_deref().unwrap_or("")),
            csv_field(error.unwrap_or(""))
        );
    }
}

/// Text of `--specs` lines per block: a block holds at most this much, and
/// at most [`BLOCK`] lines (parsing takes about 30 times the text, so a file
/// of large trains is read and solved a few lines at a time).
const SPECS_BLOCK_BYTES: usize = 16 << 20;

/// The non-blank lines of a `--specs` input, read a block at a time (the
/// file is never held whole). A line longer than a spec may be
/// ([`MAX_SPEC_BYTES`](egt_core::spec::parse::MAX_SPEC_BYTES)) is not kept:
/// its error stands in its place and the rest of it is skipped.
struct SpecLines<R> {
    reader: R,
    source: String,
    /// Lines read so far (blank ones included), for the line numbers.
    read: usize,
}

/// A `--specs` line: its number from 0, and its text or why it has none.
type SpecLine = (usize, Result<String, String>);

impl<R: std::io::BufRead> SpecLines<R> {
    /// The next block of lines; empty at the end of the input.
    fn next_block(&mut self) -> anyhow::Result<Vec<SpecLine>> {
        use egt_core::spec::parse::{MAX_SPEC_BYTES, check_spec_size};
        use std::io::{BufRead, Read};
        let (mut block, mut bytes) = (Vec::new(), 0);
        while block.len() < BLOCK && bytes < SPECS_BLOCK_BYTES {
            let mut buf = Vec::new();
            let n = (&mut self.reader)
                .take(MAX_SPEC_BYTES as u64 + 1)
                .read_until(b'\n', &mut buf)
                .with_context(|| format!("reading {}", self.source))?;
            if n == 0 {
                break;
            }
            let k = self.read;
            self.read += 1;
            let text = buf.strip_suffix(b"\n").unwrap_or(&buf);
            if text.len() > MAX_SPEC_BYTES {
                // The rest of the line, unread.
                loop {
                    let rest = self.reader.fill_buf()?;
                    if rest.is_empty() {
                        break;
                    }
                    let (used, done) = rest
                        .iter()
                        .position(|&c| c == b'\n')
                        .map_or((rest.len(), false), |i| (i + 1, true));
                    self.reader.consume(used);
                    if done {
                        break;
                    }
                }
                let name = format!("{}:{}", self.source, k + 1);
                let e = check_spec_size(text.len(), &name)
                    .err()
                    .map(|e| e.to_string());
                block.push((k, Err(e.unwrap_or_default())));
                continue;
            }
            match String::from_utf8(text.to_vec()) {
                Ok(t) if t.trim().is_empty() => {}
                Ok(t) => {
                    bytes += t.len();
                    block.push((k, Ok(t)));
                }
                Err(_) => block.push((k, Err("the line is not UTF-8 text".into()))),
            }
        }
        Ok(block)
    }
}

/// `--specs`: one whole spec per line, each its own train and plan.
fn run_specs(
    args: &Args,
    path: &PathBuf,
    compute: Compute,
    out: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    size_global_pool(args.threads);
    let reader: Box<dyn std::io::BufRead> = if path.as_os_str() == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        let file =
            std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
        Box::new(std::io::BufReader::with_capacity(1 << 20, file))
    };
    let source = path.display().to_string();
    let mut lines = SpecLines {
        reader,
        source: source.clone(),
        read: 0,
    };
    let json = args.output == BatchOutput::Jsonl;
    let mut columnar = match args.output {
        BatchOutput::Parquet | BatchOutput::Arrow => Some(long_columnar(args.output)?),
        BatchOutput::Jsonl | BatchOutput::Csv => None,
    };
    if !json && columnar.is_none() {
        out.write_all(b"row,name,quantity,value\n")?;
    }
    // The number of lines is not known before the end.
    let bar = ProgressBar::no_length();
    if let Ok(style) = ProgressStyle::with_template("{human_pos} specs") {
        bar.set_style(style);
    }
    let (mut failed, mut first_error) = (0, None);
    let mut first = 0;
    for b in 0.. {
        let block = lines.next_block()?;
        if block.is_empty() {
            break;
        }
        // Each line solved (its plan dropped at once), then written in the
        // output's form.
        let solved: Vec<Long> = block
            .par_iter()
            .map(|(line_no, line)| {
                let name = format!("{source}:{}", line_no + 1);
                let line = line.as_ref().map_err(|e| (name.clone(), e.clone()))?;
                match one_spec(line, &name, compute, args) {
                    Ok((title, plan, o)) => Ok(Solved {
                        title,
                        outputs: select(&args.columns, &plan)
                            .into_iter()
                            .map(|i| (plan.outputs()[i].clone(), o[i]))
                            .collect(),
                        warning: warning(&plan, &o),
                    }),
                    Err(e) => Err((name, format!("{e:#}"))),
                }
            })
            .collect();
        match columnar.as_mut() {
            Some((encoder, sink)) => sink.append(long_block(encoder, b, first, &solved)?, out)?,
            None => {
                let text: Vec<String> = solved
                    .par_iter()
                    .enumerate()
                    .map(|(r, s)| long_text(first + r, s, json))
                    .collect();
                for t in &text {
                    out.write_all(t.as_bytes())?;
                }
            }
        }
        for (r, s) in solved.iter().enumerate() {
            if let Err((name, e)) = s {
                failed += 1;
                first_error.get_or_insert(format!("row {} ({name}): {e}", first + r));
            }
        }
        first += block.len();
        bar.inc(block.len() as u64);
    }
    bar.finish_and_clear();
    if let Some((_, sink)) = columnar {
        sink.finish(out)?;
    }
    Ok((first, failed, first_error))
}

/// One `--specs` line as JSON Lines or as the CSV's long form (a row per
/// output, or one `error` row).
fn long_text(row: usize, s: &Long, json: bool) -> String {
    let mut buf = String::new();
    match s {
        Ok(l) if json => {
            let _ = write!(buf, "{{\"row\":{row},\"name\":{}", quoted(&l.title));
            for (q, v) in &l.outputs {
                let _ = write!(buf, ",{}:", quoted(q));
                number(&mut buf, *v, true);
            }
            if let Some(w) = &l.warning {
                let _ = write!(buf, ",\"warning\":{}", quoted(w));
            }
            buf.push_str("}\n");
        }
        Ok(l) => {
            for (q, v) in &l.outputs {
                let _ = write!(buf, "{row},{},{},", csv_field(&l.title), csv_field(q));
                number(&mut buf, *v, false);
                buf.push('\n');
            }
        }
        Err((name, msg)) if json => {
            let _ = writeln!(
                buf,
                "{{\"row\":{row},\"name\":{},\"error\":{}}}",
                quoted(name),
                quoted(msg)
            );
        }
        Err((name, msg)) => {
            let _ = writeln!(buf, "{row},{},error,{}", csv_field(name), csv_field(msg));
        }
    }
    buf
}

/// A solved `--specs` line: its title, its selected (output, value) pairs
/// and its condition warning.
struct Solved {
    title: String,
    outputs: Vec<(String, f64)>,
    warning: Option<String>,
}

/// One `--specs` line: solved, or its line name and error.
type Long = Result<Solved, (String, String)>;

/// Block `b` of `--specs` lines, whose first is row `first`, in long form,
/// as the CSV writes it: a row per selected output of each line, or one
/// `error` row for a failed line.
fn long_block(
    encoder: &Encoder,
    b: usize,
    first: usize,
    solved: &[Long],
) -> anyhow::Result<Encoded> {
    use arrow_array::{ArrayRef, Float64Array, StringArray, UInt64Array};
    use std::sync::Arc;
    let (mut row, mut name, mut quantity) = (Vec::new(), Vec::new(), Vec::new());
    let (mut value, mut error) = (Vec::new(), Vec::new());
    for (r, s) in solved.iter().enumerate() {
        let r = (first + r) as u64;
        match s {
            Ok(Solved { title, outputs, .. }) => {
                for (q, v) in outputs {
                    row.push(r);
                    name.push(title.as_str());
                    quantity.push(q.as_str());
                    value.push(v.is_finite().then_some(*v));
                    error.push(None);
                }
            }
            Err((line, e)) => {
                row.push(r);
                name.push(line.as_str());
                quantity.push("error");
                value.push(None);
                error.push(Some(e.as_str()));
            }
        }
    }
    let columns: Vec<ArrayRef> = vec![
        Arc::new(UInt64Array::from(row)),
        Arc::new(StringArray::from(name)),
        Arc::new(StringArray::from(quantity)),
        Arc::new(Float64Array::from(value)),
        Arc::new(StringArray::from(error)),
    ];
    encoder.record_batch(columns, b)
}

/// Parse, validate, prepare and solve one spec line.
fn one_spec(
    line: &str,
    name: &str,
    compute: Compute,
    args: &Args,
) -> anyhow::Result<(String, BatchPlan, Vec<f64>)> {
    let train = Train::from_str(line, Format::Json, name)?;
    let plan = BatchPlan::new(&train, &BatchSpec::from_analysis(&train, compute)?)?;
    let mut row = plan.base().to_vec();
    for (p, v) in &args.set {
        if let Some(c) = plan.parameter(p) {
            row[c] = *v;
        }
    }
    let mut o = vec![0.0; plan.outputs().len()];
    plan.worker().eval(&row, &mut o)?;
    let title = train
        .name()
        .map_or_else(|| name.to_string(), str::to_string);
    Ok((title, plan, o))
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use crate::cli::{Cli, Command};

    const FIG3: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/fig3_example61.toml"
    );

    /// Run `egt batch ARGS...`; the bytes written and the outcome.
    pub(super) fn batch_bytes(args: &[&str]) -> (Vec<u8>, anyhow::Result<()>) {
        let cli = Cli::try_parse_from(["egt", "batch"].iter().chain(args))
            .unwrap_or_else(|e| panic!("{e}"));
        let Command::Batch(a) = cli.command else {
            panic!("not a batch command")
        };
        let mut out = Vec::new();
        let r = super::run(&a, &mut out);
        (out, r)
    }

    /// Run `egt batch ARGS...`; the text written and the outcome.
    fn batch(args: &[&str]) -> (String, anyhow::Result<()>) {
        let (out, r) = batch_bytes(args);
        (String::from_utf8(out).unwrap_or_default(), r)
    }

    fn json_lines(text: &str) -> Vec<serde_json::Value> {
        text.lines()
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
            .collect()
    }

    /// Fig. 3's spec as one line of JSON (a `--specs` line).
    pub(super) fn fig3_json() -> String {
        let text = std::fs::read_to_string(FIG3).unwrap_or_else(|e| panic!("{FIG3}: {e}"));
        let good = egt_core::parse_spec(&text, egt_core::Format::Toml, "x")
            .unwrap_or_else(|e| panic!("{e}"));
        serde_json::to_string(&good).unwrap_or_else(|e| panic!("{e}"))
    }

    fn temp(name: &str, text: &str) -> String {
        let dir = std::env::temp_dir().join(format!("egt-batch-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap_or_else(|e| panic!("{e}"));
        p.display().to_string()
    }

    #[test]
    fn bad_rows_are_reported_in_place_and_the_rest_go_on() {
        let rows = temp(
            "rows.jsonl",
            "{\"torque.4\": -10}\nnot json\n{\"torque.9\": 1}\n{\"ratio.G1\": 0}\n{\"inertia.2\": -1}\n{\"torque.4\": -20, \"accel.4\": 0}\n",
        );
        let (text, r) = batch(&[FIG3, "--rows", &rows]);
        let lines = json_lines(&text);
        assert_eq!(lines.len(), 6, "{text}");
        for (k, l) in lines.iter().enumerate() {
            assert_eq!(l["row"], k);
        }
        let failed: Vec<usize> = (0..6)
            .filter(|&k| lines[k].get("error").is_some())
            .collect();
        assert_eq!(failed, vec![1, 2, 3, 4]);
        assert!(
            lines[2]["error"]
                .as_str()
                .unwrap_or("")
                .contains("torque.9")
        );
        assert!(
            lines[3]["error"]
                .as_str()
                .unwrap_or("")
                .contains("ratio.G1")
        );
        // The good rows carry results that differ as their loads do.
        let t0 = lines[0]["driving_torque.2"].as_f64().unwrap_or(f64::NAN);
        let t5 = lines[5]["driving_torque.2"].as_f64().unwrap_or(f64::NAN);
        assert!(t0.is_finite() && t5.is_finite() && t0 != t5);
        let e = r.expect_err("failed rows make the run fail");
        assert!(e.to_string().starts_with("4 of 6 scenarios failed"), "{e}");
    }

    /// Asking for no `cond.*` column (condition bounds in the lanes) keeps
    /// every number, warning and error: Fig. 3 swept through its lock
    /// (tau_2 = 1 / tau_1 = -1.5), where the rows next to it are warned
    /// about and the lock itself refused.
    #[test]
    fn columns_without_conditions_keep_the_warnings_and_errors() {
        let args = [
            FIG3,
            "--grid",
            "ratio.G2=-1.5000001:-1.4999999:21",
            "--grid",
            "torque.4=-10:-50:8",
            "--output",
            "csv",
        ];
        let table = |extra: &[&str]| {
            let all: Vec<&str> = args.iter().chain(extra).copied().collect();
            let (text, r) = batch(&all);
            assert!(r.is_err(), "the locked rows fail");
            let mut lines = text.lines();
            let header: Vec<String> = lines
                .next()
                .unwrap_or_default()
                .split(',')
                .map(String::from)
                .collect();
            let rows: Vec<Vec<String>> = lines
                .map(|l| l.split(',').map(String::from).collect())
                .collect();
            (header, rows)
        };
        let (h_all, all) = table(&[]);
        let (h_one, one) = table(&["--columns", "driving_torque.2"]);
        assert_eq!(all.len(), 168);
        assert_eq!(one.len(), all.len());
        let (mut warned, mut failed) = (0, 0);
        for name in ["row", "driving_torque.2", "warning", "error"] {
            let (i, j) = (
                h_all.iter().position(|h| h == name),
                h_one.iter().position(|h| h == name),
            );
            let (Some(i), Some(j)) = (i, j) else {
                panic!("no column {name}: {h_all:?} {h_one:?}")
            };
            for (a, b) in all.iter().zip(&one) {
                assert_eq!(a[i], b[j], "{name}, row {}", a[0]);
                warned += usize::from(name == "warning" && !a[i].is_empty());
                failed += usize::from(name == "error" && !a[i].is_empty());
            }
        }
        assert!(
            warned >= 16 && failed >= 8,
            "{warned} warned, {failed} failed"
        );
    }

    /// `number` writes what `{v:?}` writes, for every kind of double: edge
    /// values, random bit patterns, log-uniform magnitudes across the plain
    /// decimal range, short decimals, and doubles of few significant bits
    /// (where two shortest decimals are often equally near, the case zmij
    /// and std decide otherwise), of either sign; NaN and infinities empty
    /// in CSV, null in JSON.
    #[test]
    fn numbers_are_written_as_std_writes_them() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut values = vec![
            0.0,
            -0.0,
            1e-4,
            f64::from_bits(1e-4f64.to_bits() - 1),
            1e16,
            f64::from_bits(1e16f64.to_bits() - 1),
            1e-5,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            0.1,
            1.0 / 3.0,
            100.0,
            637_158_808_661_681.0 + 0.25,
            1.0 + 2f64.powi(-17),
        ];
        for i in 0..500_000u64 {
            let r = next();
            let sign = if r >> 63 == 0 { 1.0 } else { -1.0 };
            let unit = (r >> 11) as f64 / (1u64 << 53) as f64;
            values.push(match i % 5 {
                0 => f64::from_bits(r),
                1 => sign * 10f64.powf(-4.0 + 20.0 * unit),
                2 => sign * (r >> 11) as f64 / 10f64.powi((r % 12) as i32),
                3 => sign * (1.0 + (r >> 40) as f64 * 2f64.powi(-((r % 30) as i32 + 1))),
                _ => sign * (r >> 20) as f64 * 2f64.powi(-((r % 64) as i32)),
            });
        }
        let mut otherwise = 0;
        for v in values {
            for json in [false, true] {
                let mut got = String::new();
                super::number(&mut got, v, json);
                let want = match (v.is_finite(), json) {
                    (true, _) => format!("{v:?}"),
                    (false, true) => "null".to_string(),
                    (false, false) => String::new(),
                };
                assert_eq!(got, want, "{v:e} ({:#x})", v.to_bits());
                let mut digits = zmij::Buffer::new();
                otherwise += usize::from(v.is_finite() && !json && digits.format_finite(v) != want);
            }
        }
        // Many of them zmij alone writes otherwise (a tie, or an exponent).
        assert!(
            otherwise > 1000,
            "{otherwise} numbers zmij writes otherwise"
        );
    }

    #[test]
    fn vary_zips_grid_crosses_and_set_fixes() {
        let (text, r) = batch(&[
            FIG3,
            "--vary",
            "ratio.G1=-0.7,-0.6",
            "--vary",
            "accel.4=1,2",
            "--grid",
            "torque.4=-10:-30:3",
            "--set",
            "speed.2=50",
            "--output",
            "csv",
        ]);
        r.unwrap_or_else(|e| panic!("{e}"));
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        let col = |n: &str| {
            header
                .iter()
                .position(|h| *h == n)
                .unwrap_or_else(|| panic!("{n}"))
        };
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert_eq!(rows.len(), 6);
        let got: Vec<(&str, &str, &str, &str)> = rows
            .iter()
            .map(|r| {
                (
                    r[col("ratio.G1")],
                    r[col("accel.4")],
                    r[col("torque.4")],
                    r[col("speed.2")],
                )
            })
            .collect();
        assert_eq!(
            got,
            vec![
                ("-0.7", "1.0", "-10.0", "50.0"),
                ("-0.7", "1.0", "-20.0", "50.0"),
                ("-0.7", "1.0", "-30.0", "50.0"),
                ("-0.6", "2.0", "-10.0", "50.0"),
                ("-0.6", "2.0", "-20.0", "50.0"),
                ("-0.6", "2.0", "-30.0", "50.0"),
            ]
        );
        let (_, r) = batch(&[
            FIG3,
            "--vary",
            "ratio.G1=-0.7,-0.6",
            "--vary",
            "accel.4=1,2,3",
        ]);
        assert!(r.is_err(), "zipped arrays of unequal length");
        let (_, r) = batch(&[FIG3, "--grid", "ratio.G9=1,2"]);
        let e = r.expect_err("unknown parameter");
        assert!(format!("{e:#}").contains("ratio.G9"));
    }

    #[test]
    fn specs_file_one_train_per_line_with_a_broken_line() {
        let json = fig3_json();
        let specs = temp(
            "specs.jsonl",
            &format!("{json}\n{{\"frame\": 3}}\n{json}\n"),
        );
        let (text, r) = batch(&["--specs", &specs, "--columns", "driving_torque.2"]);
        let lines = json_lines(&text);
        assert_eq!(lines.len(), 3);
        assert!(lines[1].get("error").is_some());
        assert_eq!(lines[0]["driving_torque.2"], lines[2]["driving_torque.2"]);
        assert!(lines[0]["driving_torque.2"].as_f64().is_some());
        assert!(r.is_err());
    }

    /// A `--specs` input is read a block at a time: at most SPECS_BLOCK_BYTES
    /// of text (here 1 MiB lines: 16 a block), blank lines skipped, the line
    /// numbers running on across blocks.
    #[test]
    fn specs_lines_come_in_blocks_of_bounded_text() {
        use super::{SPECS_BLOCK_BYTES, SpecLines};
        let line = "x".repeat(1 << 20);
        let mut text = String::new();
        for k in 0..40 {
            text.push_str(&line);
            text.push('\n');
            if k % 10 == 3 {
                text.push_str("  \n");
            }
        }
        let mut lines = SpecLines {
            reader: std::io::Cursor::new(text.into_bytes()),
            source: "mem".into(),
            read: 0,
        };
        let (mut sizes, mut numbers) = (Vec::new(), Vec::new());
        loop {
            let block = lines.next_block().unwrap_or_else(|e| panic!("{e}"));
            if block.is_empty() {
                break;
            }
            let bytes: usize = block
                .iter()
                .map(|(_, l)| l.as_ref().map_or(0, String::len))
                .sum();
            assert!(bytes < SPECS_BLOCK_BYTES + (1 << 20));
            sizes.push(block.len());
            numbers.extend(block.iter().map(|(k, _)| *k));
        }
        assert_eq!(sizes, [16, 16, 8]);
        // Lines 4, 15, 26, 37 (from 0) are blank.
        let expected: Vec<usize> = (0..44).filter(|k| ![4, 15, 26, 37].contains(k)).collect();
        assert_eq!(numbers, expected);
    }

    /// A `--specs` line past the spec size limit (256 MiB + 1 byte, in a
    /// sparse file) is refused in its row, naming the limit, without
    /// stopping the lines after it.
    #[test]
    fn a_specs_line_past_the_size_limit_is_refused_in_its_row() {
        use std::io::{Seek, SeekFrom, Write as _};
        let json = fig3_json();
        let path = temp("huge.jsonl", "");
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .unwrap_or_else(|e| panic!("{e}"));
        let limit = egt_core::spec::parse::MAX_SPEC_BYTES as u64;
        f.seek(SeekFrom::Start(limit + 1))
            .and_then(|_| f.write_all(format!("\n{json}\n").as_bytes()))
            .unwrap_or_else(|e| panic!("{e}"));
        drop(f);
        let (text, r) = batch(&["--specs", &path, "--columns", "driving_torque.2"]);
        let _ = std::fs::remove_file(&path);
        let lines = json_lines(&text);
        assert_eq!(lines.len(), 2, "{text}");
        let e = lines[0]["error"].as_str().unwrap_or_default();
        assert!(e.contains("huge.jsonl:1") && e.contains("256 MiB"), "{e}");
        assert!(
            lines[1]["driving_torque.2"].as_f64().is_some(),
            "{}",
            lines[1]
        );
        assert!(r.is_err());
    }

    #[test]
    fn shift_table_states_share_a_csv_header() {
        let spec = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/zf_8hp70.toml");
        let (text, r) = batch(&[
            spec,
            "--state",
            "all",
            "--set",
            "speed.input=100",
            "--set",
            "torque.input=200",
            "--compute",
            "power",
            "--output",
            "csv",
            "--columns",
            "speed.output,power.efficiency",
        ]);
        r.unwrap_or_else(|e| panic!("{e}"));
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "row,state,speed.output,power.efficiency,warning,error"
        );
        assert_eq!(lines.len(), 10, "nine gear states");
        for l in &lines[1..] {
            let f: Vec<&str> = l.split(',').collect();
            let eta: f64 = f[3].parse().unwrap_or(f64::NAN);
            assert!(eta > 0.9 && eta <= 1.0, "{l}");
        }
    }
}

#[cfg(test)]
mod columnar_tests {
    use arrow_array::{Array, Float64Array, RecordBatch, StringArray, UInt64Array};

    use super::tests::batch_bytes as batch;

    fn example(name: &str) -> String {
        format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))
    }

    /// The cells of a CSV line (quoted fields with doubled quotes).
    fn cells(line: &str) -> Vec<String> {
        let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '"' if quoted && chars.peek() == Some(&'"') => {
                    cur.push('"');
                    chars.next();
                }
                '"' => quoted = !quoted,
                ',' if !quoted => out.push(std::mem::take(&mut cur)),
                c => cur.push(c),
            }
        }
        out.push(cur);
        out
    }

    /// Every cell of `batches` against the CSV of the same batch: numbers
    /// bit for bit (the CSV's shortest round-trip decimals), empty cells as
    /// nulls, texts equal.
    fn assert_same_as_csv(batches: &[RecordBatch], csv: &str) {
        let mut lines = csv.lines();
        let header = cells(lines.next().unwrap_or_default());
        let schema = batches[0].schema();
        let names: Vec<&str> = schema.fields().iter().map(|f| f.name().as_str()).collect();
        assert_eq!(names, header);
        let rows: Vec<Vec<String>> = lines.map(cells).collect();
        let mut r = 0;
        for b in batches {
            for i in 0..b.num_rows() {
                let row = &rows[r];
                for (c, col) in b.columns().iter().enumerate() {
                    let cell = &row[c];
                    let what = format!("row {r} column {}", header[c]);
                    if let Some(a) = col.as_any().downcast_ref::<Float64Array>() {
                        if cell.is_empty() {
                            assert!(a.is_null(i), "{what}: {} for an empty cell", a.value(i));
                        } else {
                            let v: f64 = cell.parse().unwrap_or_else(|e| panic!("{what}: {e}"));
                            assert!(a.is_valid(i), "{what}: null for {cell}");
                            assert_eq!(a.value(i).to_bits(), v.to_bits(), "{what}");
                        }
                    } else if let Some(a) = col.as_any().downcast_ref::<StringArray>() {
                        let got = if a.is_null(i) { "" } else { a.value(i) };
                        assert_eq!(got, cell, "{what}");
                    } else if let Some(a) = col.as_any().downcast_ref::<UInt64Array>() {
                        assert_eq!(a.value(i).to_string(), *cell, "{what}");
                    } else {
                        panic!("{what}: unexpected type {:?}", col.data_type());
                    }
                }
                r += 1;
            }
        }
        assert_eq!(r, rows.len(), "every CSV row is in the columnar file");
    }

    fn parquet_batches(bytes: Vec<u8>) -> Vec<RecordBatch> {
        let dir = std::env::temp_dir().join(format!("egt-columnar-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        let path = dir.join(format!("{}.parquet", bytes.len()));
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{e}"));
        let file = std::fs::File::open(&path).unwrap_or_else(|e| panic!("{e}"));
        let builder = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file)
            .unwrap_or_else(|e| panic!("{e}"));
        // The row numbers are delta-encoded in every row group.
        for g in builder.metadata().row_groups() {
            let row = g.column(0);
            assert_eq!(row.column_path().string(), "row");
            let delta = parquet::basic::Encoding::DELTA_BINARY_PACKED;
            assert!(
                row.encodings().any(|e| e == delta),
                "row encodings {:?}",
                row.encodings().collect::<Vec<_>>()
            );
        }
        builder
            .build()
            .unwrap_or_else(|e| panic!("{e}"))
            .collect::<Result<Vec<_>, _>>()
            .unwrap_or_else(|e| panic!("{e}"))
    }

    fn arrow_batches(bytes: Vec<u8>) -> Vec<RecordBatch> {
        arrow_ipc::reader::FileReader::try_new(std::io::Cursor::new(bytes), None)
            .unwrap_or_else(|e| panic!("{e}"))
            .collect::<Result<Vec<_>, _>>()
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// A grid's or a zip's columns filled in runs hold what row-by-row
    /// setting gives, whatever the block's start and length.
    #[test]
    fn grids_and_zips_fill_blocks_as_row_by_row() {
        use super::{Layout, Rows};
        let grid = |axes: &[usize], zip: usize| Rows::Product {
            zipped: (0..zip.min(1) * 2)
                .map(|z| (10 + z, (0..zip).map(|v| (100 * z + v) as f64).collect()))
                .collect(),
            axes: (axes.iter().enumerate())
                .map(|(a, &n)| (2 * a, (0..n).map(|v| (1000 * (a + 1) + v) as f64).collect()))
                .collect(),
            count: axes.iter().product::<usize>() * zip.max(1),
        };
        for (axes, zip) in [
            (vec![1000, 1000], 0),
            (vec![3, 5, 7], 0),
            (vec![7], 4),
            (vec![], 9),
            (vec![2, 1, 3], 5),
        ] {
            let rows = grid(&axes, zip);
            for (start, len) in [(0, 1), (0, 64), (5, 17), (999, 1002), (13, 300)] {
                let len = len.min(rows.count().saturating_sub(start));
                let mut by_columns = vec![f64::NAN; 12 * len];
                let mut by_rows = vec![f64::NAN; 12 * len];
                assert!(rows.fill((start, len), &mut by_columns, Layout::Columns));
                assert!(rows.fill((start, len), &mut by_rows, Layout::Rows(12)));
                // The varied columns only, in reverse order of their index.
                let Rows::Product { zipped, axes, .. } = &rows else {
                    unreachable!()
                };
                let mut set: Vec<usize> = zipped.iter().chain(axes).map(|z| z.0).collect();
                set.sort_unstable_by(|a, b| b.cmp(a));
                let mut slot = [None; 12];
                for (j, &c) in set.iter().enumerate() {
                    slot[c] = Some(j);
                }
                let mut by_varied = vec![f64::NAN; set.len() * len];
                assert!(rows.fill((start, len), &mut by_varied, Layout::Varied(&slot)));
                for r in 0..len {
                    let mut want = [f64::NAN; 12];
                    rows.set(start + r, |c, v| want[c] = v)
                        .unwrap_or_else(|e| panic!("{e}"));
                    for (c, w) in want.iter().enumerate() {
                        // (A column not varied is NaN in `want` and left out.)
                        let varied = slot[c].map_or(f64::NAN, |j| by_varied[j * len + r]);
                        for (got, layout) in [
                            (by_columns[c * len + r], "columns"),
                            (by_rows[r * 12 + c], "rows"),
                            (varied, "varied columns"),
                        ] {
                            assert!(
                                got.to_bits() == w.to_bits(),
                                "{axes:?} zip {zip} by {layout}: row {} column {c}: {got} against {w}",
                                start + r
                            );
                        }
                    }
                }
            }
        }
        assert!(!Rows::Listed(super::rows::Listed::empty()).fill((0, 0), &mut [], Layout::Columns));
    }

    /// Blocks come back in order whatever order they finish in; the writer
    /// solves blocks too, between its writes; an error of the writer stops
    /// the helpers within the window.
    #[test]
    fn in_order_writes_blocks_in_order_and_stops_on_an_error() {
        use super::{AHEAD, Buffers, in_order};
        use std::sync::atomic::{AtomicUsize, Ordering};
        let all = 40;
        let solved = AtomicUsize::new(0);
        let solvers = std::sync::Mutex::new(std::collections::HashMap::new());
        let solve = |(b, i): (&mut Buffers, usize)| {
            b.params.push(i as f64);
            // Later blocks finish sooner.
            std::thread::sleep(std::time::Duration::from_micros(((all - i) * 50) as u64));
            solved.fetch_add(1, Ordering::SeqCst);
            let mut by = solvers.lock().unwrap_or_else(|e| e.into_inner());
            *by.entry(std::thread::current().id()).or_insert(0) += 1;
            i
        };
        let mut seen = Vec::new();
        let mut ahead = 0;
        in_order(all, AHEAD, 3, &solve, |i| {
            if i == 0 {
                // A slow writer: the helpers wait, the window ahead of it.
                std::thread::sleep(std::time::Duration::from_millis(30));
                ahead = solved.load(Ordering::SeqCst);
            }
            seen.push(i);
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(seen, (0..all).collect::<Vec<_>>());
        assert!(
            ahead <= AHEAD * 3,
            "{ahead} blocks solved before the first was written"
        );
        assert_eq!(solved.load(Ordering::SeqCst), all);
        // Three threads solved, the writer one of them (no thread only waits).
        let by = std::mem::take(&mut *solvers.lock().unwrap_or_else(|e| e.into_inner()));
        assert!(by.len() <= 3, "{} threads solved", by.len());
        assert!(
            by.get(&std::thread::current().id()).is_some_and(|&n| n > 0),
            "the writer solved no block: {by:?}"
        );
        solved.store(0, Ordering::SeqCst);
        let failed = in_order(all, AHEAD, 3, &solve, |i| {
            anyhow::ensure!(i < 5, "full disk at block {i}");
            Ok(())
        });
        let e = failed.err().map(|e| e.to_string());
        assert_eq!(e.as_deref(), Some("full disk at block 5"));
        // Block 5 and those before it, and at most the window's past them.
        let n = solved.load(Ordering::SeqCst);
        assert!(n > 5 && n <= 6 + AHEAD * 3, "{n} blocks solved");
    }

    /// A large train's rows are wide, so its blocks hold fewer rows: at most
    /// `BLOCK_BYTES` of parameters and outputs at once (16 384 rows of a
    /// 10 000-link chain would be 10 GB a thread). Here 2 500 rows of a
    /// 1 502-link chain come out as Parquet row groups (one per block) of
    /// `block_rows` rows, and each driving torque balances its load (the
    /// alternating sets' speed ratio is 1).
    #[test]
    fn wide_rows_are_cut_into_short_blocks() {
        use super::{BLOCK, BLOCK_BYTES, COLUMNAR_BLOCK, block_rows};
        assert_eq!(block_rows(45, BLOCK), BLOCK);
        assert_eq!(block_rows(45, COLUMNAR_BLOCK), COLUMNAR_BLOCK);
        let w = 75_000;
        let r = block_rows(w, COLUMNAR_BLOCK);
        assert!(r < BLOCK && r * w * 8 <= BLOCK_BYTES && (r + 1) * w * 8 > BLOCK_BYTES);
        assert_eq!(block_rows(w, BLOCK), r);
        assert_eq!(block_rows(usize::MAX / 4, COLUMNAR_BLOCK), 1);

        let sets = 750;
        let mut spec = String::from("frame = \"case\"\n");
        for i in 1..=sets {
            let (sun, carrier) = if i % 2 == 1 {
                (format!("m{}", i - 1), format!("m{i}"))
            } else {
                (format!("m{i}"), format!("m{}", i - 1))
            };
            spec.push_str(&format!(
                "[[planetary]]\nname = \"P{i}\"\nsun = \"{sun}\"\nring = \"case\"\ncarrier = \"{carrier}\"\nteeth = {{ sun = 30, planet = 21, ring = 72 }}\n"
            ));
        }
        spec.push_str(&format!(
            "[analysis]\nspeeds = {{ m0 = 100.0 }}\ntorques = {{ m{sets} = -1.0 }}\ndriving = [\"m0\"]\n"
        ));
        let dir = std::env::temp_dir().join(format!("egt-wide-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        let path = dir.join("chain.toml");
        std::fs::write(&path, spec).unwrap_or_else(|e| panic!("{e}"));
        let path = path.display().to_string();
        let grid = format!("torque.m{sets}=-1:-2:2500");
        let args = [
            path.as_str(),
            "--grid",
            grid.as_str(),
            "--columns",
            "driving_torque.m0",
            "--output",
            "parquet",
        ];
        let (bytes, r) = batch(&args);
        r.unwrap_or_else(|e| panic!("{e}"));
        // The row groups as written (the reader's batches have a size of their own).
        let file = dir.join("out.parquet");
        std::fs::write(&file, &bytes).unwrap_or_else(|e| panic!("{e}"));
        let meta = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(
            std::fs::File::open(&file).unwrap_or_else(|e| panic!("{e}")),
        )
        .unwrap_or_else(|e| panic!("{e}"))
        .metadata()
        .clone();
        let sizes: Vec<i64> = meta.row_groups().iter().map(|g| g.num_rows()).collect();
        assert_eq!(sizes.iter().sum::<i64>(), 2500);
        assert!(sizes.len() >= 3, "row groups {sizes:?}");
        assert!(sizes.iter().all(|&s| s <= sizes[0]), "row groups {sizes:?}");
        let groups = parquet_batches(bytes);
        for g in &groups {
            let column = |name: &str| {
                g.column_by_name(name)
                    .and_then(|c| c.as_any().downcast_ref::<arrow_array::Float64Array>())
                    .unwrap_or_else(|| panic!("no column {name}"))
                    .clone()
            };
            let (load, driving) = (
                column(&format!("torque.m{sets}")),
                column("driving_torque.m0"),
            );
            for (t, d) in load.iter().zip(driving.iter()) {
                let (t, d) = (t.unwrap_or(f64::NAN), d.unwrap_or(f64::NAN));
                assert!(
                    (d + t).abs() <= 1e-9 * t.abs(),
                    "load {t}, driving torque {d}"
                );
            }
        }
    }

    /// Parquet and Arrow files hold the CSV's cells: a shift table (states,
    /// a varied torque) and rows with bad values (errors, empty outputs).
    #[test]
    fn parquet_and_arrow_hold_the_csv_cells() {
        let zf = example("zf_8hp70.toml");
        let fig3 = example("fig3_example61.toml");
        let dir = std::env::temp_dir().join(format!("egt-columnar-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        let rows = dir.join("rows.jsonl");
        std::fs::write(
            &rows,
            "{\"torque.4\": -10}\nnot json\n{\"ratio.G1\": 0}\n{\"torque.4\": -20, \"accel.4\": 0}\n",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let rows = rows.display().to_string();
        let shift = [
            zf.as_str(),
            "--state",
            "all",
            "--set",
            "speed.input=200",
            "--grid",
            "torque.input=0:400:5",
        ];
        let bad = [fig3.as_str(), "--rows", rows.as_str()];
        let bad_some = [
            fig3.as_str(),
            "--rows",
            rows.as_str(),
            "--columns",
            "driving_torque.2",
        ];
        // Three blocks and a part (Parquet's and Arrow's; twelve and a part
        // of text): blocks are solved in parallel waves and must come out in
        // order.
        let n = 3 * super::COLUMNAR_BLOCK + 100;
        let grid = format!("torque.4=-10:-20:{n}");
        let long = [
            fig3.as_str(),
            "--grid",
            grid.as_str(),
            "--columns",
            "driving_torque.2",
        ];
        // Through the lock of Fig. 3 (tau_2 = 1 / tau_1): warned and refused
        // rows, with and without the conditions' columns.
        let lock = [fig3.as_str(), "--grid", "ratio.G2=-1.5000001:-1.4999999:21"];
        let lock_some = [
            fig3.as_str(),
            "--grid",
            "ratio.G2=-1.5000001:-1.4999999:21",
            "--columns",
            "force.G1,driving_torque.2",
        ];
        // One warned row among unwarned ones, column-major (the scan for a
        // warning reads four rows at a time: row 2 is in the first four,
        // and the last row, read alone, is not warned).
        let lock_one = [
            fig3.as_str(),
            "--vary",
            "ratio.G2=-1.4,-1.45,-1.5000001,-1.55,-1.6,-1.65,-1.7,-1.75,-1.8",
            "--columns",
            "driving_torque.2",
        ];
        // Column-major blocks of the varied columns only (a program, a
        // ratio varied): a zip and grid axes, one axis twice, a fixed
        // value set; and every gear state of the 8HP70.
        let varied = [
            fig3.as_str(),
            "--vary",
            "ratio.G1=-2.1,-2.2,-2.3",
            "--grid",
            "ratio.G2=-1.2:-1.4:4",
            "--grid",
            "ratio.G2=-1.3:-1.5:2",
            "--grid",
            "torque.4=-10:-20:3",
            "--set",
            "inertia.2=0.5",
            "--columns",
            "driving_torque.2,speed.3",
        ];
        // Two blocks of a grid whose first axis holds each value for 100
        // rows and whose last repeats after 100 (egt writes the Snappy
        // streams of both: repeats.rs).
        let repeats = [
            fig3.as_str(),
            "--grid",
            "torque.4=-10:-20:300",
            "--grid",
            "ratio.G2=-1.2:-1.4:100",
            "--columns",
            "driving_torque.2",
        ];
        let states = [
            zf.as_str(),
            "--state",
            "all",
            "--set",
            "speed.input=200",
            "--grid",
            "ratio.P1/sun-planet=-1.9:-2.1:3",
            "--grid",
            "torque.input=100:200:2",
            "--columns",
            "driving_torque.output",
        ];
        for (args, ok) in [
            (&varied[..], true),
            (&repeats[..], true),
            (&states[..], true),
            (&shift[..], true),
            (&bad[..], false),
            (&bad_some[..], false),
            (&long[..], true),
            (&lock[..], false),
            (&lock_some[..], false),
            (&lock_one[..], true),
        ] {
            let with = |fmt: &str| {
                let mut a = args.to_vec();
                a.extend(["--output", fmt]);
                let (bytes, r) = batch(&a);
                assert_eq!(r.is_ok(), ok, "{fmt}");
                bytes
            };
            let csv = String::from_utf8(with("csv")).unwrap_or_else(|e| panic!("{e}"));
            if args[1..3] == lock[1..3] || args == lock_one {
                assert!(csv.contains("ill-conditioned"), "no warning: {csv}");
            }
            // Rows in order: numbered 0, 1, ... and the grid's values in its order.
            let mut last = f64::INFINITY;
            for (r, line) in csv.lines().skip(1).enumerate() {
                let c = cells(line);
                assert_eq!(c[0], r.to_string(), "row numbers in order");
                if args == long {
                    let t: f64 = c[1].parse().unwrap_or_else(|e| panic!("row {r}: {e}"));
                    assert!(t < last, "row {r}: torque.4 {t} after {last}");
                    last = t;
                }
            }
            let p = parquet_batches(with("parquet"));
            assert_same_as_csv(&p, &csv);
            let a = arrow_batches(with("arrow"));
            assert_same_as_csv(&a, &csv);
        }
    }

    /// A failed row's message stays in its row: a task's buffers reused
    /// after a block with a failure hold none in the later blocks (one
    /// thread, and two), as CSV and as Parquet.
    #[test]
    fn a_failed_row_leaves_no_message_in_later_blocks() {
        let fig3 = example("fig3_example61.toml");
        let n = 4 * super::COLUMNAR_BLOCK + 100;
        // Row 0 is Fig. 3's lock (tau_2 = -1.5), the others far from it.
        let grid = format!("ratio.G2=-1.5:-1.9:{n}");
        for threads in ["1", "2"] {
            let with = |fmt: &str| {
                let a = [
                    fig3.as_str(),
                    "--grid",
                    grid.as_str(),
                    "--columns",
                    "driving_torque.2",
                    "--threads",
                    threads,
                    "--output",
                    fmt,
                ];
                let (bytes, r) = batch(&a);
                let e = r.err().map(|e| e.to_string()).unwrap_or_default();
                assert!(
                    e.starts_with(&format!("1 of {n} scenarios failed")),
                    "{threads} threads, {fmt}: {e}"
                );
                bytes
            };
            let csv = String::from_utf8(with("csv")).unwrap_or_else(|e| panic!("{e}"));
            let failed: Vec<String> = (csv.lines().skip(1))
                .map(cells)
                .filter(|c| c.last().is_some_and(|e| !e.is_empty()))
                .map(|c| c[0].clone())
                .collect();
            assert_eq!(failed, ["0"], "{threads} threads");
            assert_same_as_csv(&parquet_batches(with("parquet")), &csv);
        }
    }

    #[test]
    fn binary_output_to_a_terminal_is_refused_naming_the_flag() {
        use clap::Parser;
        let args = |extra: &[&str]| {
            let mut a = vec!["egt", "batch", "x.toml"];
            a.extend(extra);
            match crate::cli::Cli::try_parse_from(a).map(|c| c.command) {
                Ok(crate::cli::Command::Batch(b)) => b,
                other => panic!("{other:?}"),
            }
        };
        for f in ["parquet", "arrow"] {
            let r = super::refuse_binary_to_terminal(&args(&["--output", f]));
            let e = format!("{:#}", r.err().unwrap_or_else(|| panic!("{f} accepted")));
            assert!(e.contains("--output") && e.contains("terminal"), "{e}");
            assert!(super::refuse_binary_to_terminal(&args(&["--output", f, "--list"])).is_ok());
        }
        for f in ["csv", "jsonl"] {
            assert!(super::refuse_binary_to_terminal(&args(&["--output", f])).is_ok());
        }
    }

    #[test]
    fn columnar_output_of_whole_spec_lines_holds_the_long_csv() {
        let json = super::tests::fig3_json();
        let dir = std::env::temp_dir().join(format!("egt-columnar-specs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        let specs = dir.join("specs.jsonl");
        std::fs::write(&specs, format!("{json}\n{{\"frame\": 3}}\n{json}\n"))
            .unwrap_or_else(|e| panic!("{e}"));
        let specs = specs.display().to_string();
        let with = |fmt: &str| {
            let (bytes, r) = batch(&["--specs", &specs, "--output", fmt]);
            assert!(r.is_err(), "{fmt}: the broken line fails the batch");
            bytes
        };
        let csv = String::from_utf8(with("csv")).unwrap_or_else(|e| panic!("{e}"));
        let rows: Vec<Vec<String>> = csv.lines().skip(1).map(cells).collect();
        assert!(rows.iter().any(|r| r[2] == "error"), "{csv}");
        assert!(rows.len() > 10, "{csv}");
        for batches in [
            parquet_batches(with("parquet")),
            arrow_batches(with("arrow")),
        ] {
            let names: Vec<String> = batches[0]
                .schema()
                .fields()
                .iter()
                .map(|f| f.name().clone())
                .collect();
            assert_eq!(names, ["row", "name", "quantity", "value", "error"]);
            let mut r = 0;
            for b in &batches {
                let col = |c: usize| b.column(c).as_any();
                let row = col(0).downcast_ref::<UInt64Array>();
                let name = col(1).downcast_ref::<StringArray>();
                let quantity = col(2).downcast_ref::<StringArray>();
                let value = col(3).downcast_ref::<Float64Array>();
                let error = col(4).downcast_ref::<StringArray>();
                let (Some(row), Some(name), Some(quantity), Some(value), Some(error)) =
                    (row, name, quantity, value, error)
                else {
                    panic!("unexpected column types: {:?}", b.schema());
                };
                for i in 0..b.num_rows() {
                    let csv = &rows[r];
                    let what = format!("row {r}");
                    assert_eq!(row.value(i).to_string(), csv[0], "{what}");
                    assert_eq!(name.value(i), csv[1], "{what}");
                    assert_eq!(quantity.value(i), csv[2], "{what}");
                    if csv[2] == "error" {
                        assert!(value.is_null(i), "{what}");
                        assert_eq!(error.value(i), csv[3], "{what}");
                    } else {
                        assert!(error.is_null(i), "{what}");
                        let v: f64 = csv[3].parse().unwrap_or_else(|e| panic!("{what}: {e}"));
                        assert_eq!(value.value(i).to_bits(), v.to_bits(), "{what}");
                    }
                    r += 1;
                }
            }
            assert_eq!(r, rows.len(), "every CSV row is in the columnar file");
        }
    }
}
