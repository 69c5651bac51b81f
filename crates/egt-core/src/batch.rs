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
//! The layout is row-major `f64` ([`BatchPlan::run`]) or column-major
//! ([`BatchPlan::run_columns`]: each parameter and each output a contiguous
//! column, as a Fortran-ordered NumPy array or Arrow's columns), so a NumPy
//! array maps onto it without copying. Both give the same numbers bit for
//! bit; the straight-line program and the linear path read and write
//! columns without transposing them, so column-major is the quicker (about
//! 20 % at 6 links with the program).
//! [`BatchPlan::run_column_set`] takes each parameter column row by row or
//! as one value for every row ([`Column`]): a sweep of a few parameters
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
//! its direction-dependent losses) are solved by the lanes or row by row.
//! Both give the same numbers to round-off (tested).
//!
//! **Lanes.** Other blocks of kinematics or ideal dynamics (ratio, inertia or
//! mass sweeps, every row its own train) are solved eight rows at a time,
//! the rows in the lanes of every matrix entry (structure of arrays), with
//! the vector instructions the machine has (AVX2 through `pulp` when
//! present). The eight share one pivot order; a row whose partial pivoting
//! would choose another, whose system is singular or past the refusal
//! threshold, or that holds a bad value, leaves its group and is solved on
//! its own, which gives its error. A row solved in the lanes gets the numbers
//! a fresh [`Worker`] gives it, condition estimates included (tested bit for
//! bit); power flow is always row by row.
//!
//! **Condition bounds.** The dlacn2 estimate costs four to ten substitutions
//! per factorisation, a fifth to a quarter of a small train's row in the
//! lanes. When the `cond.*` columns are not wanted for themselves
//! ([`BatchPlan::with_condition_bounds`]; `egt batch --columns` without a
//! `cond.*` column), a group first bounds every row's 1-norm condition
//! number from above, `||A|| ||U^-1|| ||L^-1||` through the comparison
//! matrices of the factors (one substitution, no iteration), and is
//! estimated only when the bound cannot show every row below `COND_WARN` / 2.
//! The estimate is a lower bound of the condition number, so the rows warned
//! about or refused are exactly those without bounds (tested on trains swept
//! through their lock).
//!
//! **Straight-line program.** With condition bounds, a dense train's
//! kinematics and ideal dynamics are eliminated once, symbolically, in the
//! base row's pivot order: the program keeps only the operations on
//! structural non-zeros (the constants folded in), gives each result a slot
//! reused once its last reader has run, and runs each operation over 64
//! rows at once. Each row checks that the fixed order is still a safe pivot
//! order (no multiplier past 2 in magnitude), bounds each system's condition
//! number as above, and that every result is finite; a row that fails any
//! check, or holds a bad value, goes to the lanes, which give its estimate,
//! warning or error. The program's numbers differ from the row-by-row
//! solve's by rounding only (another order of the same operations; tested
//! within 1e-12 of the row's largest output); the rows warned about or
//! refused are the same (tested). With the `jit` feature, the program runs
//! as machine code compiled for the train where the machine has AVX-512 or
//! AVX2, with the same numbers bit for bit ([`Executor`]).
//!
//! ```
//! use egt_core::batch::{BatchPlan, BatchSpec};
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
//! let errors = plan.run(&params, &mut out);
//! // The NaN row is reported; the others are solved.
//! assert_eq!(errors.len(), 1);
//! assert_eq!(errors[0].row, 2);
//! let torque = plan.output("driving_torque.s1").unwrap();
//! let q = plan.outputs().len();
//! // A larger load on the output needs a larger torque on the input.
//! let (t1, t2) = (out[torque], out[q + torque]);
//! assert!(t2 > t1 && t1 > 0.0);
//! ```

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::error::{AnalysisError, Error, Result};
use crate::model::train::{LinkId, Train};
use crate::numerics::lanes::{LANES, Lane};
use crate::solve::prepared::{Compute, PreparedTrain, Scenario, Workspace};
use crate::solve::prepared::{
    LaneWorkspace, PROGRAM_BLOCK, Program, ProgramColumns, ProgramWorkspace, efficiency_ok,
    non_negative, ratio_ok,
};
use crate::solve::rows::Extra;

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
const ROWS_PER_TASK: usize = 256;

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

/// Where each parameter group starts in a row.
#[derive(Debug, Clone, Copy, Default)]
struct Groups {
    ratio: usize,
    speed: usize,
    accel: usize,
    torque: usize,
    inertia: usize,
    mass: usize,
    efficiency: usize,
    end: usize,
}

/// A failed row.
#[derive(Debug, Clone, PartialEq)]
pub struct RowError {
    /// Index of the row.
    pub row: usize,
    /// Why it failed.
    pub error: Error,
}

/// How a [`BatchPlan`]'s straight-line program runs
/// ([`BatchPlan::with_executor`]); every executor gives the same numbers,
/// bit for bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Executor {
    /// Compiled to machine code for the train where the `jit` feature is
    /// on and the machine runs the code ([`BatchPlan::program_compiled`]
    /// says whether it does), else interpreted.
    #[default]
    Auto,
    /// Interpreted, whatever the build and the machine.
    Interpreted,
}

/// A train prepared for batch evaluation. `Sync`, and immutable but for
/// the buffers it keeps from a call on the calling thread for the next
/// (which change no number).
#[derive(Debug, Clone)]
pub struct BatchPlan {
    prepared: PreparedTrain,
    compute: Compute,
    parameters: Vec<String>,
    base: Vec<f64>,
    /// Every output the solve writes, in its order (see
    /// [`BatchPlan::outputs`] for the chosen ones).
    all: Vec<String>,
    /// The chosen outputs: their columns in `all`, their names, and the
    /// positions of the `cond.*` columns among them.
    chosen: Vec<usize>,
    names: Vec<String>,
    cond_at: Vec<usize>,
    /// Every output is chosen, in the solve's order.
    whole: bool,
    groups: Groups,
    /// Coordinates whose speed is known (sized links), in link order.
    known: Vec<usize>,
    /// Gear pairs with a radius for gear i, and the radius (eq. 11).
    forces: Vec<(usize, f64)>,
    /// Condition bounds where they show a row well-conditioned (see
    /// [`BatchPlan::with_condition_bounds`]).
    bounds: bool,
    /// With bounds, the straight-line program of the train (see
    /// `solve/prepared/tape.rs`), when the base row factors.
    program: Option<Program>,
    /// How the program runs.
    executor: Executor,
    /// A call's buffers, kept for the next call on a calling thread.
    spares: Spares,
}

impl BatchPlan {
    /// Prepare a batch.
    ///
    /// # Errors
    /// As [`PreparedTrain::new`]: wrong counts, the frame or repeated links,
    /// mass data with unknown offsets.
    pub fn new(train: &Train, spec: &BatchSpec) -> Result<Self> {
        let extras: Vec<Extra> = spec.extras.iter().map(|e| e.1).collect();
        let prepared = PreparedTrain::new(
            train,
            &spec.inputs,
            &spec.accelerated,
            &spec.driving,
            &extras,
        )?;
        let dynamic = spec.compute != Compute::Kinematics;
        let a = train.analysis();
        let name = |l: LinkId| train.link_name(l).to_string();
        let (mut parameters, mut base) = (Vec::new(), Vec::new());
        let mut push = |p: String, v: f64| {
            parameters.push(p);
            base.push(v);
        };
        let mut groups = Groups::default();
        for g in train.gears() {
            let v = g.ratio.as_ref().map_or(f64::NAN, |r| r.value);
            push(format!("ratio.{}", g.name), v);
        }
        groups.speed = train.gears().len();
        for &l in &spec.inputs {
            let v = a.speeds.iter().find(|s| s.0 == l).map_or(f64::NAN, |s| s.1);
            push(format!("speed.{}", name(l)), v);
        }
        groups.accel = groups.speed + spec.inputs.len();
        groups.torque = groups.accel;
        groups.inertia = groups.accel;
        groups.mass = groups.accel;
        groups.efficiency = groups.accel;
        if dynamic {
            for &l in &spec.accelerated {
                let v = a
                    .accelerations
                    .iter()
                    .find(|s| s.0 == l)
                    .map_or(0.0, |s| s.1);
                push(format!("accel.{}", name(l)), v);
            }
            groups.torque = groups.accel + spec.accelerated.len();
            for &l in train.coordinates() {
                let v = a
                    .torques
                    .iter()
                    .filter(|s| s.0 == l)
                    .fold(0.0, |acc, s| acc + s.1);
                push(format!("torque.{}", name(l)), v);
            }
            groups.inertia = groups.torque + train.coordinates().len();
            let mm = prepared.mass_model();
            let (inertia, mass) = mm.train_values(train);
            for (&l, &v) in mm.inertia_links().iter().zip(&inertia) {
                push(format!("inertia.{}", name(l)), v);
            }
            groups.mass = groups.inertia + inertia.len();
            for (&l, &v) in mm.mass_links().iter().zip(&mass) {
                push(format!("mass.{}", name(l)), v);
            }
            groups.efficiency = groups.mass + mass.len();
        }
        if spec.compute == Compute::Power {
            for g in train.gears() {
                push(format!("efficiency.{}", g.name), g.efficiency);
            }
        }
        groups.end = parameters.len();

        let known: Vec<usize> = train
            .coordinates()
            .iter()
            .enumerate()
            .filter(|(_, l)| train.link(**l).sized)
            .map(|(k, _)| k)
            .collect();
        let coord_name = |k: usize| name(train.coordinates()[k]);
        let mut outputs: Vec<String> = known
            .iter()
            .map(|&k| format!("speed.{}", coord_name(k)))
            .collect();
        let mut forces = Vec::new();
        if dynamic {
            outputs.extend(known.iter().map(|&k| format!("accel.{}", coord_name(k))));
            outputs.extend(train.gears().iter().map(|g| format!("lambda.{}", g.name)));
            outputs.extend(spec.extras.iter().map(|e| format!("lambda.{}", e.0)));
            outputs.extend(
                spec.driving
                    .iter()
                    .map(|&l| format!("driving_torque.{}", name(l))),
            );
            for (m, g) in train.gears().iter().enumerate() {
                if let Some(r) = prepared.radii()[m] {
                    forces.push((m, r));
                    outputs.push(format!("force.{}", g.name));
                }
            }
        }
        if spec.compute == Compute::Power {
            for p in ["input", "output", "loss", "kinetic_rate", "efficiency"] {
                outputs.push(format!("power.{p}"));
            }
        }
        outputs.push("cond.speeds".into());
        if dynamic {
            outputs.push("cond.accelerations".into());
            outputs.push("cond.forces".into());
        }
        let mut plan = BatchPlan {
            prepared,
            compute: spec.compute,
            parameters,
            base,
            all: outputs,
            chosen: Vec::new(),
            names: Vec::new(),
            cond_at: Vec::new(),
            whole: true,
            groups,
            known,
            forces,
            bounds: false,
            program: None,
            executor: Executor::Auto,
            spares: Spares::default(),
        };
        plan.choose((0..plan.all.len()).collect());
        Ok(plan)
    }

    fn choose(&mut self, chosen: Vec<usize>) {
        let conds = self.all_conditions().start;
        self.names = chosen.iter().map(|&o| self.all[o].clone()).collect();
        self.cond_at = (chosen.iter().enumerate())
            .filter(|(_, o)| **o >= conds)
            .map(|(k, _)| k)
            .collect();
        self.whole =
            chosen.len() == self.all.len() && chosen.iter().enumerate().all(|(k, &o)| k == o);
        self.chosen = chosen;
    }

    /// Keep only the output columns `names`, in that order: [`BatchPlan::run`]
    /// then writes those columns, and the straight-line program (with
    /// condition bounds) computes only what they need (a driving torque
    /// alone needs no meshing force, and kinematics outputs no multiplier).
    /// The rows solved, their errors and their warnings are the same with any
    /// choice; the numbers of a chosen column are those of the plan with
    /// every output, bit for bit (tested), but for one case: only chosen
    /// results are checked finite in the program, so a row whose unchosen
    /// output overflows stays in the program instead of going to the
    /// lanes, and its chosen numbers may then differ by rounding.
    ///
    /// # Errors
    /// An empty list, an output the plan does not have, or one named twice.
    pub fn with_outputs<S: AsRef<str>>(mut self, names: &[S]) -> Result<Self> {
        let invalid =
            |message: String| Error::spec("outputs", crate::SpecErrorKind::Invalid { message });
        if names.is_empty() {
            return Err(invalid("no output column chosen".into()));
        }
        let mut chosen = Vec::with_capacity(names.len());
        for name in names {
            let name = name.as_ref();
            let o = self.all.iter().position(|a| a == name).ok_or_else(|| {
                invalid(format!(
                    "unknown output column `{name}`; the plan has {}",
                    self.all.join(", ")
                ))
            })?;
            if chosen.contains(&o) {
                return Err(invalid(format!("output column `{name}` chosen twice")));
            }
            chosen.push(o);
        }
        self.choose(chosen);
        self.reprogram();
        Ok(self)
    }

    /// Every output column is written, in the solve's order.
    fn writes_all(&self) -> bool {
        self.whole
    }

    /// The chosen columns of a row of every output.
    #[inline]
    fn gather(&self, all: &[f64], out: &mut [f64]) {
        for (d, &o) in out.iter_mut().zip(&self.chosen) {
            *d = all[o];
        }
    }

    /// Rows of every output (`all`, `n` rows) into the chosen columns of `out`.
    fn gather_rows(&self, all: &[f64], out: &mut [f64]) {
        let (qa, q) = (self.all.len(), self.names.len());
        for (a, o) in all.chunks_exact(qa).zip(out.chunks_exact_mut(q)) {
            self.gather(a, o);
        }
    }

    /// The columns of the condition estimates (`cond.*`) among every output: the last ones.
    fn all_conditions(&self) -> std::ops::Range<usize> {
        let q = self.all.len();
        let k = if self.compute == Compute::Kinematics {
            1
        } else {
            3
        };
        q - k..q
    }

    /// Parameter column names, in row order.
    pub fn parameters(&self) -> &[String] {
        &self.parameters
    }
    /// The column of a parameter.
    pub fn parameter(&self, name: &str) -> Option<usize> {
        self.parameters.iter().position(|p| p == name)
    }
    /// The spec's own values, one per parameter (NaN where the spec gives none).
    pub fn base(&self) -> &[f64] {
        &self.base
    }
    /// Output column names, in row order: every output, or those of
    /// [`BatchPlan::with_outputs`].
    pub fn outputs(&self) -> &[String] {
        &self.names
    }
    /// The output column of a name.
    pub fn output(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|p| p == name)
    }
    /// Every output column the plan can write (those [`BatchPlan::with_outputs`] chooses from).
    pub fn all_outputs(&self) -> &[String] {
        &self.all
    }
    /// The output columns of the condition estimates (`cond.*`) among
    /// [`BatchPlan::outputs`] (with every output, the last ones).
    pub fn condition_columns(&self) -> &[usize] {
        &self.cond_at
    }
    /// What each row computes.
    pub fn compute(&self) -> Compute {
        self.compute
    }
    /// Solve with the sparse (or the dense) factorisations and \[M\] as
    /// terms, whatever the train's size (see
    /// [`PreparedTrain::with_sparse`]): to compare the two on one train.
    ///
    /// # Errors
    /// As [`PreparedTrain::with_sparse`].
    pub fn with_sparse(mut self, sparse: bool) -> Result<Self> {
        self.prepared = self.prepared.with_sparse(sparse)?;
        self.reprogram();
        Ok(self)
    }

    /// Make a condition estimate (dlacn2, four to ten substitutions per
    /// factorisation) only where it matters, when the `cond.*` columns are
    /// not wanted for themselves: rows solved eight at a time first bound
    /// their condition numbers from the LU factors (one substitution; see
    /// the module docs), and only a group where the bound cannot show every
    /// row below `COND_WARN` / 2 (10^8 / 2) is estimated. Every refused row
    /// and every row whose condition is past `COND_WARN` (those warned
    /// about, or refused) are as without bounds; the `cond.*` columns of the
    /// other rows then hold either the estimate or an upper bound of the
    /// condition number at most `COND_WARN` / 2. Kinematics and ideal
    /// dynamics of trains up to [`PROGRAM_MAX_COORDINATES`] coordinates are
    /// then solved by the straight-line program (see the module docs),
    /// whose other outputs differ from the row-by-row solve's by rounding
    /// only. Off by default ([`BatchPlan::bounds_serve`] says when they
    /// change nothing a caller asked for).
    pub fn with_condition_bounds(mut self, bounds: bool) -> Self {
        self.bounds = bounds;
        self.reprogram();
        self
    }

    /// The program for the plan as it now is, and no buffers kept for the
    /// plan as it was (their sizes follow the program and the prepared train).
    fn reprogram(&mut self) {
        self.program = self.program();
        self.spares = Spares::default();
    }

    /// The straight-line program the bounds allow, for a train of at most
    /// [`PROGRAM_MAX_COORDINATES`] coordinates whose base row factors.
    fn program(&self) -> Option<Program> {
        let g = self.groups;
        let cols = ProgramColumns {
            ratio: g.ratio,
            speed: g.speed,
            accel: g.accel,
            torque: g.torque,
            inertia: g.inertia,
            mass: g.mass,
            end: g.efficiency,
        };
        (self.bounds && self.prepared.n() <= PROGRAM_MAX_COORDINATES)
            .then(|| {
                self.prepared.program(
                    self.compute,
                    cols,
                    &self.base,
                    (&self.known, &self.forces),
                    &self.chosen,
                )
            })
            .flatten()
            .map(|p| match self.executor {
                Executor::Auto => p.compile(),
                Executor::Interpreted => p,
            })
    }

    /// Whether rows are solved by the straight-line program (see
    /// [`BatchPlan::with_condition_bounds`]).
    pub fn has_program(&self) -> bool {
        self.program.is_some()
    }

    /// Whether condition bounds ([`BatchPlan::with_condition_bounds`]) serve
    /// a batch whose chosen outputs are `names` (empty: every output): when
    /// none is a `cond.*` column, a condition estimate would only decide
    /// the warnings and refusals, which are the same with bounds. The
    /// default of `egt batch --columns` and of the Python module's `outputs`.
    pub fn bounds_serve(names: &[String]) -> bool {
        !names.is_empty() && !names.iter().any(|n| n.starts_with("cond."))
    }

    /// Whether the straight-line program runs as machine code compiled for
    /// this train ([`Executor::Auto`] with the `jit` feature, on x86-64 with
    /// AVX-512F and DQ or AVX2, BMI2 and FMA; `EGT_JIT=0` turns it off),
    /// rather than interpreted. The numbers are the same, bit for bit.
    pub fn program_compiled(&self) -> bool {
        self.program.as_ref().is_some_and(Program::compiled)
    }

    /// The same plan with its straight-line program (if any) run by
    /// `executor`: to compare or time them on one machine. Every executor
    /// gives the same numbers, bit for bit.
    pub fn with_executor(mut self, executor: Executor) -> Self {
        if executor != self.executor {
            self.executor = executor;
            self.reprogram();
        }
        self
    }

    /// The length of the straight-line program (operations and checks),
    /// when rows are solved by one: it shrinks with
    /// [`BatchPlan::with_outputs`].
    pub fn program_operations(&self) -> Option<usize> {
        self.program.as_ref().map(Program::len)
    }

    /// The prepared train underneath.
    pub fn prepared(&self) -> &PreparedTrain {
        &self.prepared
    }
    /// A single-threaded evaluator with its own buffers.
    pub fn worker(&self) -> Worker<'_> {
        Worker {
            plan: self,
            ws: self.prepared.workspace(),
            all: vec![0.0; self.all.len()],
        }
    }

    /// Whether [`BatchPlan::run`] solves a block of rows (row-major) by the
    /// linear path: kinematics or dynamics, at least 8 rows, and the ratio,
    /// inertia and mass columns equal in every row (see the module docs).
    /// Blocks are `run`'s chunks of up to 256 rows.
    pub fn is_linear_block(&self, rows: &[f64]) -> bool {
        let g = self.groups;
        let p = self.parameters.len();
        let n = rows.len().checked_div(p).unwrap_or(0);
        if self.compute == Compute::Power || n < LINEAR_MIN_ROWS {
            return false;
        }
        let row0 = &rows[..p];
        let fixed = |c: usize| c < g.speed || c >= g.inertia;
        rows.chunks(p)
            .all(|r| (0..p).all(|c| !fixed(c) || r[c].to_bits() == row0[c].to_bits()))
    }

    /// Whether parameter column `c` may vary within a block that the linear
    /// path solves (an input speed, a prescribed acceleration or an
    /// applied torque; see [`BatchPlan::is_linear_block`]).
    pub fn is_linear_parameter(&self, c: usize) -> bool {
        self.compute != Compute::Power && (self.groups.speed..self.groups.inertia).contains(&c)
    }

    /// Whether [`BatchPlan::run`] solves a block of rows (row-major) by the
    /// lanes: kinematics or ideal dynamics of a dense train (below
    /// [`PREPARED_SPARSE_FROM`](crate::solve::prepared::PREPARED_SPARSE_FROM)
    /// coordinates) and at least [`LANES_MIN_ROWS`] rows.
    pub fn lanes_apply(&self, rows: &[f64]) -> bool {
        let n = rows.len().checked_div(self.parameters.len()).unwrap_or(0);
        matches!(self.compute, Compute::Kinematics | Compute::Dynamics)
            && n >= LANES_MIN_ROWS
            && !self.prepared.is_sparse()
    }

    fn lanes(&self) -> Lanes {
        Lanes {
            w: self.prepared.lane_workspace(),
            program: self.program.as_ref().map(Program::workspace),
            left: Vec::new(),
            left_rows: Vec::new(),
            left_out: Vec::new(),
            all: Vec::new(),
        }
    }

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

    /// Solve every row of `params` (row-major, `parameters().len()` columns)
    /// into `out` (row-major, `outputs().len()` columns), in parallel on the
    /// current rayon pool; on the calling thread when the batch is one task
    /// (256 rows or fewer) or the pool has one thread (`RAYON_NUM_THREADS=1`).
    /// Failed rows get NaN outputs and are returned, in row order.
    ///
    /// # Panics
    /// When the slice lengths do not match the column counts.
    pub fn run(&self, params: &[f64], out: &mut [f64]) -> Vec<RowError> {
        self.run_with(Threads::Pool, params, out)
    }

    /// [`BatchPlan::run`], on the rayon pool or on the calling thread only
    /// (the same numbers and errors, bit for bit).
    ///
    /// # Panics
    /// When the slice lengths do not match the column counts.
    pub fn run_with(&self, threads: Threads, params: &[f64], out: &mut [f64]) -> Vec<RowError> {
        let (p, q) = (self.parameters.len(), self.names.len());
        self.rows_of(params, out);
        let tasks: Vec<(&[f64], &mut [f64])> = params
            .chunks(p * ROWS_PER_TASK)
            .zip(out.chunks_mut(q * ROWS_PER_TASK))
            .collect();
        each_task(threads, tasks, self, |t, task, (pin, pout)| {
            let mut errors = Vec::new();
            let first = task * ROWS_PER_TASK;
            t.w.eval_task(&mut t.lin, &mut t.lanes, pin, pout, first, &mut errors);
            errors
        })
    }
}

/// One parameter column of a column-major batch
/// ([`BatchPlan::run_column_set`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Column<'a> {
    /// A value for each row.
    Rows(&'a [f64]),
    /// One value for every row.
    Every(f64),
}

/// Where a batch call ([`BatchPlan::run_with`], [`BatchPlan::run_columns_with`]) runs.
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
fn each_task<T: Send>(
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
    /// Whether the linear path may take a block held column by column: its
    /// ratios, inertias, masses and efficiencies are the same in every row
    /// (as `Worker::eval_linear` asks, before its other conditions).
    fn linear_may<'c>(&self, column: impl Fn(usize) -> &'c [f64], n: usize) -> bool {
        let g = self.groups;
        self.compute != Compute::Power
            && n >= LINEAR_MIN_ROWS
            && (0..g.speed).chain(g.inertia..g.end).all(|k| {
                let c = column(k);
                c.iter().all(|x| x.to_bits() == c[0].to_bits())
            })
    }

    /// [`BatchPlan::run`] with both matrices column-major: parameter column
    /// `k` is `params[k * rows..(k + 1) * rows]`, output column `o` is
    /// `out[o * rows..(o + 1) * rows]` (a NumPy array in Fortran order, or
    /// the columns of an Arrow record batch). The linear path (a block
    /// whose ratios, inertias, masses and efficiencies are equal in every
    /// row) and, with condition bounds, the straight-line program read and
    /// write blocks a column at a time with no transposition, the linear
    /// path computing only the chosen outputs; other blocks' rows are
    /// transposed into the row-major solve and back. The numbers and the errors are those of
    /// [`BatchPlan::run`] on the same rows, bit for bit.
    ///
    /// # Panics
    /// When the slice lengths do not match the column counts.
    pub fn run_columns(&self, params: &[f64], out: &mut [f64]) -> Vec<RowError> {
        self.run_columns_with(Threads::Pool, params, out)
    }

    /// [`BatchPlan::run_columns`], on the rayon pool or on the calling
    /// thread only (the same numbers and errors, bit for bit).
    ///
    /// # Panics
    /// When the slice lengths do not match the column counts.
    pub fn run_columns_with(
        &self,
        threads: Threads,
        params: &[f64],
        out: &mut [f64],
    ) -> Vec<RowError> {
        let rows = self.rows_of(params, out);
        if rows == 0 {
            return Vec::new();
        }
        let inputs = params.chunks(rows).map(|c| (c, false)).collect();
        self.run_inputs(threads, inputs, rows, out, &AtomicUsize::new(0))
    }

    /// [`BatchPlan::run_columns_with`] with each parameter column given
    /// row by row or as one value for every row ([`Column`]): a sweep of a
    /// few parameters of a train passes those few columns and the others'
    /// values, and no column of repeated values is built or read. The
    /// numbers and errors are those of [`BatchPlan::run_columns`] on the
    /// same rows with every column written out, bit for bit (the same
    /// operations read the same values; a fixed column is read from a
    /// short buffer of its value, at most 256 rows long, that stays in cache).
    ///
    /// # Panics
    /// When `params` does not hold a column for each parameter, a
    /// [`Column::Rows`] is not `rows` long, or `out` is not `rows` times
    /// the output columns.
    pub fn run_column_set(
        &self,
        threads: Threads,
        params: &[Column<'_>],
        rows: usize,
        out: &mut [f64],
    ) -> Vec<RowError> {
        self.column_set(threads, params, rows, out, &AtomicUsize::new(0))
    }

    /// [`BatchPlan::run_column_set`], and whether every row's `cond.*`
    /// values are at most `COND_WARN` / 2, so that no row is warned about:
    /// true when the straight-line program, with condition bounds, solved
    /// every row (a row it leaves, which is estimated or refused, or a block
    /// another path solves, makes it false). A caller that warns about a
    /// large condition number need not read those columns then.
    ///
    /// # Panics
    /// As [`BatchPlan::run_column_set`].
    pub fn run_column_set_bounded(
        &self,
        threads: Threads,
        params: &[Column<'_>],
        rows: usize,
        out: &mut [f64],
    ) -> (Vec<RowError>, bool) {
        let unbounded = AtomicUsize::new(0);
        let errors = self.column_set(threads, params, rows, out, &unbounded);
        (errors, unbounded.into_inner() == 0)
    }

    /// [`BatchPlan::run_column_set`], counting in `unbounded` the rows the
    /// program did not solve.
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

    /// [`BatchPlan::run_column_set`] of `inputs`: each parameter column
    /// whole (`(column, false)`) or, fixed, as long as a task (`true`).
    /// `unbounded` counts the rows the straight-line program did not solve
    /// ([`BatchPlan::run_column_set_bounded`]).
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
                lanes,
                pin,
                pout,
            } = t;
            let mut errors = Vec::new();
            let first = task * ROWS_PER_TASK;
            let n = cols.first().map_or(0, |c| c.len());
            let column = |k: usize| match inputs[k] {
                (c, false) => &c[first..first + n],
                (c, true) => &c[..n],
            };
            let linear = self.linear_may(column, n);
            if !linear && self.program.is_some() && n >= LANES_MIN_ROWS {
                let solved = w.eval_program_columns(lanes, column, &mut cols, first, &mut errors);
                unbounded.fetch_add(n - solved, Ordering::Relaxed);
                return errors;
            }
            // Not the program's rows: their `cond.*` may be anything.
            unbounded.fetch_add(n, Ordering::Relaxed);
            if linear {
                // Column by column, as `eval_linear` would row by row.
                if w.eval_linear_columns(lin, column, &mut cols, first, &mut errors) {
                    return errors;
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
            w.eval_task(lin, lanes, pin, pout, first, &mut errors);
            for (t, tile) in pout.chunks(TILE * q).enumerate() {
                let at = t * TILE;
                for (o, c) in cols.iter_mut().enumerate() {
                    for (d, &v) in c[at..].iter_mut().zip(tile[o..].iter().step_by(q)) {
                        *d = v;
                    }
                }
            }
            errors
        })
    }
}

/// What a batch task works with: a worker, the linear path's and the lanes'
/// buffers, and the transposition's (column-major calls).
struct TaskState<'a> {
    w: Worker<'a>,
    lin: Linear,
    lanes: Lanes,
    pin: Vec<f64>,
    pout: Vec<f64>,
}

impl<'a> TaskState<'a> {
    fn new(plan: &'a BatchPlan) -> Self {
        TaskState {
            w: plan.worker(),
            lin: Linear::default(),
            lanes: plan.lanes(),
            pin: Vec::new(),
            pout: Vec::new(),
        }
    }
}

/// A [`TaskState`]'s buffers, without the plan.
struct Spare {
    ws: Workspace,
    all: Vec<f64>,
    lin: Linear,
    lanes: Lanes,
    pin: Vec<f64>,
    pout: Vec<f64>,
}

/// Buffers a plan keeps from its calls on a calling thread for the next
/// ones (at most [`SPARES`], for callers on several threads at once): a
/// call of 8 rows spent more on building and freeing them than on solving
/// (docs/performance.md (history: git log -p -- docs/benchmarks.md)). A clone of the plan starts with none; so does a
/// plan whose program or prepared train changes (`BatchPlan::reprogram`).
#[derive(Default)]
struct Spares(std::sync::Mutex<Vec<Spare>>);

impl std::fmt::Debug for Spares {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kept = self.0.lock().map_or(0, |v| v.len());
        write!(f, "Spares({kept} kept)")
    }
}

/// Most buffers a plan keeps.
const SPARES: usize = 4;

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
                lanes: s.lanes,
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
                lanes: t.lanes,
                pin: t.pin,
                pout: t.pout,
            });
        }
    }
}

/// Fewest rows in a block for the linear path (below it, row by row is as fast).
const LINEAR_MIN_ROWS: usize = 8;
/// Fewest rows in a block for the lanes.
pub const LANES_MIN_ROWS: usize = 4;

/// Buffers of the linear path: the varying columns, the base row, the
/// response columns and the conditions.
#[derive(Debug, Default)]
struct Linear {
    /// Per column: differs within the block.
    diff: Vec<bool>,
    /// The varying columns (input speeds, accelerations, torques).
    varying: Vec<usize>,
    /// The varying accelerations.
    accel_varying: Vec<usize>,
    /// The base row of the response held (varying columns at zero).
    row: Vec<f64>,
    y0: Vec<f64>,
    /// Row-major, one row of outputs per varying column: R_j = f(base + e_j) - f(base).
    response: Vec<f64>,
    /// Per varying column, the outputs it moves: R_j is zero outside
    /// `spans[j]` (an input speed moves no torque, a torque no speed).
    spans: Vec<(usize, usize)>,
    /// The condition outputs of a moving row (some acceleration not zero).
    cond_moving: Vec<f64>,
    /// The base row prescribes no acceleration.
    static_base: bool,
    /// A response is held.
    valid: bool,
    /// A column-major block's first row.
    first_row: Vec<f64>,
}

impl Linear {
    /// Whether the response held is that of the block whose first row is
    /// `row0` and whose varying columns (among `linear`) are marked in
    /// `diff`: the same base row (the varying columns at zero) and the same
    /// varying columns.
    fn same_base(&self, row0: &[f64], linear: std::ops::Range<usize>) -> bool {
        self.valid
            && self.row.len() == row0.len()
            && (0..row0.len()).all(|c| {
                let v = if self.diff[c] { 0.0 } else { row0[c] };
                v.to_bits() == self.row[c].to_bits()
            })
            && self
                .varying
                .iter()
                .copied()
                .eq(linear.filter(|&c| self.diff[c]))
    }
}

/// Coordinates up to which a batch with condition bounds runs the
/// straight-line program rather than the lanes: every dense train (the
/// program was 1.8 to 5 times faster than the lanes from 4 to 30 links, its
/// lead growing with the size; docs/performance.md (history: git log -p -- docs/benchmarks.md)).
pub const PROGRAM_MAX_COORDINATES: usize = crate::solve::prepared::PREPARED_SPARSE_FROM;

/// Buffers of the lanes path: the group's structure of arrays; the
/// program's block, and the rows it leaves to the lanes.
#[derive(Debug)]
struct Lanes {
    w: LaneWorkspace,
    program: Option<ProgramWorkspace>,
    /// Rows of the task the program left (their index, their parameters,
    /// their outputs): kept between tasks, so they allocate once.
    left: Vec<usize>,
    left_rows: Vec<f64>,
    left_out: Vec<f64>,
    /// A task's rows of every output, when only some are chosen.
    all: Vec<f64>,
}

/// The plan's program and a thread's workspace for it (`Lanes::program`).
fn program_of<'p, 'w>(
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
    plan: &'a BatchPlan,
    ws: Workspace,
    /// A row of every output, when only some are chosen.
    all: Vec<f64>,
}

impl Worker<'_> {
    /// Solve one row into `out`; on error `out` is filled with NaN. Allocates
    /// nothing unless the row fails.
    ///
    /// # Errors
    /// A non-finite or out-of-range parameter (naming it); the analysis errors
    /// of [`PreparedTrain::solve`].
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
    fn eval_all(&mut self, row: &[f64], out: &mut [f64]) -> Result<()> {
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

    /// A block of rows by the lanes ([`LANES`] rows solved at once, see the
    /// module docs); rows the lanes leave (a bad parameter, another pivot
    /// order, a singular or ill-conditioned system) are solved one at a time.
    /// Returns how many rows the lanes solved.
    fn eval_lanes(
        &mut self,
        lanes: &mut Lanes,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> usize {
        let plan = self.plan;
        let g = plan.groups;
        let pt = &plan.prepared;
        let (p, q) = (plan.parameters.len(), plan.all.len());
        let lw = &mut lanes.w;
        let mut solved = 0;
        for (k, (group, gout)) in rows
            .chunks(p * LANES)
            .zip(out.chunks_mut(q * LANES))
            .enumerate()
        {
            let count = group.len() / p;
            let mut live = [false; LANES];
            for (l, row) in group.chunks(p).enumerate() {
                live[l] = check(plan, row).is_ok();
            }
            if let Some(f) = live.iter().position(|&x| x) {
                // Padding and bad rows take the first good row's values.
                for l in 0..LANES {
                    let row = &group[if live[l] { l } else { f } * p..][..p];
                    let put = |dst: &mut [Lane], from: usize| {
                        for (d, &v) in dst.iter_mut().zip(&row[from..]) {
                            d[l] = v;
                        }
                    };
                    put(&mut lw.ratios, g.ratio);
                    put(&mut lw.speeds, g.speed);
                    put(&mut lw.accelerations, g.accel);
                    put(&mut lw.torques, g.torque);
                    put(&mut lw.inertia, g.inertia);
                    put(&mut lw.mass, g.mass);
                }
                pt.solve_lanes(lw, &mut live, plan.compute, plan.bounds);
            }
            for (l, (row, o)) in group.chunks(p).zip(gout.chunks_mut(q)).enumerate() {
                if live[l] {
                    solved += 1;
                    write_outputs(plan, &(&*lw, l), o);
                } else if let Err(error) = self.eval_all(row, o) {
                    errors.push(RowError {
                        row: first + k * LANES + l,
                        error,
                    });
                }
            }
            debug_assert!(count <= LANES);
        }
        solved
    }

    /// One task's rows (row-major) by the quickest path that applies: the
    /// linear path, the program, the lanes, or row by row.
    fn eval_task(
        &mut self,
        lin: &mut Linear,
        lanes: &mut Lanes,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) {
        let plan = self.plan;
        // The paths other than the program write every output: into `out`
        // when all are chosen, else into `lanes.all` and then the chosen.
        let mut all = std::mem::take(&mut lanes.all);
        let whole = plan.writes_all();
        if !whole {
            all.clear();
            all.resize(rows.len() / plan.parameters.len() * plan.all.len(), 0.0);
        }
        let target = if whole { &mut *out } else { &mut all[..] };
        let program = plan.program.is_some();
        let wrote = if self.eval_linear(lin, rows, target, first, errors) {
            // Solved as y0 + sum p_j R_j.
            true
        } else if plan.lanes_apply(rows) && program {
            self.eval_program(lanes, rows, out, first, errors);
            false
        } else {
            let target = if whole { &mut *out } else { &mut all[..] };
            if plan.lanes_apply(rows) {
                self.eval_lanes(lanes, rows, target, first, errors);
            } else {
                self.eval_rows(rows, target, first, errors);
            }
            true
        };
        if wrote && !whole {
            plan.gather_rows(&all, out);
        }
        lanes.all = all;
    }

    /// A block of rows by the straight-line program ([`PROGRAM_BLOCK`] rows at
    /// once); the rows it leaves (a bad parameter, other pivots, a bound past
    /// `COND_WARN` / 2, a result not finite) go to the lanes together.
    /// Returns how many rows the program solved.
    fn eval_program(
        &mut self,
        lanes: &mut Lanes,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> usize {
        let plan = self.plan;
        let (p, q) = (plan.parameters.len(), plan.names.len());
        let (program, pw) = program_of(plan, &mut lanes.program);
        lanes.left.clear();
        lanes.left_rows.clear();
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
                    lanes.left.push(k * PROGRAM_BLOCK + r);
                    lanes.left_rows.extend_from_slice(row);
                }
            }
        }
        let solved = rows.len() / p - lanes.left.len();
        self.eval_left(lanes, first, errors);
        for (&i, o) in lanes.left.iter().zip(lanes.left_out.chunks(plan.all.len())) {
            plan.gather(o, &mut out[i * q..(i + 1) * q]);
        }
        solved
    }

    /// [`Worker::eval_program`] on a block held column by column: `column(k)`
    /// is the block's part of parameter column `k`, `out[o]` of output column `o`.
    fn eval_program_columns<'c>(
        &mut self,
        lanes: &mut Lanes,
        column: impl Fn(usize) -> &'c [f64],
        out: &mut [&mut [f64]],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> usize {
        let plan = self.plan;
        let p = plan.parameters.len();
        let n = out.first().map_or(0, |c| c.len());
        let (program, pw) = program_of(plan, &mut lanes.program);
        lanes.left.clear();
        lanes.left_rows.clear();
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
                    lanes.left.push(r);
                    lanes.left_rows.extend((0..p).map(|k| column(k)[r]));
                }
            }
        }
        let solved = n - lanes.left.len();
        self.eval_left(lanes, first, errors);
        let q = plan.all.len();
        for (&i, o) in lanes.left.iter().zip(lanes.left_out.chunks(q)) {
            for (c, &k) in out.iter_mut().zip(&plan.chosen) {
                c[i] = o[k];
            }
        }
        solved
    }

    /// The rows the program left (`lanes.left_rows`, row-major) by the lanes
    /// or row by row into `lanes.left_out`; their errors numbered from `first`.
    fn eval_left(&mut self, lanes: &mut Lanes, first: usize, errors: &mut Vec<RowError>) {
        let plan = self.plan;
        let q = plan.all.len();
        if lanes.left.is_empty() {
            lanes.left_out.clear();
            return;
        }
        let (left, left_rows, mut left_out) = (
            std::mem::take(&mut lanes.left),
            std::mem::take(&mut lanes.left_rows),
            std::mem::take(&mut lanes.left_out),
        );
        left_out.clear();
        left_out.resize(left.len() * q, 0.0);
        let mut failed = Vec::new();
        if plan.lanes_apply(&left_rows) {
            self.eval_lanes(lanes, &left_rows, &mut left_out, 0, &mut failed);
        } else {
            self.eval_rows(&left_rows, &mut left_out, 0, &mut failed);
        }
        errors.extend(failed.into_iter().map(|e| RowError {
            row: first + left[e.row],
            error: e.error,
        }));
        (lanes.left, lanes.left_rows, lanes.left_out) = (left, left_rows, left_out);
    }

    /// A block of rows by the linear path when it applies (see the module
    /// docs): true when every row of `rows` was written (failed rows to
    /// `errors`); false when the block must be solved row by row.
    fn eval_linear(
        &mut self,
        lin: &mut Linear,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> bool {
        let plan = self.plan;
        let g = plan.groups;
        let (p, q) = (plan.parameters.len(), plan.all.len());
        let n = rows.len().checked_div(p).unwrap_or(0);
        if plan.compute == Compute::Power || n < LINEAR_MIN_ROWS {
            return false;
        }
        let row0 = &rows[..p];
        let fixed = |c: usize| c < g.speed || c >= g.inertia;
        // A ratio sweep leaves at its second row, before the whole pass.
        if (0..p).any(|c| fixed(c) && rows[p + c].to_bits() != row0[c].to_bits()) {
            return false;
        }
        // One pass: which columns differ from the first row's.
        lin.diff.clear();
        lin.diff.resize(p, false);
        for r in rows.chunks(p) {
            for ((d, a), b) in lin.diff.iter_mut().zip(r).zip(row0) {
                *d |= a.to_bits() != b.to_bits();
            }
        }
        if (0..p).any(|c| fixed(c) && lin.diff[c]) {
            return false;
        }
        let same = lin.same_base(row0, g.speed..g.inertia);
        if !same && !self.linear_response(lin, row0) {
            return false;
        }
        let conds = plan.all_conditions().start;
        let m = lin.varying.len();
        for (r, (row, o)) in rows.chunks(p).zip(out.chunks_mut(q)).enumerate() {
            // Every other column equals the base row's, which solved: only
            // the varying columns can be bad (the first in column order, as
            // `check` would name it).
            if let Some(&c) = lin.varying.iter().find(|&&c| !row[c].is_finite()) {
                o.fill(f64::NAN);
                errors.push(RowError {
                    row: first + r,
                    error: bad_parameter(plan, c, row[c]),
                });
                continue;
            }
            o.copy_from_slice(&lin.y0);
            for j in 0..m {
                let pj = row[lin.varying[j]];
                let (lo, hi) = lin.spans[j];
                for (y, rj) in o[lo..hi]
                    .iter_mut()
                    .zip(&lin.response[j * q + lo..j * q + hi])
                {
                    *y += pj * rj;
                }
            }
            if lin.static_base && lin.accel_varying.iter().any(|&c| row[c] != 0.0) {
                o[conds..].copy_from_slice(&lin.cond_moving);
            }
        }
        true
    }

    /// [`Worker::eval_linear`] on a block held column by column (`column(k)`
    /// is the block's part of parameter column `k`, `out[o]` of chosen output
    /// column `o`), for a block whose fixed columns are equal in every row
    /// (`BatchPlan::linear_may`). Each output element takes the operations
    /// `eval_linear` gives it, in the same order (y0, then `+= p_j R_j` for
    /// each varying column in order), so the numbers are its numbers bit for
    /// bit; only the chosen outputs are computed. False when the block must
    /// be solved otherwise (a base or unit row that fails to solve).
    fn eval_linear_columns<'c>(
        &mut self,
        lin: &mut Linear,
        column: impl Fn(usize) -> &'c [f64],
        out: &mut [&mut [f64]],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> bool {
        let plan = self.plan;
        let g = plan.groups;
        let p = plan.parameters.len();
        let n = out.first().map_or(0, |c| c.len());
        if plan.compute == Compute::Power || n < LINEAR_MIN_ROWS {
            return false;
        }
        let mut row0 = std::mem::take(&mut lin.first_row);
        row0.clear();
        row0.extend((0..p).map(|k| column(k)[0]));
        lin.diff.clear();
        lin.diff.resize(p, false);
        for (k, d) in lin
            .diff
            .iter_mut()
            .enumerate()
            .take(g.inertia)
            .skip(g.speed)
        {
            let (c, b) = (column(k), row0[k].to_bits());
            *d = c.iter().any(|x| x.to_bits() != b);
        }
        let same = lin.same_base(&row0, g.speed..g.inertia);
        let solved = same || self.linear_response(lin, &row0);
        lin.first_row = row0;
        if !solved {
            return false;
        }
        let conds = plan.all_conditions().start;
        let q = plan.all.len();
        for (o, &k) in out.iter_mut().zip(&plan.chosen) {
            o.fill(lin.y0[k]);
            for (j, &c) in lin.varying.iter().enumerate() {
                let (lo, hi) = lin.spans[j];
                if (lo..hi).contains(&k) {
                    let rj = lin.response[j * q + k];
                    for (y, &pj) in o.iter_mut().zip(column(c)) {
                        *y += pj * rj;
                    }
                }
            }
            if lin.static_base && k >= conds {
                let v = lin.cond_moving[k - conds];
                for &c in &lin.accel_varying {
                    for (y, &a) in o.iter_mut().zip(column(c)) {
                        if a != 0.0 {
                            *y = v;
                        }
                    }
                }
            }
        }
        // Only the varying columns can be bad (the first in column order,
        // as `check` would name it); such a row's outputs are NaN.
        for r in 0..n {
            if let Some(&c) = lin.varying.iter().find(|&&c| !column(c)[r].is_finite()) {
                out.iter_mut().for_each(|o| o[r] = f64::NAN);
                errors.push(RowError {
                    row: first + r,
                    error: bad_parameter(plan, c, column(c)[r]),
                });
            }
        }
        true
    }

    /// The linear path's response for a block whose first row is `row0` and
    /// whose varying columns are marked in `lin.diff`: y0 at the base row
    /// (varying columns at zero) and R_j = f(base + e_j) - y0; false when a
    /// solve fails (the block is then solved row by row, with its errors).
    fn linear_response(&mut self, lin: &mut Linear, row0: &[f64]) -> bool {
        let plan = self.plan;
        let g = plan.groups;
        let q = plan.all.len();
        lin.valid = false;
        lin.varying.clear();
        lin.varying
            .extend((g.speed..g.inertia).filter(|&c| lin.diff[c]));
        lin.row.clear();
        lin.row.extend_from_slice(row0);
        for &c in &lin.varying {
            lin.row[c] = 0.0;
        }
        lin.y0.resize(q, 0.0);
        if self.eval_all(&lin.row, &mut lin.y0).is_err() {
            return false;
        }
        let m = lin.varying.len();
        lin.response.resize(m * q, 0.0);
        for j in 0..m {
            let c = lin.varying[j];
            lin.row[c] = 1.0;
            let rj = &mut lin.response[j * q..(j + 1) * q];
            let solved = self.eval_all(&lin.row, rj);
            lin.row[c] = 0.0;
            if solved.is_err() {
                return false;
            }
            for (r, y) in rj.iter_mut().zip(&lin.y0) {
                *r -= y;
            }
        }
        // The conditions are not linear: eq. (8) is factored only when some
        // acceleration is prescribed. Keep those of a moving row apart.
        let conds = plan.all_conditions().start;
        let accel = g.accel..g.torque;
        lin.static_base = accel.clone().all(|c| lin.row[c] == 0.0);
        lin.accel_varying.clear();
        lin.accel_varying
            .extend(lin.varying.iter().copied().filter(|c| accel.contains(c)));
        lin.cond_moving.clear();
        lin.cond_moving.extend_from_slice(&lin.y0[conds..]);
        if let Some(j) = lin.varying.iter().position(|c| accel.contains(c)) {
            // R_j's conditions are y_j - y0: add y0 back.
            for (k, v) in lin.cond_moving.iter_mut().enumerate() {
                *v += lin.response[j * q + conds + k];
            }
        }
        lin.spans.clear();
        for j in 0..m {
            let rj = &mut lin.response[j * q..(j + 1) * q];
            rj[conds..].fill(0.0);
            let lo = rj.iter().position(|&v| v != 0.0).unwrap_or(0);
            let hi = rj.iter().rposition(|&v| v != 0.0).map_or(0, |k| k + 1);
            lin.spans.push((lo, hi.max(lo)));
        }
        lin.valid = true;
        true
    }
}

/// One row's results, wherever they were solved: a worker's slices, or one
/// lane of a group (read in place, no copy).
trait Solution {
    fn speed(&self, k: usize) -> f64;
    fn accel(&self, k: usize) -> f64;
    /// Multipliers, then driving torques.
    fn x(&self, k: usize) -> f64;
    fn cond(&self) -> [f64; 3];
    fn power(&self) -> Option<crate::solve::prepared::PowerSummary>;
}

impl Solution for (&Workspace, &BatchPlan) {
    fn speed(&self, k: usize) -> f64 {
        self.0.speeds()[k]
    }
    fn accel(&self, k: usize) -> f64 {
        self.0.accelerations()[k]
    }
    fn x(&self, k: usize) -> f64 {
        let pt = &self.1.prepared;
        let m = self.0.multipliers(pt);
        m.get(k)
            .copied()
            .unwrap_or_else(|| self.0.driving_torques(pt)[k - m.len()])
    }
    fn cond(&self) -> [f64; 3] {
        self.0.conditions()
    }
    fn power(&self) -> Option<crate::solve::prepared::PowerSummary> {
        (self.1.compute == Compute::Power).then(|| self.0.power())
    }
}

/// Lane `.1` of a group.
impl Solution for (&LaneWorkspace, usize) {
    fn speed(&self, k: usize) -> f64 {
        self.0.speed[k][self.1]
    }
    fn accel(&self, k: usize) -> f64 {
        self.0.accel[k][self.1]
    }
    fn x(&self, k: usize) -> f64 {
        self.0.x[k][self.1]
    }
    fn cond(&self) -> [f64; 3] {
        self.0.cond.map(|c| c[self.1])
    }
    fn power(&self) -> Option<crate::solve::prepared::PowerSummary> {
        None
    }
}

/// Write a row's output columns, in the order of [`BatchPlan::outputs`].
#[inline]
fn write_outputs(plan: &BatchPlan, s: &impl Solution, out: &mut [f64]) {
    let mut o = 0;
    let mut put = |v: f64| {
        out[o] = v;
        o += 1;
    };
    for &k in &plan.known {
        put(s.speed(k));
    }
    if plan.compute != Compute::Kinematics {
        for &k in &plan.known {
            put(s.accel(k));
        }
        let pt = &plan.prepared;
        for k in 0..pt.constraints() + pt.dof() {
            put(s.x(k));
        }
        for &(m, r) in &plan.forces {
            put(s.x(m) / r);
        }
    }
    if let Some(p) = s.power() {
        put(p.input);
        put(p.output);
        put(p.loss);
        put(p.kinetic_rate);
        put(if p.input > 0.0 {
            crate::analysis::power::efficiency(p.input, p.loss, p.kinetic_rate)
        } else {
            f64::NAN
        });
    }
    let cond = s.cond();
    put(cond[0]);
    if plan.compute != Compute::Kinematics {
        put(cond[1]);
        put(cond[2]);
    }
}

/// Every parameter finite; inertias and masses non-negative; efficiencies in (0, 1].
fn check(plan: &BatchPlan, row: &[f64]) -> Result<()> {
    let g = plan.groups;
    // One pass per group of columns; the column-by-column search below only
    // runs to name the bad one.
    let good = row[..g.speed].iter().all(|&v| ratio_ok(v))
        && row[g.speed..g.inertia].iter().all(|v| v.is_finite())
        && row[g.inertia..g.efficiency]
            .iter()
            .all(|&v| non_negative(v))
        && row[g.efficiency..].iter().all(|&v| efficiency_ok(v));
    if good {
        return Ok(());
    }
    for (c, &v) in row.iter().enumerate() {
        let ok = if c < g.speed {
            ratio_ok(v)
        } else if c < g.inertia {
            v.is_finite()
        } else if c < g.efficiency {
            non_negative(v)
        } else {
            efficiency_ok(v)
        };
        if !ok {
            return Err(bad_parameter(plan, c, v));
        }
    }
    Ok(())
}

#[cold]
fn bad_parameter(plan: &BatchPlan, c: usize, v: f64) -> Error {
    let g = plan.groups;
    let expected = if v.is_nan() {
        "a number (the spec gives no value; set it)"
    } else if !v.is_finite() {
        "a finite number"
    } else if c < g.speed {
        "a non-zero Willis ratio"
    } else if c >= g.efficiency {
        "an efficiency in (0, 1]"
    } else {
        "a value >= 0"
    };
    Error::spec(
        plan.parameters[c].clone(),
        crate::SpecErrorKind::OutOfRange {
            value: v,
            expected: expected.into(),
        },
    )
}

// The generated train families the core's other tests share (a file
// module, so that the path is from this folder).
#[cfg(test)]
#[allow(dead_code)]
#[path = "../lab/families.rs"]
mod families;

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(feature = "jit")]
    use crate::solve::prepared::Isa;
    use crate::{Format, Train};

    /// A ratio sweep goes through the lanes: every good row of a smooth
    /// sweep, none of the rows the lanes must leave (a bad value, a pivot
    /// order of its own). The results themselves are compared with solving
    /// each row alone in `tests/core/batch.rs`.
    #[test]
    fn lanes_solve_the_rows_of_a_ratio_sweep() {
        let text = include_str!("../../../examples/fig3_example61.toml");
        let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
        let p = BatchPlan::new(
            &t,
            &BatchSpec::from_analysis(&t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}")),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let np = p.parameters().len();
        let rows = 256;
        let mut params = Vec::new();
        for r in 0..rows {
            let mut row = p.base().to_vec();
            row[0] *= 1.0 + 0.001 * r as f64;
            params.extend(row);
        }
        let mut out = vec![0.0; rows * p.outputs().len()];
        let (mut w, mut lanes) = (p.worker(), p.lanes());
        let mut errors = Vec::new();
        assert_eq!(
            w.eval_lanes(&mut lanes, &params, &mut out, 0, &mut errors),
            rows
        );
        assert!(errors.is_empty());
        params[3 * np + 1] = f64::NAN;
        // Far from the others' ratio: it leaves the lanes (another pivot order).
        params[9 * np] *= -40.0;
        let solved = w.eval_lanes(&mut lanes, &params, &mut out, 0, &mut errors);
        assert_eq!(solved, rows - 2);
        assert_eq!(errors.len(), 1);
        assert_eq!(errors[0].row, 3);
    }

    /// The straight-line program solves a sweep's rows and leaves the bad,
    /// the far-off and the ill-conditioned ones to the lanes, which give
    /// their error or estimate; its numbers are the lanes' within rounding.
    #[test]
    fn the_program_solves_the_rows_it_can_vouch_for() {
        let text = include_str!("../../../examples/fig3_example61.toml");
        let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
        let p = BatchPlan::new(
            &t,
            &BatchSpec::from_analysis(&t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}")),
        )
        .unwrap_or_else(|e| panic!("{e}"))
        .with_condition_bounds(true);
        assert!(p.has_program());
        let (np, nq) = (p.parameters().len(), p.outputs().len());
        let rows = 300;
        let mut params = Vec::new();
        for r in 0..rows {
            let mut row = p.base().to_vec();
            row[0] *= 1.0 + 0.001 * r as f64;
            params.extend(row);
        }
        let col = |name: &str| p.parameter(name).unwrap_or_else(|| panic!("no {name}"));
        let (g1, g2) = (col("ratio.G1"), col("ratio.G2"));
        let t1 = p.base()[g1];
        params[3 * np + 1] = f64::NAN;
        // Far from the base ratio: other pivots.
        params[9 * np] *= -40.0;
        // Near the lock (tau_1 tau_2 = 1): past the warning.
        params[70 * np + g1] = t1;
        params[70 * np + g2] = (1.0 + 1e-10) / t1;
        let mut out = vec![0.0; rows * nq];
        let (mut w, mut lanes) = (p.worker(), p.lanes());
        let mut errors = Vec::new();
        let solved = w.eval_program(&mut lanes, &params, &mut out, 0, &mut errors);
        assert_eq!(solved, rows - 3);
        assert_eq!(errors.len(), 1);
        assert_eq!(errors[0].row, 3);
        let conds = p.condition_columns();
        let cond = (conds.iter())
            .map(|&c| out[70 * nq + c])
            .fold(0.0, f64::max);
        assert!(cond > crate::numerics::linalg::COND_WARN, "{cond}");
        let mut reference = vec![0.0; rows * nq];
        let mut errors = Vec::new();
        let lanes_solved = w.eval_lanes(&mut lanes, &params, &mut reference, 0, &mut errors);
        assert!(lanes_solved >= rows - 3);
        for r in (0..rows).filter(|&r| r != 3) {
            let (a, b) = (&out[r * nq..][..nq], &reference[r * nq..][..nq]);
            let scale = a.iter().map(|v| v.abs()).fold(0.0, f64::max);
            for c in (0..nq).filter(|c| !conds.contains(c)) {
                assert!((a[c] - b[c]).abs() <= 1e-13 * scale, "row {r} column {c}");
            }
        }
    }

    /// `run_column_set_bounded` vouches for a block only when the program
    /// solved every row, and then every row's `cond.*` is at most
    /// `COND_WARN` / 2: a row near the lock of Fig. 3 (past the warning) in
    /// the third task of the block makes it false, and so does a plan
    /// without condition bounds (no program); on the calling thread and on
    /// the pool alike.
    #[test]
    fn a_block_is_bounded_only_when_the_program_solved_every_row() {
        use crate::numerics::linalg::COND_WARN;
        let text = include_str!("../../../examples/fig3_example61.toml");
        let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
        let spec =
            BatchSpec::from_analysis(&t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}"));
        let plain = BatchPlan::new(&t, &spec).unwrap_or_else(|e| panic!("{e}"));
        let bounded = plain.clone().with_condition_bounds(true);
        assert!(bounded.has_program() && !plain.has_program());
        let col = |name: &str| plain.parameter(name).unwrap_or_else(|| panic!("no {name}"));
        let (g1, g2) = (col("ratio.G1"), col("ratio.G2"));
        let t1 = plain.base()[g1];
        let rows = 600;
        let ratios: Vec<f64> = (0..rows).map(|r| t1 * (1.0 + 0.001 * r as f64)).collect();
        let mut near = ratios.clone();
        near[550] = t1;
        let lock = (1.0 + 1e-10) / t1;
        for threads in [Threads::Calling, Threads::Pool] {
            for (p, g1s, at_550, vouched) in [
                (&bounded, &ratios, None, true),
                (&bounded, &near, Some(lock), false),
                (&plain, &ratios, None, false),
            ] {
                let g2s: Vec<f64> = (0..rows)
                    .map(|r| match at_550 {
                        Some(v) if r == 550 => v,
                        _ => p.base()[g2],
                    })
                    .collect();
                let columns: Vec<Column<'_>> = (0..p.parameters().len())
                    .map(|k| match k {
                        k if k == g1 => Column::Rows(g1s),
                        k if k == g2 => Column::Rows(&g2s),
                        k => Column::Every(p.base()[k]),
                    })
                    .collect();
                let mut out = vec![0.0; rows * p.outputs().len()];
                let (errors, said) = p.run_column_set_bounded(threads, &columns, rows, &mut out);
                assert!(errors.is_empty(), "{errors:?}");
                let locked = at_550.is_some();
                assert_eq!(said, vouched, "{threads:?}, near the lock: {locked}");
                let worst = |r: usize| {
                    (p.condition_columns().iter())
                        .map(|&c| out[c * rows + r])
                        .fold(0.0, f64::max)
                };
                if said {
                    assert!((0..rows).all(|r| worst(r) <= COND_WARN / 2.0));
                }
                if locked {
                    assert!(worst(550) > COND_WARN, "{}", worst(550));
                }
            }
        }
    }

    /// The program compiled to machine code gives the interpreter's numbers,
    /// validity and errors bit for bit (a NaN's payload apart): row-major
    /// and column-major, whole blocks (read and written in place) and a part
    /// block, with rows the checks must refuse in among them. Trains: Fig. 3
    /// and Fig. 5 (kinematics and dynamics, every output and a choice), and
    /// every gear state of the 8HP70. On a machine without AVX-512 there is
    /// no code, and the test says so by failing only where there should be.
    /// (With the `jit` feature only: without it there is no code.)
    #[cfg(feature = "jit")]
    #[test]
    fn compiled_and_interpreted_programs_agree_bit_for_bit() {
        // The instruction sets this machine runs, detected here rather than
        // asked of the compiler's own choice.
        let has = |features: &[&str]| {
            #[cfg(target_arch = "x86_64")]
            {
                features.iter().all(|f| match *f {
                    "avx512f" => std::arch::is_x86_feature_detected!("avx512f"),
                    "avx512dq" => std::arch::is_x86_feature_detected!("avx512dq"),
                    "avx2" => std::arch::is_x86_feature_detected!("avx2"),
                    "bmi2" => std::arch::is_x86_feature_detected!("bmi2"),
                    "fma" => std::arch::is_x86_feature_detected!("fma"),
                    other => panic!("no check for {other}"),
                })
            }
            #[cfg(not(target_arch = "x86_64"))]
            {
                let _ = features;
                false
            }
        };
        let isas = [
            (Isa::Avx512, has(&["avx512f", "avx512dq"])),
            (Isa::Avx2, has(&["avx2", "bmi2", "fma"])),
        ];
        let jit = std::env::var("EGT_JIT").unwrap_or_default();
        let default = match jit.as_str() {
            "0" => None,
            "avx2" => isas[1].1.then_some(Isa::Avx2),
            _ => isas.iter().find(|i| i.1).map(|i| i.0),
        };
        let example = |text: &str, name: &str| {
            Train::from_str(text, Format::Toml, name).unwrap_or_else(|e| panic!("{e}"))
        };
        let fig3 = example(
            include_str!("../../../examples/fig3_example61.toml"),
            "fig3",
        );
        let fig5 = example(
            include_str!("../../../examples/fig5_example62.toml"),
            "fig5",
        );
        let zf = example(include_str!("../../../examples/zf_8hp70.toml"), "8hp");
        // Chains of 6 and 30 links: more values live than registers, so
        // values are spilled and reloaded (AVX2 has 14 registers for them).
        let chain6 = example(&families::planetary_chain(2), "chain 6");
        let chain30 = example(&families::planetary_chain(14), "chain 30");
        let mut plans: Vec<(String, BatchPlan)> = Vec::new();
        for (name, t) in [("chain6", &chain6), ("chain30", &chain30)] {
            let spec =
                BatchSpec::from_analysis(t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}"));
            let p = BatchPlan::new(t, &spec).unwrap_or_else(|e| panic!("{e}"));
            plans.push((name.to_string(), p.with_condition_bounds(true)));
        }
        for (name, t) in [("fig3", &fig3), ("fig5", &fig5)] {
            for compute in [Compute::Kinematics, Compute::Dynamics] {
                let spec = BatchSpec::from_analysis(t, compute).unwrap_or_else(|e| panic!("{e}"));
                let p = BatchPlan::new(t, &spec).unwrap_or_else(|e| panic!("{e}"));
                let p = p.with_condition_bounds(true);
                let some: Vec<String> = p.outputs().iter().step_by(3).cloned().collect();
                let chosen = p
                    .clone()
                    .with_outputs(&some)
                    .unwrap_or_else(|e| panic!("{e}"));
                plans.push((format!("{name} {compute:?}"), p));
                plans.push((format!("{name} {compute:?} chosen"), chosen));
            }
        }
        let states = zf
            .checked_transmission()
            .unwrap_or_else(|e| panic!("{e}"))
            .states
            .clone();
        for s in &states {
            let spec = BatchSpec::for_gear_state(&zf, &s.name, Compute::Dynamics)
                .unwrap_or_else(|e| panic!("{e}"));
            let p = BatchPlan::new(&zf, &spec).unwrap_or_else(|e| panic!("{e}"));
            plans.push((format!("8HP {}", s.name), p.with_condition_bounds(true)));
        }
        for (name, p) in &plans {
            let program = p
                .program
                .as_ref()
                .unwrap_or_else(|| panic!("{name}: no program"));
            assert_eq!(program.isa(), default, "{name}: compiled where it runs");
            let mut interpreted = p.clone();
            interpreted.program = interpreted.program.take().map(|q| q.with_code(None));
            for &(isa, runs) in &isas {
                let mut p = p.clone();
                p.program = p.program.take().map(|q| q.with_code(Some(isa)));
                let got = p.program.as_ref().and_then(Program::isa);
                assert_eq!(
                    got,
                    runs.then_some(isa),
                    "{name}: {isa:?} code where it runs"
                );
                if runs {
                    compare(&format!("{name} {isa:?}"), &p, &interpreted);
                }
            }
        }
    }

    /// The rows of `plan` on its compiled program, and on `interpreted`: the
    /// same bits, errors and valid rows.
    #[cfg(feature = "jit")]
    fn compare(name: &str, p: &BatchPlan, interpreted: &BatchPlan) {
        // 512 rows: the output columns start at one offset modulo 4 KiB, so
        // a plan of more than 12 outputs writes them through the slots.
        for rows in [300, 512] {
            let program = p
                .program
                .as_ref()
                .unwrap_or_else(|| panic!("{name}: no program"));
            let (np, nq) = (p.parameters().len(), p.outputs().len());
            let mut params = Vec::new();
            for r in 0..rows {
                params.extend(p.base().iter().enumerate().map(|(c, &v)| {
                    let wave = (r as f64 * 0.37 + c as f64).sin();
                    // The 8HP's base has no input speed (NaN): 1.
                    let v = if v.is_nan() { 1.0 } else { v };
                    if p.parameters()[c].starts_with("efficiency.") {
                        v
                    } else {
                        v * (1.0 + 0.05 * wave)
                    }
                }));
            }
            let col = |prefix: &str| p.parameters().iter().position(|n| n.starts_with(prefix));
            assert!(p.parameters()[0].starts_with("ratio."), "{name}");
            // Rows every check must refuse.
            let mut refused = vec![3, 70];
            params[3 * np] = f64::NAN;
            params[70 * np] = 0.0;
            for (row, prefix, value) in [
                (130, "torque.", f64::INFINITY),
                (131, "torque.", f64::NEG_INFINITY),
                (150, "inertia.", -1.0),
                (151, "mass.", f64::NAN),
                (152, "speed.", f64::INFINITY),
            ] {
                if let Some(c) = col(prefix) {
                    params[row * np + c] = value;
                    refused.push(row);
                }
            }
            // Far from the base ratio: other pivots.
            params[9 * np] *= -40.0;
            // Finite, but the parameters' sum may overflow; and a large load.
            let last = col("efficiency.").unwrap_or(np) - 1;
            params[200 * np + last] = f64::MAX;
            params[200 * np + last - 1] = f64::MAX;
            params[201 * np + last] = -f64::MAX;
            params[260 * np + last] = 1e300;
            if let Some(c) = col("accel") {
                params[270 * np + c] = 0.5;
            }
            let columns: Vec<f64> = (0..np)
                .flat_map(|k| params[k..].iter().step_by(np).copied())
                .collect();
            let same = |a: &[f64], b: &[f64], what: &str| {
                for (i, (x, y)) in a.iter().zip(b).enumerate() {
                    assert!(
                        x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                        "{name} {what} cell {i}: {x} compiled vs {y} interpreted"
                    );
                }
            };
            let errors = |e: &[RowError]| {
                e.iter()
                    .map(|e| (e.row, e.error.to_string()))
                    .collect::<Vec<_>>()
            };
            let mut a = vec![0.0; rows * nq];
            let mut b = vec![0.0; rows * nq];
            let (ea, eb) = (p.run(&params, &mut a), interpreted.run(&params, &mut b));
            same(&a, &b, "rows");
            assert_eq!(errors(&ea), errors(&eb), "{name}");
            assert!(ea.iter().any(|e| e.row == 3), "{name}: the NaN row refused");
            let (ea, eb) = (
                p.run_columns(&columns, &mut a),
                interpreted.run_columns(&columns, &mut b),
            );
            same(&a, &b, "columns");
            assert_eq!(errors(&ea), errors(&eb), "{name} columns");
            // Block by block: the same rows valid, the same outputs in them.
            let (pa, pb) = (
                program,
                interpreted.program.as_ref().unwrap_or_else(|| panic!()),
            );
            let (mut wa, mut wb) = (pa.workspace(), pb.workspace());
            let mut valid = 0;
            for (k, block) in params.chunks(np * PROGRAM_BLOCK).enumerate() {
                let n = block.len() / np;
                let (mut oa, mut ob) = (vec![0.0; n * nq], vec![0.0; n * nq]);
                pa.run(&mut wa, block, np);
                pb.run(&mut wb, block, np);
                assert_eq!(wa.valid, wb.valid, "{name}");
                pa.write(&wa, &mut oa);
                pb.write(&wb, &mut ob);
                for r in (0..n).filter(|&r| wa.valid[r]) {
                    same(&oa[r * nq..][..nq], &ob[r * nq..][..nq], "block");
                    valid += 1;
                }
                for r in (0..n).filter(|r| refused.contains(&(k * PROGRAM_BLOCK + r))) {
                    assert!(!wa.valid[r], "{name}: row {} valid", k * PROGRAM_BLOCK + r);
                }
            }
            assert!(valid > rows / 2, "{name}: {valid} rows valid");
        }
    }

    /// Column-major runs give `run`'s numbers and errors bit for bit, on
    /// every path: the program (with its left rows), the linear path (a
    /// load sweep), the lanes (no bounds) and row by row (power flow).
    #[test]
    fn column_major_runs_give_the_row_major_numbers_bit_for_bit() {
        let text = include_str!("../../../examples/fig3_example61.toml");
        let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
        for compute in [Compute::Kinematics, Compute::Dynamics, Compute::Power] {
            for bounds in [false, true] {
                let spec = BatchSpec::from_analysis(&t, compute).unwrap_or_else(|e| panic!("{e}"));
                let p = BatchPlan::new(&t, &spec)
                    .unwrap_or_else(|e| panic!("{e}"))
                    .with_condition_bounds(bounds);
                assert_eq!(p.has_program(), bounds && compute != Compute::Power);
                let (np, nq) = (p.parameters().len(), p.outputs().len());
                let rows = 700;
                let g1 = p.parameter("ratio.G1").unwrap_or_else(|| panic!("no G1"));
                let speed = p.groups.speed;
                let mut params = Vec::new();
                for r in 0..rows {
                    let mut row = p.base().to_vec();
                    if (256..512).contains(&r) {
                        // A task of loads and speeds only: the linear path.
                        row[speed] *= 1.0 + 0.01 * r as f64;
                    } else {
                        row[g1] *= 1.0 + 0.001 * r as f64;
                    }
                    params.extend(row);
                }
                params[3 * np + 1] = f64::NAN;
                params[9 * np] *= -40.0;
                params[600 * np + g1] = f64::INFINITY;
                let t1 = p.base()[g1];
                let g2 = p.parameter("ratio.G2").unwrap_or_else(|| panic!("no G2"));
                params[70 * np + g1] = t1;
                params[70 * np + g2] = (1.0 + 1e-10) / t1;
                params[71 * np + g1] = t1;
                params[71 * np + g2] = 1.0 / t1;
                let mut by_rows = vec![0.0; rows * nq];
                let errors = p.run(&params, &mut by_rows);
                assert!(errors.len() >= 2, "{compute:?} {errors:?}");
                let columns: Vec<f64> = (0..np)
                    .flat_map(|k| params[k..].iter().step_by(np).copied())
                    .collect();
                let mut by_columns = vec![0.0; rows * nq];
                let column_errors = p.run_columns(&columns, &mut by_columns);
                // Debug forms: an error may hold the NaN it refused.
                assert_eq!(
                    format!("{errors:?}"),
                    format!("{column_errors:?}"),
                    "{compute:?} bounds {bounds}"
                );
                for r in 0..rows {
                    for o in 0..nq {
                        assert_eq!(
                            by_rows[r * nq + o].to_bits(),
                            by_columns[o * rows + r].to_bits(),
                            "{compute:?} bounds {bounds}: row {r}, {}",
                            p.outputs()[o]
                        );
                    }
                }
            }
        }
    }
}
