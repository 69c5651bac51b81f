//! The extremes a shift report gives (output torque, element torques, slip
//! speeds) over the whole run, not only over its samples.
//!
//! The quantities jump at a mode change (static to kinetic friction, a lock,
//! a slip that reverses), so their extremes often sit just before one: every
//! event is sampled on both sides (the run records its left limit, the old
//! mode at the event, before the right limit). Between samples a smooth
//! extremum is found on the step's dense output: where a quantity's slope
//! changes sign across a step, golden-section search on the interpolant
//! finds the turning point. Both make the extremes converge with the
//! tolerance, as the lock time does, instead of being the last accepted
//! step's values.

use super::train_mode::Observed;

/// Largest and smallest value of each quantity seen so far.
#[derive(Debug, Clone)]
pub(super) struct Extremes {
    pub(super) max: Observed,
    pub(super) min: Observed,
}

/// Golden-section iterations: the bracket shrinks by 0.618^60, about 3e-13.
const GOLDEN_STEPS: usize = 60;

impl Extremes {
    pub(super) fn new() -> Self {
        Self {
            max: [f64::NEG_INFINITY; 5],
            min: [f64::INFINITY; 5],
        }
    }

    /// Takes a value seen (a sample, or a turning point).
    pub(super) fn add(&mut self, q: &Observed) {
        for (k, &v) in q.iter().enumerate() {
            self.max[k] = self.max[k].max(v);
            self.min[k] = self.min[k].min(v);
        }
    }

    /// The turning points inside `(t0, t1)`, on `at` (the quantities on the
    /// step's dense output), whose ends gave `q0` and `q1`. A quantity turns
    /// inside when its slope just after `t0` and just before `t1` differ in sign.
    pub(super) fn within(
        &mut self,
        mut at: impl FnMut(f64) -> Observed,
        t0: f64,
        t1: f64,
        q0: &Observed,
        q1: &Observed,
    ) {
        if t1 <= t0 {
            return;
        }
        let delta = 1e-3 * (t1 - t0);
        let (qa, qb) = (at(t0 + delta), at(t1 - delta));
        for k in 0..q0.len() {
            let (s0, s1) = (qa[k] - q0[k], q1[k] - qb[k]);
            let sign = if s0 > 0.0 && s1 < 0.0 {
                1.0 // a maximum
            } else if s0 < 0.0 && s1 > 0.0 {
                -1.0 // a minimum
            } else {
                continue;
            };
            let best = golden(|s| sign * at(s)[k], t0, t1) * sign;
            self.max[k] = self.max[k].max(best);
            self.min[k] = self.min[k].min(best);
        }
    }
}

/// The largest value of `f` on `[a, b]` by golden-section search (`f` one-peaked there).
fn golden(mut f: impl FnMut(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
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
    fc.max(fd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turning_point_inside_a_step_is_found() {
        // q0 = sin(t) over [1, 2]: a maximum of 1 at pi/2, between the ends.
        let at = |t: f64| [t.sin(), -t.sin(), 0.0, 0.0, 0.0];
        let mut e = Extremes::new();
        let (q0, q1) = (at(1.0), at(2.0));
        e.add(&q0);
        e.add(&q1);
        e.within(at, 1.0, 2.0, &q0, &q1);
        assert!((e.max[0] - 1.0).abs() < 1e-14, "{}", e.max[0]);
        assert!((e.min[1] + 1.0).abs() < 1e-14, "{}", e.min[1]);
        // a monotone quantity keeps its end values
        assert_eq!(e.min[0], 2f64.sin().min(1f64.sin()));
    }
}
