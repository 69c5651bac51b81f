//! The shift model advanced piece by piece (a co-simulation unit's
//! `fmi2DoStep`): every shift element of the transmission carries a capacity
//! the caller sets before each piece, the state is kept between pieces, and
//! [`ShiftStepper::advance`] integrates over `[t, t + h]` with the same modes,
//! event location, consistent modes and lock-up projections as
//! [`super::shift::ShiftSim::run`], stopping exactly at `t + h`.
//!
//! Unlike `run`, no element is held rigidly by the gear: the elements of the
//! initial gear start locked and stay so while their capacity holds them; the
//! others slip (with no torque at zero capacity). A piece takes each
//! element's capacity as a straight line over the piece (its value at `t` and
//! its rate; rate 0 holds it), and the input torque as a constant; since
//! inputs may jump between pieces, each piece starts by making the mode
//! consistent (as `run` does at `t = 0`). The step-size control is `run`'s;
//! `run` itself is unchanged.

use nalgebra::{DMatrix, DVector};

use super::consistent::{Cause, Settled, settle};
use super::friction::Capacity;
use super::mode::{element_row, mode_basis};
use super::ode;
use super::shift::{InputTorque, MAX_STEP, ModeChange, ShiftSim};
use super::train_mode::{Mode, Phase, Setup, refuse};
use crate::analysis::transmission::is_one_way;
use crate::error::{AnalysisError, Error, Result};
use crate::model::train::{ElementId, Train};

/// What the caller sets for one piece: the input torque (constant over the
/// piece) and each element's capacity at the piece's start with its rate
/// (N m per unit friction coefficient, and per second), in the order of
/// [`ShiftStepper::elements`].
#[derive(Debug, Clone, PartialEq)]
pub struct StepInputs {
    /// Torque on the input link (N m).
    pub input_torque: f64,
    /// Torque the surroundings apply against the output's motion, whatever
    /// its direction (N m), on top of the road load; constant over the piece.
    pub load_torque: f64,
    /// Each element's capacity at the piece's start (>= 0).
    pub capacity: Vec<f64>,
    /// Each element's capacity rate over the piece (1/s times N m); 0 holds it.
    pub capacity_rate: Vec<f64>,
}

/// The shift model of a whole transmission, advanced piece by piece.
#[derive(Debug, Clone)]
pub struct ShiftStepper {
    train: Train,
    /// Friction law, input speed, road load, vehicle inertia, tolerances,
    /// method and step budget (per piece); `from` is the initial gear.
    sim: ShiftSim,
    elements: Vec<ElementId>,
    names: Vec<String>,
    m: DMatrix<f64>,
    rows: Vec<DVector<f64>>,
    one_way: Vec<bool>,
    input: usize,
    output: usize,
    state: StepState,
    cached: Cached,
}

/// The mode the last piece ended in, for the next piece to start from: its
/// basis and factors depend on the phases alone, and re-making them was most
/// of a piece's time. A clone starts without it.
struct Cached(Option<Mode>);

impl Clone for Cached {
    fn clone(&self) -> Self {
        Cached(None)
    }
}

impl std::fmt::Debug for Cached {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() {
            "Cached(mode)"
        } else {
            "Cached(none)"
        })
    }
}

/// The state kept between pieces.
#[derive(Debug, Clone)]
struct StepState {
    t: f64,
    y: Vec<f64>,
    phases: Vec<Phase>,
    /// The step size the control proposes next.
    h: f64,
    lock_loss: f64,
    implicit: bool,
    limited: usize,
    steps: usize,
    changes: Vec<ModeChange>,
    lock_time: Vec<Option<f64>>,
    /// The output torque, each element's torque, each one's slip, at `t`.
    observed: Vec<f64>,
}

/// Consecutive stability-limited explicit steps that call a mode stiff (as `run`).
const STIFF_STEPS: usize = 10;
/// The Bogacki–Shampine stability boundary (as `run`).
const EXPLICIT_LIMIT: f64 = 2.5;
/// Mode changes in a row at one instant before a piece is refused (as `run`).
const MAX_AT_ONCE: usize = 8;

impl ShiftStepper {
    /// The model at `t = 0` in gear `sim.from`'s steady motion at
    /// `sim.input_speed`, with `start`'s input torque, load torque and
    /// capacities (in the order of the spec's elements; its rates are not
    /// used). `sim`'s input torque, `to`, ramps, `t_end` and output shaft are
    /// not used (a compliant output shaft is refused).
    ///
    /// # Errors
    /// A named invalid field (a capacity not finite or negative), an unknown
    /// gear, missing inertias, a tie-up.
    pub fn new(train: &Train, sim: &ShiftSim, start: &StepInputs) -> Result<Self> {
        sim.validate()?;
        if sim.output_shaft.is_some() {
            return Err(Error::invalid(
                "shift.output_shaft",
                "a compliant output shaft is not supported when stepping",
            ));
        }
        let t = train.checked_transmission()?;
        let from = t
            .states
            .iter()
            .find(|s| s.name == sim.from)
            .ok_or_else(|| {
                Error::invalid(
                    "shift.from",
                    format!(
                        "no gear state `{}`; the states are {}",
                        sim.from,
                        t.states
                            .iter()
                            .map(|s| format!("`{}`", s.name))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })?;
        let elements: Vec<ElementId> = (0..train.elements().len())
            .map(ElementId::from_index)
            .collect();
        let names: Vec<String> = train.elements().iter().map(|e| e.name.clone()).collect();
        let (input, output) = (
            train.coordinate(t.input).expect("checked: input moves"),
            train.coordinate(t.output).expect("checked: output moves"),
        );
        let mut m = train.mass_matrix()?.matrix()?;
        m[(output, output)] += sim.vehicle_inertia;
        let n = m.nrows();
        let rows = elements
            .iter()
            .map(|&e| element_row(train, e).map(DVector::from_vec))
            .collect::<Result<Vec<_>>>()?;
        let one_way = train
            .elements()
            .iter()
            .map(|e| is_one_way(e.kind))
            .collect();
        let basis = mode_basis(train, &from.engaged)?;
        let col = basis.basis.column(0);
        let scale = sim.input_speed / col[input];
        let mut y: Vec<f64> = col.iter().map(|c| c * scale).collect();
        let k = elements.len();
        y.extend(std::iter::repeat_n(0.0, k + 1));
        let mut stepper = ShiftStepper {
            train: train.clone(),
            sim: sim.clone(),
            elements,
            names,
            m,
            rows,
            one_way,
            input,
            output,
            state: StepState {
                t: 0.0,
                y,
                phases: Vec::new(),
                h: 1e-4,
                lock_loss: 0.0,
                implicit: sim.method == super::shift::ShiftMethod::Implicit,
                limited: 0,
                steps: 0,
                changes: Vec::new(),
                lock_time: vec![None; k],
                observed: Vec::new(),
            },
            cached: Cached(None),
        };
        let inputs = StepInputs {
            capacity_rate: vec![0.0; k],
            ..start.clone()
        };
        let ys = stepper.state.y.clone();
        stepper.state.phases = (0..k)
            .map(|i| {
                let slip = stepper.rows[i]
                    .iter()
                    .zip(&ys[..n])
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
                if from.engaged.contains(&stepper.elements[i]) || slip == 0.0 {
                    Phase::Locked
                } else {
                    Phase::Slipping(slip.signum())
                }
            })
            .collect();
        stepper.start(&inputs)?;
        Ok(stepper)
    }

    /// The elements, in the order of the inputs and outputs (the spec's).
    pub fn elements(&self) -> &[String] {
        &self.names
    }

    /// The time reached (s).
    pub fn time(&self) -> f64 {
        self.state.t
    }

    /// Every coordinate's speed (rad/s), in the order of `Train::coordinates`.
    pub fn speeds(&self) -> &[f64] {
        &self.state.y[..self.m.nrows()]
    }

    /// The input link's speed (rad/s).
    pub fn input_speed(&self) -> f64 {
        self.state.y[self.input]
    }

    /// The output link's speed (rad/s).
    pub fn output_speed(&self) -> f64 {
        self.state.y[self.output]
    }

    /// The torque the output delivers to the vehicle (vehicle inertia times
    /// output acceleration plus the road load), at the time reached.
    pub fn output_torque(&self) -> f64 {
        self.state.observed[0]
    }

    /// Element `i`'s torque on its first link (its multiplier when locked,
    /// its friction torque when slipping).
    pub fn element_torque(&self, i: usize) -> f64 {
        self.state.observed[1 + i]
    }

    /// Element `i`'s slip speed (rad/s).
    pub fn slip(&self, i: usize) -> f64 {
        self.state.observed[1 + self.elements.len() + i]
    }

    /// The energy element `i` has dissipated since `t = 0` (J).
    pub fn dissipated(&self, i: usize) -> f64 {
        self.state.y[self.m.nrows() + i]
    }

    /// Whether element `i` is locked (a one-way element: holding).
    pub fn locked(&self, i: usize) -> bool {
        self.state.phases[i] == Phase::Locked
    }

    /// The last time element `i` locked after `t = 0`, if it has.
    pub fn lock_time(&self, i: usize) -> Option<f64> {
        self.state.lock_time[i]
    }

    /// The mode changes so far, in time order.
    pub fn changes(&self) -> &[ModeChange] {
        &self.state.changes
    }

    /// Accepted steps so far.
    pub fn steps(&self) -> usize {
        self.state.steps
    }

    /// The setup of one piece: `inputs` as the input torque and capacities.
    fn setup(&self, inputs: &StepInputs, t0: f64, h: f64) -> Setup<'_> {
        let capacity = (inputs.capacity.iter().zip(&inputs.capacity_rate))
            .map(|(&c, &r)| {
                if r == 0.0 {
                    Capacity::Constant(c)
                } else if c + r * h < 0.0 {
                    // A falling capacity stops at zero inside the piece (an
                    // importer extrapolating past its table's end): no
                    // negative capacity, and so no negative dissipation.
                    Capacity::Ramp {
                        t0,
                        t1: t0 + c / -r,
                        from: c,
                        to: 0.0,
                    }
                } else {
                    Capacity::Ramp {
                        t0,
                        t1: t0 + h,
                        from: c,
                        to: c + r * h,
                    }
                }
            })
            .collect();
        Setup {
            train: &self.train,
            sim: &self.sim,
            m: self.m.clone(),
            input: self.input,
            output: self.output,
            kept: Vec::new(),
            elements: self.elements.clone(),
            rows: self.rows.clone(),
            one_way: self.one_way.clone(),
            capacity,
            n: self.m.nrows(),
            // The stepper runs the ideal model: mesh losses are `run`'s only.
            losses: None,
            load: inputs.load_torque,
        }
    }

    fn check(&self, inputs: &StepInputs) -> Result<()> {
        let k = self.elements.len();
        if inputs.capacity.len() != k || inputs.capacity_rate.len() != k {
            return Err(Error::invalid(
                "capacity",
                format!("{k} capacities and rates expected"),
            ));
        }
        for (what, v) in [
            ("input_torque", inputs.input_torque),
            ("load_torque", inputs.load_torque),
        ] {
            if !v.is_finite() {
                return Err(Error::invalid(what, format!("{v} is not finite")));
            }
        }
        for (i, (&c, &r)) in inputs
            .capacity
            .iter()
            .zip(&inputs.capacity_rate)
            .enumerate()
        {
            if !(c.is_finite() && c >= 0.0) {
                return Err(Error::invalid(
                    format!("{}.capacity", self.names[i]),
                    format!("capacity {c} must be finite and >= 0"),
                ));
            }
            if !r.is_finite() {
                return Err(Error::invalid(
                    format!("{}.capacity", self.names[i]),
                    format!("capacity rate {r} is not finite"),
                ));
            }
        }
        Ok(())
    }

    /// The consistent mode at `t = 0` and the outputs there.
    fn start(&mut self, inputs: &StepInputs) -> Result<()> {
        self.check(inputs)?;
        self.sim.input_torque = InputTorque::Constant(inputs.input_torque);
        let setup = self.setup(inputs, 0.0, 0.0);
        let st = &self.state;
        let settled = settle(&setup, &st.phases, 0.0, &st.y, Cause::Start, None)?;
        let (changes, lock_time) = self.taken(&settled, 0.0);
        let f = setup.rhs(&settled.mode, 0.0, &settled.y);
        let observed = setup.observe(&settled.mode, 0.0, &settled.y, &f);
        let st = &mut self.state;
        st.changes.extend(changes);
        for (i, l) in lock_time {
            st.lock_time[i] = Some(l);
        }
        st.lock_loss += settled.lost;
        st.phases = settled.mode.phases.clone();
        st.y = settled.y;
        st.observed = observed;
        Ok(())
    }

    /// The changes a consistent mode makes at `t`, and the elements it locks.
    fn taken(&self, s: &Settled, t: f64) -> (Vec<ModeChange>, Vec<(usize, f64)>) {
        let mut changes = Vec::new();
        let mut locks = Vec::new();
        for &i in &s.changed {
            let now = match s.mode.phases[i] {
                Phase::Locked => {
                    if t > 0.0 {
                        locks.push((i, t));
                    }
                    "locked"
                }
                Phase::Slipping(_) if self.one_way[i] => "overrunning",
                Phase::Slipping(_) => "slipping",
            };
            changes.push(ModeChange {
                t,
                element: self.names[i].clone(),
                now: now.to_string(),
                dof: s.mode.basis.ncols(),
            });
        }
        (changes, locks)
    }

    /// Advances from the time reached to `t + h` with `inputs` over the
    /// piece; events inside the piece are located as in `run`. On an error
    /// the state is left as it was (the piece is computed on a copy).
    ///
    /// # Errors
    /// A named invalid input (a capacity not finite or negative, a torque
    /// not finite, a step `h` not finite and positive); the step budget
    /// (`sim.max_steps` per piece); a state that stops being finite; no
    /// consistent mode.
    pub fn advance(&mut self, inputs: &StepInputs, h: f64) -> Result<()> {
        self.check(inputs)?;
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::invalid(
                "step",
                format!("{h} must be finite and > 0"),
            ));
        }
        let before = std::mem::replace(
            &mut self.sim.input_torque,
            InputTorque::Constant(inputs.input_torque),
        );
        let done = self.piece(inputs, h);
        if done.is_err() {
            self.sim.input_torque = before;
        }
        done
    }

    fn piece(&mut self, inputs: &StepInputs, h_piece: f64) -> Result<()> {
        let cached = self.cached.0.take();
        let sim = &self.sim;
        let t_start = self.state.t;
        let t_end = t_start + h_piece;
        let setup = self.setup(inputs, t_start, h_piece);
        let n = setup.n;
        let k = setup.k();
        let mut st = self.state.clone();
        // The inputs may have jumped since the last piece (an importer that
        // holds them over each step): the mode is made consistent with the
        // new capacities first, as at t = 0 (a locked element they cannot
        // hold releases now, not never: its event function starts negative).
        // Only a violated element (an event function already below zero)
        // can change the mode here, so the settling is skipped otherwise.
        let mut mode: Mode = match cached {
            Some(m) if m.phases == st.phases => m,
            _ => setup.mode(&st.phases)?,
        };
        let mut y = std::mem::take(&mut st.y);
        let d0 = setup.rhs(&mode, t_start, &y);
        if setup
            .events(&mode, t_start, &y, &d0)
            .iter()
            .any(|g| *g < 0.0)
        {
            let settled = settle(&setup, &mode.phases, t_start, &y, Cause::Start, None)?;
            let (changes, locks) = self.taken(&settled, t_start);
            st.changes.extend(changes);
            for (i, l) in locks {
                st.lock_time[i] = Some(l);
            }
            st.lock_loss += settled.lost;
            (mode, y) = (settled.mode, settled.y);
        }
        let mut t_now = t_start;
        let mut f0 = setup.rhs(&mode, t_now, &y);
        let mut h = st.h;
        let mut attempts = 0usize;
        let mut at_once = 0usize;
        let mut g_end: Option<Vec<f64>> = None;
        while t_now < t_end {
            attempts += 1;
            if attempts > sim.max_steps {
                return Err(Error::Analysis(AnalysisError::Budget {
                    what: format!("a shift piece from t = {t_start} s to {t_end} s"),
                    estimate: format!("{} steps reached at t = {t_now:e} s", sim.max_steps),
                    limit: format!("{} steps", sim.max_steps),
                    raise: "raise the step budget, loosen rtol, or shorten the step".into(),
                }));
            }
            // A step clipped to the piece's end does not shrink the proposal.
            let clipped = h >= t_end - t_now;
            let hs = h.min(t_end - t_now).min(MAX_STEP);
            let mut rhs = |tt: f64, yy: &[f64]| setup.rhs(&mode, tt, yy);
            let step = if st.implicit {
                ode::implicit_step(&mut rhs, t_now, &y, hs)
            } else {
                Some(ode::bs23(&mut rhs, t_now, &y, &f0, hs))
            };
            let order = 3.0;
            let Some((y1, f1, err)) = step else {
                h = hs * 0.25;
                if h < 1e-14 * t_end.max(1e-3) {
                    return Err(refuse(format!(
                        "the implicit step's matrix is singular at t = {t_now} for every step size"
                    )));
                }
                continue;
            };
            let norm = ode::error_norm(&err, &y, &y1, sim.rtol, sim.atol);
            if !norm.is_finite() {
                return Err(Error::Analysis(AnalysisError::NonFinite {
                    what: "the state of the shift simulation".into(),
                    detail: format!("it overflowed in a step from t = {t_now}"),
                }));
            }
            if norm > 1.0 {
                h = hs * (0.9 * norm.powf(-1.0 / order)).max(0.2);
                if h < 16.0 * f64::EPSILON * t_now.max(1e-6) {
                    return Err(Error::Analysis(AnalysisError::NotConverged {
                        what: format!(
                            "the shift simulation's step control (the step fell to {h:e} s, against rtol {:e} and atol {:e})",
                            sim.rtol, sim.atol
                        ),
                        t: t_now,
                    }));
                }
                continue;
            }
            st.steps += 1;
            if !st.implicit {
                let euler: Vec<f64> = y.iter().zip(&f0).map(|(a, b)| a + hs * b).collect();
                let fe = setup.rhs(&mode, t_now + hs, &euler);
                let (mut num, mut den) = (0.0f64, 0.0f64);
                for i in 0..n {
                    num += (f1[i] - fe[i]).powi(2);
                    den += (y1[i] - euler[i]).powi(2);
                }
                let size = y1[..n].iter().fold(1.0f64, |m, v| m.max(v.abs()));
                let rate = if den.sqrt() > 1e-9 * size {
                    (num / den).sqrt()
                } else {
                    0.0
                };
                if hs * rate > 0.8 * EXPLICIT_LIMIT {
                    st.limited += 1;
                    if st.limited >= STIFF_STEPS && sim.method == super::shift::ShiftMethod::Auto {
                        st.implicit = true;
                    }
                } else {
                    st.limited = 0;
                }
            }
            let t1 = if t_end - (t_now + hs) <= 1e-15 * t_end.abs().max(1.0) {
                t_end
            } else {
                t_now + hs
            };
            // The last accepted step's end, unless an event came between.
            let g0 = match g_end.take() {
                Some(g) => g,
                None => setup.events(&mode, t_now, &y, &f0),
            };
            let g1 = setup.events(&mode, t1, &y1, &f1);
            let mut first: Option<(f64, usize)> = None;
            for i in 0..k {
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
            if let Some((te, i)) = first {
                let ye = ode::hermite(t_now, &y, &f0, t1, &y1, &f1, te);
                if te > t_now {
                    at_once = 0;
                } else {
                    at_once += 1;
                    if at_once > MAX_AT_ONCE {
                        return Err(refuse(format!(
                            "the elements change mode again and again at t = {te} (no consistent mode)"
                        )));
                    }
                }
                let s = settle(&setup, &mode.phases, te, &ye, Cause::Element(i), None)?;
                let (changes, locks) = self.taken(&s, te);
                st.changes.extend(changes);
                for (i, l) in locks {
                    st.lock_time[i] = Some(l);
                }
                st.lock_loss += s.lost;
                (mode, y) = (s.mode, s.y);
                t_now = te;
                f0 = setup.rhs(&mode, t_now, &y);
                continue;
            }
            g_end = Some(g1);
            t_now = t1;
            y = y1;
            f0 = f1;
            let grow = if norm == 0.0 {
                5.0
            } else {
                (0.9 * norm.powf(-1.0 / order)).min(5.0)
            };
            h = if clipped { h.max(hs * grow) } else { hs * grow };
        }
        st.observed = setup.observe(&mode, t_now, &y, &f0);
        st.t = t_now;
        st.h = h;
        st.phases = mode.phases.clone();
        st.y = y;
        self.state = st;
        self.cached.0 = Some(mode);
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::motion::shift_dynamics::shift::tests::{zf, zf_2_3};

    /// Element capacities (A, B, C, D, E) of the 8HP 2-3 upshift at `t` and
    /// their rates: `A` and `C` as `zf_2_3`'s ramps, `B` and `E` far above
    /// their torque (held, as the kept elements of `run`), `D` zero.
    fn ramps_at(sim: &ShiftSim, t: f64) -> (Vec<f64>, Vec<f64>) {
        let (a, c) = (sim.off_going.unwrap(), sim.on_coming.unwrap());
        let rate = |cap: Capacity| match cap {
            Capacity::Ramp { t0, t1, from, to } if t >= t0 && t < t1 => (to - from) / (t1 - t0),
            _ => 0.0,
        };
        (
            vec![a.at(t), 1e7, c.at(t), 0.0, 1e7],
            vec![rate(a), 0.0, rate(c), 0.0, 0.0],
        )
    }

    /// The inputs at `t = 0`: 300 N m in, no load, capacities `c0`.
    fn start(c0: Vec<f64>) -> StepInputs {
        let k = c0.len();
        StepInputs {
            input_torque: 300.0,
            load_torque: 0.0,
            capacity: c0,
            capacity_rate: vec![0.0; k],
        }
    }

    fn stepped(h: f64) -> ShiftStepper {
        let (train, sim) = (zf(), zf_2_3());
        let (c0, _) = ramps_at(&sim, 0.0);
        let mut s = ShiftStepper::new(&train, &sim, &start(c0)).unwrap();
        let pieces = (sim.t_end / h).round() as usize;
        for j in 0..pieces {
            let (capacity, capacity_rate) = ramps_at(&sim, j as f64 * h);
            let inputs = StepInputs {
                input_torque: 300.0,
                load_torque: 0.0,
                capacity,
                capacity_rate,
            };
            s.advance(&inputs, h).unwrap();
        }
        s
    }

    #[test]
    fn the_8hp_2_3_upshift_stepped_in_pieces_equals_the_whole_run() {
        let (train, sim) = (zf(), zf_2_3());
        let run = sim.run(&train).unwrap();
        let last = run.samples.last().unwrap();
        let (input, output) = (
            train.link_id("input").unwrap().index(),
            train.link_id("output").unwrap().index(),
        );
        for h in [1e-3, 1e-2] {
            let s = stepped(h);
            assert!((s.time() - 1.0).abs() < 1e-12);
            assert!((s.lock_time(2).unwrap() - run.lock_time.unwrap()).abs() < 1e-6);
            assert!(s.locked(2) && !s.locked(0));
            for (i, e) in [(0, 0), (2, 1)] {
                let rel = (s.dissipated(i) - run.dissipated[e]).abs() / run.dissipated[e];
                assert!(rel < 1e-6, "h {h} element {i}: {rel:e}");
            }
            for (w, l) in [(s.input_speed(), input), (s.output_speed(), output)] {
                assert!((w - last.speed[l]).abs() < 1e-6 * last.speed[l].abs());
            }
            assert!((s.output_torque() - last.output_torque).abs() < 1e-6 * last.output_torque);
        }
    }

    #[test]
    fn capacities_held_over_each_piece_still_release_and_lock_a_little_later() {
        // The staircase an importer that cannot interpolate sends: a
        // capacity that drops below the locked torque between pieces
        // releases its element at the piece's start.
        let (train, sim) = (zf(), zf_2_3());
        let run = sim.run(&train).unwrap();
        let h = 1e-2;
        let (c0, _) = ramps_at(&sim, 0.0);
        let mut s = ShiftStepper::new(&train, &sim, &start(c0)).unwrap();
        for j in 0..100 {
            let (capacity, _) = ramps_at(&sim, f64::from(j) * h);
            let inputs = StepInputs {
                input_torque: 300.0,
                load_torque: 0.0,
                capacity_rate: vec![0.0; 5],
                capacity,
            };
            s.advance(&inputs, h).unwrap();
        }
        assert!(!s.locked(0) && s.locked(2));
        let lock = s.lock_time(2).unwrap();
        assert!(lock > run.lock_time.unwrap() && lock < run.lock_time.unwrap() + 2.0 * h);
        let released = s.changes().iter().find(|c| c.element == "A").unwrap();
        assert_eq!(released.now, "slipping");
        // In the new gear: the input over the output speed is third's ratio.
        let last = run.samples.last().unwrap();
        let (i, o) = (
            train.link_id("input").unwrap().index(),
            train.link_id("output").unwrap().index(),
        );
        let ratio = last.speed[i] / last.speed[o];
        assert!((s.input_speed() / s.output_speed() - ratio).abs() < 1e-9 * ratio);
    }

    #[test]
    fn a_load_torque_that_balances_the_input_holds_the_speeds_and_is_the_output_torque() {
        // In second (A, B, E held) with no road load, the load i T_in at the
        // output (i the gear's speed ratio, from power balance) keeps every
        // speed where it is; the output delivers exactly that load.
        let (train, mut sim) = (zf(), zf_2_3());
        sim.road_load = [0.0; 3];
        let held = vec![1e7, 1e7, 0.0, 0.0, 1e7];
        let free = ShiftStepper::new(&train, &sim, &start(held.clone())).unwrap();
        let ratio = free.input_speed() / free.output_speed();
        let load = 300.0 * ratio;
        let inputs = StepInputs {
            load_torque: load,
            ..start(held)
        };
        let mut s = ShiftStepper::new(&train, &sim, &inputs).unwrap();
        let w0 = s.speeds().to_vec();
        for _ in 0..10 {
            s.advance(&inputs, 1e-2).unwrap();
        }
        for (w, v) in s.speeds().iter().zip(&w0) {
            assert!((w - v).abs() < 1e-9 * w0[s.input], "{w} vs {v}");
        }
        assert!((s.output_torque() - load).abs() < 1e-9 * load);
        assert!(s.locked(0) && s.locked(1) && s.locked(4));
        // Twice the load decelerates the train at (i T_in - 2 i T_in) / J_out.
        let braked = StepInputs {
            load_torque: 2.0 * load,
            ..inputs.clone()
        };
        s.advance(&braked, 1e-2).unwrap();
        assert!(s.output_speed() < w0[s.output]);
        let e = s.advance(
            &StepInputs {
                load_torque: f64::NAN,
                ..inputs
            },
            1e-3,
        );
        assert!(e.unwrap_err().to_string().contains("load_torque"));
    }

    #[test]
    fn a_capacity_falling_past_zero_inside_a_piece_stops_at_zero() {
        // A's 5000 N m falls at 1e7 N m/s: zero after 0.5 ms of a 1 ms
        // piece, then held at zero (not -5000 at the piece's end): A slips
        // with no torque, and no element's energy goes negative.
        let (train, sim) = (zf(), zf_2_3());
        let (c0, _) = ramps_at(&sim, 0.0);
        let mut s = ShiftStepper::new(&train, &sim, &start(c0.clone())).unwrap();
        let mut rate = vec![0.0; 5];
        rate[0] = -1e7;
        let inputs = StepInputs {
            capacity_rate: rate,
            ..start(c0)
        };
        s.advance(&inputs, 1e-3).unwrap();
        assert!(!s.locked(0));
        assert!(s.element_torque(0).abs() < 1e-9, "{}", s.element_torque(0));
        for i in 0..5 {
            assert!(s.dissipated(i) >= 0.0, "{i}: {}", s.dissipated(i));
        }
    }

    #[test]
    fn a_bad_capacity_is_refused_by_name_and_leaves_the_state() {
        let (train, sim) = (zf(), zf_2_3());
        let (c0, r0) = ramps_at(&sim, 0.0);
        let mut s = ShiftStepper::new(&train, &sim, &start(c0.clone())).unwrap();
        let (w, t) = (s.input_speed(), s.time());
        for bad in [f64::NAN, -1.0] {
            let mut capacity = c0.clone();
            capacity[2] = bad;
            let inputs = StepInputs {
                input_torque: 300.0,
                load_torque: 0.0,
                capacity,
                capacity_rate: r0.clone(),
            };
            let e = s.advance(&inputs, 1e-3).unwrap_err().to_string();
            assert!(e.contains("C.capacity"), "{e}");
        }
        assert_eq!((s.input_speed(), s.time()), (w, t));
    }
}
