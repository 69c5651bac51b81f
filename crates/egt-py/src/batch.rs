//! Batch evaluation for screening, over egt-core's [`BatchPlan`]: one prepared
//! train, a row-major parameter matrix (one row per scenario, named columns
//! such as `ratio.G1`, `speed.sun`, `inertia.3`), solved in parallel (rayon,
//! one workspace per worker) with the GIL released.
//!
//! Rows are independent. A row that cannot be solved is reported by index,
//! kind and message; its outputs are set to 0.0 here (egt-core writes NaN), so
//! the arrays handed to Python never hold NaN: `ok` says which rows are valid.
//! The one NaN a valid row could carry, `power.efficiency` without input
//! power, is written as 0.0 too (documented in `egt.BatchResult`).

use egt_core::batch::{BatchPlan, BatchSpec, Column, Executor, Layout, Threads};
use egt_core::solve::prepared::Compute;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, mat2};
use crate::errors::{Result, guard, kind, value_error};
use crate::train::TrainCore;

/// A batch's outputs (rows x outputs) and its failed rows as (row, kind,
/// message).
type Solved<'py> = (
    Bound<'py, PyArray2<f64>>,
    Vec<(usize, &'static str, String)>,
);

/// A prepared batch (see `egt.BatchPlan`).
#[pyclass(frozen, module = "egt._egt", name = "BatchPlanCore")]
#[derive(Debug)]
pub struct BatchPlanCore {
    plan: BatchPlan,
}

fn compute_of(s: &str) -> Result<Compute> {
    match s {
        "kinematics" => Ok(Compute::Kinematics),
        "dynamics" => Ok(Compute::Dynamics),
        "power" => Ok(Compute::Power),
        other => Err(value_error(format!(
            "compute must be \"kinematics\", \"dynamics\" or \"power\", got {other:?}"
        ))),
    }
}

/// Prepare a batch. `inputs`, `accelerated`, `driving` default to the spec's
/// `[analysis]` choices (accelerated and driving: the inputs); with
/// `gear_state`, to the transmission's input in that state, whose engaged
/// elements are added to `engaged`. `condition_bounds`: see
/// [`BatchPlan::with_condition_bounds`] (None: [`BatchPlan::bounds_serve`]
/// of `outputs`, as `egt batch --columns`); `outputs`: see
/// [`BatchPlan::with_outputs`]; `executor`: how the straight-line program
/// runs, `"auto"` (compiled where the machine runs the code) or
/// `"interpreted"` (see [`BatchPlan::with_executor`]).
// One argument per Python keyword.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (core, compute, inputs = None, accelerated = None, driving = None, engaged = Vec::new(), gear_state = None, condition_bounds = None, outputs = None, executor = "auto"))]
pub fn batch_plan(
    core: &TrainCore,
    compute: &str,
    inputs: Option<Vec<String>>,
    accelerated: Option<Vec<String>>,
    driving: Option<Vec<String>>,
    engaged: Vec<String>,
    gear_state: Option<String>,
    condition_bounds: Option<bool>,
    outputs: Option<Vec<String>>,
    executor: &str,
) -> Result<BatchPlanCore> {
    let compute = compute_of(compute)?;
    let executor = match executor {
        "auto" => Executor::Auto,
        "interpreted" => Executor::Interpreted,
        other => {
            return Err(value_error(format!(
                "executor must be \"auto\" or \"interpreted\", got {other:?}"
            )));
        }
    };
    guard(|| {
        let t = &core.train;
        let mut spec = match (&gear_state, &inputs) {
            (Some(state), _) => BatchSpec::for_gear_state(t, state, compute)?,
            (None, Some(_)) => BatchSpec {
                compute,
                ..BatchSpec::default()
            },
            (None, None) => BatchSpec::from_analysis(t, compute)?,
        };
        if let Some(names) = &inputs {
            spec.inputs = convert::links(t, names, "inputs")?;
            spec.accelerated = spec.inputs.clone();
            spec.driving = spec.inputs.clone();
        }
        if let Some(names) = &accelerated {
            spec.accelerated = convert::links(t, names, "accelerations")?;
        }
        if let Some(names) = &driving {
            spec.driving = convert::links(t, names, "driving")?;
        }
        spec.extras
            .extend(engaged.iter().cloned().zip(convert::engaged(t, &engaged)?));
        let bounds = condition_bounds
            .unwrap_or_else(|| outputs.as_deref().is_some_and(BatchPlan::bounds_serve));
        // The outputs first: the program is then compiled once, for them.
        let mut plan = BatchPlan::new(t, &spec)?;
        if let Some(names) = &outputs {
            plan = plan.with_outputs(names)?;
        }
        let plan = plan.with_executor(executor).with_condition_bounds(bounds);
        Ok(BatchPlanCore { plan })
    })
}

#[pymethods]
impl BatchPlanCore {
    /// Parameter column names, in row order.
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.plan.parameters().to_vec()
    }

    /// Output column names, in row order.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.plan.outputs().to_vec()
    }

    /// The plan's straight-line program: `"compiled"` (to machine code for
    /// the train), `"interpreted"`, or None (no program: rows are
    /// solved in SIMD groups of eight). Rows that vary only loads, speeds
    /// or accelerations share one factorisation instead, whatever this says.
    #[getter]
    fn program(&self) -> Option<&'static str> {
        self.plan
            .has_program()
            .then_some(if self.plan.program_compiled() {
                "compiled"
            } else {
                "interpreted"
            })
    }

    /// The spec's own parameter values (NaN where the spec gives none).
    #[getter]
    fn base<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        convert::vec1(py, self.plan.base().to_vec())
    }

    /// Solve every row of `params` (rows x parameters, float64, C- or
    /// Fortran-contiguous) in parallel with the GIL released; `threads`
    /// sizes a private pool (default: rayon's global pool), and
    /// `threads=1` solves on the calling thread with no pool. Returns the
    /// outputs (rows x outputs, in the order of `params`: a Fortran-ordered
    /// input is solved column by column, `Layout::Columns`, and each
    /// output column comes back contiguous; 0.0 in failed rows) and the
    /// failed rows as (row, kind, message).
    #[pyo3(signature = (params, threads = None))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        params: PyReadonlyArray2<'py, f64>,
        threads: Option<usize>,
    ) -> Result<Solved<'py>> {
        let p = self.plan.parameters().len();
        let shape = params.shape();
        if shape[1] != p {
            return Err(value_error(format!(
                "params has {} columns, the plan has {p} parameters",
                shape[1]
            )));
        }
        let rows = shape[0];
        // A C-contiguous array is read as rows (also when it is both, one
        // row or one column); otherwise a Fortran-contiguous one as columns.
        let columns = !params.is_c_contiguous() && params.is_fortran_contiguous();
        let input = params
            .as_slice()
            .map_err(|_| value_error("params must be C- or Fortran-contiguous"))?;
        self.solve(py, rows, columns, threads, |threads, out| {
            if columns {
                self.plan.run(Layout::Columns(input), out, threads).errors
            } else {
                self.plan.run(Layout::Rows(input), out, threads).errors
            }
        })
    }

    /// Solve `rows` scenarios from the base row `base` with the parameter
    /// columns `varied` given row by row ((column, values), each `rows`
    /// long; the later of two for one column wins) and every other column
    /// at its `base` value, which no matrix holds
    /// (`Layout::ColumnSet`). Returns what `run` returns for a
    /// Fortran-ordered input.
    #[pyo3(signature = (base, varied, rows, threads = None))]
    fn run_set<'py>(
        &self,
        py: Python<'py>,
        base: PyReadonlyArray1<'py, f64>,
        varied: Vec<(usize, PyReadonlyArray1<'py, f64>)>,
        rows: usize,
        threads: Option<usize>,
    ) -> Result<Solved<'py>> {
        let p = self.plan.parameters().len();
        let base = base
            .as_slice()
            .map_err(|_| value_error("base must be contiguous"))?;
        if base.len() != p {
            return Err(value_error(format!(
                "base has {} values, the plan has {p} parameters",
                base.len()
            )));
        }
        let mut set: Vec<Column<'_>> = base.iter().map(|&v| Column::Every(v)).collect();
        for (k, values) in &varied {
            let name = self.plan.parameters().get(*k).ok_or_else(|| {
                value_error(format!("no parameter column {k} (the plan has {p})"))
            })?;
            let v = values
                .as_slice()
                .map_err(|_| value_error(format!("the values of {name} must be contiguous")))?;
            if v.len() != rows {
                return Err(value_error(format!(
                    "{name} has {} values for {rows} rows",
                    v.len()
                )));
            }
            set[*k] = Column::Rows(v);
        }
        self.solve(py, rows, true, threads, |threads, out| {
            self.plan
                .run(
                    Layout::ColumnSet {
                        columns: &set,
                        rows,
                    },
                    out,
                    threads,
                )
                .errors
        })
    }

    /// The plan's columns and base row as a dict (for repr and debugging).
    fn describe<'py>(&self, py: Python<'py>) -> Result<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("parameters", self.parameters())?;
        d.set_item("outputs", self.outputs())?;
        d.set_item("base", self.base(py))?;
        Ok(d)
    }
}

impl BatchPlanCore {
    /// `solve(threads, out)` for `rows` rows with the GIL released, on the
    /// pool `threads` asks for; the outputs (rows x outputs, Fortran-ordered
    /// when `columns`; 0.0 in failed rows and for an undefined efficiency)
    /// and the failed rows as (row, kind, message).
    fn solve<'py>(
        &self,
        py: Python<'py>,
        rows: usize,
        columns: bool,
        threads: Option<usize>,
        solve: impl Fn(Threads, &mut [f64]) -> Vec<egt_core::batch::RowError> + Send + Sync,
    ) -> Result<Solved<'py>> {
        let q = self.plan.outputs().len();
        let efficiency = self.plan.output("power.efficiency");
        guard(|| {
            // Refused, not aborted, when the outputs cannot be held (a
            // mapping of scalars with a large `rows` builds no input first).
            let cells = rows.saturating_mul(q);
            let mut out: Vec<f64> = Vec::new();
            out.try_reserve_exact(cells).map_err(|_| {
                pyo3::exceptions::PyMemoryError::new_err(format!(
                    "the outputs of {rows} rows ({q} columns of 8-byte numbers) do not fit in memory"
                ))
            })?;
            out.resize(cells, 0.0);
            // Element (row, output) of `out`.
            let at = |r: usize, o: usize| if columns { o * rows + r } else { r * q + o };
            let errors = py.detach(|| -> Result<_> {
                let errors = match threads {
                    // No pool to build and hand the call to (a thread's
                    // start and a wake-up each way).
                    Some(1) => solve(Threads::Calling, &mut out),
                    Some(n) => rayon::ThreadPoolBuilder::new()
                        .num_threads(egt_core::batch::worker_threads(Some(n)).0)
                        .build()
                        .map_err(|e| value_error(e.to_string()))?
                        .install(|| solve(Threads::Pool, &mut out)),
                    None => solve(Threads::Pool, &mut out),
                };
                for e in &errors {
                    for o in 0..q {
                        out[at(e.row, o)] = 0.0;
                    }
                }
                if let Some(c) = efficiency {
                    for r in 0..rows {
                        if out[at(r, c)].is_nan() {
                            out[at(r, c)] = 0.0;
                        }
                    }
                }
                Ok(errors)
            })?;
            let errors = errors
                .into_iter()
                .map(|e| (e.row, kind(&e.error), e.error.to_string()))
                .collect();
            let values = convert::mat2_ordered(py, rows, q, out, columns)?;
            Ok((values, errors))
        })
    }
}

/// A refused row: (row, error kind, message).
type Refused = (usize, String, String);

/// Willis ratios from tooth counts, `teeth` of shape (rows, gears, 2), by the
/// core's one rule (`Train::ratios_from_teeth`): the (rows, gears) ratios and
/// the rows whose counts are refused, as (row, kind, message); their ratios
/// are -1.0 so that the batch still runs (the caller marks them failed).
///
/// # Errors
/// A gear pair whose mesh kind is unknown (the whole request fails).
#[pyfunction]
pub fn ratios_from_teeth<'py>(
    py: Python<'py>,
    core: &TrainCore,
    teeth: numpy::PyReadonlyArray3<'py, i64>,
) -> Result<(Bound<'py, PyArray2<f64>>, Vec<Refused>)> {
    guard(|| {
        let t = &core.train;
        let g = t.gears().len();
        let shape = teeth.shape();
        if shape.len() != 3 || shape[1] != g || shape[2] != 2 {
            return Err(value_error(format!(
                "`teeth` must have shape (rows, {g}, 2), got {shape:?}"
            )));
        }
        let z = teeth.as_slice().map_err(|e| value_error(e.to_string()))?;
        let rows = shape[0];
        let mut out = vec![0.0; rows * g];
        let mut bad = Vec::new();
        let mut counts = vec![[0i64; 2]; g];
        for (r, row) in out.chunks_mut(g.max(1)).enumerate().take(rows) {
            for (m, c) in counts.iter_mut().enumerate() {
                *c = [z[(r * g + m) * 2], z[(r * g + m) * 2 + 1]];
            }
            match t.ratios_from_teeth(&format!("teeth[{r}]"), &counts, row) {
                Ok(()) => {}
                // No mesh kind for a pair: no row can have ratios; refuse the request.
                Err(e) if e.code() == "missing" => return Err(e.into()),
                Err(e) => {
                    row.iter_mut().for_each(|v| *v = -1.0);
                    bad.push((r, e.code().to_string(), e.to_string()));
                }
            }
        }
        Ok((mat2(py, rows, g, out)?, bad))
    })
}
