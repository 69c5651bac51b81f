//! A friction clutch joining two inertias: the reference case of a shift's
//! inertia phase. Side 1 (`j1`, driven by a constant torque `t1`) and side 2
//! (`j2`, a constant torque `t2` minus a speed-proportional road load
//! `damping · ω2`) are coupled by a clutch whose friction law and capacity
//! ramp are given. The clutch is either slipping (Coulomb torque opposing the
//! slip) or locked (one inertia `j1 + j2`, the clutch carrying whatever torque
//! keeps the slip at zero while that stays within the static limit).
//!
//! Integration: Bogacki–Shampine 3(2), adaptive, with its cubic Hermite dense
//! output; mode changes (slip reaching zero, locked torque reaching the static
//! limit) are located as roots of the event function on the dense output
//! (Illinois false position), never by shrinking steps. The friction work and
//! the applied work ride along as two extra states, so the energy balance
//! `W_applied = ΔKE + E_friction + E_lock` is checked to the integrator's
//! tolerance at every accepted step.

use crate::error::{AnalysisError, Error, Result};

use super::friction::{Capacity, FrictionLaw};
use super::ode;

/// Which mode the clutch is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Side 1 turns faster than side 2 (`dir = +1`) or slower (`dir = -1`).
    Slipping,
    /// Both sides turn together.
    Locked,
}

/// The problem: two inertias, their torques, the clutch and the tolerances.
#[derive(Debug, Clone, PartialEq)]
pub struct Engagement {
    /// Inertia of side 1 (kg·m²).
    pub j1: f64,
    /// Inertia of side 2 (kg·m²).
    pub j2: f64,
    /// Initial speeds (rad/s).
    pub speed: [f64; 2],
    /// Constant torque on side 1 (N·m).
    pub t1: f64,
    /// Constant torque on side 2 (N·m).
    pub t2: f64,
    /// Road-load coefficient on side 2 (N·m·s/rad, >= 0).
    pub damping: f64,
    /// Friction law of the clutch.
    pub law: FrictionLaw,
    /// Capacity of the clutch against time.
    pub capacity: Capacity,
    /// A one-way element instead of a friction clutch: it never lets side 1
    /// run faster than side 2 (it locks in drive, carrying any torque that
    /// holds side 1 back) and overruns freely, with no torque, when side 1
    /// falls behind (coast). `law` and `capacity` are then unused.
    pub one_way: bool,
    /// End time (s).
    pub t_end: f64,
    /// Relative tolerance of the integrator.
    pub rtol: f64,
    /// Absolute tolerance of the integrator (rad/s, J).
    pub atol: f64,
}

/// One accepted step (or located event).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EngagementSample {
    /// Time (s).
    pub t: f64,
    /// Speeds of side 1 and side 2 (rad/s).
    pub speed: [f64; 2],
    /// Slip speed `ω1 - ω2` (rad/s).
    pub slip: f64,
    /// Clutch torque acting on side 1 (N·m).
    pub clutch_torque: f64,
    /// Friction energy dissipated so far (J).
    pub dissipated: f64,
    /// `W_applied - ΔKE - E_friction - E_lock` (J): zero up to the tolerance.
    pub energy_residual: f64,
    /// Mode.
    pub phase: Phase,
}

/// Result of an engagement simulation.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EngagementResult {
    /// Accepted steps and located events.
    pub samples: Vec<EngagementSample>,
    /// Mode changes: (time, new mode).
    pub events: Vec<(f64, Phase)>,
    /// Time of the first lock-up, if any (s).
    pub lock_time: Option<f64>,
    /// Common speed at the first lock-up (rad/s).
    pub lock_speed: Option<f64>,
    /// Friction energy dissipated over the run (J).
    pub dissipated: f64,
    /// Kinetic energy removed by lock-up projections (J, >= 0, ~0 for a clutch).
    pub lock_loss: f64,
    /// Largest |energy residual| over the run (J).
    pub max_energy_residual: f64,
    /// Accepted steps.
    pub steps: usize,
}

/// Steps allowed before the run is refused.
pub const MAX_STEPS: usize = 1_000_000;

// State: ω1, ω2, friction energy, applied work.
type State = [f64; 4];

impl Engagement {
    fn validate(&self) -> Result<()> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        for (name, v) in [("j1", self.j1), ("j2", self.j2)] {
            if !pos(v) {
                return Err(Error::invalid(
                    format!("engagement.{name}"),
                    format!("inertia {v} must be finite and > 0"),
                ));
            }
        }
        for (name, v) in [
            ("speed[0]", self.speed[0]),
            ("speed[1]", self.speed[1]),
            ("t1", self.t1),
            ("t2", self.t2),
        ] {
            if !v.is_finite() {
                return Err(Error::invalid(
                    format!("engagement.{name}"),
                    format!("{v} is not finite"),
                ));
            }
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return Err(Error::invalid(
                "engagement.damping",
                format!("{} must be finite and >= 0", self.damping),
            ));
        }
        for (name, v) in [
            ("t_end", self.t_end),
            ("rtol", self.rtol),
            ("atol", self.atol),
        ] {
            if !pos(v) {
                return Err(Error::invalid(
                    format!("engagement.{name}"),
                    format!("{v} must be finite and > 0"),
                ));
            }
        }
        self.law.validate("engagement.law")?;
        self.capacity.validate("engagement.capacity")
    }

    /// Torque that keeps a locked clutch locked, acting on side 1.
    fn locked_torque(&self, w: f64) -> f64 {
        let load = self.t2 - self.damping * w;
        let a = (self.t1 + load) / (self.j1 + self.j2);
        self.j1 * a - self.t1
    }

    fn rhs(&self, phase: Phase, dir: f64, t: f64, y: &State) -> State {
        let load = self.t2 - self.damping * y[1];
        match phase {
            Phase::Locked => {
                let a = (self.t1 + load) / (self.j1 + self.j2);
                [a, a, 0.0, self.t1 * y[0] + load * y[1]]
            }
            Phase::Slipping => {
                let slip = y[0] - y[1];
                let tc = self.slipping_torque(dir, t, slip);
                [
                    (self.t1 + tc) / self.j1,
                    (load - tc) / self.j2,
                    -tc * slip,
                    self.t1 * y[0] + load * y[1],
                ]
            }
        }
    }

    /// Clutch torque on side 1 while slipping (none for an overrunning one-way).
    fn slipping_torque(&self, dir: f64, t: f64, slip: f64) -> f64 {
        if self.one_way {
            0.0
        } else {
            -dir * self.law.mu(slip) * self.capacity.at(t)
        }
    }

    fn kinetic(&self, y: &State) -> f64 {
        0.5 * (self.j1 * y[0] * y[0] + self.j2 * y[1] * y[1])
    }

    /// Event function of the current mode: crosses zero at a mode change.
    fn event(&self, phase: Phase, dir: f64, t: f64, y: &State) -> f64 {
        match phase {
            Phase::Slipping => dir * (y[0] - y[1]),
            Phase::Locked if self.one_way => -self.locked_torque(y[0]),
            Phase::Locked => {
                self.law.static_limit(self.capacity.at(t)) - self.locked_torque(y[0]).abs()
            }
        }
    }

    /// Mode entered at zero slip: locked if the static limit holds, else
    /// slipping in the direction the free relative acceleration points.
    fn mode_at_zero_slip(&self, t: f64, w: f64) -> (Phase, f64) {
        let tc = self.locked_torque(w);
        if self.one_way {
            // Holds while it pulls side 1 back (tc <= 0), else side 1 falls behind.
            return if tc <= 0.0 {
                (Phase::Locked, 0.0)
            } else {
                (Phase::Slipping, -1.0)
            };
        }
        if tc.abs() <= self.law.static_limit(self.capacity.at(t)) {
            return (Phase::Locked, 0.0);
        }
        // With the clutch torque at its kinetic value opposing the slip, the
        // slip accelerates the way the locked torque could not hold.
        (Phase::Slipping, -tc.signum())
    }

    /// Runs the engagement from `t = 0` to `t_end`.
    ///
    /// # Errors
    /// A spec error naming an invalid field; an `Analysis` error when the step
    /// count exceeds [`MAX_STEPS`] or the state stops being finite.
    pub fn simulate(&self) -> Result<EngagementResult> {
        self.validate()?;
        let mut y: State = [self.speed[0], self.speed[1], 0.0, 0.0];
        let ke0 = self.kinetic(&y);
        let mut t = 0.0;
        let mut lock_loss = 0.0;
        let (mut phase, mut dir) = if y[0] == y[1] {
            self.mode_at_zero_slip(0.0, y[0])
        } else if self.one_way && y[0] > y[1] {
            // A one-way element meeting side 1 ahead engages at once: the
            // momentum-consistent jump of lockup.rs, its energy loss recorded.
            let w = (self.j1 * y[0] + self.j2 * y[1]) / (self.j1 + self.j2);
            let before = self.kinetic(&y);
            y[0] = w;
            y[1] = w;
            lock_loss = before - self.kinetic(&y);
            self.mode_at_zero_slip(0.0, w)
        } else {
            (Phase::Slipping, (y[0] - y[1]).signum())
        };
        let mut out = EngagementResult {
            samples: Vec::new(),
            events: vec![(0.0, phase)],
            lock_time: None,
            lock_speed: None,
            dissipated: 0.0,
            lock_loss: 0.0,
            max_energy_residual: 0.0,
            steps: 0,
        };
        if lock_loss > 0.0 && phase == Phase::Locked {
            out.lock_time = Some(0.0);
            out.lock_speed = Some(y[0]);
        }
        let record =
            |out: &mut EngagementResult, t: f64, y: &State, phase: Phase, dir: f64, loss: f64| {
                let tc = match phase {
                    Phase::Locked => self.locked_torque(y[0]),
                    Phase::Slipping => self.slipping_torque(dir, t, y[0] - y[1]),
                };
                let residual = y[3] - (self.kinetic(y) - ke0) - y[2] - loss;
                out.max_energy_residual = out.max_energy_residual.max(residual.abs());
                out.samples.push(EngagementSample {
                    t,
                    speed: [y[0], y[1]],
                    slip: y[0] - y[1],
                    clutch_torque: tc,
                    dissipated: y[2],
                    energy_residual: residual,
                    phase,
                });
            };
        record(&mut out, t, &y, phase, dir, lock_loss);
        let mut h = (self.t_end * 1e-3).min(1e-3);
        let mut f0 = self.rhs(phase, dir, t, &y);
        let breaks = self.capacity.breakpoints();
        while t < self.t_end {
            if out.steps >= MAX_STEPS {
                return Err(refuse(format!(
                    "{MAX_STEPS} steps reached at t = {t} before t_end = {}",
                    self.t_end
                )));
            }
            // Never step across a kink of the capacity or past the end.
            let mut stop = self.t_end;
            for b in breaks {
                if b > t * (1.0 + 1e-15) && b < stop {
                    stop = b;
                }
            }
            h = h.min(stop - t);
            let mut rhs = |tt: f64, yy: &[f64]| self.rhs(phase, dir, tt, &state(yy)).to_vec();
            let (y1, f1, err) = ode::bs23(&mut rhs, t, &y, &f0, h);
            let (y1, f1) = (state(&y1), state(&f1));
            let norm = ode::error_norm(&err, &y, &y1, self.rtol, self.atol);
            if !norm.is_finite() {
                return Err(refuse(format!("state stopped being finite at t = {t}")));
            }
            if norm > 1.0 {
                h *= (0.9 * norm.powf(-1.0 / 3.0)).max(0.2);
                continue;
            }
            out.steps += 1;
            let t1 = if stop - (t + h) <= 1e-15 * stop.abs().max(1.0) {
                stop
            } else {
                t + h
            };
            let g0 = self.event(phase, dir, t, &y);
            let g1 = self.event(phase, dir, t1, &y1);
            if g0 > 0.0 && g1 <= 0.0 {
                // Locate the mode change on the dense output.
                let dense = |s: f64| state(&ode::hermite(t, &y, &f0, t1, &y1, &f1, s));
                let te = ode::locate(|s| self.event(phase, dir, s, &dense(s)), t, t1, g0, g1);
                let mut ye = dense(te);
                match phase {
                    Phase::Slipping => {
                        // Momentum-consistent lock (see lockup.rs): the common
                        // speed is the momentum average; the loss is ~0 here
                        // since the slip was located at zero.
                        let w = (self.j1 * ye[0] + self.j2 * ye[1]) / (self.j1 + self.j2);
                        let before = self.kinetic(&ye);
                        let (next, ndir) = self.mode_at_zero_slip(te, w);
                        if next == Phase::Locked {
                            ye[0] = w;
                            ye[1] = w;
                            lock_loss += before - self.kinetic(&ye);
                            if out.lock_time.is_none() {
                                out.lock_time = Some(te);
                                out.lock_speed = Some(w);
                            }
                        }
                        phase = next;
                        dir = ndir;
                    }
                    Phase::Locked => {
                        let tc = self.locked_torque(ye[0]);
                        phase = Phase::Slipping;
                        dir = -tc.signum();
                    }
                }
                out.events.push((te, phase));
                t = te;
                y = ye;
                f0 = self.rhs(phase, dir, t, &y);
                record(&mut out, t, &y, phase, dir, lock_loss);
                continue;
            }
            t = t1;
            y = y1;
            f0 = self.rhs(phase, dir, t, &y);
            record(&mut out, t, &y, phase, dir, lock_loss);
            let grow = if norm == 0.0 {
                5.0
            } else {
                (0.9 * norm.powf(-1.0 / 3.0)).min(5.0)
            };
            h *= grow;
        }
        out.dissipated = y[2];
        out.lock_loss = lock_loss;
        Ok(out)
    }
}

/// A state from a slice of four.
fn state(v: &[f64]) -> State {
    [v[0], v[1], v[2], v[3]]
}

fn refuse(detail: String) -> Error {
    Error::Analysis(AnalysisError::Singular {
        what: "clutch engagement".into(),
        detail,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Engagement {
        Engagement {
            j1: 0.25,
            j2: 1.5,
            speed: [300.0, 120.0],
            t1: 0.0,
            t2: 0.0,
            damping: 0.0,
            law: FrictionLaw::coulomb(0.12),
            capacity: Capacity::Constant(2500.0),
            one_way: false,
            t_end: 2.0,
            rtol: 1e-10,
            atol: 1e-10,
        }
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn constant_capacity_matches_the_closed_forms() {
        // Free inertias: slip falls at C (1/J1 + 1/J2); the lock speed is the
        // momentum average; the loss is ½ J1 J2/(J1+J2) s0².
        let e = base();
        let r = e.simulate().expect("test case is valid");
        let c = 0.12 * 2500.0;
        let s0 = 180.0;
        let t_lock = s0 / (c * (1.0 / e.j1 + 1.0 / e.j2));
        let w = (e.j1 * 300.0 + e.j2 * 120.0) / (e.j1 + e.j2);
        let loss = 0.5 * e.j1 * e.j2 / (e.j1 + e.j2) * s0 * s0;
        assert!(
            rel(r.lock_time.expect("test case is valid"), t_lock) < 1e-9,
            "{r:?}"
        );
        assert!(rel(r.lock_speed.expect("test case is valid"), w) < 1e-9);
        assert!(rel(r.dissipated, loss) < 1e-9);
        assert!(r.lock_loss.abs() < 1e-9 * loss);
        // It stays locked (no torque to break it) and the events say so.
        assert_eq!(r.events.len(), 2);
        assert_eq!(r.events[1].1, Phase::Locked);
        let last = r.samples.last().expect("test case is valid");
        assert!((last.speed[0] - w).abs() < 1e-9 * w);
    }

    #[test]
    fn driven_engagement_matches_its_closed_forms() {
        // Constant drive and load torques: the slip is still linear in time.
        let e = Engagement {
            t1: 80.0,
            t2: -30.0,
            ..base()
        };
        let r = e.simulate().expect("test case is valid");
        let c = 0.12 * 2500.0;
        let rate = (80.0 - c) / e.j1 - (-30.0 + c) / e.j2;
        let t_lock = -180.0 / rate;
        let w = 300.0 + (80.0 - c) / e.j1 * t_lock;
        assert!(rel(r.lock_time.expect("test case is valid"), t_lock) < 1e-9);
        assert!(rel(r.lock_speed.expect("test case is valid"), w) < 1e-9);
        assert!(rel(r.dissipated, 0.5 * c * 180.0 * t_lock) < 1e-9);
        // Locked torque (J1 a - T1) is within the static limit, so it holds.
        assert_eq!(
            r.events.last().expect("test case is valid").1,
            Phase::Locked
        );
    }

    #[test]
    fn ramped_stribeck_run_balances_energy_at_every_step() {
        let e = Engagement {
            t1: 120.0,
            t2: -10.0,
            damping: 0.4,
            law: FrictionLaw {
                mu_static: 0.14,
                mu_kinetic: 0.1,
                decay: Some(5.0),
            },
            capacity: Capacity::Ramp {
                t0: 0.05,
                t1: 0.4,
                from: 0.0,
                to: 4000.0,
            },
            rtol: 1e-8,
            atol: 1e-8,
            ..base()
        };
        let r = e.simulate().expect("test case is valid");
        assert!(r.lock_time.is_some());
        // The residual of W = ΔKE + E_f is an integration error: bounded by
        // the tolerance times the energies moved, not by a fixed epsilon.
        let scale = r.samples.iter().map(|s| s.dissipated).fold(1.0, f64::max);
        for s in &r.samples {
            assert!(s.energy_residual.abs() < 1e-5 * scale, "{s:?}");
        }
        assert!(r.lock_loss >= 0.0);
        // Friction never feeds energy in: dissipation is non-decreasing.
        for w in r.samples.windows(2) {
            assert!(w[1].dissipated >= w[0].dissipated - 1e-12 * scale);
        }
    }

    #[test]
    fn a_falling_capacity_breaks_the_lock_where_torque_meets_the_limit() {
        // Locked from the start with 100 N·m on side 1 and 20 N·m load; the
        // capacity ramps down so the static limit meets the locked torque.
        let e = Engagement {
            speed: [100.0, 100.0],
            t1: 100.0,
            t2: -20.0,
            capacity: Capacity::Ramp {
                t0: 0.0,
                t1: 1.0,
                from: 1000.0,
                to: 0.0,
            },
            ..base()
        };
        let r = e.simulate().expect("test case is valid");
        assert_eq!(r.events[0].1, Phase::Locked);
        let a = 80.0 / (e.j1 + e.j2);
        let tc = (e.j1 * a - 100.0).abs();
        // 0.12 · 1000 (1 - t) = tc.
        let t_break = 1.0 - tc / 120.0;
        assert_eq!(r.events[1].1, Phase::Slipping);
        assert!(rel(r.events[1].0, t_break) < 1e-9, "{:?}", r.events);
        // After the break the driven side runs ahead.
        assert!(r.samples.last().expect("test case is valid").slip > 0.0);
    }

    #[test]
    fn bad_input_is_named() {
        let e = Engagement { j2: 0.0, ..base() };
        assert!(
            e.simulate()
                .expect_err("test case is invalid")
                .to_string()
                .contains("engagement.j2")
        );
        let e = Engagement {
            t1: f64::NAN,
            ..base()
        };
        assert!(
            e.simulate()
                .expect_err("test case is invalid")
                .to_string()
                .contains("engagement.t1")
        );
    }

    #[test]
    fn one_way_locks_in_drive_and_overruns_in_coast() {
        // Drive: equal speeds, engine torque pushes side 1 ahead: it locks
        // and carries J1 a - T1 < 0 on side 1 for the whole run.
        let drive = Engagement {
            speed: [100.0, 100.0],
            t1: 100.0,
            t2: -20.0,
            one_way: true,
            ..base()
        };
        let r = drive.simulate().expect("test case is valid");
        assert_eq!(r.events, vec![(0.0, Phase::Locked)]);
        let a = 80.0 / (drive.j1 + drive.j2);
        for s in &r.samples {
            assert!(s.slip.abs() < 1e-12 * s.speed[0]);
            assert!((s.clutch_torque - (drive.j1 * a - 100.0)).abs() < 1e-9);
        }
        // Coast: engine drag holds side 1 back; the element overruns with no
        // torque, each side decelerating on its own torque.
        let coast = Engagement {
            speed: [100.0, 100.0],
            t1: -30.0,
            t2: -5.0,
            one_way: true,
            ..base()
        };
        let r = coast.simulate().expect("test case is valid");
        assert_eq!(r.events, vec![(0.0, Phase::Slipping)]);
        let last = r.samples.last().expect("samples");
        assert!((last.speed[0] - (100.0 - 30.0 / coast.j1 * last.t)).abs() < 1e-9 * 100.0);
        assert!((last.speed[1] - (100.0 - 5.0 / coast.j2 * last.t)).abs() < 1e-9 * 100.0);
        assert!(
            r.samples
                .iter()
                .all(|s| s.clutch_torque == 0.0 && s.slip <= 0.0)
        );
        assert_eq!(r.dissipated, 0.0);
    }

    #[test]
    fn one_way_engaging_with_side_1_ahead_loses_the_closed_form_energy() {
        // Side 1 ahead by 100 rad/s: the element engages at once by the
        // momentum-consistent jump; KE falls by ½ J1 J2/(J1+J2) Δω², never rises.
        let e = Engagement {
            speed: [200.0, 100.0],
            one_way: true,
            ..base()
        };
        let r = e.simulate().expect("test case is valid");
        let loss = 0.5 * e.j1 * e.j2 / (e.j1 + e.j2) * 100.0f64.powi(2);
        assert!(rel(r.lock_loss, loss) < 1e-12);
        let w = (e.j1 * 200.0 + e.j2 * 100.0) / (e.j1 + e.j2);
        assert!(rel(r.lock_speed.expect("locked"), w) < 1e-12);
        assert!(r.max_energy_residual < 1e-9 * loss);
    }
}
