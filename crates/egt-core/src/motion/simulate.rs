//! Forward dynamics in reduced coordinates (paper eq. 12, for any F).
//!
//! With F driving speeds x, every link speed is w = V x and the equations of
//! motion are V^T M V x' = V^T T(t, V x) (eq. 12, 25). The state used here is
//! the same motion in an orthonormal basis N of the null space of \[psi_w\]
//! (V = N N_S^-1, see `stability.rs`): w = N u,
//!
//!   N^T M N u' = N^T T(t, N u),
//!
//! which is as well conditioned as the train itself whichever links drive.
//! The Willis equations (eq. 2) hold by construction and only rounding can
//! make them drift (the drift is measured at every sample).
//!
//! for any applied torques T (a [`TorqueModel`]: the linearised curves of the
//! spec, or any nonlinear law). Directions of V^T M V without inertia are
//! algebraic (V^T T = 0 along them, an index-1 DAE): the explicit method
//! re-solves them after every stage, the implicit method handles them as they
//! are, since its Newton matrix M - h gamma J stays regular.
//!
//! Two fixed-step integrators:
//! - `rk4`: the classical explicit Runge-Kutta method, order 4; stable for
//!   |lambda| h <= 2.785 on the negative real axis, so a stiff train (large
//!   slopes, small inertias) needs tiny steps or blows up.
//! - `implicit`: the two-stage, stiffly accurate, L-stable SDIRK method of
//!   Alexander (gamma = 1 - 1/sqrt 2), order 2, with Newton iterations on the
//!   analytic Jacobian V^T (dT/dw) V: stable for any step on a decaying mode,
//!   and it damps the stiff ones instead of ringing like the trapezoidal rule.
//!
//! Alongside the state the work of the applied torques W = int w.T dt is
//! integrated with the same stages, so E(t) - E(0) - W(t) (E = w^T M w / 2)
//! measures the integration error (the energy balance).
//!
//! ```
//! use egt_core::{Format, Method, SimulationOptions, SimulationRequest, Train};
//!
//! // A motor geared to a flywheel, 1 rad/s above its steady speed of 100 rad/s.
//! let spec = r#"
//!     frame = "0"
//!     links = [{ name = "m", inertia = 0.5 }, { name = "o", inertia = 0.3 }]
//!     revolutes = [{ links = ["0", "m"], level = "a" }, { links = ["0", "o"], level = "b" }]
//!     gears = [{ links = ["m", "o"], ratio = -2.0 }]
//!     [analysis]
//!     curves = [{ link = "m", torque = 0.0, slope = -0.8, speed = 100.0 }]
//! "#;
//! let train = Train::from_str(spec, Format::Toml, "example").unwrap();
//! let m = train.link_id("m").unwrap();
//! let req = SimulationRequest {
//!     initial: vec![(m, 101.0)],
//!     options: SimulationOptions { t_end: 1.0, dt: 1e-3, method: Method::Rk4, every: 0 },
//! };
//! let sim = train.simulate(&req).unwrap();
//! let last = sim.samples.last().unwrap();
//! let lambda: f64 = -0.8 / (0.5 + 0.3 / 4.0);
//! assert!((last.speed[m.index()] - (100.0 + lambda.exp())).abs() < 1e-9);
//! assert!(sim.max_drift < 1e-14 && sim.energy_error < 1e-9);
//! ```

use std::str::FromStr;

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::analysis::dynamics::{DynamicsRequest, InverseDynamics};
use crate::analysis::stability::RK4_REAL_LIMIT;
use crate::error::{AnalysisError, Error, Result, SpecErrorKind};
use crate::model::mass::MassMatrix;
use crate::model::train::{Curve, LinkId, Train};
use crate::numerics::linalg::Lu;
use crate::solve::kinematics::willis_residual;
use crate::solve::reduced::{InertiaSplit, ReducedModel, num};

/// Stop when a speed exceeds this [rad/s]: the solution has blown up.
pub const DIVERGED_SPEED: f64 = 1e100;
/// Newton iterations converge when the update is below this fraction of the state.
const NEWTON_TOL: f64 = 1e-12;
/// Newton iterations per attempt.
const NEWTON_MAX: usize = 25;
/// Halvings of an implicit step whose Newton iteration fails.
const MAX_HALVINGS: usize = 12;
/// Above this relative energy-balance error a simulation carries a warning.
pub const ENERGY_WARN: f64 = 1e-3;
/// Above this relative Willis drift a simulation carries a warning.
pub const DRIFT_WARN: f64 = 1e-10;
/// Default number of stored samples.
pub const DEFAULT_SAMPLES: usize = 2000;
/// Largest number of steps accepted.
pub const MAX_STEPS: usize = 50_000_000;

/// Applied torques on the links as functions of time and link speeds.
pub trait TorqueModel {
    /// The applied torque on every link (by link index) at time `t` and link
    /// speeds `speed`, written into `torque`.
    fn torques(&self, t: f64, speed: &[f64], torque: &mut [f64]);

    /// dT_i/dw_j (links x links). The default differentiates
    /// [`TorqueModel::torques`] by central differences.
    fn jacobian(&self, t: f64, speed: &[f64], jac: &mut DMatrix<f64>) {
        let n = speed.len();
        let mut w = speed.to_vec();
        let (mut tp, mut tm) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let h = 1e-6 * speed[j].abs().max(1.0);
            w[j] = speed[j] + h;
            self.torques(t, &w, &mut tp);
            w[j] = speed[j] - h;
            self.torques(t, &w, &mut tm);
            w[j] = speed[j];
            for i in 0..n {
                jac[(i, j)] = (tp[i] - tm[i]) / (2.0 * h);
            }
        }
    }
}

/// The linearised torque-speed curves T_l = T0_l + K_l (w_l - w0_l) (eq. 13-15).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearCurves {
    slope: Vec<f64>,
    offset: Vec<f64>,
    active: Vec<bool>,
}

impl LinearCurves {
    /// From the reduced model's per-link slopes and offsets.
    pub fn from_model(model: &ReducedModel) -> Self {
        LinearCurves {
            slope: model.link_slope.clone(),
            offset: model.link_offset.clone(),
            active: model.has_curve.clone(),
        }
    }

    /// From curves on a train's links (several on one link add up; a curve on the frame does nothing).
    ///
    /// # Errors
    /// A non-finite number in a curve.
    pub fn new(train: &Train, curves: &[Curve]) -> Result<Self> {
        let n = train.links().len();
        let mut c = LinearCurves {
            slope: vec![0.0; n],
            offset: vec![0.0; n],
            active: vec![false; n],
        };
        for k in curves {
            for v in [k.torque, k.slope, k.speed] {
                if !v.is_finite() {
                    return Err(Error::spec(
                        format!("curve on `{}`", train.link_name(k.link)),
                        SpecErrorKind::NonFinite { value: v },
                    ));
                }
            }
            if k.link == train.frame() {
                continue;
            }
            let l = k.link.index();
            c.slope[l] += k.slope;
            c.offset[l] += k.torque - k.slope * k.speed;
            c.active[l] = true;
        }
        Ok(c)
    }
}

impl TorqueModel for LinearCurves {
    fn torques(&self, _t: f64, speed: &[f64], torque: &mut [f64]) {
        for (l, t) in torque.iter_mut().enumerate() {
            *t = if self.active[l] {
                self.offset[l] + self.slope[l] * speed[l]
            } else {
                0.0
            };
        }
    }

    fn jacobian(&self, _t: f64, _speed: &[f64], jac: &mut DMatrix<f64>) {
        jac.fill(0.0);
        for (l, &k) in self.slope.iter().enumerate() {
            jac[(l, l)] = k;
        }
    }
}

/// Any closure `|t, speeds, torques|` as a torque model (Jacobian by differences).
pub struct TorqueFn<F>(pub F);

impl<F> std::fmt::Debug for TorqueFn<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("TorqueFn(..)")
    }
}

impl<F: Fn(f64, &[f64], &mut [f64])> TorqueModel for TorqueFn<F> {
    fn torques(&self, t: f64, speed: &[f64], torque: &mut [f64]) {
        (self.0)(t, speed, torque);
    }
}

/// The integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Classical explicit Runge-Kutta, order 4, fixed step.
    #[default]
    Rk4,
    /// Two-stage L-stable SDIRK (Alexander), order 2, fixed step, Newton on the analytic Jacobian.
    Implicit,
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "rk4" | "explicit" => Ok(Method::Rk4),
            "implicit" | "sdirk" | "sdirk2" => Ok(Method::Implicit),
            other => Err(format!(
                "unknown integrator `{other}` (expected `rk4` or `implicit`)"
            )),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Rk4 => "rk4",
            Method::Implicit => "implicit",
        })
    }
}

/// Step control of a simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulationOptions {
    /// End time \[s\].
    pub t_end: f64,
    /// Fixed step \[s\] (the last step is shortened to end at `t_end`).
    pub dt: f64,
    /// Integrator.
    pub method: Method,
    /// Store every `every`-th step (0: about [`DEFAULT_SAMPLES`] samples). The last step is always stored.
    pub every: usize,
}

/// One stored instant.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sample {
    /// Time \[s\].
    pub t: f64,
    /// Every link's speed (by link index).
    pub speed: Vec<f64>,
    /// Willis drift: max |psi_m(w)| / max |w| (eq. 2).
    pub drift: f64,
    /// Kinetic energy w^T M w / 2.
    pub energy: f64,
    /// Work of the applied torques since t = 0.
    pub work: f64,
    /// Power of the applied torques, w . T.
    pub power: f64,
}

/// Why a simulation stopped early.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Divergence {
    /// Time of the last finite state.
    pub t: f64,
    /// In words.
    pub reason: String,
}

/// A simulated time series and its checks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Simulation {
    /// The integrator.
    pub method: Method,
    /// The step.
    pub dt: f64,
    /// Steps taken.
    pub steps: usize,
    /// Stored samples (t = 0 first).
    pub samples: Vec<Sample>,
    /// Largest Willis drift over the samples.
    pub max_drift: f64,
    /// max |E - E0 - W| relative to the largest energy or work: the integration error.
    pub energy_error: f64,
    /// Set when the solution blew up; `samples` end at the last finite state.
    pub diverged: Option<Divergence>,
    /// RK4's stable step on the linearisation at the initial state, when it has a decaying mode.
    pub rk4_step_limit: Option<f64>,
    /// Eigenvalues of the linearisation at the initial state (largest first).
    pub eigenvalues: Vec<f64>,
    /// Newton iterations (implicit) or algebraic re-solves (massless directions).
    pub newton_iterations: usize,
    /// Implicit steps that were halved because Newton failed.
    pub halvings: usize,
    /// Warnings.
    pub warnings: Vec<String>,
}

impl Simulation {
    /// Growth rate of the deviation from `reference` (link speeds), in the
    /// energy norm sqrt(dw^T M dw): ln(d(t_end) / d(t_from)) / (t_end - t_from),
    /// with `t_from` the first sample at or after `from`. None when the
    /// deviation vanishes or there is no such interval.
    pub fn growth_rate(
        &self,
        train: &Train,
        mass: &MassMatrix,
        reference: &[f64],
        from: f64,
    ) -> Option<f64> {
        // sqrt(2 K(dw)), with dw scaled to unit size first: K is quadratic, and
        // squaring a deviation of 1e-200 would underflow to a zero norm.
        let norm = |s: &Sample| {
            let dw: Vec<f64> = s.speed.iter().zip(reference).map(|(a, b)| a - b).collect();
            let size = dw.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            if size == 0.0 || !size.is_finite() {
                return size;
            }
            let unit: Vec<f64> = dw.iter().map(|v| v / size).collect();
            size * (2.0 * train.kinetic_energy(mass, &unit)).max(0.0).sqrt()
        };
        let last = self.samples.last()?;
        let first = self.samples.iter().find(|s| s.t >= from)?;
        let (a, b) = (norm(first), norm(last));
        (last.t > first.t && a > 0.0 && b > 0.0).then(|| (b / a).ln() / (last.t - first.t))
    }
}

/// Where a simulation starts and how long it runs, with the spec's defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationRequest {
    /// F initial link speeds; empty: the spec's `simulate.initial`, else its `speeds`.
    pub initial: Vec<(LinkId, f64)>,
    /// Step control.
    pub options: SimulationOptions,
}

/// What a caller sets over the spec's `[analysis.simulate]` settings (the
/// CLI's flags, Python's keywords); `None` keeps the spec's value.
#[derive(Debug, Clone, Default)]
pub struct SimulationOverrides {
    /// End time \[s\].
    pub t_end: Option<f64>,
    /// Step \[s\].
    pub dt: Option<f64>,
    /// Integrator.
    pub method: Option<Method>,
    /// Keep every n-th step (0 or 1: every step).
    pub every: Option<usize>,
    /// F initial link speeds.
    pub initial: Option<Vec<(LinkId, f64)>>,
}

impl SimulationRequest {
    /// The spec's `[analysis.simulate]` settings: t_end (required), dt
    /// (default t_end / 1000), method (default rk4), initial speeds.
    ///
    /// # Errors
    /// No `t_end`; an unknown method name.
    pub fn from_spec(train: &Train) -> Result<Self> {
        Self::resolve(train, &SimulationOverrides::default())
    }

    /// The request a caller's overrides and the spec's settings resolve to:
    /// each setting from the override, else the spec, else its default
    /// (dt = t_end / 1000, rk4, every step, the spec's initial speeds). The
    /// one place those defaults are decided, for the CLI and Python alike.
    ///
    /// # Errors
    /// No end time anywhere; an unknown method name in the spec.
    pub fn resolve(train: &Train, over: &SimulationOverrides) -> Result<Self> {
        let sim = train.analysis().simulate.clone().unwrap_or_default();
        let t_end = over.t_end.or(sim.t_end).ok_or_else(|| {
            Error::spec(
                "analysis.simulate.t_end",
                SpecErrorKind::Missing {
                    what: "the end time of the simulation (`t_end`)".into(),
                },
            )
        })?;
        let method = match (over.method, &sim.method) {
            (Some(m), _) => m,
            (None, Some(m)) => m
                .parse()
                .map_err(|e: String| Error::invalid("analysis.simulate.method", e))?,
            (None, None) => Method::default(),
        };
        Ok(SimulationRequest {
            initial: over.initial.clone().unwrap_or_else(|| sim.initial.clone()),
            options: SimulationOptions {
                t_end,
                dt: over.dt.or(sim.dt).unwrap_or(t_end / 1000.0),
                method,
                every: over.every.unwrap_or(0),
            },
        })
    }
}

/// The prepared forward dynamics: the basis N, N^T M N and its inertia
/// split, the torque model, and buffers sized once.
pub struct ReducedDynamics<'a> {
    train: &'a Train,
    torque: &'a dyn TorqueModel,
    model: ReducedModel,
    ratios: Vec<f64>,
    split: InertiaSplit,
    q1: DMatrix<f64>,
    q0: DMatrix<f64>,
    w: Vec<f64>,
    tq: Vec<f64>,
    jac: DMatrix<f64>,
    newton: usize,
}

impl std::fmt::Debug for ReducedDynamics<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReducedDynamics")
            .field("dof", &self.model.dof())
            .field("inertial_directions", &self.split.r)
            .finish_non_exhaustive()
    }
}

impl<'a> ReducedDynamics<'a> {
    /// Prepare for applied torques `torque`.
    ///
    /// # Errors
    /// As [`Train::reduced_model`]; no inertia at all or an indefinite mass matrix.
    pub fn new(train: &'a Train, torque: &'a dyn TorqueModel) -> Result<Self> {
        let coordinates = train.automatic_coordinates()?;
        let model = train.reduced_model(&coordinates, &[])?;
        let split = InertiaSplit::new(&model.basis_mass)?;
        let n = train.links().len();
        Ok(ReducedDynamics {
            train,
            torque,
            ratios: train.ratios()?,
            q1: split.q1(),
            q0: split.q0(),
            split,
            model,
            w: vec![0.0; n],
            tq: vec![0.0; n],
            jac: DMatrix::zeros(n, n),
            newton: 0,
        })
    }

    /// The reduced model (without curves) for well-conditioned driving links.
    pub fn model(&self) -> &ReducedModel {
        &self.model
    }

    /// Number of massless directions (algebraic equations).
    pub fn massless(&self) -> usize {
        self.model.dof() - self.split.r
    }

    fn links_of(&mut self, x: &DVector<f64>) {
        let v = &self.model.basis;
        for (l, w) in self.w.iter_mut().enumerate() {
            *w = (0..x.len()).map(|k| v[(l, k)] * x[k]).sum();
        }
    }

    /// g(x) = V^T T(t, V x), and the power w . T.
    fn g(&mut self, t: f64, x: &DVector<f64>) -> (DVector<f64>, f64) {
        self.links_of(x);
        self.torque.torques(t, &self.w, &mut self.tq);
        let v = &self.model.basis;
        let g = DVector::from_iterator(
            x.len(),
            (0..x.len()).map(|k| (0..self.w.len()).map(|l| v[(l, k)] * self.tq[l]).sum()),
        );
        let p = self.w.iter().zip(&self.tq).map(|(a, b)| a * b).sum();
        (g, p)
    }

    /// J = V^T (dT/dw) V at x.
    fn jr(&mut self, t: f64, x: &DVector<f64>) -> DMatrix<f64> {
        self.links_of(x);
        self.torque.jacobian(t, &self.w, &mut self.jac);
        let v = &self.model.basis;
        v.transpose() * &self.jac * v
    }

    /// Solve the massless directions: Q0^T g(Q1 y + Q0 z) = 0 for z (Newton).
    fn project(&mut self, t: f64, x: &mut DVector<f64>) -> Result<()> {
        if self.split.r == self.model.dof() {
            return Ok(());
        }
        let q0 = self.q0.clone();
        for _ in 0..NEWTON_MAX {
            let (g, _) = self.g(t, x);
            let res = q0.tr_mul(&g);
            let scale = self
                .tq
                .iter()
                .fold(0.0_f64, |m, v| m.max(v.abs()))
                .max(f64::MIN_POSITIVE);
            if res.amax() <= NEWTON_TOL * scale {
                return Ok(());
            }
            let j = self.jr(t, x);
            let jz = q0.tr_mul(&j) * &q0;
            let dz = jz.lu().solve(&res).ok_or_else(|| AnalysisError::Singular {
                what: "the massless directions of the reduced model".into(),
                detail: "their torques do not depend on their speeds at this state".into(),
            })?;
            *x -= &q0 * dz;
            self.newton += 1;
        }
        Err(AnalysisError::NotConverged {
            what: "the torque balance along the massless directions".into(),
            t,
        }
        .into())
    }

    /// x' for a consistent state x (explicit form): M^+ g along the inertial directions.
    fn xdot(&mut self, t: f64, x: &DVector<f64>) -> (DVector<f64>, f64) {
        let (g, p) = self.g(t, x);
        let y = self.q1.tr_mul(&g);
        let y = DVector::from_iterator(y.len(), y.iter().zip(&self.split.mu).map(|(a, m)| a / m));
        (&self.q1 * y, p)
    }

    /// Every link's acceleration at time `t` and link speeds `speed` (which
    /// must satisfy the Willis equations), including the massless directions
    /// (from the derivative of their torque balance).
    ///
    /// # Errors
    /// Singular massless block.
    pub fn acceleration(&mut self, t: f64, speed: &[f64]) -> Result<Vec<f64>> {
        let x = self.model.basis.tr_mul(&DVector::from_column_slice(speed));
        let (mut xd, _) = self.xdot(t, &x);
        if self.split.r < self.model.dof() {
            let j = self.jr(t, &x);
            let a = self.q0.tr_mul(&j) * &self.q0;
            let b = -(self.q0.tr_mul(&j) * &xd);
            let zd = a.lu().solve(&b).ok_or_else(|| AnalysisError::Singular {
                what: "the massless directions of the reduced model".into(),
                detail: "their torques do not depend on their speeds".into(),
            })?;
            xd += &self.q0 * zd;
        }
        Ok((&self.model.basis * xd).iter().copied().collect())
    }

    /// The constraint torques at an instant: inverse dynamics (eq. 6-11) with
    /// every applied torque known and the driving links' accelerations from
    /// the forward dynamics. The solved driving torques are the torques the
    /// forward model leaves unbalanced: zero up to rounding.
    ///
    /// # Errors
    /// As [`ReducedDynamics::acceleration`] and [`Train::inverse_dynamics`].
    pub fn reactions(&mut self, t: f64, speed: &[f64]) -> Result<InverseDynamics> {
        let acc = self.acceleration(t, speed)?;
        self.torque.torques(t, speed, &mut self.tq);
        let torques: Vec<(LinkId, f64)> = self
            .tq
            .iter()
            .enumerate()
            .filter(|(l, v)| **v != 0.0 && LinkId::from_index(*l) != self.train.frame())
            .map(|(l, &v)| (LinkId::from_index(l), v))
            .collect();
        let req = DynamicsRequest {
            torques,
            accelerations: self
                .model
                .coordinates
                .iter()
                .map(|&l| (l, acc[l.index()]))
                .collect(),
            driving: self.model.coordinates.clone(),
            extras: vec![],
        };
        let mass = self.train.constant_mass_matrix("the simulation")?;
        self.train.inverse_dynamics(&req, Some(&mass))
    }

    /// The linearisation at x: (lambda M - J_sym) X = 0 over the inertial
    /// directions (massless ones eliminated), eigenvalues largest first.
    fn linearisation_at(
        &mut self,
        t: f64,
        x: &DVector<f64>,
    ) -> Option<crate::analysis::stability::Stability> {
        let j = self.jr(t, x);
        let mut lin = self.model.clone();
        lin.basis_slope = (&j + j.transpose()) * 0.5;
        lin.stability().ok()
    }

    /// Integrate from F initial link speeds `initial` (given for any F
    /// independent links; the rest follow from the Willis equations).
    ///
    /// # Errors
    /// Invalid step control; initial speeds that do not determine the train;
    /// a failed algebraic or Newton solve. A blow-up is not an error: it is
    /// reported in [`Simulation::diverged`].
    pub fn simulate(
        &mut self,
        initial: &[(LinkId, f64)],
        opts: &SimulationOptions,
    ) -> Result<Simulation> {
        let SimulationOptions {
            t_end,
            dt,
            method,
            every,
        } = *opts;
        for (what, v) in [("t_end", t_end), ("dt", dt)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::spec(
                    format!("simulate.{what}"),
                    SpecErrorKind::OutOfRange {
                        value: v,
                        expected: "must be finite and > 0".into(),
                    },
                ));
            }
        }
        let steps_f = (t_end / dt - 1e-9).ceil().max(1.0);
        if steps_f > MAX_STEPS as f64 {
            return Err(Error::spec(
                "simulate.dt",
                SpecErrorKind::OutOfRange {
                    value: dt,
                    expected: format!("t_end / dt must be at most {MAX_STEPS} steps"),
                },
            ));
        }
        let steps = steps_f as usize;
        let every = if every == 0 {
            steps.div_ceil(DEFAULT_SAMPLES).max(1)
        } else {
            every
        };
        let w0 = self.train.speeds_from(initial)?;
        let mut x = self.model.basis.tr_mul(&DVector::from_vec(w0));
        let mut warnings = self.model.warnings.clone();
        if self.split.nearly_massless {
            warnings.push("a direction is nearly massless: the model is stiff".into());
        }
        if self.split.r < self.model.dof() {
            let before = x.clone();
            self.project(0.0, &mut x)?;
            if (&x - &before).amax() > 1e-12 * before.amax().max(1.0) {
                warnings.push(format!(
                    "{} massless direction(s): the initial speeds were moved onto their torque balance",
                    self.model.dof() - self.split.r
                ));
            }
        }
        let linear = self.linearisation_at(0.0, &x);
        if let Some(m) = linear
            .as_ref()
            .and_then(|l| l.massless.iter().find(|m| m.slope > 0.0))
        {
            warnings.push(format!(
                "a massless direction has a rising torque (slope {}): the torque balance followed here is unstable, and with any parasitic inertia the train would run away from it",
                num(m.slope)
            ));
        }
        let eigenvalues = linear.map(|l| l.eigenvalues).unwrap_or_default();
        let rk4_step_limit = eigenvalues
            .last()
            .filter(|&&l| l < 0.0)
            .map(|l| RK4_REAL_LIMIT / -l);
        if method == Method::Rk4
            && let Some(limit) = rk4_step_limit
            && dt > limit
        {
            warnings.push(format!(
                        "dt = {} exceeds RK4's stability limit {} = 2.785 / |lambda| (lambda = {}): expect a numerical blow-up; use --method implicit or a smaller dt",
                        num(dt),
                        num(limit),
                        num(eigenvalues.last().copied().unwrap_or(0.0))
                    ));
        }
        let mass = self.train.constant_mass_matrix("the simulation")?;
        let mut samples = Vec::with_capacity(steps / every + 2);
        let (_, p0) = self.g(0.0, &x);
        samples.push(self.sample(0.0, &x, 0.0, p0, &mass));
        let (mut t, mut work) = (0.0, 0.0);
        let mut diverged = None;
        let mut halvings = 0;
        for n in 0..steps {
            let h = if n + 1 == steps { t_end - t } else { dt };
            let (xn, dw) = match method {
                Method::Rk4 => self.rk4(t, &x, h)?,
                Method::Implicit => self.sdirk(t, &x, h, 0, &mut halvings)?,
            };
            if !xn.iter().all(|v| v.is_finite()) || xn.amax() > DIVERGED_SPEED || !dw.is_finite() {
                diverged = Some(Divergence {
                    t,
                    reason: format!(
                        "a speed exceeded {DIVERGED_SPEED:e} rad/s in the step from t = {t:e} ({method}, dt = {h:e})"
                    ),
                });
                break;
            }
            x = xn;
            work += dw;
            t = if n + 1 == steps {
                t_end
            } else {
                (n + 1) as f64 * dt
            };
            if (n + 1) % every == 0 || n + 1 == steps {
                let (_, p) = self.g(t, &x);
                samples.push(self.sample(t, &x, work, p, &mass));
            }
        }
        if let Some(d) = &diverged {
            warnings.push(d.reason.clone());
        }
        let e0 = samples[0].energy;
        let scale = samples
            .iter()
            .fold(e0.abs(), |m, s| m.max(s.energy.abs()).max(s.work.abs()))
            .max(f64::MIN_POSITIVE);
        let energy_error = samples
            .iter()
            .map(|s| (s.energy - e0 - s.work).abs())
            .fold(0.0, f64::max)
            / scale;
        let max_drift = samples.iter().map(|s| s.drift).fold(0.0, f64::max);
        if energy_error > ENERGY_WARN {
            warnings.push(format!(
                "the energy balance is off by {energy_error:.2e} of the largest energy: the integration is inaccurate; reduce dt"
            ));
        }
        if max_drift > DRIFT_WARN {
            warnings.push(format!(
                "the Willis equations drift by {max_drift:.2e} (relative): rounding has accumulated"
            ));
        }
        Ok(Simulation {
            method,
            dt,
            steps,
            samples,
            max_drift,
            energy_error,
            diverged,
            rk4_step_limit,
            eigenvalues,
            newton_iterations: self.newton,
            halvings,
            warnings,
        })
    }

    fn sample(
        &mut self,
        t: f64,
        x: &DVector<f64>,
        work: f64,
        power: f64,
        mass: &MassMatrix,
    ) -> Sample {
        let speed: Vec<f64> = (&self.model.basis * x).iter().copied().collect();
        Sample {
            t,
            drift: willis_residual(self.train, &self.ratios, &speed),
            energy: self.train.kinetic_energy(mass, &speed),
            speed,
            work,
            power,
        }
    }

    /// One classical RK4 step; returns the new state and the work increment.
    fn rk4(&mut self, t: f64, x: &DVector<f64>, h: f64) -> Result<(DVector<f64>, f64)> {
        let (k1, p1) = self.xdot(t, x);
        let mut x2 = x + &k1 * (h / 2.0);
        self.project(t + h / 2.0, &mut x2)?;
        let (k2, p2) = self.xdot(t + h / 2.0, &x2);
        let mut x3 = x + &k2 * (h / 2.0);
        self.project(t + h / 2.0, &mut x3)?;
        let (k3, p3) = self.xdot(t + h / 2.0, &x3);
        let mut x4 = x + &k3 * h;
        self.project(t + h, &mut x4)?;
        let (k4, p4) = self.xdot(t + h, &x4);
        let mut xn = x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        if xn.iter().all(|v| v.is_finite()) {
            self.project(t + h, &mut xn)?;
        }
        Ok((xn, h / 6.0 * (p1 + 2.0 * p2 + 2.0 * p3 + p4)))
    }

    /// One step of Alexander's 2-stage SDIRK (L-stable, stiffly accurate),
    /// halving the step when Newton fails.
    fn sdirk(
        &mut self,
        t: f64,
        x: &DVector<f64>,
        h: f64,
        depth: usize,
        halvings: &mut usize,
    ) -> Result<(DVector<f64>, f64)> {
        match self.sdirk_once(t, x, h) {
            Ok(r) => Ok(r),
            Err(_) if depth < MAX_HALVINGS => {
                *halvings += 1;
                let (xm, w1) = self.sdirk(t, x, h / 2.0, depth + 1, halvings)?;
                let (xn, w2) = self.sdirk(t + h / 2.0, &xm, h / 2.0, depth + 1, halvings)?;
                Ok((xn, w1 + w2))
            }
            Err(e) => Err(e),
        }
    }

    fn sdirk_once(&mut self, t: f64, x: &DVector<f64>, h: f64) -> Result<(DVector<f64>, f64)> {
        let gamma = 1.0 - std::f64::consts::FRAC_1_SQRT_2;
        let f = self.model.dof();
        let m = self.model.basis_mass.clone();
        let j = self.jr(t, x);
        let mut lu = Lu::new(f);
        let fill = |lu: &mut Lu, j: &DMatrix<f64>| -> Result<()> {
            let a = lu.matrix_mut();
            for r in 0..f {
                for c in 0..f {
                    a[r * f + c] = m[(r, c)] - h * gamma * j[(r, c)];
                }
            }
            lu.factor().map_err(|_| {
                AnalysisError::Singular {
                    what: "the implicit step's Newton matrix M - h gamma J".into(),
                    detail: format!("at t = {t:e}, h = {h:e}"),
                }
                .into()
            })
        };
        fill(&mut lu, &j)?;
        // Stage i: M (X - x) - h sum_{j<i} a_ij G_j - h gamma g(t_i, X) = 0.
        let stages = [(gamma, 0.0), (1.0, 1.0 - gamma)];
        let mut g1 = DVector::zeros(f);
        let mut p1 = 0.0;
        let mut xs = x.clone();
        let mut out = (DVector::zeros(f), 0.0);
        for (i, &(c, a21)) in stages.iter().enumerate() {
            let ti = t + c * h;
            let known = &g1 * (h * a21);
            let mut converged = false;
            for _ in 0..NEWTON_MAX {
                let (g, _) = self.g(ti, &xs);
                let res = &m * (&xs - x) - &known - &g * (h * gamma);
                let mut d: Vec<f64> = res.iter().copied().collect();
                lu.solve(&mut d);
                let d = DVector::from_vec(d);
                xs -= &d;
                self.newton += 1;
                if !xs.iter().all(|v| v.is_finite()) {
                    break;
                }
                if d.amax() <= NEWTON_TOL * xs.amax().max(x.amax()).max(f64::MIN_POSITIVE) {
                    converged = true;
                    break;
                }
            }
            if !converged {
                return Err(AnalysisError::NotConverged {
                    what: format!("the implicit step (h = {h:e})"),
                    t,
                }
                .into());
            }
            let (g, p) = self.g(ti, &xs);
            if i == 0 {
                g1 = g;
                p1 = p;
            } else {
                out = (xs.clone(), h * ((1.0 - gamma) * p1 + gamma * p));
            }
        }
        Ok(out)
    }
}

impl Train {
    /// Simulate under the spec's curves from the request's initial speeds,
    /// else the spec's `simulate.initial`, else its `speeds`.
    ///
    /// # Errors
    /// No curves; as [`ReducedDynamics::new`] and [`ReducedDynamics::simulate`].
    pub fn simulate(&self, req: &SimulationRequest) -> Result<Simulation> {
        let curves = &self.analysis().curves;
        let torque = LinearCurves::new(self, curves)?;
        self.simulate_with(req, &torque)
    }

    /// As [`Train::simulate`] with any torque model.
    ///
    /// # Errors
    /// As [`Train::simulate`].
    pub fn simulate_with(
        &self,
        req: &SimulationRequest,
        torque: &dyn TorqueModel,
    ) -> Result<Simulation> {
        let initial = self.initial_speeds(req)?;
        let mut dynamics = ReducedDynamics::new(self, torque)?;
        dynamics.simulate(&initial, &req.options)
    }

    /// The initial speeds a request resolves to.
    ///
    /// # Errors
    /// None given anywhere.
    pub fn initial_speeds(&self, req: &SimulationRequest) -> Result<Vec<(LinkId, f64)>> {
        if !req.initial.is_empty() {
            return Ok(req.initial.clone());
        }
        if let Some(s) = self
            .analysis()
            .simulate
            .as_ref()
            .filter(|s| !s.initial.is_empty())
        {
            return Ok(s.initial.clone());
        }
        if !self.analysis().speeds.is_empty() {
            return Ok(self.analysis().speeds.iter().map(|s| (s.0, s.1)).collect());
        }
        Err(AnalysisError::MissingData {
            what: "initial speeds".into(),
            analysis: "the simulation".into(),
            hint: "give `[analysis.simulate] initial` or `[analysis] speeds`, one per degree of freedom".into(),
        }
        .into())
    }
}
