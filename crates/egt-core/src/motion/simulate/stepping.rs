//! The forward dynamics advanced piece by piece (a co-simulation unit's
//! `fmi2DoStep` for a train without shift elements): the caller applies a
//! torque to each link before each piece, on top of the spec's curves, and
//! [`SimulationStepper::advance`] integrates over `[t, t + h]` with
//! [`ReducedDynamics`]' own fixed-step methods (RK4 or the implicit SDIRK),
//! in as many equal steps of at most `dt` as the piece needs. The prepared
//! model (basis, inertia split, buffers) is made once and kept between pieces.

use super::*;

/// The spec's curves plus a torque per link that the caller sets.
struct Applied<'a> {
    curves: &'a LinearCurves,
    extra: &'a [f64],
}

impl TorqueModel for Applied<'_> {
    fn torques(&self, t: f64, speed: &[f64], torque: &mut [f64]) {
        self.curves.torques(t, speed, torque);
        for (x, e) in torque.iter_mut().zip(self.extra) {
            *x += e;
        }
    }

    fn jacobian(&self, t: f64, speed: &[f64], jac: &mut DMatrix<f64>) {
        self.curves.jacobian(t, speed, jac);
    }
}

/// A train's forward dynamics under its curves and caller-set torques,
/// advanced piece by piece.
#[derive(Debug, Clone)]
pub struct SimulationStepper {
    train: Train,
    curves: LinearCurves,
    /// Always `Some` between calls.
    parts: Option<Parts>,
    mass: MassMatrix,
    x: DVector<f64>,
    speeds: Vec<f64>,
    t: f64,
    work: f64,
    dt: f64,
    method: Method,
    halvings: usize,
}

impl SimulationStepper {
    /// The train at `t = 0` with the `initial` speeds of F independent links
    /// (the rest follow from the Willis equations; massless directions are
    /// moved onto their torque balance under the curves alone), stepping
    /// with `method` in steps of at most `dt`.
    ///
    /// # Errors
    /// `dt` not finite and positive; as [`ReducedDynamics::new`]; initial
    /// speeds that do not determine the train; a failed algebraic solve.
    pub fn new(train: &Train, initial: &[(LinkId, f64)], dt: f64, method: Method) -> Result<Self> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::spec(
                "simulate.dt",
                SpecErrorKind::OutOfRange {
                    value: dt,
                    expected: "must be finite and > 0".into(),
                },
            ));
        }
        let curves = LinearCurves::new(train, &train.analysis().curves)?;
        let zero = vec![0.0; train.links().len()];
        let applied = Applied {
            curves: &curves,
            extra: &zero,
        };
        let mut rd = ReducedDynamics::new(train, &applied)?;
        let w0 = train.speeds_from(initial)?;
        let mut x = rd.p.model.basis.tr_mul(&DVector::from_vec(w0));
        rd.project(0.0, &mut x)?;
        let speeds = (&rd.p.model.basis * &x).iter().copied().collect();
        let parts = rd.into_parts();
        let mass = train.constant_mass_matrix("the stepped simulation")?;
        Ok(SimulationStepper {
            train: train.clone(),
            curves,
            parts: Some(parts),
            mass,
            x,
            speeds,
            t: 0.0,
            work: 0.0,
            dt,
            method,
            halvings: 0,
        })
    }

    /// The time reached (s).
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Every link's speed (rad/s), by link index (the frame's is 0).
    pub fn speeds(&self) -> &[f64] {
        &self.speeds
    }

    /// The work of the applied torques (the curves' and the caller's) since
    /// `t = 0` (J), integrated with the same stages as the state.
    pub fn work(&self) -> f64 {
        self.work
    }

    /// The kinetic energy at the time reached (J).
    pub fn energy(&self) -> f64 {
        self.train.kinetic_energy(&self.mass, &self.speeds)
    }

    /// Implicit steps halved so far because Newton failed.
    pub fn halvings(&self) -> usize {
        self.halvings
    }

    /// Advances from the time reached to `t + h`, with `torques` (one per
    /// link, by link index; the frame's is ignored) added to the curves and
    /// held over the piece. On an error the state is left as it was.
    ///
    /// # Errors
    /// A torque not finite or the wrong count (named by link), `h` not finite
    /// and positive, more than [`MAX_STEPS`] steps, a speed that blows up
    /// (past [`DIVERGED_SPEED`] or not finite), a failed Newton or algebraic
    /// solve.
    pub fn advance(&mut self, torques: &[f64], h: f64) -> Result<()> {
        let links = self.train.links().len();
        if torques.len() != links {
            return Err(Error::invalid(
                "torques",
                format!(
                    "{links} torques expected (one per link), {} given",
                    torques.len()
                ),
            ));
        }
        if let Some((l, v)) = torques.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::invalid(
                format!("{}.torque", self.train.link_name(LinkId::from_index(l))),
                format!("{v} is not finite"),
            ));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::invalid(
                "step",
                format!("{h} must be finite and > 0"),
            ));
        }
        let steps = (h / self.dt - 1e-9).ceil().max(1.0);
        if steps > MAX_STEPS as f64 {
            return Err(Error::invalid(
                "step",
                format!(
                    "{h} s in steps of at most dt = {} s is more than {MAX_STEPS} steps",
                    self.dt
                ),
            ));
        }
        let (steps, sub) = (steps as usize, h / steps);
        let applied = Applied {
            curves: &self.curves,
            extra: torques,
        };
        let parts = self.parts.take().expect("kept between calls");
        let mut rd = ReducedDynamics::from_parts(&self.train, &applied, parts);
        let (mut x, mut t, mut work, mut halvings) = (self.x.clone(), self.t, 0.0, 0);
        let mut done = Ok(());
        for _ in 0..steps {
            let step = match self.method {
                Method::Rk4 => rd.rk4(t, &x, sub),
                Method::Implicit => rd.sdirk(t, &x, sub, 0, &mut halvings),
            };
            let (xn, dw) = match step {
                Ok(s) => s,
                Err(e) => {
                    done = Err(e);
                    break;
                }
            };
            if !xn.iter().all(|v| v.is_finite()) || xn.amax() > DIVERGED_SPEED || !dw.is_finite() {
                done = Err(AnalysisError::NonFinite {
                    what: "the state of the stepped simulation".into(),
                    detail: format!(
                        "a speed exceeded {DIVERGED_SPEED:e} rad/s in the step from t = {t:e} ({}, step {sub:e} s)",
                        self.method
                    ),
                }
                .into());
                break;
            }
            x = xn;
            work += dw;
            t += sub;
        }
        let speeds: Vec<f64> = (&rd.p.model.basis * &x).iter().copied().collect();
        self.parts = Some(rd.into_parts());
        done?;
        self.x = x;
        self.speeds = speeds;
        self.t += h;
        self.work += work;
        self.halvings += halvings;
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::Format;

    /// A motor geared to a flywheel (the module's doctest in `simulate.rs`):
    /// `J = 0.5 + 0.3 / 4` at the motor, a curve of slope -0.8 through
    /// 100 rad/s.
    fn motor() -> Train {
        let spec = r#"
            frame = "0"
            links = [{ name = "m", inertia = 0.5 }, { name = "o", inertia = 0.3 }]
            revolutes = [{ links = ["0", "m"], level = "a" }, { links = ["0", "o"], level = "b" }]
            gears = [{ links = ["m", "o"], ratio = -2.0 }]
            [analysis]
            curves = [{ link = "m", torque = 0.0, slope = -0.8, speed = 100.0 }]
        "#;
        Train::from_str(spec, Format::Toml, "motor").unwrap()
    }

    #[test]
    fn a_held_torque_moves_the_steady_speed_as_the_closed_form_says() {
        // J w' = -0.8 (w - 100) + T: w(t) = w_ss + (w0 - w_ss) e^(lambda t),
        // w_ss = 100 + T / 0.8, lambda = -0.8 / J.
        let train = motor();
        let m = train.link_id("m").unwrap();
        let o = train.link_id("o").unwrap();
        for method in [Method::Rk4, Method::Implicit] {
            let mut s = SimulationStepper::new(&train, &[(m, 101.0)], 1e-4, method).unwrap();
            let mut torques = vec![0.0; 3];
            torques[m.index()] = 2.0;
            for _ in 0..100 {
                s.advance(&torques, 1e-2).unwrap();
            }
            let j: f64 = 0.5 + 0.3 / 4.0;
            let (w_ss, lambda) = (100.0 + 2.0 / 0.8, -0.8 / j);
            let exact = w_ss + (101.0 - w_ss) * lambda.exp();
            let tol = if method == Method::Rk4 { 1e-11 } else { 1e-7 };
            let w = s.speeds()[m.index()];
            assert!((w - exact).abs() < tol, "{method}: {w} vs {exact}");
            assert!((s.time() - 1.0).abs() < 1e-12);
            // The flywheel turns at -1/2 the motor's speed (Willis).
            assert!((s.speeds()[o.index()] + 0.5 * w).abs() < 1e-12 * w);
            // Energy balance: E(1) - E(0) is the applied torques' work.
            let e0 = 0.5 * j * 101.0 * 101.0;
            assert!((s.energy() - e0 - s.work()).abs() < 1e-6 * e0, "{method}");
        }
    }

    #[test]
    fn pieces_of_a_fixed_step_simulation_are_the_whole_simulation() {
        let train = motor();
        let m = train.link_id("m").unwrap();
        let req = SimulationRequest {
            initial: vec![(m, 101.0)],
            options: SimulationOptions {
                t_end: 0.5,
                dt: 1e-3,
                method: Method::Rk4,
                every: 1,
            },
        };
        let whole = train.simulate(&req).unwrap();
        let mut s = SimulationStepper::new(&train, &[(m, 101.0)], 1e-3, Method::Rk4).unwrap();
        for _ in 0..50 {
            s.advance(&[0.0; 3], 1e-2).unwrap();
        }
        let last = whole.samples.last().unwrap();
        assert!((s.speeds()[m.index()] - last.speed[m.index()]).abs() < 1e-12 * 101.0);
        assert!((s.work() - last.work).abs() < 1e-9 * last.work.abs().max(1.0));
    }

    #[test]
    fn bad_torques_and_steps_are_named_and_leave_the_state() {
        let train = motor();
        let m = train.link_id("m").unwrap();
        let mut s = SimulationStepper::new(&train, &[(m, 101.0)], 1e-3, Method::Rk4).unwrap();
        let mut nan = vec![0.0; 3];
        nan[m.index()] = f64::NAN;
        let e = s.advance(&nan, 1e-3).unwrap_err().to_string();
        assert!(e.contains("m.torque"), "{e}");
        let e = s.advance(&[0.0; 2], 1e-3).unwrap_err().to_string();
        assert!(e.contains("3 torques expected"), "{e}");
        let e = s.advance(&[0.0; 3], -1.0).unwrap_err().to_string();
        assert!(e.contains("step"), "{e}");
        assert!(SimulationStepper::new(&train, &[(m, 1.0)], 0.0, Method::Rk4).is_err());
        // A torque that blows the speed up past DIVERGED_SPEED is refused
        // and the state stays.
        let w0 = s.speeds()[m.index()];
        assert!((w0 - 101.0).abs() < 1e-12);
        let mut huge = vec![0.0; 3];
        huge[m.index()] = 1e300;
        let e = s.advance(&huge, 1.0).unwrap_err().to_string();
        assert!(e.contains("exceeded"), "{e}");
        assert_eq!((s.time(), s.speeds()[m.index()]), (0.0, w0));
    }
}
