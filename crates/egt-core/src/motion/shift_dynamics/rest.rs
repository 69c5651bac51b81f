//! A train brought to rest: when an event leaves every link at zero speed
//! and the only mode that can hold the state is a tie-up (its locked rows
//! leave no degree of freedom), the train stands still instead of being
//! refused. Such a *rest* mode has no coordinates: its speeds are zero, its
//! accelerations zero, and its locked elements carry the static torques
//! (the multipliers of `A^T lambda = -f`, unique when its rows are
//! independent). It lasts while each locked element holds its static torque
//! within `mu_s C(t)` (a one-way element with its holding sign): those are
//! its events, located as the others, and the run leaves rest by the
//! consistent mode after one (`consistent.rs`).
//!
//! The typical case is braking with both elements holding: an on-coming
//! element applied while the off-going one still holds drags the train down
//! (a tie-up brake); the on-coming slip reaches zero exactly when every link
//! stops, and the train then rests, held by both.

use super::train_mode::{Mode, Phase, Setup};
use crate::error::Result;

/// Speeds at most this fraction of the run's initial speed scale count as
/// rest (an event located at zero slip leaves speeds of rounding size).
pub(super) const REST_ZERO: f64 = 1e-9;

impl Setup<'_> {
    /// Whether the speeds `v` are those of a train at rest, against the
    /// input speed at the start (exactly zero when that is zero).
    pub(super) fn at_rest(&self, v: &[f64]) -> bool {
        let scale = self.sim.input_speed.abs();
        v.iter().all(|w| w.abs() <= REST_ZERO * scale)
    }

    /// The mode of `phases`; when it ties the train up and the speeds `v`
    /// are at rest, the rest mode (no DOF) instead of the refusal.
    ///
    /// # Errors
    /// As [`Setup::mode`]: the tie-up of a train that moves, dependent rows,
    /// missing inertia.
    pub(super) fn mode_or_rest(&self, phases: &[Phase], v: &[f64]) -> Result<Mode> {
        match self.mode(phases) {
            Err(e) if self.at_rest(v) => match self.rest_mode(phases) {
                Ok(m) if m.basis.ncols() == 0 => Ok(m),
                _ => Err(e),
            },
            other => other,
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::super::friction::{Capacity, FrictionLaw};
    use super::super::shift::tests::{rel, two_speed, two_speed_upshift};
    use super::super::shift::{InputTorque, ShiftSim};

    /// The two-speed train braked by a tie-up: the ring brake keeps holding
    /// (a capacity far above its torque) while the direct clutch applies at
    /// a constant capacity. With the brake locked the train moves in first
    /// (carrier w, sun 3.4 w), and the clutch slips at 2.4 w, so its
    /// kinetic torque mu_k C brakes the output with T = 2.4 mu_k C on the
    /// reduced inertia J = J_carrier + J_vehicle + 3.4^2 J_sun: the train
    /// stops at t = J w0 / T having dissipated 1/2 J w0^2, and rests there,
    /// held by both elements.
    fn tie_up_brake() -> ShiftSim {
        ShiftSim {
            input_speed: 200.0,
            input_torque: InputTorque::Constant(0.0),
            road_load: [0.0; 3],
            vehicle_inertia: 2.0,
            law: FrictionLaw {
                mu_static: 0.15,
                mu_kinetic: 0.12,
                decay: None,
            },
            off_going: Some(Capacity::Constant(1e6)),
            on_coming: Some(Capacity::Constant(1000.0)),
            t_end: 2.0,
            ..two_speed_upshift()
        }
    }

    #[test]
    fn a_train_braked_by_both_elements_is_simulated_to_rest() {
        let train = two_speed();
        let sim = tie_up_brake();
        let r = sim.run(&train).unwrap();
        let (jc, js, jv, mu, c) = (0.05, 0.01, 2.0, 0.12, 1000.0);
        let j = jc + jv + 3.4 * 3.4 * js;
        let w0 = 200.0 / 3.4;
        let torque = 2.4 * mu * c;
        let t_rest = j * w0 / torque;
        let energy = 0.5 * j * w0 * w0;
        let rest = r.rest_time.unwrap();
        assert!(rel(rest, t_rest) < 1e-9, "{rest} vs {t_rest}");
        assert!(
            rel(r.dissipated[1], energy) < 1e-9,
            "{:?} vs {energy}",
            r.dissipated
        );
        assert_eq!(r.dissipated[0], 0.0);
        let last = r.changes.last().unwrap();
        assert_eq!(
            (last.element.as_str(), last.now.as_str(), last.dof),
            ("direct_clutch", "locked", 0)
        );
        // At rest to the end: every speed zero, the energy balanced.
        let end = r.samples.last().unwrap();
        assert_eq!(end.t, 2.0);
        assert!(end.speed.iter().all(|&w| w == 0.0));
        assert!(r.max_energy_residual < 1e-9 * energy);
    }

    #[test]
    fn a_rest_lasts_while_the_elements_hold_its_static_torques() {
        // An input torque of 20 N m: the train stops at
        // t = J w0 / (2.4 mu_k C - 3.4 T_in), then rests with the brake
        // holding the whole input torque (the carrier is free, so the case
        // reacts T_in through the ring). The brake's capacity falls from
        // 1e5 to 0 over [1, 1.5]: it lets go where mu_s C(t) = T_in, and the
        // train leaves rest in second (the clutch locked, every link at one
        // speed).
        let train = two_speed();
        let (t_in, j, w0) = (20.0, 0.05 + 2.0 + 3.4 * 3.4 * 0.01, 200.0 / 3.4);
        let sim = ShiftSim {
            input_torque: InputTorque::Constant(t_in),
            off_going: Some(Capacity::Ramp {
                t0: 1.0,
                t1: 1.5,
                from: 1e5,
                to: 0.0,
            }),
            ..tie_up_brake()
        };
        let r = sim.run(&train).unwrap();
        let stop = j * w0 / (2.4 * 0.12 * 1000.0 - 3.4 * t_in);
        let release = 1.0 + 0.5 * (1.0 - t_in / (0.15 * 1e5));
        let what: Vec<(&str, &str, usize)> = (r.changes.iter())
            .map(|c| (c.element.as_str(), c.now.as_str(), c.dof))
            .collect();
        assert_eq!(
            what,
            [
                ("direct_clutch", "locked", 0),
                ("ring_brake", "slipping", 1)
            ]
        );
        assert!(
            rel(r.changes[0].t, stop) < 1e-9,
            "{} vs {stop}",
            r.changes[0].t
        );
        assert!(
            rel(r.changes[1].t, release) < 1e-9,
            "{} vs {release}",
            r.changes[1].t
        );
        // It did not stay at rest; at rest the brake held T_in.
        assert_eq!(r.rest_time, None);
        let resting = (r.samples.iter())
            .find(|s| s.t > r.changes[0].t && s.t < r.changes[1].t)
            .unwrap();
        assert!(rel(resting.element_torque[0].abs(), t_in) < 1e-12);
        let end = r.samples.last().unwrap();
        let (sun, carrier) = (end.speed[1], end.speed[2]);
        assert!(sun > 1.0 && rel(sun, carrier) < 1e-9, "{:?}", end.speed);
        assert!(r.max_energy_residual < 1e-9 * r.dissipated[1]);
    }
}
