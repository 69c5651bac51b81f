//! Running a batch: the one entry point [`BatchPlan::run`] (row-major,
//! column-major or a set of columns; on the pool or the calling thread),
//! its tasks and the tasks' states, and the spare states a plan keeps
//! between calls.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::error::Error;
use crate::solve::prepared::Workspace;

use super::linear::Linear;
use super::outputs::{all_finite, overflowed, refuse};
use super::plan::BatchPlan;
use super::worker::{Blocks, PROGRAM_MIN_ROWS, Worker};

/// The worker threads for a batch: the request, capped at the machine's
/// parallelism (more threads than cores only add switching, and a huge
/// request would exhaust the machine), with a note when the cap applied.
/// `None` or 0 asks for all cores. (The machine's parallelism is read once
/// a process: Linux's reading opens cgroup files, about 50 µs.)
pub fn worker_threads(requested: Option<usize>) -> (usize, Option<String>) {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    let cores = *CORES.get_or_init(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    match requested {
        None | Some(0) => (cores, None),
        Some(n) if n > cores => (
            cores,
            Some(format!(
                "{n} threads asked for; using {cores}, the machine's parallelism"
            )),
        ),
        Some(n) => (n, None),
    }
}

/// Rows solved by one worker before rayon may hand the rest to another thread.
pub(super) const ROWS_PER_TASK: usize = 256;

/// A failed row.
#[derive(Debug, Clone, PartialEq)]
pub struct RowError {
    /// Index of the row.
    pub row: usize,
    /// Why it failed.
    pub error: Error,
}

impl BatchPlan {
    /// The rows of `params`, whose length must be a whole number of rows
    /// with `out` as long in outputs.
    ///
    /// # Panics
    /// When the slice lengths do not match the column counts.
    fn rows_of(&self, params: &[f64], out: &[f64]) -> usize {
        let (p, q) = (self.parameters.len(), self.names.len());
        let rows = params.len().checked_div(p).unwrap_or(0);
        assert_eq!(
            params.len(),
            rows * p,
            "params is not a whole number of rows"
        );
        assert_eq!(
            out.len(),
            rows * q,
            "out does not have one row per scenario"
        );
        rows
    }

    /// Solve every row of a batch into `out`, in parallel on the current
    /// rayon pool ([`Threads::Pool`]; on the calling thread when the batch
    /// is one task, 256 rows or fewer, or the pool has one thread) or on the
    /// calling thread only ([`Threads::Calling`]): the same numbers and
    /// errors, bit for bit, on either and in every [`Layout`]. Failed rows
    /// get NaN outputs and are returned, in row order, with whether every
    /// row was shown well-conditioned ([`Solved::bounded`]).
    ///
    /// The linear path (a block whose ratios, inertias, masses and
    /// efficiencies are equal in every row) and, with condition bounds, the
    /// straight-line program read and write a column-major block a column
    /// at a time with no transposition; other blocks' rows are transposed
    /// into the row-major solve and back.
    ///
    /// # Panics
    /// When the lengths do not match the column counts: `out` must be the
    /// rows times `outputs().len()`, a row-major or column-major `params`
    /// a whole number of rows of `parameters().len()` values, a
    /// [`Layout::ColumnSet`] a column for each parameter with every
    /// [`Column::Rows`] `rows` long.
    pub fn run(&self, layout: Layout<'_>, out: &mut [f64], threads: Threads) -> Solved {
        let unbounded = AtomicUsize::new(0);
        let errors = match layout {
            Layout::Rows(params) => self.run_rows(threads, params, out, &unbounded),
            Layout::Columns(params) => {
                let rows = self.rows_of(params, out);
                if rows == 0 {
                    Vec::new()
                } else {
                    let inputs = params.chunks(rows).map(|c| (c, false)).collect();
                    self.run_inputs(threads, inputs, rows, out, &unbounded)
                }
            }
            Layout::ColumnSet { columns, rows } => {
                self.column_set(threads, columns, rows, out, &unbounded)
            }
        };
        Solved {
            errors,
            bounded: unbounded.into_inner() == 0,
        }
    }

    /// [`BatchPlan::run`] of a row-major batch.
    fn run_rows(
        &self,
        threads: Threads,
        params: &[f64],
        out: &mut [f64],
        unbounded: &AtomicUsize,
    ) -> Vec<RowError> {
        let (p, q) = (self.parameters.len(), self.names.len());
        self.rows_of(params, out);
        let tasks: Vec<(&[f64], &mut [f64])> = params
            .chunks(p * ROWS_PER_TASK)
            .zip(out.chunks_mut(q * ROWS_PER_TASK))
            .collect();
        each_task(threads, tasks, self, |t, task, (pin, pout)| {
            let mut errors = Vec::new();
            let first = task * ROWS_PER_TASK;
            let n = pin.len() / p.max(1);
            let solved =
                t.w.eval_task(&mut t.lin, &mut t.blocks, pin, pout, first, &mut errors);
            unbounded.fetch_add(n - solved, Ordering::Relaxed);
            if !all_finite(pout) {
                let n = pout.len() / q;
                let bad = overflowed(self, n, first, |r, o| pout[r * q + o], &errors);
                for &(r, _) in &bad {
                    pout[r * q..(r + 1) * q].fill(f64::NAN);
                }
                refuse(self, bad, first, &mut errors);
            }
            errors
        })
    }
}

/// How a batch's parameters are laid out ([`BatchPlan::run`]); `out` has the
/// same layout, one column per output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Layout<'a> {
    /// Row-major: row `r`'s parameters are `params[r * p..(r + 1) * p]`
    /// (`p` = `parameters().len()`), and its outputs likewise in `out`.
    Rows(&'a [f64]),
    /// Column-major: parameter column `k` is `params[k * rows..(k + 1) *
    /// rows]`, output column `o` is `out[o * rows..(o + 1) * rows]` (a NumPy
    /// array in Fortran order, or the columns of an Arrow record batch).
    Columns(&'a [f64]),
    /// Column-major, each parameter column given row by row or as one value
    /// for every row ([`Column`]): a sweep of a few parameters of a train
    /// passes those few columns and the others' values, and no column of
    /// repeated values is built or read (a fixed column is read from a short
    /// buffer of its value, at most 256 rows long, that stays in cache).
    ColumnSet {
        /// One per parameter.
        columns: &'a [Column<'a>],
        /// The rows of the batch.
        rows: usize,
    },
}

/// What [`BatchPlan::run`] reports beside its outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct Solved {
    /// The rows that failed (their outputs NaN), in row order.
    pub errors: Vec<RowError>,
    /// Whether every row's `cond.*` values are at most `COND_WARN` / 2, so
    /// that no row is warned about: true when the straight-line program,
    /// with condition bounds, solved every row (a row it leaves, which is
    /// estimated or refused, or a block another path solves, makes it
    /// false). A caller that warns about a large condition number need not
    /// read those columns then.
    pub bounded: bool,
}

/// One parameter column of a column-major batch ([`Layout::ColumnSet`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Column<'a> {
    /// A value for each row.
    Rows(&'a [f64]),
    /// One value for every row.
    Every(f64),
}

/// Where a batch call ([`BatchPlan::run`]) runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Threads {
    /// In parallel on the current rayon pool; on the calling thread when
    /// the batch is one task (256 rows or fewer) or the pool has one thread.
    #[default]
    Pool,
    /// On the calling thread only. For a caller with threads of its own (a
    /// process pool, a server's request threads) or with small batches:
    /// handing work to a pool thread and waiting for it costs a wake-up
    /// each way, about 100 µs a call on the machine of docs/performance.md (history: git log -p -- docs/benchmarks.md).
    Calling,
}

/// `f(state, index, task)` for every task, on the current rayon pool with a
/// state per thread; the errors in row order. One task, a pool of one
/// thread, or [`Threads::Calling`] runs on the calling thread: handing work
/// to a pool thread and waiting for it (a wake-up each way) cost about 100
/// µs a call on the machine of docs/performance.md (history: git log -p -- docs/benchmarks.md), as much as 2 500 rows'
/// solves. There the state is one the plan kept from an earlier call
/// (building it cost more than solving 64 rows), and is kept again after.
pub(super) fn each_task<T: Send>(
    threads: Threads,
    tasks: Vec<T>,
    plan: &BatchPlan,
    f: impl Fn(&mut TaskState<'_>, usize, T) -> Vec<RowError> + Sync + Send,
) -> Vec<RowError> {
    let here = threads == Threads::Calling || tasks.len() <= 1;
    let mut errors: Vec<RowError> = if here || rayon::current_num_threads() <= 1 {
        let mut state = plan.spares.take(plan);
        let errors = (tasks.into_iter().enumerate())
            .flat_map(|(i, t)| f(&mut state, i, t))
            .collect();
        plan.spares.keep(state);
        errors
    } else {
        (tasks.into_par_iter().enumerate())
            .map_init(|| TaskState::new(plan), |state, (i, t)| f(state, i, t))
            .flatten()
            .collect()
    };
    errors.sort_by_key(|e| e.row);
    errors
}

impl BatchPlan {
    /// [`BatchPlan::run`] of a [`Layout::ColumnSet`], counting in `unbounded`
    /// the rows the program did not solve.
    fn column_set(
        &self,
        threads: Threads,
        params: &[Column<'_>],
        rows: usize,
        out: &mut [f64],
        unbounded: &AtomicUsize,
    ) -> Vec<RowError> {
        let (p, q) = (self.parameters.len(), self.names.len());
        assert_eq!(params.len(), p, "params is not a column for each parameter");
        assert_eq!(
            out.len(),
            rows * q,
            "out does not have one row per scenario"
        );
        if rows == 0 {
            return Vec::new();
        }
        // Each fixed column's value, as long as a task, in one buffer: every
        // task reads it there. Each is 64 bytes longer than that, so that
        // they do not all start at one offset modulo 4 KiB (`crowded`).
        let n = rows.min(ROWS_PER_TASK);
        let stride = n + 8;
        let mut fixed = Vec::new();
        for c in params {
            match *c {
                Column::Rows(v) => {
                    assert_eq!(v.len(), rows, "a parameter column is not `rows` long");
                }
                Column::Every(v) => fixed.extend(std::iter::repeat_n(v, stride)),
            }
        }
        let mut at = 0;
        let inputs = (params.iter())
            .map(|c| match *c {
                Column::Rows(v) => (v, false),
                Column::Every(_) => {
                    at += stride;
                    (&fixed[at - stride..at - 8], true)
                }
            })
            .collect();
        self.run_inputs(threads, inputs, rows, out, unbounded)
    }

    /// [`BatchPlan::run`] of column-major `inputs`: each parameter column
    /// whole (`(column, false)`) or, fixed, as long as a task (`true`).
    /// `unbounded` counts the rows the straight-line program did not solve
    /// ([`Solved::bounded`]).
    fn run_inputs(
        &self,
        threads: Threads,
        inputs: Vec<(&[f64], bool)>,
        rows: usize,
        out: &mut [f64],
        unbounded: &AtomicUsize,
    ) -> Vec<RowError> {
        let (p, q) = (self.parameters.len(), self.names.len());
        // Each task: its rows of every output column.
        let mut tasks: Vec<Vec<&mut [f64]>> = (0..rows.div_ceil(ROWS_PER_TASK))
            .map(|_| Vec::with_capacity(q))
            .collect();
        for column in out.chunks_mut(rows) {
            for (task, part) in tasks.iter_mut().zip(column.chunks_mut(ROWS_PER_TASK)) {
                task.push(part);
            }
        }
        each_task(threads, tasks, self, |t, task, mut cols| {
            let TaskState {
                w,
                lin,
                blocks,
                pin,
                pout,
            } = t;
            let mut errors = Vec::new();
            let first = task * ROWS_PER_TASK;
            let n = cols.first().map_or(0, |c| c.len());
            'solve: {
                let column = |k: usize| match inputs[k] {
                    (c, false) => &c[first..first + n],
                    (c, true) => &c[..n],
                };
                let linear = self.linear_may(column, n);
                if !linear && self.program.is_some() && n >= PROGRAM_MIN_ROWS {
                    let solved =
                        w.eval_program_columns(blocks, column, &mut cols, first, &mut errors);
                    unbounded.fetch_add(n - solved, Ordering::Relaxed);
                    break 'solve;
                }
                // Not the program's rows: their `cond.*` may be anything.
                unbounded.fetch_add(n, Ordering::Relaxed);
                if linear {
                    // Column by column, as `eval_linear` would row by row.
                    if w.eval_linear_columns(lin, column, &mut cols, first, &mut errors) {
                        break 'solve;
                    }
                }
                // Transposed into rows, solved as `run` does, and back, a
                // tile of TILE rows at a time: the tile's rows stay in L1
                // while every column passes. (Column by column over the
                // whole task, a row-major buffer larger than L1 was read
                // again from L2 for every column: 337 ns a row at 10 links
                // against 46 for the same rows row-major, docs/performance.md (history: git log -p -- docs/benchmarks.md).)
                const TILE: usize = 8;
                pin.clear();
                pin.resize(n * p, 0.0);
                for (t, tile) in pin.chunks_mut(TILE * p).enumerate() {
                    let at = t * TILE;
                    for k in 0..p {
                        let c = &column(k)[at..];
                        for (d, &v) in tile[k..].iter_mut().step_by(p).zip(c) {
                            *d = v;
                        }
                    }
                }
                pout.clear();
                pout.resize(n * q, 0.0);
                w.eval_task(lin, blocks, pin, pout, first, &mut errors);
                for (t, tile) in pout.chunks(TILE * q).enumerate() {
                    let at = t * TILE;
                    for (o, c) in cols.iter_mut().enumerate() {
                        for (d, &v) in c[at..].iter_mut().zip(tile[o..].iter().step_by(q)) {
                            *d = v;
                        }
                    }
                }
            }
            if !cols.iter().all(|c| all_finite(c)) {
                let bad = overflowed(self, n, first, |r, o| cols[o][r], &errors);
                for &(r, _) in &bad {
                    for c in cols.iter_mut() {
                        c[r] = f64::NAN;
                    }
                }
                refuse(self, bad, first, &mut errors);
            }
            errors
        })
    }
}

/// What a batch task works with: a worker, the linear path's and the
/// program's buffers, and the transposition's (column-major calls).
pub(super) struct TaskState<'a> {
    pub(super) w: Worker<'a>,
    pub(super) lin: Linear,
    pub(super) blocks: Blocks,
    pub(super) pin: Vec<f64>,
    pub(super) pout: Vec<f64>,
}

impl<'a> TaskState<'a> {
    fn new(plan: &'a BatchPlan) -> Self {
        TaskState {
            w: plan.worker(),
            lin: Linear::default(),
            blocks: plan.blocks(),
            pin: Vec::new(),
            pout: Vec::new(),
        }
    }
}

/// A [`TaskState`]'s buffers, without the plan.
pub(super) struct Spare {
    pub(super) ws: Workspace,
    pub(super) all: Vec<f64>,
    pub(super) lin: Linear,
    pub(super) blocks: Blocks,
    pub(super) pin: Vec<f64>,
    pub(super) pout: Vec<f64>,
}

/// Buffers a plan keeps from its calls on a calling thread for the next
/// ones (at most [`SPARES`], for callers on several threads at once): a
/// call of 8 rows spent more on building and freeing them than on solving
/// (docs/performance.md (history: git log -p -- docs/benchmarks.md)). A clone of the plan starts with none; so does a
/// plan whose program or prepared train changes (`BatchPlan::reprogram`).
#[derive(Default)]
pub(super) struct Spares(std::sync::Mutex<Vec<Spare>>);

impl std::fmt::Debug for Spares {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kept = self.0.lock().map_or(0, |v| v.len());
        write!(f, "Spares({kept} kept)")
    }
}

/// Most buffers a plan keeps.
pub(super) const SPARES: usize = 4;

impl Clone for Spares {
    fn clone(&self) -> Self {
        Spares::default()
    }
}

impl Spares {
    /// A kept state, or a new one.
    fn take<'a>(&self, plan: &'a BatchPlan) -> TaskState<'a> {
        let spare = self.0.lock().ok().and_then(|mut v| v.pop());
        match spare {
            Some(s) => TaskState {
                w: Worker {
                    plan,
                    ws: s.ws,
                    all: s.all,
                },
                lin: s.lin,
                blocks: s.blocks,
                pin: s.pin,
                pout: s.pout,
            },
            None => TaskState::new(plan),
        }
    }

    /// Keep `t`'s buffers (dropped when [`SPARES`] are kept already, or
    /// when another thread panicked holding the lock).
    fn keep(&self, t: TaskState<'_>) {
        if let Ok(mut v) = self.0.lock()
            && v.len() < SPARES
        {
            v.push(Spare {
                ws: t.w.ws,
                all: t.w.all,
                lin: t.lin,
                blocks: t.blocks,
                pin: t.pin,
                pout: t.pout,
            });
        }
    }
}
