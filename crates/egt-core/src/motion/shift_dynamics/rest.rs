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
//!
//! A vehicle stopped by its road load is *parked*: the road load's Coulomb
//! term `c0` (its brakes, its rolling resistance) is a static friction at
//! rest. When the train stops in a mode of one DOF (an element's slip
//! reaching zero with every link, e.g. the released one after a shift), the
//! mode is tried with the output held (a row `w_out = 0`, no DOF left); it
//! holds while the static torque at the output, that row's multiplier, is
//! within `c0` (an event), and the output torque at rest is that reaction.
//! A static torque above `c0` rolls the vehicle back. Not with a compliant
//! output (the vehicle is not the output link).

use nalgebra::{Cholesky, DMatrix};

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
    /// The road load's Coulomb term `c0`: the torque that holds the output
    /// of a vehicle at rest (its brakes, its rolling resistance); 0 with a
    /// compliant output (the vehicle is not the output link: never parked).
    pub(super) fn stopping(&self) -> f64 {
        match self.sim.output_shaft {
            Some(_) => 0.0,
            None => self.sim.road_load[0].max(0.0),
        }
    }

    /// `phases` with the vehicle parked: a mode of one DOF whose output
    /// moves, held at the output by the road load (an extra row `w_out =
    /// 0`), so no DOF is left. `None` when `phases` does not give such a
    /// mode (a tie-up, more DOF, or an output that does not move in it).
    pub(super) fn parked_mode(&self, phases: &[Phase]) -> Option<Mode> {
        let mut mode = self.mode(phases).ok()?;
        let (n, r) = (self.n, mode.rows.nrows());
        let moves = mode.basis.ncols() == 1 && mode.basis[(self.output, 0)].abs() > 1e-9;
        if !moves {
            return None;
        }
        let mut rows = mode.rows.clone().insert_row(r, 0.0);
        rows[(r, self.output)] = 1.0;
        mode.lambda_map = (&rows * rows.transpose()).try_inverse()? * &rows;
        mode.rows = rows;
        mode.basis = DMatrix::zeros(n, 0);
        mode.reduced = Cholesky::new(DMatrix::zeros(0, 0))?;
        mode.park_row = Some(r);
        Some(mode)
    }

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

    /// The two-speed power-on 1-2 upshift, then braked by the road load's
    /// Coulomb term `c0` against a constant input torque `t_in`: in second
    /// (direct, every link at one speed, J = J_sun + J_carrier + J_vehicle)
    /// the output decelerates at `(c0 - t_in) / J` once the brake's capacity
    /// is gone (t = 0.25 s).
    fn braked_in_second(t_in: f64, c0: f64) -> (ShiftSim, f64) {
        let sim = ShiftSim {
            input_torque: InputTorque::Constant(t_in),
            road_load: [c0, 0.0, 0.0],
            t_end: 3.0,
            ..two_speed_upshift()
        };
        (sim, 0.01 + 0.05 + 2.0)
    }

    #[test]
    fn a_vehicle_braked_by_its_road_load_stops_and_is_held_by_it() {
        // 20 N m in against c0 = 300: the vehicle stops at
        // t_a + J w_a / (c0 - t_in) from any sample (t_a, w_a) after the
        // lock and the brake's ramp, and stays parked: the road load holds
        // the static 20 N m (below c0), which is the output torque at rest.
        let train = two_speed();
        let (t_in, c0) = (20.0, 300.0);
        let (sim, j) = braked_in_second(t_in, c0);
        let r = sim.run(&train).unwrap();
        let lock = r.lock_time.unwrap();
        let carrier = train.link_id("carrier").unwrap().index();
        let a = (r.samples.iter())
            .find(|s| s.t >= lock.max(0.25) && s.dof == 1)
            .unwrap();
        let stop = a.t + j * a.speed[carrier] / (c0 - t_in);
        let rest = r.rest_time.unwrap();
        assert!(rel(rest, stop) < 1e-9, "{rest} vs {stop}");
        let last = r.changes.last().unwrap();
        assert_eq!((last.element.as_str(), last.dof), ("ring_brake", 0));
        let end = r.samples.last().unwrap();
        assert_eq!(end.t, 3.0);
        assert!(end.speed.iter().all(|&w| w == 0.0));
        assert!(rel(end.output_torque, t_in) < 1e-9, "{}", end.output_torque);
        let dissipated: f64 = r.dissipated.iter().sum();
        assert!(r.max_energy_residual < 1e-8 * dissipated);
    }

    #[test]
    fn a_static_torque_above_the_road_loads_c0_rolls_the_vehicle_back() {
        // -100 N m (engine braking) against c0 = 50: the vehicle stops,
        // but at rest the road load cannot hold 100 N m, so it rolls back,
        // accelerating at (t_in + c0) / J with the road load now forward.
        let train = two_speed();
        let (t_in, c0) = (-100.0, 50.0);
        let (sim, j) = braked_in_second(t_in, c0);
        let r = sim.run(&train).unwrap();
        assert_eq!(r.rest_time, None);
        let carrier = train.link_id("carrier").unwrap().index();
        let stop = r.changes.last().unwrap();
        assert_eq!((stop.element.as_str(), stop.dof), ("ring_brake", 1));
        let end = r.samples.last().unwrap();
        let back = (t_in + c0) / j * (end.t - stop.t);
        assert!(end.speed[carrier] < 0.0);
        assert!(
            rel(end.speed[carrier], back) < 1e-9,
            "{} vs {back}",
            end.speed[carrier]
        );
        let dissipated: f64 = r.dissipated.iter().sum();
        assert!(r.max_energy_residual < 1e-8 * dissipated);
    }
}
