//! The extremes a shift report gives (output torque, element torques, slip
//! speeds) over the whole run, not only over its samples.
//!
//! The quantities jump at a mode change (static to kinetic friction, a lock,
//! a slip that reverses), so their extremes often sit just before one: every
//! event is sampled on both sides (the run records its left limit, the old
//! mode at the event, before the right limit). Between samples a smooth
//! extremum is found on the step's dense output: where a quantity's slope
//! changes sign across a step, golden-section search on the interpolant
//! finds the turning point of a torque, and the slips (linear in the speeds,
//! so their interpolant is the dense output's cubic itself) turn where that
//! cubic's derivative vanishes. Both make the extremes converge with the
//! tolerance, as the lock time does, instead of being the last accepted
//! step's values.

use super::train_mode::Observed;

/// Largest and smallest value of each quantity seen so far.
#[derive(Debug, Clone)]
pub(super) struct Extremes {
    pub(super) max: Observed,
    pub(super) min: Observed,
    /// The turning points found by golden section between samples, in the
    /// order found (the shift quality takes the output torque's as candidates
    /// for its dip and overshoot, `quality.rs`).
    pub(super) turns: Vec<Turn>,
    /// The quantities' rates (per second) just before the last step's end,
    /// and that end's time: the next step's rates just after its start when
    /// the step joins on smoothly (the same mode, no capacity corner), which
    /// saves one probe of the dense output per step.
    end_rates: Option<(f64, Vec<f64>)>,
}

/// A turning point between samples, found on a step's dense output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Turn {
    /// Which quantity (its index in [`Observed`]).
    pub(super) quantity: usize,
    /// Time (s).
    pub(super) t: f64,
    /// The quantity's value there.
    pub(super) value: f64,
}

/// Golden-section iterations: the bracket shrinks by 0.618^40, about 4e-9 of
/// the step, so the value is off by about 1e-17 of the quantity's curvature
/// times the step squared.
const GOLDEN_STEPS: usize = 40;

impl Extremes {
    /// No values yet of `len` quantities.
    pub(super) fn new(len: usize) -> Self {
        Self {
            max: vec![f64::NEG_INFINITY; len],
            min: vec![f64::INFINITY; len],
            turns: Vec::new(),
            end_rates: None,
        }
    }

    /// The next step does not join the last one smoothly (a mode change, a
    /// capacity ramp's corner): its rates at the start are probed again.
    pub(super) fn break_here(&mut self) {
        self.end_rates = None;
    }

    /// Takes a value seen (a sample, or a turning point).
    pub(super) fn add(&mut self, q: &[f64]) {
        for (k, &v) in q.iter().enumerate() {
            self.max[k] = self.max[k].max(v);
            self.min[k] = self.min[k].min(v);
        }
    }

    /// The turning points inside `(t0, t1)`, on `at` (the quantities on the
    /// step's dense output), whose ends gave `q0` and `q1`. A quantity turns
    /// inside when its slope just after `t0` and just before `t1` differ in
    /// sign. `rates` gives, for a quantity whose interpolant is the dense
    /// output's cubic itself, its exact rates at both ends: its turning point
    /// is then the cubic's, with no evaluation.
    pub(super) fn within(
        &mut self,
        mut at: impl FnMut(f64) -> Observed,
        t0: f64,
        t1: f64,
        q0: &[f64],
        q1: &[f64],
        rates: &[Option<(f64, f64)>],
    ) {
        let h = t1 - t0;
        if h <= 0.0 {
            return;
        }
        for (k, rate) in rates.iter().enumerate() {
            if let Some((r0, r1)) = *rate {
                let hi = cubic_peak(q0[k], q1[k], r0 * h, r1 * h);
                let lo = -cubic_peak(-q0[k], -q1[k], -r0 * h, -r1 * h);
                self.max[k] = self.max[k].max(hi);
                self.min[k] = self.min[k].min(lo);
            }
        }
        if rates.iter().all(Option::is_some) {
            self.end_rates = None;
            return;
        }
        let delta = 1e-3 * h;
        // The slopes just after t0: the last step's at its end when this
        // step joins on there, else a probe.
        let start: Vec<f64> = match self.end_rates.take() {
            Some((t, r)) if t == t0 => r.iter().map(|x| x * delta).collect(),
            _ => at(t0 + delta).iter().zip(q0).map(|(a, b)| a - b).collect(),
        };
        let qb = at(t1 - delta);
        self.end_rates = Some((
            t1,
            q1.iter().zip(&qb).map(|(a, b)| (a - b) / delta).collect(),
        ));
        for k in (0..q0.len()).filter(|&k| rates[k].is_none()) {
            let (s0, s1) = (start[k], q1[k] - qb[k]);
            let sign = if s0 > 0.0 && s1 < 0.0 {
                1.0 // a maximum
            } else if s0 < 0.0 && s1 > 0.0 {
                -1.0 // a minimum
            } else {
                continue;
            };
            // The turning value of the cubic through the ends' values and
            // slopes, and how far it rises past the ends: the search runs only
            // where twice that rise reaches the extreme so far (not at every
            // wiggle of a stability-limited explicit run).
            let held = if sign > 0.0 {
                self.max[k]
            } else {
                -self.min[k]
            };
            let (p0, p1) = (sign * q0[k], sign * q1[k]);
            let guess = cubic_peak(p0, p1, sign * s0 / 1e-3, sign * s1 / 1e-3);
            let rise = (guess - p0.max(p1)).max(0.0);
            if guess + rise < held {
                continue;
            }
            let (t, peak) = golden(|s| sign * at(s)[k], t0, t1);
            let best = peak * sign;
            self.turns.push(Turn {
                quantity: k,
                t,
                value: best,
            });
            self.max[k] = self.max[k].max(best);
            self.min[k] = self.min[k].min(best);
        }
    }
}

/// The largest value on `[0, 1]` of the cubic with values `p0`, `p1` and
/// slopes `m0`, `m1` (per unit of the interval) at its ends: at an end, or
/// where its derivative `3 a x^2 + 2 b x + m0` vanishes inside.
fn cubic_peak(p0: f64, p1: f64, m0: f64, m1: f64) -> f64 {
    let a = 2.0 * p0 + m0 - 2.0 * p1 + m1;
    let b = -3.0 * p0 - 2.0 * m0 + 3.0 * p1 - m1;
    let value = |x: f64| ((a * x + b) * x + m0) * x + p0;
    let mut roots = [f64::NAN; 2];
    if a.abs() <= 1e-14 * (b.abs() + m0.abs()) {
        if b != 0.0 {
            roots[0] = -m0 / (2.0 * b);
        }
    } else {
        let disc = b * b - 3.0 * a * m0;
        if disc >= 0.0 {
            // the stable pair of roots of 3a x^2 + 2b x + m0
            let q = -(b + b.signum() * disc.sqrt());
            roots = [q / (3.0 * a), if q == 0.0 { 0.0 } else { m0 / q }];
        }
    }
    roots
        .into_iter()
        .filter(|x| *x > 0.0 && *x < 1.0)
        .map(value)
        .fold(p0.max(p1), f64::max)
}

/// Where on `[a, b]` `f` is largest, and its value there, by golden-section
/// search (`f` one-peaked there).
fn golden(mut f: impl FnMut(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - r * (b - a);
    let mut d = a + r * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..GOLDEN_STEPS {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    if fc > fd { (c, fc) } else { (d, fd) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turning_point_inside_a_step_is_found() {
        // q0 = sin(t) over [1, 2]: a maximum of 1 at pi/2, between the ends.
        let at = |t: f64| vec![t.sin(), -t.sin(), 0.0, 0.0, 0.0];
        let mut e = Extremes::new(5);
        let (q0, q1) = (at(1.0), at(2.0));
        e.add(&q0);
        e.add(&q1);
        e.within(at, 1.0, 2.0, &q0, &q1, &[None; 5]);
        assert!((e.max[0] - 1.0).abs() < 1e-14, "{}", e.max[0]);
        assert!((e.min[1] + 1.0).abs() < 1e-14, "{}", e.min[1]);
        // and recorded with its time
        let turn = e
            .turns
            .iter()
            .find(|t| t.quantity == 0)
            .expect("the turn of sin");
        assert!(
            (turn.t - std::f64::consts::FRAC_PI_2).abs() < 1e-7,
            "{turn:?}"
        );
        // a monotone quantity keeps its end values
        assert_eq!(e.min[0], 2f64.sin().min(1f64.sin()));
    }

    #[test]
    fn a_cubic_turns_where_its_derivative_vanishes() {
        // q = 1 + 3 t - t^3 on [0, 2]: q' = 3 - 3 t^2, a maximum of 3 at t = 1;
        // the ends: 1 and -1, rates 3 and -9.
        let mut e = Extremes::new(5);
        let (q0, q1) = (vec![1.0; 5], vec![-1.0; 5]);
        let never = |_: f64| -> Observed { unreachable!("no evaluation for an exact cubic") };
        e.within(never, 0.0, 2.0, &q0, &q1, &[Some((3.0, -9.0)); 5]);
        assert!((e.max[3] - 3.0).abs() < 1e-14, "{}", e.max[3]);
        assert_eq!(e.min[3], -1.0);
    }
}
