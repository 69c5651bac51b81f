//! `--specs`: a JSON Lines file of whole specs, one train a line, read a
//! block at a time and written in the long form (a row per output).

use std::fmt::Write as _;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use egt_core::batch::{BatchPlan, BatchSpec};
use egt_core::solve::prepared::Compute;
use egt_core::{Format, Train};
use rayon::prelude::*;

use super::columnar::{Encoder, long_columnar};
use super::order::size_global_pool;
use super::text::{csv_field, number, quoted};
use super::{Args, BLOCK, BatchOutput, Encoded, Outcome, interrupted, select, warning};
use crate::interrupt;
use crate::progress::Progress;

/// Text of `--specs` lines per block: a block holds at most this much, and
/// at most [`BLOCK`] lines (parsing takes about 30 times the text, so a file
/// of large trains is read and solved a few lines at a time).
pub(super) const SPECS_BLOCK_BYTES: usize = 16 << 20;

/// The non-blank lines of a `--specs` input, read a block at a time (the
/// file is never held whole). A line longer than a spec may be
/// ([`MAX_SPEC_BYTES`](egt_core::spec::parse::MAX_SPEC_BYTES)) is not kept:
/// its error stands in its place and the rest of it is skipped.
pub(super) struct SpecLines<R> {
    pub(super) reader: R,
    pub(super) source: String,
    /// Lines read so far (blank ones included), for the line numbers.
    pub(super) read: usize,
}

/// A `--specs` line: its number from 0, and its text or why it has none.
pub(super) type SpecLine = (usize, Result<String, String>);

impl<R: std::io::BufRead> SpecLines<R> {
    /// The next block of lines; empty at the end of the input.
    pub(super) fn next_block(&mut self) -> anyhow::Result<Vec<SpecLine>> {
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
pub(super) fn run_specs(
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
    let bar = Progress::new(args.progress, "specs", None);
    let (mut failed, mut first_error) = (0, None);
    let mut first = 0;
    for b in 0.. {
        // Ctrl-C: stop before the next block; the output ends after a whole one.
        if interrupt::requested() {
            drop(bar);
            if let Some((_, sink)) = columnar {
                sink.finish(out)?;
            }
            return Err(interrupted(first, None, failed, "specs lines"));
        }
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
        bar.add(block.len() as u64);
    }
    drop(bar);
    if let Some((_, sink)) = columnar {
        sink.finish(out)?;
    }
    Ok((first, failed, first_error))
}

/// One `--specs` line as JSON Lines or as the CSV's long form (a row per
/// output, or one `error` row).
pub(super) fn long_text(row: usize, s: &Long, json: bool) -> String {
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
pub(super) struct Solved {
    title: String,
    outputs: Vec<(String, f64)>,
    warning: Option<String>,
}

/// One `--specs` line: solved, or its line name and error.
pub(super) type Long = Result<Solved, (String, String)>;

/// Block `b` of `--specs` lines, whose first is row `first`, in long form,
/// as the CSV writes it: a row per selected output of each line, or one
/// `error` row for a failed line.
pub(super) fn long_block(
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
pub(super) fn one_spec(
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
