//! A train prepared for many scenarios: every index map, matrix and buffer is
//! built once, and each scenario (one set of ratios, speeds, accelerations,
//! loads, inertias, masses and efficiencies) is then solved without allocating.
//!
//! * [`MassModel`]: the mass matrix of eq. (3)-(5) as a fill from parameter
//!   slices, built once from the eq. (4) offset chains.
//! * [`PreparedTrain`] (immutable, shared between threads) and [`Workspace`]
//!   (one per thread): speeds from the Willis equations (eq. 2) completed by
//!   the input rows; accelerations from \[Psi_w\] (eq. 8); multipliers and driving
//!   torques from the transposed system (eq. 10); with mesh losses, the
//!   power-flow directions found as in `power.rs`.
//!
//! When the accelerated links are the input links, one LU factorisation serves
//! speeds and accelerations; when the driving links are the accelerated links
//! and the meshes are ideal, the force matrix of eq. (10) is the matrix of
//! eq. (8) with those rows negated, so the same factorisation also gives the
//! torques. In the common case (one set of input links) a scenario costs one LU.

use std::ops::Range;

#[cfg(feature = "jit")]
mod jit;
#[cfg(all(test, feature = "jit"))]
pub(crate) use jit::Isa;
mod build;
mod fill;
mod mass_model;
mod solve;
mod tape;
pub use mass_model::MassModel;
pub(crate) use mass_model::exact_of;
pub(crate) use tape::{
    BLOCK as PROGRAM_BLOCK, Columns as ProgramColumns, Program, ProgramWorkspace, crowded,
};

use crate::solve::rows::{Extra, Rows, dof_with, link_columns};
use num_traits::Zero;

use crate::error::{AnalysisError, Result};
use crate::model::equations::willis_row;
use crate::model::mass::MassMatrix;
use crate::model::train::{LinkId, Train};
use crate::numerics::exact::{self, Q, QMatrix};
use crate::numerics::linalg::Lu;
use crate::numerics::sparse::SparseLu;
use crate::solve::losses::{
    Directions, Driver, ForceSolution, LossySolver, Meshes, idle_tolerance, mesh_torque,
};

/// What a scenario computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compute {
    /// Speeds only (eq. 2).
    Kinematics,
    /// Accelerations, multipliers and driving torques without the speeds
    /// (eq. 8, 10): inverse dynamics and the static-force analysis.
    Forces,
    /// Speeds, accelerations, multipliers, driving torques and meshing forces (eq. 2, 8, 10, 11).
    #[default]
    Dynamics,
    /// As `Dynamics`, with mesh losses and the power balance.
    Power,
}

/// One scenario's parameters, borrowed from the caller.
#[derive(Debug, Clone, Copy)]
pub struct Scenario<'a> {
    /// Willis ratios, one per gear pair.
    pub ratios: &'a [f64],
    /// Speeds of the input links, in input order.
    pub speeds: &'a [f64],
    /// Accelerations of the accelerated links, in their order (ignored for `Kinematics`).
    pub accelerations: &'a [f64],
    /// Known applied torque on every coordinate (ignored for `Kinematics`).
    pub torques: &'a [f64],
    /// One per [`MassModel::inertia_links`].
    pub inertia: &'a [f64],
    /// One per [`MassModel::mass_links`].
    pub mass: &'a [f64],
    /// Basic mesh efficiencies, one per gear pair (read by `Power` only).
    pub efficiency: &'a [f64],
    /// A whole mass matrix to use instead of filling one from `inertia` and
    /// `mass`: a single analysis with a given \[M\].
    pub mass_matrix: Option<&'a MassMatrix>,
}

impl<'a> Scenario<'a> {
    /// A scenario of what [`Compute::Kinematics`] reads: the ratios and the
    /// input speeds (no loads, no masses).
    pub fn kinematic(ratios: &'a [f64], speeds: &'a [f64]) -> Self {
        Scenario {
            ratios,
            speeds,
            accelerations: &[],
            torques: &[],
            inertia: &[],
            mass: &[],
            efficiency: &[],
            mass_matrix: None,
        }
    }
}

/// A power balance (for [`Compute::Power`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PowerSummary {
    /// Sum of positive external powers.
    pub input: f64,
    /// Minus the sum of negative external powers.
    pub output: f64,
    /// Power lost in the meshes.
    pub loss: f64,
    /// dK/dt = w^T M w'.
    pub kinetic_rate: f64,
    /// Direction iterations used.
    pub iterations: usize,
}

// The rules of a scenario's parameters (one place, for the batch's check
// and the straight-line program's).

/// The rule of the ratio columns (a zero ratio has no Willis row).
#[inline(always)]
pub(crate) fn ratio_ok(v: f64) -> bool {
    v.is_finite() && v != 0.0
}

/// The rule of the inertia and mass columns.
#[inline(always)]
pub(crate) fn non_negative(v: f64) -> bool {
    v.is_finite() && v >= 0.0
}

/// The rule of the efficiency columns.
#[inline(always)]
pub(crate) fn efficiency_ok(v: f64) -> bool {
    v > 0.0 && v <= 1.0
}

/// A train prepared for one choice of input links, driving links and extra
/// constraints. Immutable: share it between threads, one [`Workspace`] each.
#[derive(Debug, Clone)]
pub struct PreparedTrain {
    n: usize,
    circuits: Vec<[Option<usize>; 3]>,
    extras: Vec<[(Option<usize>, f64); 2]>,
    inputs: Vec<usize>,
    accelerated: Vec<usize>,
    driving: Vec<usize>,
    /// Accelerated links = inputs: eq. (8) is the speed system.
    accel_shared: bool,
    /// Driving links = accelerated links: eq. (10) is eq. (8) transposed, rows negated.
    force_shared: bool,
    mass: MassModel,
    radii: Vec<Option<f64>>,
    /// For large trains, the sparse LUs of the three systems (their
    /// patterns analysed once; each workspace clones them), and \[M\] is
    /// held as a list of terms; else everything is dense.
    sparse: Option<Box<[Factor; 3]>>,
}

/// Coordinates from which a [`PreparedTrain`] factors sparsely and holds
/// \[M\] as a list of terms: time and memory per scenario then grow about
/// linearly in the links. One scenario alone is faster sparse from about 20
/// coordinates (`cargo bench -p egt-core --bench scenarios --
/// large::dynamics`: 2.8 against 2.3 µs at 22 links, 19.9 against 8.3 µs at
/// 66), but a batch solves dense trains by the straight-line program, which
/// holds dense factors, so the switch sits higher; every production train
/// is far below it.
pub const PREPARED_SPARSE_FROM: usize = 64;

/// A factorisation of one of the three systems.
#[derive(Debug, Clone)]
enum Factor {
    Dense(Lu),
    /// With the value slot of each term [`PreparedTrain::for_each_entry`] visits.
    Sparse(Box<SparseLu>, Vec<usize>),
}

impl Factor {
    /// Fill system `system` (0 speeds, 1 \[Psi_w\], 2 force) for `ratios`,
    /// factor it and estimate its condition (the checked factorisation).
    fn fill_factor(
        &mut self,
        plan: &PreparedTrain,
        ratios: &[f64],
        system: usize,
        what: &str,
        detail: &str,
    ) -> Result<f64> {
        match self {
            Factor::Dense(lu) => {
                match system {
                    0 => plan.kinematic_matrix(ratios, lu.matrix_mut()),
                    1 => plan.acceleration_matrix(ratios, lu.matrix_mut()),
                    _ => plan.force_matrix(ratios, lu.matrix_mut()),
                }
                lu.factor_checked(what, detail)
            }
            Factor::Sparse(lu, slots) => {
                let values = lu.values_mut();
                values.iter_mut().for_each(|v| *v = 0.0);
                let mut k = 0;
                plan.for_each_entry(ratios, system, |_, _, v| {
                    values[slots[k]] += v;
                    k += 1;
                });
                lu.factor_checked(what, detail)
            }
        }
    }

    fn solve(&mut self, b: &mut [f64]) {
        match self {
            Factor::Dense(lu) => lu.solve(b),
            Factor::Sparse(lu, _) => lu.solve(b),
        }
    }

    fn solve2(&mut self, b: &mut [f64], c: &mut [f64]) {
        match self {
            Factor::Dense(lu) => lu.solve2(b, c),
            Factor::Sparse(lu, _) => {
                lu.solve(b);
                lu.solve(c);
            }
        }
    }

    fn solve_transpose(&mut self, b: &mut [f64]) {
        match self {
            Factor::Dense(lu) => lu.solve_transpose(b),
            Factor::Sparse(lu, _) => lu.solve_transpose(b),
        }
    }
}

/// \[M\] of a workspace: dense (row-major n x n) or a list of terms.
#[derive(Debug, Clone)]
enum Mass {
    Dense(Vec<f64>),
    Terms(Vec<(usize, usize, f64)>),
}

impl Mass {
    /// \[M\]{x} into `out` (dense: each row's products summed in order).
    fn mul_vec(&self, n: usize, x: &[f64], out: &mut [f64]) {
        match self {
            Mass::Dense(m) => {
                for (k, o) in out.iter_mut().enumerate() {
                    *o = m[k * n..(k + 1) * n]
                        .iter()
                        .zip(x)
                        .map(|(a, b)| a * b)
                        .sum::<f64>();
                }
            }
            Mass::Terms(t) => {
                out.iter_mut().for_each(|v| *v = 0.0);
                for &(r, c, v) in t {
                    out[r] += v * x[c];
                }
            }
        }
    }
}

/// Per-thread buffers for [`PreparedTrain::solve`]; results are read from here.
#[derive(Debug, Clone)]
pub struct Workspace {
    kin: Factor,
    acc: Factor,
    force: Factor,
    speed: Vec<f64>,
    accel: Vec<f64>,
    x: Vec<f64>,
    m: Mass,
    /// \[M\]{w'} (power balance, residual).
    mw: Vec<f64>,
    rhs: Vec<f64>,
    tau: Vec<f64>,
    rolling: Vec<f64>,
    directions: Directions,
    cond: [f64; 3],
    /// The LU that holds \[Psi_w\] (eq. 8) for the current ratios, if any, and its condition.
    psi: Option<Psi>,
    psi_cond: f64,
    power: PowerSummary,
    /// The ratios the factorisations below were made with, and which of them
    /// are valid for those ratios: a batch that varies loads, speeds,
    /// accelerations or inertias under fixed ratios factors once.
    key: Vec<f64>,
    cache: Cache,
}

/// Which LU of a [`Workspace`] holds \[Psi_w\].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Psi {
    Kin,
    Acc,
}

/// Which factorisations in a [`Workspace`] hold for its `key` ratios.
#[derive(Debug, Clone, Copy, Default)]
struct Cache {
    kin: bool,
    acc: bool,
    force: bool,
}

impl Workspace {
    /// Speeds of the coordinates (every link but the frame, in link order).
    pub fn speeds(&self) -> &[f64] {
        &self.speed
    }
    /// Accelerations of the coordinates.
    pub fn accelerations(&self) -> &[f64] {
        &self.accel
    }
    /// Lagrange multipliers: Willis rows, then extra rows (element reaction torques).
    pub fn multipliers(&self, plan: &PreparedTrain) -> &[f64] {
        &self.x[..plan.constraints()]
    }
    /// Driving torques, in the order of the driving links.
    pub fn driving_torques(&self, plan: &PreparedTrain) -> &[f64] {
        &self.x[plan.constraints()..]
    }
    /// The mass matrix of the last scenario, row-major, when held dense
    /// (a train below [`PREPARED_SPARSE_FROM`] coordinates).
    pub fn mass_matrix(&self) -> Option<&[f64]> {
        match &self.m {
            Mass::Dense(m) => Some(m),
            Mass::Terms(_) => None,
        }
    }
    /// The force ratios of the last scenario (the Willis ratios unless losses applied).
    pub fn force_ratios(&self) -> &[f64] {
        &self.tau
    }
    /// 1-norm condition estimates of the speed system, of \[Psi_w\] (eq. 8)
    /// and of the force system (eq. 10), from the last scenario.
    pub fn conditions(&self) -> [f64; 3] {
        self.cond
    }
    /// The power balance of the last [`Compute::Power`] scenario.
    pub fn power(&self) -> PowerSummary {
        self.power
    }
    /// The direction of rolling power in each mesh after the last
    /// [`Compute::Power`] scenario (none for ideal and idle meshes).
    pub fn directions(&self) -> &[Driver] {
        &self.directions.dirs
    }
    /// Rolling speeds w_j - w_k of the meshes after the last [`Compute::Power`] scenario.
    pub fn rolling(&self) -> &[f64] {
        &self.rolling
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::parse::Format;

    const FIG3: &str = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/fig3_example61.toml"
    ));

    #[test]
    fn mass_model_reproduces_mass_matrix() {
        let t = Train::from_str(FIG3, Format::Toml, "fig3").expect("valid");
        let mm = MassModel::new(&t).expect("mass data");
        let (i, m) = mm.train_values(&t);
        let mut buf = vec![0.0; mm.n() * mm.n()];
        mm.fill(&i, &m, &mut buf);
        let reference = t.mass_matrix().expect("mass data");
        let n = mm.n();
        for r in 0..n {
            for c in 0..n {
                assert_eq!(buf[r * n + c], reference.get(r, c), "({r}, {c})");
            }
        }
    }
}
