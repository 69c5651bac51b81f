//! One spec's scenarios (`--vary`, `--grid`, `--rows`, `--state`): its
//! plans, the output's columns, and its blocks solved, encoded and written
//! in order, step by step.

use std::fmt::Write as _;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use egt_core::batch::{BatchPlan, BatchSpec, Threads};
use egt_core::solve::prepared::Compute;
use egt_core::{Error, SpecErrorKind};

use super::block::Sweep;
use super::columnar::{columnar, design_metadata};
use super::design::{Design, design, unknown};
use super::order::{AHEAD, batch_threads, in_order, size_global_pool};
use super::text::{csv_field, quoted};
use super::{
    Args, BLOCK, BatchOutput, COLUMNAR_BLOCK, Encoded, Outcome, block_rows, interrupted, select,
};
use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::interrupt;
use crate::progress::Progress;

/// One plan's share of the output: which of the CSV columns it fills.
pub(super) struct Columns {
    /// For each output column of the plan, its CSV position.
    pub(super) positions: Vec<usize>,
}

/// A plan for each gear state asked for (one, None, without `--state`).
pub(super) type Plans = Vec<(Option<String>, BatchPlan)>;

pub(super) fn run_one_spec(
    args: &Args,
    compute: Compute,
    out: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    let threads = batch_threads(args.threads);
    let plans = load_plans(args, compute)?;
    if args.list {
        list(&plans, out)?;
        return Ok((0, 0, None));
    }
    let mut design = design(args, &plans[0].1)?;
    check_columns(args, &plans)?;
    let plans = narrow(args, plans)?;
    let first = &plans[0].1;
    // The output columns written, per plan.
    let selected: Vec<Vec<usize>> = plans
        .iter()
        .map(|(_, p)| select(&args.columns, p))
        .collect();
    let base = base_row(args, first)?;
    let (header, columns) = output_columns(&plans, &selected);
    // A varied speed or acceleration is also an output column (the same value): write it once.
    design.varied.retain(|(name, _)| !header.contains(name));
    let json = args.output == BatchOutput::Jsonl;
    let (encoder, mut sink) = match args.output {
        BatchOutput::Parquet | BatchOutput::Arrow => {
            let states = plans[0].0.is_some();
            let (e, s) = columnar(
                args.output,
                states,
                &design.varied,
                &header,
                design_metadata(args),
            )?;
            (Some(e), Some(s))
        }
        BatchOutput::Jsonl | BatchOutput::Csv => (None, None),
    };
    if !json && encoder.is_none() {
        csv_header(&design, plans[0].0.is_some(), &header, out)?;
    }
    let per_plan = design.rows.count();
    let total = per_plan * plans.len();
    let bar = Progress::new(args.progress, "scenarios", Some(total as u64));
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
    let sweep = Sweep {
        plans: &plans,
        columns: &columns,
        selected: &selected,
        design: &design,
        base: &base,
        slot: &slot,
        encoder: encoder.as_ref(),
        json,
        keys: &keys,
        okeys: &okeys,
        header_len: header.len(),
        per_plan,
        block,
        blocks,
        within,
    };
    // Blocks are solved and encoded in the pool's tasks, each task taking
    // the next block as soon as it has finished one, and written in order
    // on this thread, which only copies bytes (docs/performance.md (history: git log -p -- docs/benchmarks.md) has the
    // history: waves of blocks left a thread idle while the other finished
    // its block and while this one wrote).
    let ahead = if block < most { 1 } else { AHEAD };
    // Ctrl-C: the writer stops before the next block, so that the output
    // ends after a whole block (a Parquet or Arrow file is then closed).
    let (mut written, mut stopped) = (0, false);
    let run = in_order(all, ahead, threads, &|(b, i)| sweep.solve(b, i), |d| {
        if interrupt::requested() {
            stopped = true;
            anyhow::bail!("interrupted");
        }
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
        written += d.len;
        bar.add(d.len as u64);
        Ok(())
    });
    drop(bar);
    if !stopped {
        run?;
    }
    if let Some(sink) = sink {
        sink.finish(out)?;
    }
    if stopped {
        return Err(interrupted(written, Some(total), failed, "scenarios"));
    }
    Ok((total, failed, first_error))
}

/// The spec's plans: one from its `[analysis]`, or one per gear state.
fn load_plans(args: &Args, compute: Compute) -> anyhow::Result<Plans> {
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
    let plans = if states.is_empty() {
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
    Ok(plans)
}

/// `--list`: the parameters with the spec's values, and each plan's outputs.
fn list(plans: &Plans, out: &mut dyn Write) -> anyhow::Result<()> {
    let first = &plans[0].1;
    writeln!(out, "parameters (with the spec's values):")?;
    for (p, v) in first.parameters().iter().zip(first.base()) {
        writeln!(out, "  {p} = {v}")?;
    }
    for (state, plan) in plans {
        match state {
            Some(s) => writeln!(out, "outputs (gear state {s}):")?,
            None => writeln!(out, "outputs:")?,
        }
        writeln!(out, "  {}", plan.outputs().join(", "))?;
    }
    Ok(())
}

/// Every `--columns` name is an output of some plan.
fn check_columns(args: &Args, plans: &Plans) -> anyhow::Result<()> {
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
    Ok(())
}

/// Each plan computes only the columns asked for (that it has), and the
/// conditions, which give the warnings. No `cond.*` column asked for:
/// estimate a condition only where a bound cannot show it below the
/// warning level (the same warnings and errors). The straight-line
/// program is compiled once, for the columns chosen (`--list` compiles
/// none).
fn narrow(args: &Args, plans: Plans) -> anyhow::Result<Plans> {
    let bounds = BatchPlan::bounds_serve(&args.columns);
    (plans.into_iter())
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
        .collect()
}

/// The row every scenario starts from: the spec's values, with `--set`'s.
fn base_row(args: &Args, first: &BatchPlan) -> anyhow::Result<Vec<f64>> {
    let mut base = first.base().to_vec();
    for (name, v) in &args.set {
        let c = first
            .parameter(name)
            .ok_or_else(|| unknown(first, name, "--set"))?;
        base[c] = *v;
    }
    Ok(base)
}

/// The union of the plans' selected outputs, in order of appearance, and
/// each plan's place in it.
fn output_columns(plans: &Plans, selected: &[Vec<usize>]) -> (Vec<String>, Vec<Columns>) {
    let mut header: Vec<String> = Vec::new();
    let mut columns = Vec::new();
    for ((_, plan), sel) in plans.iter().zip(selected) {
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
    (header, columns)
}

/// The CSV header: row, state, varied parameters, the union of outputs,
/// warning, error.
fn csv_header(
    design: &Design,
    states: bool,
    header: &[String],
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let mut h = String::from("row");
    if states {
        h.push_str(",state");
    }
    for (name, _) in &design.varied {
        let _ = write!(h, ",{}", csv_field(name));
    }
    for o in header {
        let _ = write!(h, ",{}", csv_field(o));
    }
    h.push_str(",warning,error\n");
    out.write_all(h.as_bytes())?;
    Ok(())
}
