//! The worker: one thread's evaluator of rows, one by one or by the
//! straight-line program, with its buffers.

use crate::error::Result;
use crate::solve::prepared::{PROGRAM_BLOCK, Program, ProgramWorkspace};
use crate::solve::prepared::{Scenario, Workspace};

use super::linear::Linear;
use super::outputs::{check, write_outputs};
use super::plan::BatchPlan;
use super::run::RowError;

/// Fewest rows in a block for the straight-line program.
pub const PROGRAM_MIN_ROWS: usize = 4;

/// Coordinates up to which a batch with condition bounds runs the
/// straight-line program: every dense train.
pub const PROGRAM_MAX_COORDINATES: usize = crate::solve::prepared::PREPARED_SPARSE_FROM;

/// Buffers of the blocks a worker solves together: the program's block,
/// and the rows it leaves to be solved one by one.
#[derive(Debug)]
pub(super) struct Blocks {
    pub(super) program: Option<ProgramWorkspace>,
    /// Rows of the task the program left (their index, their parameters,
    /// their outputs): kept between tasks, so they allocate once.
    pub(super) left: Vec<usize>,
    pub(super) left_rows: Vec<f64>,
    pub(super) left_out: Vec<f64>,
    /// A task's rows of every output, when only some are chosen.
    pub(super) all: Vec<f64>,
}

/// The plan's program and a thread's workspace for it (`Blocks::program`).
pub(super) fn program_of<'p, 'w>(
    plan: &'p BatchPlan,
    pw: &'w mut Option<ProgramWorkspace>,
) -> (&'p Program, &'w mut ProgramWorkspace) {
    match (&plan.program, pw) {
        (Some(program), Some(pw)) => (program, pw),
        _ => unreachable!("a plan with a program gives its workspace"),
    }
}

/// Evaluates rows one at a time with buffers of its own.
#[derive(Debug)]
pub struct Worker<'a> {
    pub(super) plan: &'a BatchPlan,
    pub(super) ws: Workspace,
    /// A row of every output, when only some are chosen.
    pub(super) all: Vec<f64>,
}

impl Worker<'_> {
    /// Solve one row into `out`; on error `out` is filled with NaN. Allocates
    /// nothing unless the row fails.
    ///
    /// # Errors
    /// A non-finite or out-of-range parameter (naming it); the analysis errors
    /// of [`PreparedTrain::solve`](crate::solve::prepared::PreparedTrain::solve).
    ///
    /// # Panics
    /// When `row` or `out` has the wrong length.
    pub fn eval(&mut self, row: &[f64], out: &mut [f64]) -> Result<()> {
        let plan = self.plan;
        assert_eq!(row.len(), plan.parameters.len(), "wrong parameter count");
        assert_eq!(out.len(), plan.names.len(), "wrong output count");
        if plan.writes_all() {
            return self.eval_all(row, out);
        }
        let mut all = std::mem::take(&mut self.all);
        let result = self.eval_all(row, &mut all);
        plan.gather(&all, out);
        self.all = all;
        result
    }

    /// [`Worker::eval`] into every output column (`BatchPlan::all`).
    pub(super) fn eval_all(&mut self, row: &[f64], out: &mut [f64]) -> Result<()> {
        let result = self.eval_inner(row, out);
        if result.is_err() {
            out.iter_mut().for_each(|v| *v = f64::NAN);
        }
        result
    }

    fn eval_inner(&mut self, row: &[f64], out: &mut [f64]) -> Result<()> {
        let plan = self.plan;
        let g = plan.groups;
        check(plan, row)?;
        let s = Scenario {
            ratios: &row[g.ratio..g.speed],
            speeds: &row[g.speed..g.accel],
            accelerations: &row[g.accel..g.torque],
            torques: &row[g.torque..g.inertia],
            inertia: &row[g.inertia..g.mass],
            mass: &row[g.mass..g.efficiency],
            efficiency: &row[g.efficiency..g.end],
            mass_matrix: None,
        };
        let pt = &plan.prepared;
        pt.solve(&mut self.ws, &s, plan.compute)?;
        write_outputs(plan, &(&self.ws, plan), out);
        Ok(())
    }

    /// Rows one at a time (row-major); the failed ones, numbered from
    /// `first`, to `errors`.
    fn eval_rows(
        &mut self,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) {
        let (p, q) = (self.plan.parameters.len(), self.plan.all.len());
        for (r, (row, o)) in rows.chunks(p).zip(out.chunks_mut(q)).enumerate() {
            if let Err(error) = self.eval_all(row, o) {
                errors.push(RowError {
                    row: first + r,
                    error,
                });
            }
        }
    }

    /// The workspace of the last row (all coordinates, multipliers, mass matrix).
    pub fn workspace(&self) -> &Workspace {
        &self.ws
    }

    /// One task's rows (row-major) by the quickest path that applies: the
    /// linear path, the program, or row by row; how many rows the program
    /// solved.
    pub(super) fn eval_task(
        &mut self,
        lin: &mut Linear,
        blocks: &mut Blocks,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> usize {
        let plan = self.plan;
        // The paths other than the program write every output: into `out`
        // when all are chosen, else into `blocks.all` and then the chosen.
        let mut all = std::mem::take(&mut blocks.all);
        let whole = plan.writes_all();
        if !whole {
            all.clear();
            all.resize(rows.len() / plan.parameters.len() * plan.all.len(), 0.0);
        }
        let target = if whole { &mut *out } else { &mut all[..] };
        let mut solved = 0;
        let wrote = if self.eval_linear(lin, rows, target, first, errors) {
            // Solved as y0 + sum p_j R_j.
            true
        } else if plan.program_applies(rows) {
            solved = self.eval_program(blocks, rows, out, first, errors);
            false
        } else {
            let target = if whole { &mut *out } else { &mut all[..] };
            self.eval_rows(rows, target, first, errors);
            true
        };
        if wrote && !whole {
            plan.gather_rows(&all, out);
        }
        blocks.all = all;
        solved
    }

    /// A block of rows by the straight-line program ([`PROGRAM_BLOCK`] rows at
    /// once); the rows it leaves (a bad parameter, other pivots, a bound past
    /// `COND_WARN` / 2, a result not finite) are then solved one by one.
    /// Returns how many rows the program solved.
    pub(super) fn eval_program(
        &mut self,
        blocks: &mut Blocks,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> usize {
        let plan = self.plan;
        let (p, q) = (plan.parameters.len(), plan.names.len());
        let (program, pw) = program_of(plan, &mut blocks.program);
        blocks.left.clear();
        blocks.left_rows.clear();
        for (k, (block, bout)) in rows
            .chunks(p * PROGRAM_BLOCK)
            .zip(out.chunks_mut(q * PROGRAM_BLOCK))
            .enumerate()
        {
            program.run(pw, block, p);
            program.write(pw, bout);
            if pw.all_valid {
                continue;
            }
            for (r, row) in block.chunks(p).enumerate() {
                if !pw.valid[r] {
                    blocks.left.push(k * PROGRAM_BLOCK + r);
                    blocks.left_rows.extend_from_slice(row);
                }
            }
        }
        let solved = rows.len() / p - blocks.left.len();
        self.eval_left(blocks, first, errors);
        for (&i, o) in blocks
            .left
            .iter()
            .zip(blocks.left_out.chunks(plan.all.len()))
        {
            plan.gather(o, &mut out[i * q..(i + 1) * q]);
        }
        solved
    }

    /// [`Worker::eval_program`] on a block held column by column: `column(k)`
    /// is the block's part of parameter column `k`, `out[o]` of output column `o`.
    pub(super) fn eval_program_columns<'c>(
        &mut self,
        blocks: &mut Blocks,
        column: impl Fn(usize) -> &'c [f64],
        out: &mut [&mut [f64]],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> usize {
        let plan = self.plan;
        let p = plan.parameters.len();
        let n = out.first().map_or(0, |c| c.len());
        let (program, pw) = program_of(plan, &mut blocks.program);
        blocks.left.clear();
        blocks.left_rows.clear();
        // Outputs written in place, unless their columns crowd the cache's
        // sets (a matrix of 512 x 2^k rows): then through the block's slots.
        let crowded = crate::solve::prepared::crowded(out.iter().map(|c| c.as_ptr() as usize));
        for at in (0..n).step_by(PROGRAM_BLOCK) {
            let to = n.min(at + PROGRAM_BLOCK);
            program.solve_columns(pw, &column, out, (at, to), crowded);
            if pw.all_valid {
                continue;
            }
            for r in at..to {
                if !pw.valid[r - at] {
                    blocks.left.push(r);
                    blocks.left_rows.extend((0..p).map(|k| column(k)[r]));
                }
            }
        }
        let solved = n - blocks.left.len();
        self.eval_left(blocks, first, errors);
        let q = plan.all.len();
        for (&i, o) in blocks.left.iter().zip(blocks.left_out.chunks(q)) {
            for (c, &k) in out.iter_mut().zip(&plan.chosen) {
                c[i] = o[k];
            }
        }
        solved
    }

    /// The rows the program left (`blocks.left_rows`, row-major) one by one
    /// into `blocks.left_out`; their errors numbered from `first`.
    fn eval_left(&mut self, blocks: &mut Blocks, first: usize, errors: &mut Vec<RowError>) {
        let plan = self.plan;
        let q = plan.all.len();
        if blocks.left.is_empty() {
            blocks.left_out.clear();
            return;
        }
        let (left, left_rows, mut left_out) = (
            std::mem::take(&mut blocks.left),
            std::mem::take(&mut blocks.left_rows),
            std::mem::take(&mut blocks.left_out),
        );
        left_out.clear();
        left_out.resize(left.len() * q, 0.0);
        let mut failed = Vec::new();
        self.eval_rows(&left_rows, &mut left_out, 0, &mut failed);
        errors.extend(failed.into_iter().map(|e| RowError {
            row: first + left[e.row],
            error: e.error,
        }));
        (blocks.left, blocks.left_rows, blocks.left_out) = (left, left_rows, left_out);
    }
}
