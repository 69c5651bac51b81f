//! Batch screening: many scenarios of one prepared train, as rows of a
//! parameter matrix, solved in parallel into rows of an output matrix.
//!
//! A [`BatchPlan`] names its parameter columns (`ratio.<gear>`, `speed.<link>`,
//! `accel.<link>`, `torque.<link>`, `inertia.<link>`, `mass.<link>`,
//! `efficiency.<gear>`) and its output columns (`speed.<link>`, `accel.<link>`,
//! `lambda.<gear or element>`, `driving_torque.<link>`, `force.<gear>`,
//! `power.*`, `cond.speeds`, `cond.accelerations`, `cond.forces`), and gives a base row holding the spec's own values.
//! A caller copies the base row, overrides the columns it varies, and calls
//! [`BatchPlan::run`] (all rows, in parallel with rayon) or a [`Worker`]
//! (one row at a time, on one thread). Rows are independent: a bad row (a
//! non-finite parameter, a singular or ill-conditioned system, a self-locking
//! train) is reported with its index, its outputs are NaN, and the others go on.
//!
//! [`BatchPlan::run`] is the one entry point; its [`Layout`] is row-major
//! `f64` ([`Layout::Rows`]) or column-major ([`Layout::Columns`]: each
//! parameter and each output a contiguous column, as a Fortran-ordered
//! NumPy array or Arrow's columns), so a NumPy array maps onto it without
//! copying. Both give the same numbers bit for bit; the straight-line
//! program and the linear path read and write columns without transposing
//! them, so column-major is the quicker (about 20 % at 6 links with the
//! program). [`Layout::ColumnSet`] takes each parameter column row by row
//! or as one value for every row ([`Column`]): a sweep of a few parameters
//! holds and reads those few columns only, with the same numbers bit for bit.
//! A row allocates nothing unless it fails.
//!
//! **Chosen outputs.** [`BatchPlan::with_outputs`] keeps only the columns
//! asked for (`egt batch --columns`, `Train.batch(..., outputs=...)`): the
//! output matrix is that narrow, and the straight-line program drops every
//! operation they do not need (at 6 links, a driving torque and the
//! conditions need no meshing force, acceleration output or multiplier).
//!
//! **Linear blocks.** Kinematics and inverse dynamics are linear in the input
//! speeds, the prescribed accelerations and the applied torques once the
//! ratios, inertias and masses are fixed. [`BatchPlan::run`] recognises a
//! block of rows (up to 256) whose other columns are all equal: it solves the
//! block's base row and one row per varying linear column (the factors of
//! that one train), and every row is then `y0 + sum_j p_j R_j`, a short
//! multiply-add over the outputs that the compiler vectorises. A load,
//! speed or acceleration sweep costs a few nanoseconds per row instead of a
//! solve; other blocks (ratio, inertia or efficiency sweeps, power flow with
//! its direction-dependent losses) are solved by the straight-line program
//! or row by row. Both give the same numbers to round-off (tested).
//!
//! **Condition bounds.** The dlacn2 estimate costs four to ten substitutions
//! per factorisation. When the `cond.*` columns are not wanted for
//! themselves ([`BatchPlan::with_condition_bounds`]; `egt batch --columns`
//! without a `cond.*` column), the straight-line program below bounds
//! every row's 1-norm condition number from above, `||A|| ||U^-1||
//! ||L^-1||` through the comparison matrices of the factors (one
//! substitution, no iteration), and leaves a row whose bound cannot show it
//! below `COND_WARN` / 2 to the row-by-row solve, which estimates it. The
//! estimate is a lower bound of the condition number, so the rows warned
//! about or refused are exactly those without bounds (tested on trains
//! swept through their lock). Without bounds, every row not on the linear
//! path is solved on its own, its condition estimated.
//!
//! **Straight-line program.** With condition bounds, a dense train's
//! kinematics and ideal dynamics are eliminated once, symbolically, in the
//! base row's pivot order: the program keeps only the operations on
//! structural non-zeros (the constants folded in), gives each result a slot
//! reused once its last reader has run, and runs each operation over 64
//! rows at once. Each row checks that the fixed order is still a safe pivot
//! order (no multiplier past 2 in magnitude), bounds each system's condition
//! number as above, and that every result is finite; a row that fails any
//! check, or holds a bad value, is solved on its own, which gives its
//! estimate, warning or error. The program's numbers differ from the row-by-row
//! solve's by rounding only (another order of the same operations; tested
//! within 1e-12 of the row's largest output); the rows warned about or
//! refused are the same (tested). With the `jit` feature, the program runs
//! as machine code compiled for the train where the machine has AVX-512 or
//! AVX2, with the same numbers bit for bit ([`Executor`]).
//!
//! ```
//! use egt_core::batch::{BatchPlan, BatchSpec, Layout, Threads};
//! use egt_core::solve::prepared::Compute;
//! use egt_core::{Format, Train};
//!
//! // Two planetary sets in series (6 links, 1 DOF), with its [analysis] data.
//! let spec = r#"
//!     frame = "case"
//!     links = [
//!         { name = "s1", inertia = 2e-4 },
//!         { name = "c1", inertia = 3.5e-3, mass = 1.8 },
//!         { name = "P1.planet", inertia = 1.5e-5, mass = 0.08, copies = 3 },
//!         { name = "c2", inertia = 7e-3, mass = 1.8 },
//!         { name = "P2.planet", inertia = 1.5e-5, mass = 0.08, copies = 3 },
//!     ]
//!     [[planetary]]
//!     name = "P1"
//!     sun = "s1"
//!     ring = "case"
//!     carrier = "c1"
//!     teeth = { sun = 28, planet = 22, ring = 72 }
//!     module = 1.5e-3
//!     [[planetary]]
//!     name = "P2"
//!     sun = "c1"
//!     ring = "case"
//!     carrier = "c2"
//!     teeth = { sun = 22, planet = 27, ring = 76 }
//!     module = 1.5e-3
//!     [analysis]
//!     speeds = { s1 = 157.0 }
//!     accelerations = { s1 = 12.5 }
//!     torques = { c2 = -40.0 }
//!     driving = ["s1"]
//! "#;
//! let train = Train::from_str(spec, Format::Toml, "chain").unwrap();
//! let plan = BatchPlan::new(&train, &BatchSpec::from_analysis(&train, Compute::Dynamics).unwrap()).unwrap();
//! // Three scenarios: the spec's values with three loads on the output carrier.
//! let load = plan.parameter("torque.c2").unwrap();
//! let mut params = Vec::new();
//! for t in [-10.0, -20.0, f64::NAN] {
//!     let mut row = plan.base().to_vec();
//!     row[load] = t;
//!     params.extend(row);
//! }
//! let mut out = vec![0.0; 3 * plan.outputs().len()];
//! let errors = plan.run(Layout::Rows(&params), &mut out, Threads::Pool).errors;
//! // The NaN row is reported; the others are solved.
//! assert_eq!(errors.len(), 1);
//! assert_eq!(errors[0].row, 2);
//! let torque = plan.output("driving_torque.s1").unwrap();
//! let q = plan.outputs().len();
//! // A larger load on the output needs a larger torque on the input.
//! let (t1, t2) = (out[torque], out[q + torque]);
//! assert!(t2 > t1 && t1 > 0.0);
//! ```

mod linear;
mod outputs;
mod plan;
mod run;
mod worker;

pub use plan::{BatchPlan, Executor};
pub use run::{Column, Layout, RowError, Solved, Threads, worker_threads};
pub use worker::{PROGRAM_MAX_COORDINATES, PROGRAM_MIN_ROWS, Worker};

use crate::error::{AnalysisError, Error, Result};
use crate::model::train::{LinkId, Train};
use crate::solve::prepared::Compute;
use crate::solve::rows::Extra;

/// What a batch asks: which links are driven at a prescribed speed, which at a
/// prescribed acceleration, which carry the unknown torques, which shift
/// elements are engaged, and what to compute.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BatchSpec {
    /// Links with prescribed speed (one per DOF left by the constraints).
    pub inputs: Vec<LinkId>,
    /// Links with prescribed acceleration (as many; usually the inputs).
    pub accelerated: Vec<LinkId>,
    /// Links whose torque is solved (as many; usually the inputs).
    pub driving: Vec<LinkId>,
    /// Engaged brakes and clutches, each with the name its reaction column takes.
    pub extras: Vec<(String, Extra)>,
    /// What each row computes.
    pub compute: Compute,
}

impl BatchSpec {
    /// The batch the spec's `[analysis]` section describes: its speed inputs,
    /// its accelerated and driving links (default: the inputs), no engaged elements.
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] when the section gives no input speeds.
    pub fn from_analysis(train: &Train, compute: Compute) -> Result<Self> {
        let a = train.analysis();
        let inputs: Vec<LinkId> = a.speeds.iter().map(|s| s.0).collect();
        if inputs.is_empty() {
            return Err(AnalysisError::MissingData {
                what: "the input links".into(),
                analysis: "a batch".into(),
                hint: "give `[analysis] speeds = { LINK = SPEED }`".into(),
            }
            .into());
        }
        let driving = if a.driving.is_empty() {
            inputs.clone()
        } else {
            a.driving.clone()
        };
        let accelerated = if a.accelerations.is_empty() {
            inputs.clone()
        } else {
            a.accelerations.iter().map(|s| s.0).collect()
        };
        Ok(BatchSpec {
            inputs,
            accelerated,
            driving,
            extras: Vec::new(),
            compute,
        })
    }
}

impl BatchSpec {
    /// One gear state of a transmission: its engaged elements as extra
    /// constraint rows (their reaction torques become `lambda.<element>`
    /// columns); speed and acceleration prescribed on the input, whose torque
    /// is a parameter (`torque.<input>`); the output torque solved.
    ///
    /// # Errors
    /// No transmission data or no such state.
    pub fn for_gear_state(train: &Train, state: &str, compute: Compute) -> Result<Self> {
        let t = train.checked_transmission()?;
        let s = t.states.iter().find(|s| s.name == state).ok_or_else(|| {
            Error::Transmission(crate::TransmissionError::UnknownState {
                state: state.to_string(),
                suggestion: crate::error::suggest(state, t.states.iter().map(|s| s.name.as_str())),
            })
        })?;
        let extras = s
            .engaged
            .iter()
            .map(|&e| {
                let el = &train.elements()[e.index()];
                (
                    el.name.clone(),
                    crate::analysis::transmission::element_constraint(el),
                )
            })
            .collect();
        Ok(BatchSpec {
            inputs: vec![t.input],
            accelerated: vec![t.input],
            driving: vec![t.output],
            extras,
            compute,
        })
    }
}

#[cfg(test)]
mod tests;
