//! The integrators' loop: fixed steps of `rk4` or the implicit SDIRK method
//! (with step halving), sampling, and the energy and drift measured.

use super::*;

impl ReducedDynamics<'_> {
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
        let mut x = self.p.model.basis.tr_mul(&DVector::from_vec(w0));
        let mut warnings = self.p.model.warnings.clone();
        if self.p.split.nearly_massless {
            warnings.push("a direction is nearly massless: the model is stiff".into());
        }
        if self.p.split.r < self.p.model.dof() {
            let before = x.clone();
            self.project(0.0, &mut x)?;
            if (&x - &before).amax() > 1e-12 * before.amax().max(1.0) {
                warnings.push(format!(
                    "{} massless direction(s): the initial speeds were moved onto their torque balance",
                    self.p.model.dof() - self.p.split.r
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
        let speed: Vec<f64> = (&self.p.model.basis * x).iter().copied().collect();
        Sample {
            t,
            drift: willis_residual(self.train, &self.p.ratios, &speed),
            energy: self.train.kinetic_energy(mass, &speed),
            speed,
            work,
            power,
        }
    }

    /// One classical RK4 step; returns the new state and the work increment.
    pub(super) fn rk4(&mut self, t: f64, x: &DVector<f64>, h: f64) -> Result<(DVector<f64>, f64)> {
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
    pub(super) fn sdirk(
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
        let f = self.p.model.dof();
        let m = self.p.model.basis_mass.clone();
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
