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

mod integrate;
mod request;
mod results;
mod stepping;
mod torque;

pub use request::{Method, SimulationOptions, SimulationOverrides, SimulationRequest};
pub use results::{Divergence, Sample, Simulation};
pub use stepping::SimulationStepper;
pub use torque::{LinearCurves, TorqueFn, TorqueModel};

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

/// The prepared forward dynamics: the basis N, N^T M N and its inertia
/// split, the torque model, and buffers sized once.
pub struct ReducedDynamics<'a> {
    train: &'a Train,
    torque: &'a dyn TorqueModel,
    p: Parts,
    newton: usize,
}

/// What [`ReducedDynamics`] prepares once and owns: the model, the inertia
/// split and buffers sized once (kept between pieces by `stepping.rs`).
#[derive(Debug, Clone)]
struct Parts {
    model: ReducedModel,
    ratios: Vec<f64>,
    split: InertiaSplit,
    q1: DMatrix<f64>,
    q0: DMatrix<f64>,
    w: Vec<f64>,
    tq: Vec<f64>,
    jac: DMatrix<f64>,
}

impl std::fmt::Debug for ReducedDynamics<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReducedDynamics")
            .field("dof", &self.p.model.dof())
            .field("inertial_directions", &self.p.split.r)
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
        let p = Parts {
            ratios: train.ratios()?,
            q1: split.q1(),
            q0: split.q0(),
            split,
            model,
            w: vec![0.0; n],
            tq: vec![0.0; n],
            jac: DMatrix::zeros(n, n),
        };
        Ok(ReducedDynamics::from_parts(train, torque, p))
    }

    /// The prepared parts without the borrowed train and torque model, to
    /// keep between pieces of a stepped simulation (`stepping.rs`).
    fn into_parts(self) -> Parts {
        self.p
    }

    /// The dynamics again from [`ReducedDynamics::into_parts`], with a torque
    /// model that may differ from the first one (the same train).
    fn from_parts(train: &'a Train, torque: &'a dyn TorqueModel, p: Parts) -> Self {
        ReducedDynamics {
            train,
            torque,
            p,
            newton: 0,
        }
    }

    /// The reduced model (without curves) for well-conditioned driving links.
    pub fn model(&self) -> &ReducedModel {
        &self.p.model
    }

    /// Number of massless directions (algebraic equations).
    pub fn massless(&self) -> usize {
        self.p.model.dof() - self.p.split.r
    }

    fn links_of(&mut self, x: &DVector<f64>) {
        let v = &self.p.model.basis;
        for (l, w) in self.p.w.iter_mut().enumerate() {
            *w = (0..x.len()).map(|k| v[(l, k)] * x[k]).sum();
        }
    }

    /// g(x) = V^T T(t, V x), and the power w . T.
    fn g(&mut self, t: f64, x: &DVector<f64>) -> (DVector<f64>, f64) {
        self.links_of(x);
        self.torque.torques(t, &self.p.w, &mut self.p.tq);
        let v = &self.p.model.basis;
        let g = DVector::from_iterator(
            x.len(),
            (0..x.len()).map(|k| (0..self.p.w.len()).map(|l| v[(l, k)] * self.p.tq[l]).sum()),
        );
        let p = self.p.w.iter().zip(&self.p.tq).map(|(a, b)| a * b).sum();
        (g, p)
    }

    /// J = V^T (dT/dw) V at x.
    fn jr(&mut self, t: f64, x: &DVector<f64>) -> DMatrix<f64> {
        self.links_of(x);
        self.torque.jacobian(t, &self.p.w, &mut self.p.jac);
        let v = &self.p.model.basis;
        v.transpose() * &self.p.jac * v
    }

    /// Solve the massless directions: Q0^T g(Q1 y + Q0 z) = 0 for z (Newton).
    fn project(&mut self, t: f64, x: &mut DVector<f64>) -> Result<()> {
        if self.p.split.r == self.p.model.dof() {
            return Ok(());
        }
        let q0 = self.p.q0.clone();
        for _ in 0..NEWTON_MAX {
            let (g, _) = self.g(t, x);
            let res = q0.tr_mul(&g);
            let scale = self
                .p
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
        let y = self.p.q1.tr_mul(&g);
        let y = DVector::from_iterator(y.len(), y.iter().zip(&self.p.split.mu).map(|(a, m)| a / m));
        (&self.p.q1 * y, p)
    }

    /// Every link's acceleration at time `t` and link speeds `speed` (which
    /// must satisfy the Willis equations), including the massless directions
    /// (from the derivative of their torque balance).
    ///
    /// # Errors
    /// Singular massless block.
    pub fn acceleration(&mut self, t: f64, speed: &[f64]) -> Result<Vec<f64>> {
        let x = self
            .p
            .model
            .basis
            .tr_mul(&DVector::from_column_slice(speed));
        let (mut xd, _) = self.xdot(t, &x);
        if self.p.split.r < self.p.model.dof() {
            let j = self.jr(t, &x);
            let a = self.p.q0.tr_mul(&j) * &self.p.q0;
            let b = -(self.p.q0.tr_mul(&j) * &xd);
            let zd = a.lu().solve(&b).ok_or_else(|| AnalysisError::Singular {
                what: "the massless directions of the reduced model".into(),
                detail: "their torques do not depend on their speeds".into(),
            })?;
            xd += &self.p.q0 * zd;
        }
        Ok((&self.p.model.basis * xd).iter().copied().collect())
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
        self.torque.torques(t, speed, &mut self.p.tq);
        let torques: Vec<(LinkId, f64)> = self
            .p
            .tq
            .iter()
            .enumerate()
            .filter(|(l, v)| **v != 0.0 && LinkId::from_index(*l) != self.train.frame())
            .map(|(l, &v)| (LinkId::from_index(l), v))
            .collect();
        let req = DynamicsRequest {
            torques,
            accelerations: self
                .p
                .model
                .coordinates
                .iter()
                .map(|&l| (l, acc[l.index()]))
                .collect(),
            driving: self.p.model.coordinates.clone(),
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
        let mut lin = self.p.model.clone();
        lin.basis_slope = (&j + j.transpose()) * 0.5;
        lin.stability().ok()
    }
}
