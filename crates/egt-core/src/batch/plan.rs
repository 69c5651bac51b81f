//! The batch plan: a train prepared for a batch, its parameter and output
//! columns, its base row and its settings (`with_*`), and the [`Executor`]
//! of its straight-line program.

use crate::error::{Error, Result};
use crate::model::train::{LinkId, Train};
use crate::solve::prepared::{Compute, PreparedTrain};
use crate::solve::prepared::{Program, ProgramColumns};
use crate::solve::rows::Extra;

use super::BatchSpec;
use super::linear::LINEAR_MIN_ROWS;
use super::run::Spares;
use super::worker::{Blocks, PROGRAM_MAX_COORDINATES, PROGRAM_MIN_ROWS, Worker};

/// Where each parameter group starts in a row.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Groups {
    pub(super) ratio: usize,
    pub(super) speed: usize,
    pub(super) accel: usize,
    pub(super) torque: usize,
    pub(super) inertia: usize,
    pub(super) mass: usize,
    pub(super) efficiency: usize,
    pub(super) end: usize,
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
    pub(super) prepared: PreparedTrain,
    pub(super) compute: Compute,
    pub(super) parameters: Vec<String>,
    pub(super) base: Vec<f64>,
    /// Every output the solve writes, in its order (see
    /// [`BatchPlan::outputs`] for the chosen ones).
    pub(super) all: Vec<String>,
    /// The chosen outputs: their columns in `all`, their names, and the
    /// positions of the `cond.*` columns among them.
    pub(super) chosen: Vec<usize>,
    pub(super) names: Vec<String>,
    pub(super) cond_at: Vec<usize>,
    /// Every output is chosen, in the solve's order.
    pub(super) whole: bool,
    pub(super) groups: Groups,
    /// Coordinates whose speed is known (sized links), in link order.
    pub(super) known: Vec<usize>,
    /// Gear pairs with a radius for gear i, and the radius (eq. 11).
    pub(super) forces: Vec<(usize, f64)>,
    /// Condition bounds where they show a row well-conditioned (see
    /// [`BatchPlan::with_condition_bounds`]).
    pub(super) bounds: bool,
    /// With bounds, the straight-line program of the train (see
    /// `solve/prepared/tape.rs`), when the base row factors.
    pub(super) program: Option<Program>,
    /// How the program runs.
    pub(super) executor: Executor,
    /// A call's buffers, kept for the next call on a calling thread.
    pub(super) spares: Spares,
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
    /// output overflows stays in the program instead of being solved on its
    /// own, and its chosen numbers may then differ by rounding.
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
    pub(super) fn writes_all(&self) -> bool {
        self.whole
    }

    /// The chosen columns of a row of every output.
    #[inline]
    pub(super) fn gather(&self, all: &[f64], out: &mut [f64]) {
        for (d, &o) in out.iter_mut().zip(&self.chosen) {
            *d = all[o];
        }
    }

    /// Rows of every output (`all`, `n` rows) into the chosen columns of `out`.
    pub(super) fn gather_rows(&self, all: &[f64], out: &mut [f64]) {
        let (qa, q) = (self.all.len(), self.names.len());
        for (a, o) in all.chunks_exact(qa).zip(out.chunks_exact_mut(q)) {
            self.gather(a, o);
        }
    }

    /// The columns of the condition estimates (`cond.*`) among every output: the last ones.
    pub(super) fn all_conditions(&self) -> std::ops::Range<usize> {
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
    /// straight-line program: a plan with a program (condition bounds, a
    /// dense train's kinematics or ideal dynamics) and at least
    /// [`PROGRAM_MIN_ROWS`] rows.
    pub fn program_applies(&self, rows: &[f64]) -> bool {
        let n = rows.len().checked_div(self.parameters.len()).unwrap_or(0);
        self.program.is_some()
            && matches!(self.compute, Compute::Kinematics | Compute::Dynamics)
            && n >= PROGRAM_MIN_ROWS
            && !self.prepared.is_sparse()
    }

    pub(super) fn blocks(&self) -> Blocks {
        Blocks {
            program: self.program.as_ref().map(Program::workspace),
            left: Vec::new(),
            left_rows: Vec::new(),
            left_out: Vec::new(),
            all: Vec::new(),
        }
    }
}
