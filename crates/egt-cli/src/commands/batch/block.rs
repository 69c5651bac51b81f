//! One block of a spec's scenarios, in a worker task: its parameters
//! filled from the design, its rows solved, and the block encoded as text,
//! Parquet or Arrow.

use egt_core::batch::{self, BatchPlan, Column, Threads};
use rayon::prelude::*;

use super::Encoded;
use super::columnar::{Block, Encoder, Matrix};
use super::design::{Design, Layout, Rows};
use super::order::Buffers;
use super::sweep::{Columns, Plans};
use super::text::{TextBlock, format_text};

/// One block solved and encoded in a worker task, to be written in order.
pub(super) struct Done {
    pub(super) len: usize,
    pub(super) encoded: Encoded,
    pub(super) failed: usize,
    pub(super) first_error: Option<String>,
}

/// What every block of a sweep shares.
pub(super) struct Sweep<'a> {
    pub(super) plans: &'a Plans,
    pub(super) columns: &'a [Columns],
    pub(super) selected: &'a [Vec<usize>],
    pub(super) design: &'a Design,
    /// The row every scenario starts from.
    pub(super) base: &'a [f64],
    /// Parameter column `c`'s place among the varied ones, if it is one.
    pub(super) slot: &'a [Option<usize>],
    pub(super) encoder: Option<&'a Encoder>,
    pub(super) json: bool,
    pub(super) keys: &'a [String],
    pub(super) okeys: &'a [Vec<String>],
    pub(super) header_len: usize,
    /// Scenarios a plan, and a block.
    pub(super) per_plan: usize,
    pub(super) block: usize,
    /// Blocks a plan.
    pub(super) blocks: usize,
    pub(super) within: Threads,
}

/// How a block's parameters are held ([`Sweep::parameters`]).
#[derive(Clone, Copy)]
struct Shape {
    /// Column-major.
    by_columns: bool,
    /// Column-major, the varied columns only.
    varied_only: bool,
    /// Columns a row.
    width: usize,
}

impl Sweep<'_> {
    /// Block `i` of the whole batch: plan `i / blocks`, its block `i % blocks`.
    pub(super) fn solve(&self, buffers: &mut Buffers, i: usize) -> anyhow::Result<Done> {
        let (k, b) = (i / self.blocks, i % self.blocks);
        let plan = &self.plans[k].1;
        let start = b * self.block;
        let len = self.block.min(self.per_plan - start);
        let (shape, unreadable) = self.parameters(plan, buffers, start, len);
        let bounded = self.run(plan, shape, buffers, len, unreadable);
        let base_row = k * self.per_plan + start;
        let encoded = self.encode(k, i, base_row, shape, bounded, buffers)?;
        let Buffers {
            messages,
            failed_rows,
            ..
        } = buffers;
        Ok(Done {
            len,
            encoded,
            failed: failed_rows.len(),
            first_error: (failed_rows.first())
                .and_then(|&r| Some(format!("row {}: {}", base_row + r, messages[r].as_ref()?))),
        })
    }

    /// Rows `start..start + len` of the design into the buffers' parameters;
    /// how they are held, and the rows that could not be read.
    fn parameters(
        &self,
        plan: &BatchPlan,
        buffers: &mut Buffers,
        start: usize,
        len: usize,
    ) -> (Shape, Vec<(usize, String)>) {
        let (design, base) = (self.design, self.base);
        // Parquet and Arrow take a block column-major when the straight-line
        // program solves it: it reads and writes whole columns, and the
        // encoders copy them. Otherwise (a sweep of loads, speeds or
        // accelerations goes to the linear path) and for text, row-major,
        // as the other paths solve rows (docs/performance.md (history: git log -p -- docs/benchmarks.md) has the A/B).
        let by_columns = self.encoder.is_some()
            && plan.has_program()
            && (design.varied.iter()).any(|&(_, c)| !plan.is_linear_parameter(c));
        let np = plan.parameters().len();
        let Buffers {
            params,
            params_by_columns,
            ..
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
                for &v in base {
                    params.extend(std::iter::repeat_n(v, len));
                }
            } else {
                for _ in 0..len {
                    params.extend_from_slice(base);
                }
            }
        }
        let layout = if varied_only {
            Layout::Varied(self.slot)
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
            match self.within {
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
        let shape = Shape {
            by_columns,
            varied_only,
            width,
        };
        (shape, unreadable)
    }

    /// Solve the block's `len` rows into the buffers' results, and set its
    /// messages: the rows' errors and the `unreadable` ones. Whether every
    /// row's condition numbers are known to be below the warning's (the
    /// compiled program, with bounds, solved every row), so that the
    /// block's warnings need no scan.
    fn run(
        &self,
        plan: &BatchPlan,
        shape: Shape,
        buffers: &mut Buffers,
        len: usize,
        unreadable: Vec<(usize, String)>,
    ) -> bool {
        let (base, slot, within) = (self.base, self.slot, self.within);
        let nq = plan.outputs().len();
        let Buffers {
            params, results, ..
        } = buffers;
        // `run` writes every output of every row (NaN on failed rows).
        results.resize(len * nq, 0.0);
        let (errors, bounded) = if shape.varied_only {
            let columns: Vec<Column<'_>> = (base.iter().zip(slot))
                .map(|(&v, j)| match *j {
                    Some(j) => Column::Rows(&params[j * len..][..len]),
                    None => Column::Every(v),
                })
                .collect();
            let solved = plan.run(
                batch::Layout::ColumnSet {
                    columns: &columns,
                    rows: len,
                },
                results,
                within,
            );
            (solved.errors, solved.bounded)
        } else if shape.by_columns {
            (
                plan.run(batch::Layout::Columns(params), results, within)
                    .errors,
                false,
            )
        } else {
            (
                plan.run(batch::Layout::Rows(params), results, within)
                    .errors,
                false,
            )
        };
        let errors = errors.into_iter().map(|e| (e.row, e.error.to_string()));
        buffers.set_messages(len, errors.chain(unreadable));
        bounded
    }

    /// Block `i` (plan `k`'s, from row `base_row` of the batch) as text,
    /// Parquet or Arrow.
    fn encode(
        &self,
        k: usize,
        i: usize,
        base_row: usize,
        shape: Shape,
        bounded: bool,
        buffers: &mut Buffers,
    ) -> anyhow::Result<Encoded> {
        let (state, plan) = &self.plans[k];
        let (cols, sel) = (&self.columns[k], &self.selected[k]);
        let (np, nq) = (plan.parameters().len(), plan.outputs().len());
        let Buffers {
            params,
            results,
            messages,
            failed_rows,
            ..
        } = buffers;
        let len = messages.len();
        // Parquet encodes a column-major block's columns where they are: the
        // buffers are lent to Arrow for the encoding (an Arrow IPC batch
        // outlives it, and takes copies).
        let lent = (shape.by_columns && self.encoder.is_some_and(Encoder::parquet)).then(|| {
            let lend = |v: &mut Vec<f64>| arrow_buffer::Buffer::from_vec(std::mem::take(v));
            (lend(params), lend(results))
        });
        let (pdata, rdata): (&[f64], &[f64]) = match &lent {
            Some((p, r)) => (p.typed_data(), r.typed_data()),
            None => (params, results),
        };
        let encoded = match self.encoder {
            Some(c) => c.encode(
                plan,
                &Block {
                    index: i,
                    first_row: base_row,
                    state: state.as_deref(),
                    varied: &self.design.varied,
                    varied_only: shape.varied_only,
                    params: Matrix {
                        data: pdata,
                        shared: lent.as_ref().map(|l| &l.0),
                        width: shape.width,
                        rows: len,
                        columns: shape.by_columns,
                    },
                    results: Matrix {
                        data: rdata,
                        shared: lent.as_ref().map(|l| &l.1),
                        width: nq,
                        rows: len,
                        columns: shape.by_columns,
                    },
                    positions: (&cols.positions, sel),
                    messages,
                    any_failed: !failed_rows.is_empty(),
                    bounded,
                },
            ),
            None => Ok(Encoded::Text(format_text(
                TextBlock {
                    json: self.json,
                    base_row,
                    state: state.as_deref(),
                    design: self.design,
                    keys: self.keys,
                    okeys: &self.okeys[k],
                    header_len: self.header_len,
                    positions: (&cols.positions, sel),
                },
                plan,
                (params, np),
                (results, nq),
                messages,
                self.within,
            ))),
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
        encoded
    }
}
