//! A gear change of a whole train: the elements of the old gear that the new
//! one does not engage release (off-going), the new gear's others apply
//! (on-coming), and the link speeds move from the old gear's ratio to the new
//! one's. A single swap changes one element each way; a skip shift or a
//! double swap may change several, each with its own capacity ramp.
//!
//! The run goes through *modes*, each a set of locked elements. The kept
//! elements (engaged in both gears) stay locked. The off-going and on-coming
//! elements are locked or slipping. A mode's speeds are `v = N q`, with `N`
//! the orthonormal null-space basis of its rows ([`mode_basis`]: Willis rows
//! plus one row `a_e` per locked element). So a mode has exactly its own
//! degrees of freedom: 1 in a gear, one more for each element that slips. The equations of motion are `N^T M N q' = N^T f` (eq. 25 with `V = N`).
//! Here `f` is the input torque at the input link, the road load and the
//! vehicle inertia at the output link, and, for each slipping element, its
//! friction torque `T_e a_e`. A slipping element's torque on its first link
//! is `-dir mu(slip) C(t)`: [`FrictionLaw`] times a [`Capacity`] ramp. A
//! slipping one-way element carries no torque. A locked element's torque is
//! its Lagrange multiplier: the least-squares solution of `A^T lambda =
//! M v' - f` over the mode's rows `A`.
//!
//! At `t = 0` and after every mode change the mode is made consistent
//! (`consistent.rs`): a locked element that cannot hold its torque is released
//! before any step. Mode changes are located as roots on each step's dense output:
//! - a slipping element's slip reaching zero (it locks, or slips on the other
//!   way when its static limit cannot hold the locked torque);
//! - a locked element's torque reaching its static limit `mu_s C(t)` (it
//!   releases);
//! - a one-way element's locked torque reaching zero (it overruns).
//!
//! At a lock, the speeds are projected onto the new mode in the metric of
//! \[M\] (as [`super::lockup::lock_projection`]).
//! That projection never raises kinetic energy; the energy it removes is
//! recorded (about zero, since the slip was located at zero). Every sample
//! carries the energy residual `W_applied - dKE - E_friction - E_lock`.
//! Every change is sampled on both sides (the old mode's state at it, then
//! the new mode's), and the reported ranges take the turning points between
//! samples too (`extremes.rs`), so they converge with the tolerance. The
//! torque and inertia phases and the quality measures are read from the
//! finished samples (`quality.rs`).

use nalgebra::DVector;
use serde::Serialize;

use super::compliance::OutputShaft;
use super::consistent::{Cause, Settled, settle};
use super::extremes::Extremes;
use super::friction::{Capacity, FrictionLaw};
use super::mesh_loss::MeshLosses;
use super::mode::{element_row, mode_basis};
use super::ode;
use super::quality::ShiftQuality;
use super::request::{first_positive, listed};
pub use super::result::{ModeChange, ShiftResult, ShiftSample, Stiffness};
use super::train_mode::{Mode, Observed, Phase, Setup, refuse};
use crate::analysis::transmission::is_one_way;
use crate::error::{AnalysisError, Error, Result};
use crate::model::train::{ElementId, Train};

/// Steps (accepted and rejected) allowed by default before a run is refused
/// with the `budget` error; [`ShiftSim::max_steps`] raises it.
pub const DEFAULT_MAX_STEPS: usize = 2_000_000;

/// The longest step (s). A shift's events and ramps take tenths of a second
/// and the vehicle's time constants are seconds, so this costs nothing in
/// accuracy; it makes `t_end / MAX_STEP` a lower bound on the steps, so an
/// end time past the step budget is refused before any work.
pub const MAX_STEP: f64 = 1.0;

/// The smallest relative tolerance a step can meet in double precision (a
/// few hundred ulps); a smaller `rtol` is refused as a usage error.
pub const MIN_RTOL: f64 = 1e-13;

/// The input torque: constant, or a table over the input speed (linear
/// between points, held at the ends), e.g. an engine's full-load curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InputTorque {
    /// The same torque at every speed (N m).
    Constant(f64),
    /// `(speed rad/s, torque N m)` points, speeds increasing.
    Table(Vec<(f64, f64)>),
}

impl InputTorque {
    /// The torque at input speed `w`.
    pub fn at(&self, w: f64) -> f64 {
        match self {
            InputTorque::Constant(t) => *t,
            InputTorque::Table(pts) => {
                let Some(i) = pts.iter().position(|&(s, _)| s > w) else {
                    return pts.last().map_or(0.0, |p| p.1);
                };
                if i == 0 {
                    return pts[0].1;
                }
                let ((s0, t0), (s1, t1)) = (pts[i - 1], pts[i]);
                t0 + (t1 - t0) * (w - s0) / (s1 - s0)
            }
        }
    }

    pub(super) fn validate(&self) -> Result<()> {
        match self {
            InputTorque::Constant(t) if !t.is_finite() => Err(Error::invalid(
                "shift.input_torque",
                format!("{t} is not finite"),
            )),
            InputTorque::Table(pts) => {
                if pts.is_empty() {
                    return Err(Error::invalid("shift.input_torque", "the table is empty"));
                }
                for (i, &(s, t)) in pts.iter().enumerate() {
                    if !(s.is_finite() && t.is_finite()) {
                        return Err(Error::invalid(
                            format!("shift.input_torque[{i}]"),
                            format!("({s}, {t}) is not finite"),
                        ));
                    }
                    if i > 0 && s <= pts[i - 1].0 {
                        return Err(Error::invalid(
                            format!("shift.input_torque[{i}]"),
                            format!("speed {s} must exceed the previous one, {}", pts[i - 1].0),
                        ));
                    }
                }
                Ok(())
            }
            InputTorque::Constant(_) => Ok(()),
        }
    }
}

/// How the shift is integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShiftMethod {
    /// Explicit Bogacki–Shampine until its steps are limited by stability
    /// (a stiff mode), then implicit for the rest of the run.
    #[default]
    Auto,
    /// Explicit Bogacki–Shampine 3(2) only; a stiff mode is reported.
    Explicit,
    /// Extrapolated linearly implicit Euler (third order, stiffly stable) throughout.
    Implicit,
}

/// What to simulate: a shift between two gear states.
#[derive(Debug, Clone, PartialEq)]
pub struct ShiftSim {
    /// The gear before (a state of the spec's `[transmission]`).
    pub from: String,
    /// The gear after.
    pub to: String,
    /// Input speed at `t = 0` (rad/s); the train starts in `from`'s steady motion.
    pub input_speed: f64,
    /// Torque applied to the input link.
    pub input_torque: InputTorque,
    /// Road load at the output, resisting motion: `c0 sgn(w) + c1 w + c2 w |w|` (N m).
    pub road_load: [f64; 3],
    /// Vehicle inertia reflected to the output link (kg m^2), added to \[M\]
    /// (or, with `output_shaft`, driven through the shaft).
    pub vehicle_inertia: f64,
    /// A compliant shaft from the output link to the vehicle inertia
    /// (`compliance.rs`); `None` joins them rigidly.
    pub output_shaft: Option<OutputShaft>,
    /// Friction law of the off-going and on-coming elements.
    pub law: FrictionLaw,
    /// Capacity (N m per unit friction coefficient) of the off-going element,
    /// when exactly one element releases and `ramps` does not name it.
    pub off_going: Option<Capacity>,
    /// Capacity of the on-coming element, when exactly one element applies
    /// and `ramps` does not name it.
    pub on_coming: Option<Capacity>,
    /// Capacity of each changing element by name (`egt shift-sim --ramp
    /// NAME=RAMP`); it comes before `off_going` and `on_coming`. Every
    /// off-going and on-coming element needs one or the other.
    pub ramps: Vec<(String, Capacity)>,
    /// End time (s).
    pub t_end: f64,
    /// Relative tolerance of the adaptive steps.
    pub rtol: f64,
    /// Absolute tolerance (rad/s, J).
    pub atol: f64,
    /// Integration method.
    pub method: ShiftMethod,
    /// Steps (accepted and rejected) allowed before the run is refused with
    /// the `budget` error ([`DEFAULT_MAX_STEPS`]; `egt shift-sim --max-steps`).
    pub max_steps: usize,
    /// Mesh losses: each gear pair's basic efficiency (the spec's
    /// `efficiency`) on the meshing forces, with `egt power`'s direction
    /// rule (`mesh_loss.rs`; `egt shift-sim --losses`). `false`: ideal
    /// meshes, the run unchanged.
    pub losses: bool,
}

/// Consecutive stability-limited explicit steps that call a mode stiff.
const STIFF_STEPS: usize = 10;
/// The Bogacki–Shampine stability boundary on the negative real axis (about 2.51).
const EXPLICIT_LIMIT: f64 = 2.5;
/// Mode changes in a row at one instant before the run is refused (each
/// settles a consistent mode, so a second one at the same time is rare).
const MAX_AT_ONCE: usize = 8;

impl ShiftSim {
    /// Simulates the shift on `train`.
    ///
    /// # Errors
    /// A named invalid field; an unknown gear state, a change that releases
    /// or applies nothing, a changing element without a capacity (named);
    /// missing inertias (a singular reduced mass
    /// matrix); a tie-up; too many steps or a state that stops being finite.
    pub fn run(&self, train: &Train) -> Result<ShiftResult> {
        self.validate()?;
        let t = train.checked_transmission()?;
        let state = |name: &str, field: &str| {
            t.states.iter().find(|s| s.name == name).ok_or_else(|| {
                Error::invalid(
                    format!("shift.{field}"),
                    format!(
                        "no gear state `{name}`; the states are {}",
                        t.states
                            .iter()
                            .map(|s| format!("`{}`", s.name))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
        };
        let (from, to) = (state(&self.from, "from")?, state(&self.to, "to")?);
        let kept: Vec<ElementId> = from
            .engaged
            .iter()
            .copied()
            .filter(|e| to.engaged.contains(e))
            .collect();
        let off: Vec<ElementId> = from
            .engaged
            .iter()
            .copied()
            .filter(|e| !to.engaged.contains(e))
            .collect();
        let on: Vec<ElementId> = to
            .engaged
            .iter()
            .copied()
            .filter(|e| !from.engaged.contains(e))
            .collect();
        let name = |e: ElementId| train.elements()[e.index()].name.clone();
        let names = |es: &[ElementId]| es.iter().map(|&e| name(e)).collect::<Vec<_>>();
        if off.is_empty() || on.is_empty() {
            return Err(Error::invalid(
                "shift.to",
                format!(
                    "`{}` -> `{}` releases {} and applies {}: a shift releases at least one element and applies at least one",
                    self.from,
                    self.to,
                    listed(&names(&off).iter().collect::<Vec<_>>()),
                    listed(&names(&on).iter().collect::<Vec<_>>()),
                ),
            ));
        }
        // Kept elements given a capacity are held by it, not rigidly.
        let (held, kept): (Vec<ElementId>, Vec<ElementId>) = kept
            .into_iter()
            .partition(|&e| self.ramps.iter().any(|(r, _)| *r == name(e)));
        let capacity = self.capacities(&names(&off), &names(&on), &names(&held))?;
        let changing: Vec<ElementId> = off.iter().chain(&on).chain(&held).copied().collect();
        let (k, n_off) = (changing.len(), off.len());
        // The on-coming elements' indices among the changing ones.
        let coming = n_off..n_off + on.len();
        let (input, output) = (
            train.coordinate(t.input).expect("checked: input moves"),
            train.coordinate(t.output).expect("checked: output moves"),
        );
        let mut m = train.mass_matrix()?.matrix()?;
        if self.output_shaft.is_none() {
            m[(output, output)] += self.vehicle_inertia;
        }
        let n = m.nrows();
        let rows = changing
            .iter()
            .map(|&e| element_row(train, e).map(DVector::from_vec))
            .collect::<Result<Vec<_>>>()?;
        let kind = |e: ElementId| train.elements()[e.index()].kind;
        let setup = Setup {
            train,
            sim: self,
            m,
            input,
            output,
            kept: kept.clone(),
            elements: changing.clone(),
            rows,
            one_way: changing.iter().map(|&e| is_one_way(kind(e))).collect(),
            capacity: capacity.clone(),
            n,
            losses: self.losses.then(|| MeshLosses::new(train)).transpose()?,
            load: 0.0,
        };
        // Start: the old gear's steady motion at the input speed.
        let start = mode_basis(train, &from.engaged)?;
        let col = start.basis.column(0);
        let scale = self.input_speed / col[input];
        let mut y: Vec<f64> = col.iter().map(|c| c * scale).collect();
        // the dissipation of each changing element, then the applied work
        y.extend(std::iter::repeat_n(0.0, k + 1));
        if let Some(shaft) = &self.output_shaft {
            // The vehicle turns with the output; the shaft's twist carries
            // the torque of the common acceleration (no shuffle at t = 0).
            let (w_in, w_out) = (y[input], y[output]);
            let reduced = col.dot(&(&setup.m * col)) / (col[output] * col[output]);
            let drive = self.input_torque.at(w_in) * col[input] / col[output];
            let accel = (drive - setup.road(w_out)) / (reduced + self.vehicle_inertia);
            y.extend([
                w_out,
                shaft.twist_for(self.vehicle_inertia * accel + setup.road(w_out)),
            ]);
        }
        if setup.losses.is_some() {
            y.push(0.0); // the meshes' loss
        }
        let ke0 = setup.energy(&y);
        let first: Vec<Phase> = (0..k)
            .map(|i| {
                let slip = setup.slip(i, &y[..n]);
                if !coming.contains(&i) || slip == 0.0 {
                    Phase::Locked
                } else {
                    Phase::Slipping(slip.signum())
                }
            })
            .collect();
        let mut out = ShiftResult {
            elements: names(&changing),
            off_going: names(&off),
            on_coming: names(&on),
            kept: names(&kept),
            held: names(&held),
            samples: Vec::new(),
            changes: Vec::new(),
            shift_start: None,
            lock_time: None,
            shift_time: None,
            output_torque_range: [f64::NEG_INFINITY, f64::INFINITY],
            element_torque_range: vec![[f64::NEG_INFINITY, f64::INFINITY]; k],
            slip_range: vec![[f64::NEG_INFINITY, f64::INFINITY]; k],
            kept_torque_range: Vec::new(),
            dissipated: vec![0.0; k],
            lock_loss: 0.0,
            rest_time: None,
            mesh_loss: None,
            max_energy_residual: 0.0,
            steps: 0,
            method: String::new(),
            stiff: None,
            quality: ShiftQuality::default(),
        };
        let mut extremes = Extremes::new(1 + 2 * k + kept.len());
        // Takes a consistent mode: its changes, the on-coming lock, the loss.
        let take = |out: &mut ShiftResult, s: &Settled, t: f64| {
            // At rest from here (no DOF), or moving again.
            out.rest_time = match s.mode.basis.ncols() {
                0 => out.rest_time.or(Some(t)),
                _ => None,
            };
            for &i in &s.changed {
                let now = match s.mode.phases[i] {
                    Phase::Locked => "locked",
                    Phase::Slipping(_) if setup.one_way[i] => "overrunning",
                    Phase::Slipping(_) => "slipping",
                };
                if coming.contains(&i)
                    && now == "locked"
                    && out.lock_time.is_none()
                    && s.mode.phases[coming.clone()]
                        .iter()
                        .all(|p| *p == Phase::Locked)
                {
                    out.lock_time = Some(t);
                }
                out.changes.push(ModeChange {
                    t,
                    element: out.elements[i].clone(),
                    now: now.to_string(),
                    dof: s.mode.basis.ncols(),
                });
            }
        };
        // One sample; its quantities go into the extremes.
        let record = |out: &mut ShiftResult,
                      ext: &mut Extremes,
                      t: f64,
                      y: &[f64],
                      dy: &[f64],
                      mode: &Mode,
                      loss: f64,
                      observed: Option<Observed>|
         -> Observed {
            let v = &y[..n];
            let q = observed.unwrap_or_else(|| setup.observe(mode, t, y, dy));
            ext.add(&q);
            // W_applied - dKE - each element's friction work - E_lock, in that order
            let mesh = setup.mesh_at().map(|at| y[at]);
            let residual = y[n..n + k]
                .iter()
                .fold(y[n + k] - (setup.energy(y) - ke0), |r, d| r - d)
                - loss
                - mesh.unwrap_or(0.0);
            out.max_energy_residual = out.max_energy_residual.max(residual.abs());
            let mut speed = vec![0.0; train.links().len()];
            for (k, &l) in train.coordinates().iter().enumerate() {
                speed[l.index()] = v[k];
            }
            out.samples.push(ShiftSample {
                t,
                speed,
                slip: q[1 + k..1 + 2 * k].to_vec(),
                element_torque: q[1..1 + k].to_vec(),
                output_torque: q[0],
                dissipated: y[n..n + k].to_vec(),
                energy_residual: residual,
                mesh_loss: mesh,
                dof: mode.basis.ncols(),
                kept_torque: q[1 + 2 * k..].to_vec(),
            });
            q
        };
        // At t = 0 every locked element is checked against its capacity: the
        // old gear's elements may not hold what the shift asks of them.
        let settled = settle(&setup, &first, 0.0, &y, Cause::Start, None)?;
        take(&mut out, &settled, 0.0);
        let Settled {
            mut mode,
            lost: mut lock_loss,
            ..
        } = settled;
        y = settled.y;
        let mut t_now = 0.0;
        let mut implicit = self.method == ShiftMethod::Implicit;
        let mut limited = 0usize;
        let mut f0 = setup.rhs(&mode, t_now, &y);
        let mut q0 = record(
            &mut out,
            &mut extremes,
            t_now,
            &y,
            &f0,
            &mode,
            lock_loss,
            None,
        );
        let breaks: Vec<f64> = capacity.iter().flat_map(Capacity::breakpoints).collect();
        let mut h = (self.t_end * 1e-4).min(1e-4);
        let mut attempts = 0usize;
        // Events in a row at one instant (each changes the mode; a few at most).
        let mut at_once = 0usize;
        // The event functions at the last accepted step's end, for the next.
        let mut g_end: Option<Vec<f64>> = None;
        while t_now < self.t_end {
            attempts += 1;
            if attempts > self.max_steps {
                return Err(Error::Analysis(AnalysisError::Budget {
                    what: format!("a shift simulation to t_end = {} s", self.t_end),
                    estimate: format!(
                        "{} steps (accepted and rejected) reached at t = {t_now:e} s",
                        self.max_steps
                    ),
                    limit: format!("{} steps", self.max_steps),
                    raise: "raise `max_steps` (`--max-steps`), loosen `rtol`, or shorten `t_end`"
                        .into(),
                }));
            }
            let mut stop = self.t_end;
            for &b in &breaks {
                if b > t_now * (1.0 + 1e-15) + 1e-300 && b < stop {
                    stop = b;
                }
            }
            h = h.min(stop - t_now).min(MAX_STEP);
            let mut rhs = |tt: f64, yy: &[f64]| setup.rhs(&mode, tt, yy);
            let step = if implicit {
                ode::implicit_step(&mut rhs, t_now, &y, h)
            } else {
                Some(ode::bs23(&mut rhs, t_now, &y, &f0, h))
            };
            // both error estimates are of a second-order solution: exponent 1/3
            let order = 3.0;
            let Some((y1, f1, err)) = step else {
                h *= 0.25;
                if h < 1e-14 * self.t_end {
                    return Err(refuse(format!(
                        "the implicit step's matrix is singular at t = {t_now} for every step size"
                    )));
                }
                continue;
            };
            let norm = ode::error_norm(&err, &y, &y1, self.rtol, self.atol);
            if !norm.is_finite() {
                return Err(Error::Analysis(AnalysisError::NonFinite {
                    what: "the state of the shift simulation".into(),
                    detail: format!("it overflowed in a step from t = {t_now}"),
                }));
            }
            if norm > 1.0 {
                h *= (0.9 * norm.powf(-1.0 / order)).max(0.2);
                // Below a few ulps of t a step cannot move the time.
                if h < 16.0 * f64::EPSILON * t_now.max(1e-6 * self.t_end) {
                    return Err(Error::Analysis(AnalysisError::NotConverged {
                        what: format!(
                            "the shift simulation's step control (the step fell to {h:e} s, the rounding of t, against rtol {:e} and atol {:e})",
                            self.rtol, self.atol
                        ),
                        t: t_now,
                    }));
                }
                continue;
            }
            out.steps += 1;
            if !implicit {
                // Stiffness: the decay rate along the step's correction,
                // |f(y1) - f(y_euler)| / |y1 - y_euler|, against the explicit
                // stability boundary.
                let euler: Vec<f64> = y.iter().zip(&f0).map(|(a, b)| a + h * b).collect();
                let fe = setup.rhs(&mode, t_now + h, &euler);
                let (mut num, mut den) = (0.0f64, 0.0f64);
                for i in 0..n {
                    num += (f1[i] - fe[i]).powi(2);
                    den += (y1[i] - euler[i]).powi(2);
                }
                let size = y1[..n].iter().fold(1.0f64, |m, v| m.max(v.abs()));
                let rate = if den.sqrt() > 1e-9 * size {
                    (num / den).sqrt()
                } else {
                    0.0 // the correction is at rounding level: no estimate
                };
                if h * rate > 0.8 * EXPLICIT_LIMIT {
                    limited += 1;
                    if limited >= STIFF_STEPS && out.stiff.is_none() {
                        out.stiff = Some(Stiffness { t: t_now, h, rate });
                        if self.method == ShiftMethod::Auto {
                            implicit = true;
                        }
                    }
                } else {
                    limited = 0;
                }
            }
            let t1 = if stop - (t_now + h) <= 1e-15 * stop.abs().max(1.0) {
                stop
            } else {
                t_now + h
            };
            // The event functions at the step's start are the last accepted
            // step's end (same mode, state and derivative) unless an event
            // or a new mode came between.
            let g0 = match g_end.take() {
                Some(g) => g,
                None => setup.events(&mode, t_now, &y, &f0),
            };
            // The quantities at the step's end, which the sample there records
            // (if no event comes first), give its event functions too.
            let q_end = setup.observe(&mode, t1, &y1, &f1);
            let g1 = setup.events_observed(&mode, t1, &y1, &f1, &q_end);
            // The earliest crossing, located on the dense output. An element
            // that entered its phase at the crossing (g = 0) and heads the
            // wrong way fires at once.
            let mut first: Option<(f64, usize)> = None;
            for i in 0..g0.len() {
                if (g0[i] > 0.0 && g1[i] <= 0.0) || (g0[i] == 0.0 && g1[i] < 0.0) {
                    let te = ode::locate(
                        |s| {
                            let ys = ode::hermite(t_now, &y, &f0, t1, &y1, &f1, s);
                            let ds = setup.rhs(&mode, s, &ys);
                            setup.events(&mode, s, &ys, &ds)[i]
                        },
                        t_now,
                        t1,
                        g0[i],
                        g1[i],
                    );
                    if first.is_none_or(|(tf, _)| te < tf) {
                        first = Some((te, i));
                    }
                }
            }
            // The quantities on the step's dense output, for turning points.
            let dense = |s: f64| {
                let ys = ode::hermite(t_now, &y, &f0, t1, &y1, &f1, s);
                let ds = setup.rhs(&mode, s, &ys);
                setup.observe(&mode, s, &ys, &ds)
            };
            if let Some((te, i)) = first {
                let ye = ode::hermite(t_now, &y, &f0, t1, &y1, &f1, te);
                if te > t_now {
                    // The left limit: the old mode's state at the event.
                    let fe = setup.rhs(&mode, te, &ye);
                    let qe = record(
                        &mut out,
                        &mut extremes,
                        te,
                        &ye,
                        &fe,
                        &mode,
                        lock_loss,
                        None,
                    );
                    extremes.within(dense, t_now, te, &q0, &qe, &slip_rates(&setup, &f0, &fe));
                    at_once = 0;
                }
                extremes.break_here();
                if te <= t_now {
                    at_once += 1;
                    if at_once > MAX_AT_ONCE {
                        return Err(refuse(format!(
                            "the elements {} change mode again and again at t = {te} (no consistent mode)",
                            listed(&out.elements.iter().collect::<Vec<_>>())
                        )));
                    }
                }
                // The right limit: a consistent mode after the change (an
                // element's event, or with losses a mesh's driver flipping).
                // An element's event, a mesh's (its driver), or the parked
                // vehicle's (its static torque reached c0): the last ones.
                let meshes = mode.lossy.as_ref().map_or(0, |l| l.drivers.len());
                let drivers = mode.lossy.as_ref().map(|l| l.drivers.clone());
                let (cause, prior) = match &mode.lossy {
                    _ if i < k => (Cause::Element(i), drivers),
                    Some(lossy) if i < k + meshes => {
                        let (prior, flipped) = lossy.after_event(i - k);
                        (Cause::Mesh(flipped), Some(prior))
                    }
                    _ => (Cause::Unpark, drivers),
                };
                let s = settle(&setup, &mode.phases, te, &ye, cause, prior.as_deref())?;
                take(&mut out, &s, te);
                lock_loss += s.lost;
                (mode, y) = (s.mode, s.y);
                t_now = te;
                f0 = setup.rhs(&mode, t_now, &y);
                q0 = record(
                    &mut out,
                    &mut extremes,
                    t_now,
                    &y,
                    &f0,
                    &mode,
                    lock_loss,
                    None,
                );
                continue;
            }
            let q1 = record(
                &mut out,
                &mut extremes,
                t1,
                &y1,
                &f1,
                &mode,
                lock_loss,
                Some(q_end),
            );
            extremes.within(dense, t_now, t1, &q0, &q1, &slip_rates(&setup, &f0, &f1));
            if t1 == stop {
                // a capacity ramp's corner (or the end): the slopes jump
                extremes.break_here();
            }
            g_end = Some(g1);
            t_now = t1;
            y = y1;
            f0 = f1;
            q0 = q1;
            let grow = if norm == 0.0 {
                5.0
            } else {
                (0.9 * norm.powf(-1.0 / order)).min(5.0)
            };
            h *= grow;
        }
        out.method = match (self.method, &out.stiff) {
            (ShiftMethod::Implicit, _) => "implicit",
            (ShiftMethod::Auto, Some(_)) => "explicit, then implicit",
            _ => "explicit",
        }
        .to_string();
        out.output_torque_range = [extremes.max[0], extremes.min[0]];
        out.element_torque_range = (0..k)
            .map(|i| [extremes.max[1 + i], extremes.min[1 + i]])
            .collect();
        out.slip_range = (0..k)
            .map(|i| [extremes.max[1 + k + i], extremes.min[1 + k + i]])
            .collect();
        out.kept_torque_range = (0..setup.kept.len())
            .map(|j| [extremes.max[1 + 2 * k + j], extremes.min[1 + 2 * k + j]])
            .collect();
        out.dissipated = y[n..n + k].to_vec();
        out.lock_loss = lock_loss;
        out.mesh_loss = setup.mesh_at().map(|at| y[at]);
        out.shift_start = capacity[coming.clone()]
            .iter()
            .filter_map(|c| first_positive(c, self.t_end))
            .reduce(f64::min);
        out.shift_time = match (out.shift_start, out.lock_time) {
            (Some(s), Some(l)) => Some(l - s),
            _ => None,
        };
        let turns: Vec<(f64, f64)> = extremes
            .turns
            .iter()
            .filter(|turn| turn.quantity == 0)
            .map(|turn| (turn.t, turn.value))
            .collect();
        out.quality = ShiftQuality::of(&out, self.vehicle_inertia, &turns);
        Ok(out)
    }
}

/// The slips' rates at both ends of a step with end derivatives `f0`, `f1`
/// (a slip is linear in the speeds, so its dense output is the step's cubic);
/// the torques have none.
fn slip_rates(setup: &Setup<'_>, f0: &[f64], f1: &[f64]) -> Vec<Option<(f64, f64)>> {
    let (n, k) = (setup.n, setup.k());
    let rate = |i: usize, f: &[f64]| setup.slip(i, &f[..n]);
    let mut rates = vec![None; 1 + k];
    rates.extend((0..k).map(|i| Some((rate(i, f0), rate(i, f1)))));
    rates.extend(std::iter::repeat_n(None, setup.kept.len()));
    rates
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
pub(super) mod tests {
    use super::*;
    use crate::spec::parse::Format;

    pub(in crate::motion::shift_dynamics) fn simpson() -> Train {
        let text = include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/ford_c4_simpson.toml"
        ));
        Train::from_str(text, Format::Toml, "ford_c4_simpson.toml").unwrap()
    }

    pub(in crate::motion::shift_dynamics) fn upshift() -> ShiftSim {
        ShiftSim {
            from: "2".into(),
            to: "3".into(),
            input_speed: 300.0,
            input_torque: InputTorque::Constant(150.0),
            road_load: [30.0, 0.1, 0.001],
            vehicle_inertia: 15.0,
            law: FrictionLaw {
                mu_static: 0.15,
                mu_kinetic: 0.12,
                decay: None,
            },
            off_going: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.25,
                from: 6000.0,
                to: 0.0,
            }),
            on_coming: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.35,
                from: 0.0,
                to: 8000.0,
            }),
            t_end: 1.0,
            rtol: 1e-8,
            atol: 1e-8,
            method: ShiftMethod::Auto,
            max_steps: DEFAULT_MAX_STEPS,
            ramps: Vec::new(),
            output_shaft: None,
            losses: false,
        }
    }

    pub(in crate::motion::shift_dynamics) fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    /// The run ends in `gear`: input over output speed is its ratio (egt shift).
    fn assert_ends_in(train: &Train, r: &ShiftResult, gear: &str) {
        let ratio = train.analyse_gear(gear).unwrap().ratio;
        let last = r.samples.last().unwrap();
        let t = train.checked_transmission().unwrap();
        let ends = last.speed[t.input.index()] / last.speed[t.output.index()];
        assert!(
            rel(ends, ratio) < 1e-9,
            "ends at {ends}, gear {gear} is {ratio}"
        );
    }

    #[test]
    fn the_2_3_upshift_releases_the_band_then_locks_the_clutch_in_third() {
        let train = simpson();
        let r = upshift().run(&train).unwrap();
        let what: Vec<(&str, &str)> = r
            .changes
            .iter()
            .map(|c| (c.element.as_str(), c.now.as_str()))
            .collect();
        assert_eq!(
            what,
            [
                ("intermediate_band", "slipping"),
                ("reverse_high_clutch", "locked")
            ]
        );
        assert_eq!(r.changes[0].dof, 2);
        assert_eq!(r.changes[1].dof, 1);
        let (start, lock) = (r.shift_start.unwrap(), r.lock_time.unwrap());
        assert_eq!(start, 0.05);
        assert!(lock > r.changes[0].t && lock < 1.0);
        // After the lock every link turns as third gear says (egt shift).
        let third = train.analyse_gear("3").unwrap();
        let last = r.samples.last().unwrap();
        let input = train.checked_transmission().unwrap().input.index();
        for (l, s) in third.speed.iter().enumerate() {
            if let Some(s) = s {
                assert!(
                    (last.speed[l] - s * last.speed[input]).abs() < 1e-9 * last.speed[input].abs()
                );
            }
        }
        // Energy: W_applied = dKE + friction + lock loss at every sample, to a
        // tolerance tied to the integrator's (rtol 1e-8).
        let dissipated = r.dissipated[0] + r.dissipated[1];
        assert!(dissipated > 100.0);
        assert!(
            r.max_energy_residual < 1e-7 * dissipated,
            "{} of {dissipated}",
            r.max_energy_residual
        );
        // Friction only removes energy; a lock located at zero slip removes ~none.
        assert!(r.dissipated.iter().all(|&d| d >= 0.0));
        assert!(r.lock_loss >= 0.0 && r.lock_loss < 1e-6 * dissipated);
    }

    #[test]
    fn the_steady_state_after_the_shift_is_egt_shifts_solution() {
        // A linear road load only: the train settles where the output torque
        // equals the load, and then every torque is the steady gear's.
        let train = simpson();
        let torque = 150.0;
        let sim = ShiftSim {
            road_load: [0.0, 2.0, 0.0],
            vehicle_inertia: 0.5,
            t_end: 12.0,
            ..upshift()
        };
        let r = sim.run(&train).unwrap();
        let last = r.samples.last().unwrap();
        let third = train.analyse_gear("3").unwrap();
        assert!(
            rel(last.output_torque, torque * third.output_torque) < 1e-7,
            "{} vs {}",
            last.output_torque,
            torque * third.output_torque
        );
        let on = third
            .elements
            .iter()
            .find(|e| train.elements()[e.element.index()].name == "reverse_high_clutch")
            .unwrap();
        assert!(
            rel(last.element_torque[1], torque * on.torque) < 1e-7,
            "{} vs {}",
            last.element_torque[1],
            torque * on.torque
        );
        // and the output speed is where the load balances it
        let out = train.checked_transmission().unwrap().output.index();
        assert!(rel(last.speed[out], torque * third.output_torque / 2.0) < 1e-7);
        // The kept forward clutch's torque, its multiplier, is the static
        // analysis's too (an independent solve: egt shift's gear equilibrium).
        assert_eq!(r.kept, ["forward_clutch"]);
        let kept = third
            .elements
            .iter()
            .find(|e| train.elements()[e.element.index()].name == "forward_clutch")
            .unwrap();
        assert!(
            rel(last.kept_torque[0], torque * kept.torque) < 1e-7,
            "{} vs {}",
            last.kept_torque[0],
            torque * kept.torque
        );
        let [hi, lo] = r.kept_torque_range[0];
        assert!(
            r.samples
                .iter()
                .all(|x| x.kept_torque[0] <= hi && x.kept_torque[0] >= lo)
        );
    }

    #[test]
    fn a_compliant_output_shuffles_after_the_lock_at_the_closed_form_frequency() {
        let train = simpson();
        let (k, jv, c0, tin) = (5000.0, 15.0, 30.0, 150.0);
        let sim = ShiftSim {
            road_load: [c0, 0.0, 0.0],
            vehicle_inertia: jv,
            output_shaft: Some(OutputShaft {
                stiffness: k,
                damping: 0.0,
            }),
            t_end: 1.5,
            rtol: 1e-10,
            atol: 1e-10,
            ..upshift()
        };
        let r = sim.run(&train).unwrap();
        let lock = r.lock_time.unwrap();
        // The train reduced to the output in third, from egt shift's speeds
        // (per unit input speed) and [M]: an independent route to J_t.
        let third = train.analyse_gear("3").unwrap();
        let m = train.mass_matrix().unwrap().matrix().unwrap();
        let s: Vec<f64> = (train.coordinates().iter())
            .map(|l| third.speed[l.index()].unwrap())
            .collect();
        let out = train.checked_transmission().unwrap().output;
        let s_out = third.speed[out.index()].unwrap();
        let jt = (0..s.len())
            .map(|i| (0..s.len()).map(|j| m[(i, j)] * s[i] * s[j]).sum::<f64>())
            .sum::<f64>()
            / (s_out * s_out);
        let omega = (k * (1.0 / jt + 1.0 / jv)).sqrt();
        // The shaft torque oscillates about the torque of the common
        // acceleration once only constant forces act: after the lock and
        // after the released band's ramp has reached 0 (t1 = 0.25 s).
        let mean = (jv * tin / s_out + jt * c0) / (jt + jv);
        let settled = lock.max(0.25);
        let after: Vec<(f64, f64)> = (r.samples.iter())
            .filter(|x| x.t > settled)
            .map(|x| (x.t, x.output_torque - mean))
            .collect();
        let crossings: Vec<f64> = after
            .windows(2)
            .filter(|w| w[0].1 * w[1].1 < 0.0)
            .map(|w| w[0].0 + (w[1].0 - w[0].0) * w[0].1 / (w[0].1 - w[1].1))
            .collect();
        assert!(crossings.len() > 10, "{} crossings", crossings.len());
        let half = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let measured = std::f64::consts::PI / half;
        assert!(
            rel(measured, omega) < 1e-6,
            "{measured} rad/s vs {omega} (J_t {jt})"
        );
        let total: f64 = r.dissipated.iter().sum();
        assert!(
            r.max_energy_residual < 1e-7 * total,
            "{} of {total}",
            r.max_energy_residual
        );
    }

    #[test]
    fn a_kept_element_with_a_capacity_holds_within_it_and_slips_past_it() {
        let train = simpson();
        let rigid = upshift().run(&train).unwrap();
        // A capacity far above its torque: held throughout, the same run.
        let big = ShiftSim {
            ramps: vec![("forward_clutch".into(), Capacity::Constant(1e6))],
            ..upshift()
        };
        let r = big.run(&train).unwrap();
        assert_eq!(r.held, ["forward_clutch"]);
        assert!(r.kept.is_empty());
        assert_eq!(r.elements[2], "forward_clutch");
        assert!(r.changes.iter().all(|c| c.element != "forward_clutch"));
        assert!(rel(r.lock_time.unwrap(), rigid.lock_time.unwrap()) < 1e-9);
        for (a, b) in r.dissipated.iter().zip(&rigid.dissipated) {
            assert!(rel(*a, *b) < 1e-8, "{a} vs {b}");
        }
        let [hi, lo] = rigid.kept_torque_range[0];
        let [hh, hl] = r.element_torque_range[2];
        assert!(
            rel(hh, hi) < 1e-8 && rel(hl, lo) < 1e-8,
            "{hh} {hl} vs {hi} {lo}"
        );
        // A capacity below what it must carry: it slips from t = 0, never
        // carries more than mu_s C, and the energy balances with its loss.
        let peak = hi.abs().max(lo.abs());
        let cap = 0.5 * peak / big.law.mu_static;
        let small = ShiftSim {
            ramps: vec![("forward_clutch".into(), Capacity::Constant(cap))],
            ..upshift()
        };
        let r = small.run(&train).unwrap();
        assert!(
            r.changes
                .iter()
                .any(|c| c.element == "forward_clutch" && c.now == "slipping"),
            "{:?}",
            r.changes
        );
        let limit = small.law.mu_static * cap;
        assert!(
            r.samples
                .iter()
                .all(|x| x.element_torque[2].abs() <= limit * (1.0 + 1e-9)),
            "limit {limit}"
        );
        assert!(r.dissipated[2] > 0.0);
        let total: f64 = r.dissipated.iter().sum();
        assert!(
            r.max_energy_residual < 1e-7 * total,
            "{} of {total}",
            r.max_energy_residual
        );
    }

    #[test]
    fn the_1_2_upshift_lets_the_low_one_way_overrun_and_never_gains_energy_at_a_lock() {
        let train = simpson();
        let sim = ShiftSim {
            from: "1".into(),
            to: "2".into(),
            ..upshift()
        };
        let r = sim.run(&train).unwrap();
        let what: Vec<(&str, &str)> = r
            .changes
            .iter()
            .map(|c| (c.element.as_str(), c.now.as_str()))
            .collect();
        assert_eq!(
            what,
            [
                ("low_one_way", "overrunning"),
                ("intermediate_band", "locked")
            ]
        );
        // it overruns in its free direction (positive slip) until the end
        let after = r.samples.iter().filter(|s| s.t > r.changes[0].t + 1e-6);
        assert!(
            after
                .clone()
                .all(|s| s.slip[0] > 0.0 && s.element_torque[0] == 0.0)
        );
        assert!(r.lock_loss >= 0.0);
        assert_ends_in(&train, &r, "2");
    }

    #[test]
    fn a_power_on_3_2_downshift_slips_the_clutch_until_the_band_locks() {
        let train = simpson();
        let sim = ShiftSim {
            from: "3".into(),
            to: "2".into(),
            input_speed: 200.0,
            off_going: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.2,
                from: 6000.0,
                to: 400.0,
            }),
            on_coming: Some(Capacity::Ramp {
                t0: 0.3,
                t1: 0.5,
                from: 0.0,
                to: 8000.0,
            }),
            ..upshift()
        };
        let r = sim.run(&train).unwrap();
        assert_eq!(r.changes.first().unwrap().element, "reverse_high_clutch");
        assert!(r.lock_time.is_some(), "{:?}", r.changes);
        assert_ends_in(&train, &r, "2");
        assert!(r.max_energy_residual < 1e-7 * (r.dissipated[0] + r.dissipated[1]));
    }

    pub(in crate::motion::shift_dynamics) fn zf() -> Train {
        let text = include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/zf_8hp70.toml"
        ));
        Train::from_str(text, Format::Toml, "zf_8hp70.toml").unwrap()
    }

    #[test]
    fn every_8hp_single_swap_upshift_and_downshift_ends_in_its_gear_with_energy_balanced() {
        let train = zf();
        let forward: Vec<&str> = ["1", "2", "3", "4", "5", "6", "7", "8"].into();
        let mut runs = 0;
        for w in forward.windows(2) {
            for (from, to) in [(w[0], w[1]), (w[1], w[0])] {
                let sim = ShiftSim {
                    from: from.into(),
                    to: to.into(),
                    input_speed: 250.0,
                    input_torque: InputTorque::Constant(200.0),
                    road_load: [20.0, 0.2, 0.002],
                    vehicle_inertia: 12.0,
                    off_going: Some(Capacity::Ramp {
                        t0: 0.05,
                        t1: 0.15,
                        from: 20000.0,
                        to: 0.0,
                    }),
                    on_coming: Some(Capacity::Ramp {
                        t0: 0.05,
                        t1: 0.4,
                        from: 0.0,
                        to: 20000.0,
                    }),
                    t_end: 1.5,
                    ..upshift()
                };
                let r = sim.run(&train).unwrap();
                assert!(r.lock_time.is_some(), "{from} -> {to}: {:?}", r.changes);
                assert_ends_in(&train, &r, to);
                let dissipated = r.dissipated[0] + r.dissipated[1];
                assert!(
                    r.max_energy_residual < 1e-7 * dissipated.max(1.0),
                    "{from} -> {to}"
                );
                runs += 1;
            }
        }
        assert_eq!(runs, 14);
    }

    #[test]
    fn a_stiff_road_load_switches_to_the_implicit_method_and_says_when() {
        // A huge viscous road load on light inertias: decay rates of about
        // 1e5 1/s, far faster than the shift. The explicit method must take
        // steps near 2.5 / rate whatever the accuracy; the auto method
        // detects it and goes on implicitly.
        let train = simpson();
        let stiff = ShiftSim {
            road_load: [0.0, 5000.0, 0.0],
            vehicle_inertia: 0.0,
            off_going: Some(Capacity::Ramp {
                t0: 0.0,
                t1: 0.02,
                from: 6000.0,
                to: 0.0,
            }),
            t_end: 0.6,
            ..upshift()
        };
        let auto = stiff.run(&train).unwrap();
        let explicit = ShiftSim {
            method: ShiftMethod::Explicit,
            ..stiff.clone()
        }
        .run(&train)
        .unwrap();
        let s = auto.stiff.clone().expect("stiffness detected");
        assert_eq!(auto.method, "explicit, then implicit");
        assert!(s.rate > 1e4, "{s:?}");
        assert!(s.h * s.rate > 2.0 && s.h * s.rate < 3.0, "{s:?}");
        assert_eq!(explicit.method, "explicit");
        assert!(explicit.stiff.is_some());
        assert!(
            auto.steps * 10 < explicit.steps,
            "{} vs {}",
            auto.steps,
            explicit.steps
        );
        eprintln!(
            "stiff run: {s:?}; steps auto {} explicit {}",
            auto.steps, explicit.steps
        );
        // Same physics: the same lock time and final speeds, energy balanced.
        let (la, le) = (auto.lock_time.unwrap(), explicit.lock_time.unwrap());
        assert!((la - le).abs() < 1e-4, "{la} vs {le}");
        let (a, e) = (
            auto.samples.last().unwrap(),
            explicit.samples.last().unwrap(),
        );
        for (x, y) in a.speed.iter().zip(&e.speed) {
            assert!((x - y).abs() < 1e-4 * (1.0 + y.abs()), "{x} vs {y}");
        }
        for r in [&auto, &explicit] {
            assert!(r.max_energy_residual < 1e-6 * (r.dissipated[0] + r.dissipated[1]));
        }
    }

    #[test]
    fn the_implicit_method_gives_the_explicit_shift() {
        let train = simpson();
        let e = upshift().run(&train).unwrap();
        assert!(e.stiff.is_none() && e.method == "explicit");
        let i = ShiftSim {
            method: ShiftMethod::Implicit,
            ..upshift()
        }
        .run(&train)
        .unwrap();
        assert_eq!(i.method, "implicit");
        assert!((i.lock_time.unwrap() - e.lock_time.unwrap()).abs() < 1e-5);
        let (a, b) = (i.samples.last().unwrap(), e.samples.last().unwrap());
        for (x, y) in a.speed.iter().zip(&b.speed) {
            assert!((x - y).abs() < 1e-5 * (1.0 + y.abs()));
        }
    }

    #[test]
    fn a_2_1_downshift_engages_the_low_one_way_when_its_slip_reaches_zero() {
        // Power on, the band lets go; the engine flares until the rear
        // carrier's backward slip returns to zero, and the one-way element
        // locks there under drive torque (it holds, T >= 0 on its link).
        let train = simpson();
        let sim = ShiftSim {
            from: "2".into(),
            to: "1".into(),
            input_speed: 200.0,
            off_going: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.15,
                from: 6000.0,
                to: 0.0,
            }),
            on_coming: Some(Capacity::Constant(0.0)),
            ..upshift()
        };
        let r = sim.run(&train).unwrap();
        let what: Vec<(&str, &str)> = r
            .changes
            .iter()
            .map(|c| (c.element.as_str(), c.now.as_str()))
            .collect();
        assert_eq!(
            what,
            [("intermediate_band", "slipping"), ("low_one_way", "locked")]
        );
        let last = r.samples.last().unwrap();
        assert!(
            last.element_torque[1] >= 0.0,
            "holds in drive: {}",
            last.element_torque[1]
        );
        assert_ends_in(&train, &r, "1");
        // No energy is created at the engagement.
        assert!(r.lock_loss >= 0.0);
        // Little is dissipated here (the band slips briefly, the one-way not
        // at all): bound the residual by the work the input does instead,
        // about 150 N m x 200 rad/s x 1 s.
        assert!(
            r.max_energy_residual < 1e-9 * 150.0 * 200.0,
            "{}",
            r.max_energy_residual
        );
        assert_eq!(r.dissipated[1], 0.0);
    }

    #[test]
    fn bad_shifts_are_named() {
        let train = simpson();
        let err = |sim: ShiftSim| sim.run(&train).unwrap_err().to_string();
        let e = err(ShiftSim {
            from: "9".into(),
            ..upshift()
        });
        assert!(e.contains("shift.from") && e.contains("`9`"), "{e}");
        let e = err(ShiftSim {
            from: "1".into(),
            to: "R".into(),
            ..upshift()
        });
        // 1 -> R releases two elements and applies two: `off_going` and
        // `on_coming` name no single element, and each needs its ramp.
        assert!(
            e.contains("shift.off_going") && e.contains("`forward_clutch`, `low_one_way`"),
            "{e}"
        );
        let e = err(ShiftSim {
            from: "1".into(),
            to: "R".into(),
            off_going: None,
            on_coming: None,
            ramps: vec![
                ("forward_clutch".into(), Capacity::Constant(0.0)),
                ("low_one_way".into(), Capacity::Constant(0.0)),
                ("reverse_high_clutch".into(), Capacity::Constant(1.0)),
            ],
            ..upshift()
        });
        assert!(
            e.contains("shift.ramps.low_reverse_band") && e.contains("no capacity ramp"),
            "{e}"
        );
        let e = err(ShiftSim {
            ramps: vec![("low_one_way".into(), Capacity::Constant(0.0))],
            ..upshift()
        });
        assert!(
            e.contains("shift.ramps.low_one_way") && e.contains("is not engaged in `2` or `3`"),
            "{e}"
        );
        let e = err(ShiftSim {
            to: "2".into(),
            ..upshift()
        });
        assert!(
            e.contains("shift.to") && e.contains("releases nothing"),
            "{e}"
        );
        let e = err(ShiftSim {
            t_end: -1.0,
            ..upshift()
        });
        assert!(e.contains("shift.t_end"), "{e}");
        let e = err(ShiftSim {
            input_torque: InputTorque::Table(vec![(1.0, 2.0), (0.5, 3.0)]),
            ..upshift()
        });
        assert!(e.contains("shift.input_torque[1]"), "{e}");
    }

    /// A two-speed planetary: sun in, carrier out; a ring brake for first
    /// (ratio 1 + 72/30 = 3.4), a sun-carrier clutch for second (direct).
    /// The ring and the planets carry no inertia, so with the brake released
    /// the sun and the carrier are two free inertias joined by the clutch.
    const TWO_SPEED: &str = r#"
name = "two-speed"
frame = "case"

[[planetary]]
name = "P"
sun = "sun"
ring = "ring"
carrier = "carrier"
teeth = { sun = 30, planet = 21, ring = 72 }

[[links]]
name = "sun"
inertia = 0.01

[[links]]
name = "carrier"
inertia = 0.05

[[elements]]
name = "ring_brake"
kind = "brake"
links = ["ring"]

[[elements]]
name = "direct_clutch"
kind = "clutch"
links = ["sun", "carrier"]

[transmission]
input = "sun"
output = "carrier"

[transmission.states]
"1" = ["ring_brake"]
"2" = ["direct_clutch"]
"#;

    pub(in crate::motion::shift_dynamics) fn two_speed() -> Train {
        Train::from_str(TWO_SPEED, Format::Toml, "two_speed.toml").unwrap()
    }

    /// A power-on 1-2 upshift of the two-speed train: the brake's capacity
    /// falls while the clutch's rises (a torque phase, then an inertia phase).
    pub(in crate::motion::shift_dynamics) fn two_speed_upshift() -> ShiftSim {
        ShiftSim {
            from: "1".into(),
            to: "2".into(),
            input_speed: 200.0,
            input_torque: InputTorque::Constant(100.0),
            road_load: [10.0, 0.1, 0.0],
            vehicle_inertia: 2.0,
            off_going: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.25,
                from: 4000.0,
                to: 0.0,
            }),
            on_coming: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.3,
                from: 0.0,
                to: 3000.0,
            }),
            t_end: 0.6,
            ..upshift()
        }
    }

    /// The 8HP 2-3 upshift of docs/shift_dynamics.md.
    pub(in crate::motion::shift_dynamics) fn zf_2_3() -> ShiftSim {
        ShiftSim {
            from: "2".into(),
            to: "3".into(),
            input_speed: 250.0,
            input_torque: InputTorque::Constant(300.0),
            road_load: [20.0, 0.2, 0.002],
            vehicle_inertia: 12.0,
            off_going: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.15,
                from: 5000.0,
                to: 0.0,
            }),
            on_coming: Some(Capacity::Ramp {
                t0: 0.05,
                t1: 0.3,
                from: 0.0,
                to: 9000.0,
            }),
            ..upshift()
        }
    }

    /// An 8HP change from `from` to `to` with a ramp for each element named.
    pub(in crate::motion::shift_dynamics) fn zf_change(
        from: &str,
        to: &str,
        ramps: &[(&str, Capacity)],
    ) -> ShiftSim {
        ShiftSim {
            from: from.into(),
            to: to.into(),
            off_going: None,
            on_coming: None,
            ramps: ramps.iter().map(|(n, c)| (n.to_string(), *c)).collect(),
            t_end: 1.5,
            ..zf_2_3()
        }
    }

    pub(in crate::motion::shift_dynamics) const RELEASE: Capacity = Capacity::Ramp {
        t0: 0.05,
        t1: 0.15,
        from: 20000.0,
        to: 0.0,
    };
    pub(in crate::motion::shift_dynamics) const APPLY: Capacity = Capacity::Ramp {
        t0: 0.05,
        t1: 0.4,
        from: 0.0,
        to: 20000.0,
    };

    /// The run released every off-going element, locked every on-coming
    /// one, ended in `to`'s ratio and balanced its energy.
    fn assert_changed_gear(train: &Train, r: &ShiftResult, to: &str) {
        for e in &r.off_going {
            assert!(
                r.changes
                    .iter()
                    .any(|c| &c.element == e && c.now != "locked"),
                "{e} released: {:?}",
                r.changes
            );
        }
        let lock = r.lock_time.expect("the on-coming elements lock");
        for e in &r.on_coming {
            let last = r.changes.iter().rev().find(|c| &c.element == e);
            assert!(
                last.is_none_or(|c| c.now == "locked" && c.t <= lock),
                "{e}: {:?}",
                r.changes
            );
        }
        assert_ends_in(train, r, to);
        let dissipated: f64 = r.dissipated.iter().sum();
        assert!(r.dissipated.iter().all(|&d| d >= 0.0));
        assert!(
            r.max_energy_residual < 1e-7 * dissipated,
            "{} of {dissipated}",
            r.max_energy_residual
        );
        assert_eq!(r.samples.last().unwrap().dissipated, r.dissipated);
    }

    #[test]
    fn an_8hp_2_4_skip_shift_releases_a_applies_d_and_ends_in_fourth() {
        // 2 = A B E, 4 = B D E: a skip shift that is a single swap.
        let train = zf();
        let r = zf_change("2", "4", &[("A", RELEASE), ("D", APPLY)])
            .run(&train)
            .unwrap();
        assert_eq!(
            (r.off_going.clone(), r.on_coming.clone()),
            (vec!["A".to_string()], vec!["D".to_string()])
        );
        assert_eq!(r.kept, ["B", "E"]);
        assert_changed_gear(&train, &r, "4");
        eprintln!(
            "8HP 2-4: lock {:?} s, dissipated {:?} J, residual {:e} J, steps {}",
            r.lock_time, r.dissipated, r.max_energy_residual, r.steps
        );
    }

    #[test]
    fn an_8hp_double_swap_releases_two_applies_two_and_ends_in_the_new_gear() {
        // 1 = A B C, 4 = B D E: A and C release, D and E apply, B holds.
        // 2 = A B E, 5 = B C D: A and E release, C and D apply.
        let train = zf();
        for (from, to, off, on) in [
            ("1", "4", ["A", "C"], ["D", "E"]),
            ("2", "5", ["A", "E"], ["C", "D"]),
        ] {
            let r = zf_change(
                from,
                to,
                &[
                    (off[0], RELEASE),
                    (off[1], RELEASE),
                    (on[0], APPLY),
                    (on[1], APPLY),
                ],
            )
            .run(&train)
            .unwrap();
            assert_eq!(r.off_going, off);
            assert_eq!(r.on_coming, on);
            assert_eq!(r.elements.len(), 4);
            assert_changed_gear(&train, &r, to);
            eprintln!(
                "8HP {from}-{to}: changes {:?}; lock {:?} s, dissipated {:?} J, residual {:e} J, steps {}",
                r.changes
                    .iter()
                    .map(|c| (c.t, c.element.as_str(), c.now.as_str(), c.dof))
                    .collect::<Vec<_>>(),
                r.lock_time,
                r.dissipated,
                r.max_energy_residual,
                r.steps
            );
        }
    }

    #[test]
    fn a_single_swap_by_ramps_is_the_single_swap_by_off_going_and_on_coming() {
        let train = zf();
        let by_role = zf_2_3().run(&train).unwrap();
        let by_name = ShiftSim {
            off_going: None,
            on_coming: None,
            ramps: vec![
                ("C".into(), zf_2_3().on_coming.unwrap()),
                ("A".into(), zf_2_3().off_going.unwrap()),
            ],
            ..zf_2_3()
        }
        .run(&train)
        .unwrap();
        assert_eq!(by_role, by_name);
    }

    #[test]
    fn the_reported_extremes_do_not_move_with_the_tolerance() {
        // The extremes sit at mode changes (just before a release, a lock):
        // they must be the same at every tolerance, as the lock time is, to
        // 1e-6 of the range. (They were the last accepted step's values: on
        // the 8HP the minimum moved from 382 to 352 N m between rtol 1e-6 and 1e-10.)
        for (train, sim) in [(zf(), zf_2_3()), (two_speed(), two_speed_upshift())] {
            let runs: Vec<ShiftResult> = [1e-6, 1e-8, 1e-10]
                .into_iter()
                .map(|tol| {
                    ShiftSim {
                        rtol: tol,
                        atol: tol,
                        ..sim.clone()
                    }
                    .run(&train)
                    .unwrap()
                })
                .collect();
            let fine = &runs[2];
            let ranges = |r: &ShiftResult| {
                [
                    r.output_torque_range,
                    r.element_torque_range[0],
                    r.element_torque_range[1],
                    r.slip_range[0],
                    r.slip_range[1],
                ]
            };
            for r in &runs[..2] {
                for (a, b) in ranges(r).iter().zip(ranges(fine)) {
                    let range = b[0] - b[1];
                    for k in 0..2 {
                        assert!(
                            (a[k] - b[k]).abs() <= 1e-6 * range,
                            "{} -> {}: {a:?} against {b:?}",
                            sim.from,
                            sim.to
                        );
                    }
                }
            }
            // Every sample lies within the reported range.
            for s in &fine.samples {
                let [hi, lo] = fine.output_torque_range;
                assert!(s.output_torque <= hi && s.output_torque >= lo);
            }
        }
    }

    #[test]
    fn a_release_is_sampled_on_both_sides_at_the_static_and_kinetic_limits() {
        // The off-going clutch releases where its torque meets mu_s C(t) (the
        // left limit) and then carries mu_k C(t) (the right limit): both are
        // samples at the release time.
        let r = zf_2_3().run(&zf()).unwrap();
        let release = &r.changes[0];
        assert_eq!(
            (release.element.as_str(), release.now.as_str()),
            ("A", "slipping")
        );
        let at: Vec<&ShiftSample> = r.samples.iter().filter(|s| s.t == release.t).collect();
        assert_eq!(at.len(), 2, "a sample on each side");
        let c = zf_2_3().off_going.unwrap().at(release.t);
        let (before, after) = (at[0].element_torque[0], at[1].element_torque[0]);
        assert!(
            rel(before.abs(), 0.15 * c) < 1e-9,
            "{before} vs {}",
            0.15 * c
        );
        assert!(
            rel(after.abs(), 0.12 * c) < 1e-12,
            "{after} vs {}",
            0.12 * c
        );
        assert_eq!((at[0].dof, at[1].dof), (1, 2));
        // the speeds are continuous across it
        assert_eq!(at[0].speed, at[1].speed);
    }

    #[test]
    fn a_constant_capacity_engagement_through_the_train_matches_the_closed_forms() {
        // The brake has no capacity at all: it cannot hold the torque the
        // slipping clutch puts on it, so it is released at t = 0, and the
        // sun (J1) and the carrier (J2) are two free inertias joined by a
        // clutch of constant capacity: slip time s0 / (mu C (1/J1 + 1/J2)),
        // energy 1/2 J1 J2 / (J1 + J2) s0^2.
        let train = two_speed();
        let (j1, j2, mu, cap, w) = (0.01, 0.05, 0.12, 1000.0, 200.0);
        let sim = ShiftSim {
            input_speed: w,
            input_torque: InputTorque::Constant(0.0),
            road_load: [0.0; 3],
            vehicle_inertia: 0.0,
            law: FrictionLaw {
                mu_static: 0.15,
                mu_kinetic: mu,
                decay: None,
            },
            off_going: Some(Capacity::Constant(0.0)),
            on_coming: Some(Capacity::Constant(cap)),
            t_end: 0.1,
            ..two_speed_upshift()
        };
        let r = sim.run(&train).unwrap();
        let s0 = w - w / 3.4; // sun minus carrier in first
        let t_lock = s0 / (mu * cap * (1.0 / j1 + 1.0 / j2));
        let energy = 0.5 * j1 * j2 / (j1 + j2) * s0 * s0;
        assert_eq!(r.changes[0].t, 0.0);
        assert_eq!(r.changes[0].element, "ring_brake");
        assert!(
            rel(r.lock_time.unwrap(), t_lock) < 1e-9,
            "{:?} vs {t_lock}",
            r.lock_time
        );
        assert!(
            rel(r.dissipated[1], energy) < 1e-9,
            "{:?} vs {energy}",
            r.dissipated
        );
        assert_eq!(r.dissipated[0], 0.0);
        // Lock-up speed: the momentum average, and the train ends direct.
        let last = r.samples.last().unwrap();
        let common = (j1 * w + j2 * w / 3.4) / (j1 + j2);
        for l in ["sun", "carrier"] {
            let k = train.link_id(l).unwrap().index();
            assert!(rel(last.speed[k], common) < 1e-9, "{l}: {}", last.speed[k]);
        }
        assert!(r.max_energy_residual < 1e-9 * energy);
    }

    #[test]
    fn a_brake_that_cannot_hold_at_the_start_is_released_at_t_0() {
        // First gear holds the ring with about 2.4 x the input torque; a
        // constant brake capacity with mu_s C = 150 N m cannot, so the brake
        // slips from t = 0 and never carries more than its limit.
        let train = two_speed();
        let limit = 150.0;
        let sim = ShiftSim {
            off_going: Some(Capacity::Constant(limit / 0.15)),
            ..two_speed_upshift()
        };
        let r = sim.run(&train).unwrap();
        assert_eq!(
            (
                r.changes[0].t,
                r.changes[0].element.as_str(),
                r.changes[0].now.as_str()
            ),
            (0.0, "ring_brake", "slipping")
        );
        for s in &r.samples {
            assert!(
                s.element_torque[0].abs() <= limit * (1.0 + 1e-12),
                "t = {}: {} N m against {limit}",
                s.t,
                s.element_torque[0]
            );
        }
        assert!(
            r.element_torque_range[0][0]
                .abs()
                .max(r.element_torque_range[0][1].abs())
                <= limit * (1.0 + 1e-12)
        );
        assert!(r.max_energy_residual < 1e-7 * (r.dissipated[0] + r.dissipated[1]));
        assert_ends_in(&train, &r, "2");
    }

    #[test]
    fn a_coast_1_2_upshift_overruns_the_one_way_brake_at_t_0() {
        // Foot off (engine braking): first gear would need the one-way brake
        // to hold a torque of the wrong sign, so it overruns from the start
        // and the band takes the train into second. (With the band ramped to
        // 8000 the band slipped against a one-way brake held the wrong way,
        // dissipating 1e5 J; to 20000 the run ended in a tie-up.)
        let train = simpson();
        for to in [8000.0, 20000.0] {
            let sim = ShiftSim {
                from: "1".into(),
                to: "2".into(),
                input_torque: InputTorque::Constant(-50.0),
                off_going: Some(Capacity::Constant(0.0)),
                on_coming: Some(Capacity::Ramp {
                    t0: 0.05,
                    t1: 0.35,
                    from: 0.0,
                    to,
                }),
                ..upshift()
            };
            let r = sim.run(&train).unwrap();
            assert_eq!(
                (
                    r.changes[0].t,
                    r.changes[0].element.as_str(),
                    r.changes[0].now.as_str()
                ),
                (0.0, "low_one_way", "overrunning")
            );
            assert!(
                r.samples
                    .iter()
                    .all(|s| s.element_torque[0] == 0.0 && s.slip[0] >= -1e-9 * 300.0)
            );
            assert!(r.lock_time.is_some());
            assert_ends_in(&train, &r, "2");
            // Little is dissipated (the band slips briefly): bound the residual
            // by the vehicle's kinetic energy at the start instead.
            let w_out = 300.0 / train.analyse_gear("1").unwrap().ratio;
            assert!(r.max_energy_residual < 1e-9 * 0.5 * 15.0 * w_out * w_out);
        }
    }

    #[test]
    fn the_step_budget_and_an_impossible_tolerance_are_named() {
        let train = simpson();
        let e = ShiftSim {
            max_steps: 10,
            ..upshift()
        }
        .run(&train)
        .unwrap_err();
        assert_eq!(e.code(), "budget", "{e}");
        // refused before any work: t_end / MAX_STEP steps at least
        let e = ShiftSim {
            t_end: 1e300,
            ..upshift()
        }
        .run(&train)
        .unwrap_err();
        assert_eq!(e.code(), "budget", "{e}");
        assert!(e.to_string().contains("max_steps"), "{e}");
        let e = ShiftSim {
            rtol: 1e-300,
            ..upshift()
        }
        .run(&train)
        .unwrap_err();
        assert_eq!(e.location().0, Some("shift.rtol"), "{e}");
    }
}
