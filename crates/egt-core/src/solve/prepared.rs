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
mod lanes;
mod tape;
pub(crate) use lanes::LaneWorkspace;
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

/// One link's share of the mass matrix.
#[derive(Debug, Clone)]
struct MassEntry {
    /// Its coordinate and its slot among the inertia parameters (own rotation, eq. 3).
    spin: Option<(usize, usize)>,
    /// Its slot among the mass parameters and its eq. (4) terms (translation on carriers).
    float: Option<(usize, Range<usize>)>,
    copies: f64,
}

/// The mass matrix \[M\] (eq. 3-5) prepared for varying inertias and masses.
///
/// Built once from the train's eq. (4) offset chains; [`MassModel::fill`] then
/// writes \[M\] for any inertias and masses into a caller's buffer. With the
/// train's own values it reproduces [`Train::mass_matrix`] exactly.
#[derive(Debug, Clone)]
pub struct MassModel {
    n: usize,
    entries: Vec<MassEntry>,
    terms: Vec<(usize, f64)>,
    inertia_links: Vec<LinkId>,
    mass_links: Vec<LinkId>,
    notes: Vec<String>,
}

impl MassModel {
    /// Prepare from the train: an inertia slot for every sized moving link, a
    /// mass slot for every link that floats on a moving carrier with known offsets.
    ///
    /// # Errors
    /// As [`Train::mass_matrix`]: a link with a mass whose offsets are unknown,
    /// or an inertia given for a planet whose speed is unknown.
    pub fn new(train: &Train) -> Result<Self> {
        // The offsets, the arms and the errors come from the one definition in mass.rs.
        let (offsets, notes) = train.axis_offsets();
        let offsets = crate::model::mass::offset_index(&offsets);
        let n = train.coordinates().len();
        let mut entries = Vec::new();
        let mut terms = Vec::new();
        let (mut inertia_links, mut mass_links) = (Vec::new(), Vec::new());
        let mut varying = Vec::new();
        for (li, link) in train.links().iter().enumerate() {
            let l = LinkId::from_index(li);
            let Some(c) = train.coordinate(l) else {
                continue;
            };
            let spin = link.sized.then(|| {
                inertia_links.push(l);
                (c, inertia_links.len() - 1)
            });
            let copies = f64::from(link.copies);
            // A satellite's arms add w_k^2 d^2 each; their cross terms cancel
            // over evenly spaced copies or vary with the configuration.
            let arms = match train.floating_terms(l, &offsets) {
                // No mass slot where the arms do not balance: [M] would vary.
                Ok(f) if !f.varying.is_empty() => {
                    if link.mass.is_some_and(|m| m > 0.0) {
                        varying.push(link.name.clone());
                    }
                    Vec::new()
                }
                Ok(f) => f.arms,
                Err(_) => Vec::new(),
            };
            let mut float = None;
            if !arms.is_empty() {
                mass_links.push(l);
                float = Some(mass_links.len() - 1);
            }
            entries.push(MassEntry {
                spin,
                float: float.map(|s| (s, terms.len()..terms.len() + 1)),
                copies,
            });
            if let Some(s) = float {
                terms.push(arms[0]);
                for &arm in &arms[1..] {
                    entries.push(MassEntry {
                        spin: None,
                        float: Some((s, terms.len()..terms.len() + 1)),
                        copies,
                    });
                    terms.push(arm);
                }
            }
        }
        if !varying.is_empty() {
            return Err(AnalysisError::ConfigurationDependent {
                links: varying,
                analysis: "a prepared (batch) train".into(),
            }
            .into());
        }
        // The errors of the one definition: missing offsets, unsized planets.
        train.mass_matrix()?;
        Ok(MassModel {
            n,
            entries,
            terms,
            inertia_links,
            mass_links,
            notes,
        })
    }

    /// A model with no inertia or mass slots, for analyses that are given
    /// their \[M\] whole ([`Scenario::mass_matrix`]) or need none.
    pub fn empty(n: usize) -> Self {
        MassModel {
            n,
            entries: Vec::new(),
            terms: Vec::new(),
            inertia_links: Vec::new(),
            mass_links: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// Order of \[M\] (the number of coordinates).
    pub fn n(&self) -> usize {
        self.n
    }
    /// The links whose inertia [`MassModel::fill`] reads, in slot order.
    pub fn inertia_links(&self) -> &[LinkId] {
        &self.inertia_links
    }
    /// The links whose mass [`MassModel::fill`] reads, in slot order: those
    /// carried on moving carriers (eq. 4).
    pub fn mass_links(&self) -> &[LinkId] {
        &self.mass_links
    }
    /// Notes from [`Train::mass_matrix`] (nested carriers, disagreeing offsets).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }
    /// The train's own inertias and masses, in slot order (0 where not given).
    pub fn train_values(&self, train: &Train) -> (Vec<f64>, Vec<f64>) {
        let value = |v: Option<f64>| v.filter(|&x| x > 0.0).unwrap_or(0.0);
        (
            self.inertia_links
                .iter()
                .map(|&l| value(train.link(l).inertia))
                .collect(),
            self.mass_links
                .iter()
                .map(|&l| value(train.link(l).mass))
                .collect(),
        )
    }

    /// Write \[M\] (row-major, n x n) for one inertia per [`MassModel::inertia_links`]
    /// and one mass per [`MassModel::mass_links`]. Allocates nothing.
    pub fn fill(&self, inertia: &[f64], mass: &[f64], m: &mut [f64]) {
        let n = self.n;
        debug_assert_eq!(m.len(), n * n);
        m.iter_mut().for_each(|v| *v = 0.0);
        self.for_each_term(inertia, mass, |a, b, v| m[a * n + b] += v);
    }

    /// [`MassModel::fill`] as a list of (row, column, value) terms (repeated
    /// positions add), for a sparse workspace. Allocates nothing once `m`
    /// has held a fill.
    pub fn fill_entries(&self, inertia: &[f64], mass: &[f64], m: &mut Vec<(usize, usize, f64)>) {
        m.clear();
        self.for_each_term(inertia, mass, |a, b, v| m.push((a, b, v)));
    }

    /// Every term of \[M\] as (row, column, value), in the one order both
    /// fills add them: each link's own rotation (eq. 3), then its eq. (4)
    /// arms, `(copies m d_a) d_b`.
    #[inline]
    fn for_each_term(&self, inertia: &[f64], mass: &[f64], mut f: impl FnMut(usize, usize, f64)) {
        for e in &self.entries {
            if let Some((c, s)) = e.spin {
                f(c, c, e.copies * inertia[s]);
            }
            if let Some((s, range)) = &e.float {
                let w = e.copies * mass[*s];
                let terms = &self.terms[range.clone()];
                for &(a, da) in terms {
                    for &(b, db) in terms {
                        f(a, b, w * da * db);
                    }
                }
            }
        }
    }
}

impl MassModel {
    /// \[M\] in exact rationals, from exact inertias and masses (the offsets
    /// taken exactly as their f64 values): a reference to verify the float
    /// fill against (the accuracy study in `lab/` does).
    pub fn fill_exact(&self, inertia: &[Q], mass: &[Q]) -> QMatrix {
        let n = self.n;
        let mut m = vec![vec![Q::zero(); n]; n];
        for e in &self.entries {
            let copies = exact_of(e.copies);
            if let Some((c, s)) = e.spin {
                m[c][c] += &copies * &inertia[s];
            }
            if let Some((s, range)) = &e.float {
                let w = &copies * &mass[*s];
                let terms = &self.terms[range.clone()];
                for &(a, da) in terms {
                    for &(b, db) in terms {
                        let (da, db) = (exact_of(da), exact_of(db));
                        m[a][b] += &w * &da * &db;
                    }
                }
            }
        }
        m
    }
}

/// The exact rational value of a finite float (0 for a non-finite one).
pub(crate) fn exact_of(v: f64) -> Q {
    exact::from_f64(v).unwrap_or_else(Q::zero)
}

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
/// 66), but a batch solves dense trains eight rows at a time in the lanes
/// (1.8 µs a row at 30 links), so the switch sits higher; every production
/// train is far below it.
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

impl PreparedTrain {
    /// Prepare. `inputs` are the links whose speed each scenario prescribes,
    /// `accelerated` those whose acceleration it prescribes (eq. 8), `driving`
    /// those whose torque is solved (eq. 10); each holds F = coordinates -
    /// gear pairs - extras links.
    ///
    /// # Errors
    /// Wrong counts, the frame or a repeated link among them; the mass-matrix
    /// errors of [`MassModel::new`].
    pub fn new(
        train: &Train,
        inputs: &[LinkId],
        accelerated: &[LinkId],
        driving: &[LinkId],
        extras: &[Extra],
    ) -> Result<Self> {
        let mut plan = Self::for_analysis(train, inputs, accelerated, driving, extras)?;
        plan.mass = MassModel::new(train)?;
        Ok(plan)
    }

    /// As [`PreparedTrain::new`] for one analysis that supplies its \[M\]
    /// whole in each scenario (or none): no mass model is built, so no mass
    /// data is asked for.
    ///
    /// # Errors
    /// Wrong counts, the frame or a repeated link among the links.
    pub fn for_analysis(
        train: &Train,
        inputs: &[LinkId],
        accelerated: &[LinkId],
        driving: &[LinkId],
        extras: &[Extra],
    ) -> Result<Self> {
        let (n, f) = dof_with(train, extras)?;
        let inputs = link_columns(train, inputs, f, "input links")?;
        let accelerated = link_columns(train, accelerated, f, "prescribed accelerations")?;
        let driving = link_columns(train, driving, f, "driving (unknown-torque) links")?;
        let Rows { circuits, extras } = Rows::new(train, extras);
        PreparedTrain {
            n,
            circuits,
            extras,
            accel_shared: inputs == accelerated,
            force_shared: accelerated == driving,
            inputs,
            accelerated,
            driving,
            mass: MassModel::empty(n),
            sparse: None,
            radii: train
                .gears()
                .iter()
                .map(|g| g.radii.map(|r| r[0]))
                .collect(),
        }
        .with_sparse(n >= PREPARED_SPARSE_FROM)
    }

    /// Number of coordinates (links but the frame).
    pub fn n(&self) -> usize {
        self.n
    }
    /// Number of constraint rows (Willis + extra).
    pub fn constraints(&self) -> usize {
        self.circuits.len() + self.extras.len()
    }
    /// Number of gear pairs.
    pub fn gears(&self) -> usize {
        self.circuits.len()
    }
    /// Degree of freedom left by the constraints (inputs, driving links).
    pub fn dof(&self) -> usize {
        self.inputs.len()
    }
    /// The mass model.
    pub fn mass_model(&self) -> &MassModel {
        &self.mass
    }
    /// Pitch radius of gear i of each gear pair, when known (for eq. 11).
    pub fn radii(&self) -> &[Option<f64>] {
        &self.radii
    }
    /// Whether the systems are factored sparsely and \[M\] held as terms
    /// (from [`PREPARED_SPARSE_FROM`] coordinates, unless set).
    pub fn is_sparse(&self) -> bool {
        self.sparse.is_some()
    }

    /// Factor sparsely (or densely) whatever the size: to compare the two
    /// on one train. Workspaces made before keep their kind.
    ///
    /// # Errors
    /// [`AnalysisError::OutOfMemory`] when faer cannot set up the analysis
    /// of a sparse pattern.
    pub fn with_sparse(mut self, sparse: bool) -> Result<Self> {
        self.sparse = if sparse {
            Some(self.sparse_factors()?)
        } else {
            None
        };
        Ok(self)
    }

    /// How many LU factorisations an ideal scenario costs (1 to 3).
    pub fn factorisations(&self) -> usize {
        1 + usize::from(!self.accel_shared) + usize::from(!self.force_shared)
    }

    /// The sparse LUs of the three systems, their patterns analysed.
    ///
    /// # Errors
    /// [`AnalysisError::OutOfMemory`] when faer cannot set up an analysis.
    fn sparse_factors(&self) -> Result<Box<[Factor; 3]>> {
        let g = self.circuits.len();
        let factor = |system: usize| -> Result<Factor> {
            let mut entries = Vec::new();
            self.for_each_entry(&vec![2.0; g], system, |r, c, _| entries.push((r, c)));
            let (lu, slots) =
                SparseLu::new(self.n, &entries).map_err(|e| AnalysisError::OutOfMemory {
                    what: "the sparse LU of the prepared train".into(),
                    detail: e.0,
                })?;
            Ok(Factor::Sparse(Box::new(lu), slots))
        };
        Ok(Box::new([factor(0)?, factor(1)?, factor(2)?]))
    }

    /// Buffers for one thread.
    pub fn workspace(&self) -> Workspace {
        let (n, g) = (self.n, self.circuits.len());
        let [kin, acc, force] = match &self.sparse {
            Some(f) => (**f).clone(),
            None => [
                Factor::Dense(Lu::new(n)),
                Factor::Dense(Lu::new(n)),
                Factor::Dense(Lu::new(n)),
            ],
        };
        Workspace {
            kin,
            acc,
            force,
            speed: vec![0.0; n],
            accel: vec![0.0; n],
            x: vec![0.0; n],
            m: if self.sparse.is_some() {
                Mass::Terms(Vec::with_capacity(n))
            } else {
                Mass::Dense(vec![0.0; n * n])
            },
            mw: vec![0.0; n],
            rhs: vec![0.0; n],
            tau: vec![0.0; g],
            rolling: vec![0.0; g],
            directions: Directions::new(g),
            cond: [1.0; 3],
            psi: None,
            psi_cond: 1.0,
            power: PowerSummary::default(),
            key: vec![f64::NAN; g],
            cache: Cache::default(),
        }
    }

    /// \[V\] of eq. (23) for `ratios`: the speed of every coordinate per unit
    /// speed of each input (one dense column per input), by the speed
    /// system's factorisation (sparse for a large train), with its condition.
    ///
    /// # Errors
    /// The checked factorisation's, naming the system `what` and what a
    /// zero pivot means (`detail`).
    pub(crate) fn velocity_columns(
        &self,
        ratios: &[f64],
        what: &str,
        detail: &str,
    ) -> Result<(nalgebra::DMatrix<f64>, f64)> {
        let (n, f) = (self.n, self.inputs.len());
        let mut lu = match &self.sparse {
            Some(factors) => factors[0].clone(),
            None => Factor::Dense(Lu::new(n)),
        };
        let cond = lu.fill_factor(self, ratios, 0, what, detail)?;
        let c = self.constraints();
        let mut v = nalgebra::DMatrix::zeros(n, f);
        let mut b = vec![0.0; n];
        for col in 0..f {
            b.iter_mut().for_each(|x| *x = 0.0);
            b[c + col] = 1.0;
            lu.solve(&mut b);
            for (r, &x) in b.iter().enumerate() {
                v[(r, col)] = x;
            }
        }
        Ok((v, cond))
    }

    /// Every term of system `system` (0: speeds, 1: \[Psi_w\], 2: the force
    /// matrix) for `ratios` as (row, column, value), in the order and with
    /// the values the dense fill adds them: the Willis rows (1, -tau, tau - 1),
    /// the extra rows, then the unit (or, for the force matrix, -1) rows.
    fn for_each_entry(&self, ratios: &[f64], system: usize, f: impl FnMut(usize, usize, f64)) {
        self.visit_terms(ratios, system, false, f);
    }

    /// Write the constraint rows (eq. 2 with `taus`, then the extras) into the
    /// zeroed row-major `out` with `n` columns.
    fn fill_constraints(&self, taus: &[f64], out: &mut [f64]) {
        let n = self.n;
        for (m, (cols, &t)) in self.circuits.iter().zip(taus).enumerate() {
            for (k, v) in cols.iter().zip(willis_row(t)) {
                if let Some(k) = k {
                    out[m * n + k] += v;
                }
            }
        }
        let base = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    out[(base + e) * n + k] += v;
                }
            }
        }
    }

    /// The speed system: constraint rows, then a unit row per input link.
    /// Row-major n x n into `out`.
    pub fn kinematic_matrix(&self, ratios: &[f64], out: &mut [f64]) {
        self.unit_rows(ratios, &self.inputs, out);
    }

    /// \[Psi_w\] of eq. (8): constraint rows, then a unit row per accelerated link.
    pub fn acceleration_matrix(&self, ratios: &[f64], out: &mut [f64]) {
        self.unit_rows(ratios, &self.accelerated, out);
    }

    fn unit_rows(&self, ratios: &[f64], links: &[usize], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        self.fill_constraints(ratios, out);
        let c = self.constraints();
        for (r, &k) in links.iter().enumerate() {
            out[(c + r) * self.n + k] = 1.0;
        }
    }

    /// The matrix whose transpose eq. (10) solves: constraint rows with the
    /// force ratios, then -1 in each driving link's column. Row-major into `out`.
    pub fn force_matrix(&self, force_ratios: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        self.fill_constraints(force_ratios, out);
        let c = self.constraints();
        for (r, &k) in self.driving.iter().enumerate() {
            out[(c + r) * self.n + k] = -1.0;
        }
    }

    /// The prepared structure as JSON, for tools outside Rust (the benchmark's
    /// SymPy and NumPy routes build the same equations from it): coordinates
    /// `n`; per circuit the columns of gear i, gear j and the carrier (null
    /// for the frame); extra rows as (column, coefficient) pairs; the input,
    /// accelerated and driving columns; the mass model (per link: its copies,
    /// its inertia slot and column, its mass slot and eq. 4 terms (column, offset)).
    pub fn structure(&self) -> serde_json::Value {
        let entries: Vec<serde_json::Value> = self
            .mass
            .entries
            .iter()
            .map(|e| {
                serde_json::json!({
                    "copies": e.copies,
                    "spin": e.spin.map(|(c, s)| serde_json::json!({"column": c, "slot": s})),
                    "float": e.float.as_ref().map(|(s, r)| serde_json::json!({
                        "slot": s,
                        "terms": self.mass.terms[r.clone()].iter().map(|&(c, d)| serde_json::json!([c, d])).collect::<Vec<_>>(),
                    })),
                })
            })
            .collect();
        serde_json::json!({
            "n": self.n,
            "circuits": self.circuits,
            "extras": self.extras,
            "inputs": self.inputs,
            "accelerated": self.accelerated,
            "driving": self.driving,
            "mass": entries,
        })
    }

    /// Every entry of the speed system (`system` 0), \[Psi_w\] (1) or the force
    /// matrix (2) as a sum of terms `f(row, column, coefficient)` whose
    /// coefficients are the data themselves (1, -tau, tau, -1), so that a
    /// residual built from them carries no rounding of tau - 1.
    pub fn for_each_term(&self, ratios: &[f64], system: usize, f: impl FnMut(usize, usize, f64)) {
        self.visit_terms(ratios, system, true, f);
    }

    /// The terms of system `system`: each Willis row as (1, -tau, tau, -1)
    /// when `split` ([`PreparedTrain::for_each_term`]), else as the dense
    /// fill adds it, (1, -tau, tau - 1) ([`PreparedTrain::for_each_entry`]);
    /// then the extra rows and the input, accelerated or driving rows.
    fn visit_terms(
        &self,
        ratios: &[f64],
        system: usize,
        split: bool,
        mut f: impl FnMut(usize, usize, f64),
    ) {
        for (m, (cols, &t)) in self.circuits.iter().zip(ratios).enumerate() {
            let row = if split { [1.0, -t, t] } else { willis_row(t) };
            for (k, v) in cols.iter().zip(row) {
                if let Some(k) = k {
                    f(m, *k, v);
                }
            }
            if let (true, Some(k)) = (split, cols[2]) {
                f(m, k, -1.0);
            }
        }
        let c0 = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    f(c0 + e, k, v);
                }
            }
        }
        let c = self.constraints();
        let (links, v) = match system {
            0 => (&self.inputs, 1.0),
            1 => (&self.accelerated, 1.0),
            _ => (&self.driving, -1.0),
        };
        for (r, &k) in links.iter().enumerate() {
            f(c + r, k, v);
        }
    }

    /// The speed system, \[Psi_w\] and the force matrix (not transposed) in
    /// exact rationals, for exact ratios: a reference to verify float solves
    /// against (the accuracy study in `lab/` does).
    pub fn exact_matrices(&self, ratios: &[Q]) -> [QMatrix; 3] {
        let n = self.n;
        let mut base = vec![vec![Q::zero(); n]; n];
        for (m, (cols, t)) in self.circuits.iter().zip(ratios).enumerate() {
            let one = exact::q(1);
            for (k, v) in cols.iter().zip([one.clone(), -t.clone(), t - &one]) {
                if let Some(k) = k {
                    base[m][*k] += v;
                }
            }
        }
        let c0 = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    base[c0 + e][k] += exact_of(v);
                }
            }
        }
        let c = self.constraints();
        let with = |links: &[usize], v: i64| {
            let mut a = base.clone();
            for (r, &k) in links.iter().enumerate() {
                a[c + r][k] = exact::q(v);
            }
            a
        };
        [
            with(&self.inputs, 1),
            with(&self.accelerated, 1),
            with(&self.driving, -1),
        ]
    }

    /// The right-hand side of the speed (or acceleration) solve: zeros, then the prescribed values.
    pub fn input_rhs(&self, values: &[f64], out: &mut [f64]) {
        let c = self.constraints();
        out.iter_mut().for_each(|v| *v = 0.0);
        out[c..].copy_from_slice(values);
    }

    /// The right-hand side of eq. (10), {Q} - \[M\]{w'}, into `out`.
    pub fn force_rhs(&self, mass: &[f64], torques: &[f64], accel: &[f64], out: &mut [f64]) {
        let n = self.n;
        for (i, o) in out.iter_mut().enumerate() {
            let row = &mass[i * n..(i + 1) * n];
            *o = torques[i] - row.iter().zip(accel).map(|(a, b)| a * b).sum::<f64>();
        }
    }

    /// Solve one scenario into `ws`. Allocates nothing. When the ratios equal
    /// (bitwise) those of the last scenario solved in `ws`, its factorisations
    /// and condition estimates are reused: the results are the same numbers
    /// a fresh workspace gives.
    ///
    /// # Errors
    /// [`AnalysisError::Singular`] or [`AnalysisError::IllConditioned`] (past
    /// \[`COND_REFUSE`\]) for eq. (8) or eq. (10); with losses, no consistent
    /// direction of power flow (self-locking).
    pub fn solve(&self, ws: &mut Workspace, s: &Scenario<'_>, what: Compute) -> Result<()> {
        // The matrices depend on the ratios only: the factorisations (and
        // their condition estimates) of the previous scenario are reused when
        // its ratios were the same.
        if ws.key[..] != s.ratios[..] {
            ws.cache = Cache::default();
            ws.key.copy_from_slice(s.ratios);
        }
        let speeds = what != Compute::Forces;
        if speeds {
            if !ws.cache.kin {
                // Speeds: the Willis equations (eq. 2) completed by the input rows.
                ws.cond[0] = ws.kin.fill_factor(
                    self,
                    s.ratios,
                    0,
                    "the speed system (eq. 2)",
                    "the inputs do not determine the motion",
                )?;
                ws.cache.kin = true;
            }
            self.input_rhs(s.speeds, &mut ws.speed);
            if what == Compute::Kinematics {
                ws.kin.solve(&mut ws.speed);
                self.keep_inputs(s.speeds, &mut ws.speed);
                return Ok(());
            }
        } else {
            ws.speed.iter_mut().for_each(|v| *v = 0.0);
        }
        // Accelerations: eq. (8), the speeds' factorisation when the links are
        // the same; none at all when no acceleration is prescribed.
        let moving = s.accelerations.iter().any(|&a| a != 0.0);
        self.input_rhs(s.accelerations, &mut ws.accel);
        ws.psi = None;
        if self.accel_shared && speeds {
            ws.psi = Some(Psi::Kin);
            ws.psi_cond = ws.cond[0];
            ws.cond[1] = ws.cond[0];
            if moving {
                ws.kin.solve2(&mut ws.speed, &mut ws.accel);
            } else {
                ws.kin.solve(&mut ws.speed);
            }
        } else {
            if speeds {
                ws.kin.solve(&mut ws.speed);
            }
            if moving && !ws.cache.acc {
                ws.psi_cond = ws.acc.fill_factor(
                    self,
                    s.ratios,
                    1,
                    "[Psi_w] (eq. 8)",
                    "the prescribed accelerations do not determine the motion",
                )?;
                ws.cache.acc = true;
            }
            if ws.cache.acc {
                ws.psi = Some(Psi::Acc);
            }
            if moving {
                ws.cond[1] = ws.psi_cond;
                ws.acc.solve(&mut ws.accel);
            } else {
                ws.cond[1] = 1.0;
            }
        }
        // The prescribed accelerations are data: keep them, not their round-off.
        for (&k, &a) in self.accelerated.iter().zip(s.accelerations) {
            ws.accel[k] = a;
        }
        if speeds {
            self.keep_inputs(s.speeds, &mut ws.speed);
        }
        let n = self.n;
        match (&mut ws.m, s.mass_matrix) {
            (Mass::Dense(m), Some(given)) => {
                m.iter_mut().for_each(|v| *v = 0.0);
                for &(r, c, v) in given.entries() {
                    m[r * n + c] = v;
                }
            }
            (Mass::Dense(m), None) => self.mass.fill(s.inertia, s.mass, m),
            (Mass::Terms(t), Some(given)) => {
                t.clear();
                t.extend_from_slice(given.entries());
            }
            (Mass::Terms(t), None) => self.mass.fill_entries(s.inertia, s.mass, t),
        }
        // {Q} - [M]{w'}.
        ws.m.mul_vec(n, &ws.accel, &mut ws.mw);
        for ((r, &q), &mw) in ws.rhs.iter_mut().zip(s.torques).zip(&ws.mw) {
            *r = q - mw;
        }
        ws.tau.copy_from_slice(s.ratios);
        self.solve_forces(ws, true)?;
        if what == Compute::Power {
            self.power(ws, s)?;
        }
        // The check is quadratic (it scans the circuits per coordinate, to
        // allocate nothing): large trains are checked by their tests instead.
        debug_assert!(self.n > 256 || self.residual_of_motion(ws, s) < 1e-8);
        Ok(())
    }

    /// The prescribed input speeds are data: keep them, not the solve's
    /// round-off (75 echoed as 75, not 74.99999999999999), and write no -0.0.
    fn keep_inputs(&self, values: &[f64], speed: &mut [f64]) {
        for (&k, &v) in self.inputs.iter().zip(values) {
            speed[k] = v;
        }
        speed.iter_mut().for_each(|v| *v += 0.0);
    }

    /// Solve eq. (10) with the force ratios in `ws.tau` and the right-hand side
    /// in `ws.rhs`; `ideal` when `ws.tau` equals the kinematic ratios.
    fn solve_forces(&self, ws: &mut Workspace, ideal: bool) -> Result<()> {
        let c = self.constraints();
        ws.x.copy_from_slice(&ws.rhs);
        if ideal
            && self.force_shared
            && let Some(psi) = ws.psi
        {
            // F = D [Psi_w] with D = diag(1, .., 1, -1, .., -1): x = D [Psi_w]^-T r.
            let lu = if psi == Psi::Kin {
                &mut ws.kin
            } else {
                &mut ws.acc
            };
            lu.solve_transpose(&mut ws.x);
            ws.x[c..].iter_mut().for_each(|v| *v = -*v);
            ws.cond[2] = ws.psi_cond;
            return Ok(());
        }
        // The ideal force matrix is cached with the others; a lossy one (its
        // ratios depend on the power-flow directions) never is.
        if !(ideal && ws.cache.force) {
            ws.cache.force = false;
            ws.cond[2] = ws.force.fill_factor(
                self,
                &ws.tau,
                2,
                "the force system (eq. 10)",
                "the driving links cannot balance the loads",
            )?;
            ws.cache.force = ideal;
        }
        ws.force.solve_transpose(&mut ws.x);
        Ok(())
    }

    /// Speed of a link given by its column (the frame is at rest).
    fn w(ws: &Workspace, k: Option<usize>) -> f64 {
        k.map_or(0.0, |k| ws.speed[k])
    }

    /// Mesh losses: the direction of rolling power in every lossy mesh (the
    /// one search of `losses.rs`), then the power balance.
    fn power(&self, ws: &mut Workspace, s: &Scenario<'_>) -> Result<()> {
        let wscale = ws.speed.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (m, cols) in self.circuits.iter().enumerate() {
            ws.rolling[m] = Self::w(ws, cols[1]) - Self::w(ws, cols[2]);
        }
        // The search's buffers leave the workspace while it solves (moving
        // them allocates nothing).
        let mut directions = std::mem::replace(&mut ws.directions, Directions::new(0));
        let rolling = std::mem::take(&mut ws.rolling);
        let meshes = Meshes {
            ratios: s.ratios,
            efficiency: s.efficiency,
            rolling: &rolling,
            speed_scale: wscale,
        };
        let settled = directions.settle(
            &mut LossyScenario {
                plan: self,
                ws,
                meshes,
            },
            &meshes,
        );
        ws.rolling = rolling;
        ws.directions = directions;
        let iterations = settled?;
        // The balance.
        let (mut input, mut output, mut kinetic_rate) = (0.0, 0.0, 0.0);
        let c = self.constraints();
        let n = self.n;
        for k in 0..n {
            let mut torque = s.torques[k];
            if let Some(r) = self.driving.iter().position(|&d| d == k) {
                torque += ws.x[c + r];
            }
            let p = torque * ws.speed[k];
            if p > 0.0 {
                input += p;
            } else {
                output -= p;
            }
            kinetic_rate += ws.mw[k] * ws.speed[k];
        }
        let loss = (0..self.circuits.len())
            .map(|m| ws.x[m] * (s.ratios[m] - ws.tau[m]) * ws.rolling[m])
            .sum();
        ws.power = PowerSummary {
            input,
            output,
            loss,
            kinetic_rate,
            iterations,
        };
        Ok(())
    }

    /// max |M w' + psi~^T lambda - Q - D^T T_d| relative to the largest torque (eq. 6).
    fn residual_of_motion(&self, ws: &Workspace, s: &Scenario<'_>) -> f64 {
        let n = self.n;
        let c = self.constraints();
        let mut worst = 0.0_f64;
        let mut scale = 1e-300_f64;
        for k in 0..n {
            let mut r = ws.mw[k];
            r -= s.torques[k];
            scale = scale.max(s.torques[k].abs());
            for (m, cols) in self.circuits.iter().enumerate() {
                let t = ws.tau[m];
                for (col, v) in cols.iter().zip(willis_row(t)) {
                    if *col == Some(k) {
                        r += v * ws.x[m];
                        scale = scale.max((v * ws.x[m]).abs());
                    }
                }
            }
            for (e, row) in self.extras.iter().enumerate() {
                for &(col, v) in row {
                    if col == Some(k) {
                        r += v * ws.x[self.circuits.len() + e];
                    }
                }
            }
            if let Some(r_d) = self.driving.iter().position(|&d| d == k) {
                r -= ws.x[c + r_d];
                scale = scale.max(ws.x[c + r_d].abs());
            }
            worst = worst.max(r.abs());
        }
        worst / scale
    }
}

/// One scenario's force system as the direction search sees it.
struct LossyScenario<'a, 'b> {
    plan: &'a PreparedTrain,
    ws: &'a mut Workspace,
    meshes: Meshes<'b>,
}

impl LossySolver for LossyScenario<'_, '_> {
    fn solve_directions(&mut self, directions: &[Driver]) -> Result<()> {
        for (m, t) in self.ws.tau.iter_mut().enumerate() {
            *t = self.meshes.force_ratio(m, directions[m]);
        }
        self.plan.solve_forces(self.ws, false)
    }
}

/// The search reads the scenario's current solution as a [`Solved`] one.
impl ForceSolution for LossyScenario<'_, '_> {
    fn multiplier(&self, m: usize) -> f64 {
        self.solved().multiplier(m)
    }
    fn torque_scale(&self) -> f64 {
        self.solved().torque_scale()
    }
    fn condition(&self) -> f64 {
        self.solved().condition()
    }
}

impl LossyScenario<'_, '_> {
    fn solved(&self) -> Solved<'_> {
        Solved {
            plan: self.plan,
            ws: self.ws,
        }
    }
}

/// A solved scenario, read by the direction rule.
struct Solved<'a> {
    plan: &'a PreparedTrain,
    ws: &'a Workspace,
}

impl ForceSolution for Solved<'_> {
    fn multiplier(&self, m: usize) -> f64 {
        self.ws.x[m]
    }
    fn torque_scale(&self) -> f64 {
        self.plan.torque_scale(self.ws)
    }
    fn condition(&self) -> f64 {
        self.ws.cond[2]
    }
}

impl PreparedTrain {
    /// The train's torque scale in a solution: the largest right-hand side of
    /// eq. (10), driving torque or mesh torque.
    fn torque_scale(&self, ws: &Workspace) -> f64 {
        let c = self.constraints();
        let applied = ws.rhs.iter().chain(&ws.x[c..]);
        let meshes = (0..self.circuits.len()).map(|m| mesh_torque(ws.x[m], ws.tau[m]));
        applied.map(|v| v.abs()).chain(meshes).fold(0.0, f64::max)
    }

    /// Which gear drives each mesh in the carrier's frame in the last solution
    /// of `ws` for `s` (none where a mesh does not roll or is idle), by the
    /// rule of the direction search. Needs the rolling speeds of a
    /// [`Compute::Power`] solve.
    pub fn drivers(&self, ws: &Workspace, s: &Scenario<'_>) -> Vec<Driver> {
        let wscale = ws.speed.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let meshes = Meshes {
            ratios: s.ratios,
            efficiency: s.efficiency,
            rolling: &ws.rolling,
            speed_scale: wscale,
        };
        let solved = Solved { plan: self, ws };
        let tol = idle_tolerance(&solved);
        (0..self.circuits.len())
            .map(|m| meshes.implied_at(&solved, m, tol))
            .collect()
    }
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
