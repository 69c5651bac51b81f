//! Solving one scenario: speeds (eq. 2), accelerations (eq. 8), multipliers and
//! driving torques (eq. 10), with mesh losses the power-flow directions and the
//! power balance.

use super::*;

impl PreparedTrain {
    /// Solve one scenario into `ws`. Allocates nothing. When the ratios equal
    /// (bitwise) those of the last scenario solved in `ws`, its factorisations
    /// and condition estimates are reused: the results are the same numbers
    /// a fresh workspace gives.
    ///
    /// # Errors
    /// [`AnalysisError::Singular`] or [`AnalysisError::IllConditioned`] (past
    /// \[`COND_REFUSE`\]) for eq. (8) or eq. (10); with losses, no consistent
    /// direction of power flow (self-locking).
    pub fn solve(&self, ws: &mut Workspace, s: &Scenario<'_>, what: Compute) -> Result<()> {
        // The matrices depend on the ratios only: the factorisations (and
        // their condition estimates) of the previous scenario are reused when
        // its ratios were the same.
        if ws.key[..] != s.ratios[..] {
            ws.cache = Cache::default();
            ws.key.copy_from_slice(s.ratios);
        }
        let speeds = what != Compute::Forces;
        if speeds {
            if !ws.cache.kin {
                // Speeds: the Willis equations (eq. 2) completed by the input rows.
                ws.cond[0] = ws.kin.fill_factor(
                    self,
                    s.ratios,
                    0,
                    "the speed system (eq. 2)",
                    "the inputs do not determine the motion",
                )?;
                ws.cache.kin = true;
            }
            self.input_rhs(s.speeds, &mut ws.speed);
            if what == Compute::Kinematics {
                ws.kin.solve(&mut ws.speed);
                self.keep_inputs(s.speeds, &mut ws.speed);
                return Ok(());
            }
        } else {
            ws.speed.iter_mut().for_each(|v| *v = 0.0);
        }
        // Accelerations: eq. (8), the speeds' factorisation when the links are
        // the same; none at all when no acceleration is prescribed.
        let moving = s.accelerations.iter().any(|&a| a != 0.0);
        self.input_rhs(s.accelerations, &mut ws.accel);
        ws.psi = None;
        if self.accel_shared && speeds {
            ws.psi = Some(Psi::Kin);
            ws.psi_cond = ws.cond[0];
            ws.cond[1] = ws.cond[0];
            if moving {
                ws.kin.solve2(&mut ws.speed, &mut ws.accel);
            } else {
                ws.kin.solve(&mut ws.speed);
            }
        } else {
            if speeds {
                ws.kin.solve(&mut ws.speed);
            }
            if moving && !ws.cache.acc {
                ws.psi_cond = ws.acc.fill_factor(
                    self,
                    s.ratios,
                    1,
                    "[Psi_w] (eq. 8)",
                    "the prescribed accelerations do not determine the motion",
                )?;
                ws.cache.acc = true;
            }
            if ws.cache.acc {
                ws.psi = Some(Psi::Acc);
            }
            if moving {
                ws.cond[1] = ws.psi_cond;
                ws.acc.solve(&mut ws.accel);
            } else {
                ws.cond[1] = 1.0;
            }
        }
        // The prescribed accelerations are data: keep them, not their round-off.
        for (&k, &a) in self.accelerated.iter().zip(s.accelerations) {
            ws.accel[k] = a;
        }
        if speeds {
            self.keep_inputs(s.speeds, &mut ws.speed);
        }
        let n = self.n;
        match (&mut ws.m, s.mass_matrix) {
            (Mass::Dense(m), Some(given)) => {
                m.iter_mut().for_each(|v| *v = 0.0);
                for &(r, c, v) in given.entries() {
                    m[r * n + c] = v;
                }
            }
            (Mass::Dense(m), None) => self.mass.fill(s.inertia, s.mass, m),
            (Mass::Terms(t), Some(given)) => {
                t.clear();
                t.extend_from_slice(given.entries());
            }
            (Mass::Terms(t), None) => self.mass.fill_entries(s.inertia, s.mass, t),
        }
        // {Q} - [M]{w'}.
        ws.m.mul_vec(n, &ws.accel, &mut ws.mw);
        for ((r, &q), &mw) in ws.rhs.iter_mut().zip(s.torques).zip(&ws.mw) {
            *r = q - mw;
        }
        ws.tau.copy_from_slice(s.ratios);
        self.solve_forces(ws, true)?;
        if what == Compute::Power {
            self.power(ws, s)?;
        }
        // The check is quadratic (it scans the circuits per coordinate, to
        // allocate nothing): large trains are checked by their tests instead.
        debug_assert!(self.n > 256 || self.residual_of_motion(ws, s) < 1e-8);
        Ok(())
    }

    /// The prescribed input speeds are data: keep them, not the solve's
    /// round-off (75 echoed as 75, not 74.99999999999999), and write no -0.0.
    fn keep_inputs(&self, values: &[f64], speed: &mut [f64]) {
        for (&k, &v) in self.inputs.iter().zip(values) {
            speed[k] = v;
        }
        speed.iter_mut().for_each(|v| *v += 0.0);
    }

    /// Solve eq. (10) with the force ratios in `ws.tau` and the right-hand side
    /// in `ws.rhs`; `ideal` when `ws.tau` equals the kinematic ratios.
    fn solve_forces(&self, ws: &mut Workspace, ideal: bool) -> Result<()> {
        let c = self.constraints();
        ws.x.copy_from_slice(&ws.rhs);
        if ideal
            && self.force_shared
            && let Some(psi) = ws.psi
        {
            // F = D [Psi_w] with D = diag(1, .., 1, -1, .., -1): x = D [Psi_w]^-T r.
            let lu = if psi == Psi::Kin {
                &mut ws.kin
            } else {
                &mut ws.acc
            };
            lu.solve_transpose(&mut ws.x);
            ws.x[c..].iter_mut().for_each(|v| *v = -*v);
            ws.cond[2] = ws.psi_cond;
            return Ok(());
        }
        // The ideal force matrix is cached with the others; a lossy one (its
        // ratios depend on the power-flow directions) never is.
        if !(ideal && ws.cache.force) {
            ws.cache.force = false;
            ws.cond[2] = ws.force.fill_factor(
                self,
                &ws.tau,
                2,
                "the force system (eq. 10)",
                "the driving links cannot balance the loads",
            )?;
            ws.cache.force = ideal;
        }
        ws.force.solve_transpose(&mut ws.x);
        Ok(())
    }

    /// Speed of a link given by its column (the frame is at rest).
    fn w(ws: &Workspace, k: Option<usize>) -> f64 {
        k.map_or(0.0, |k| ws.speed[k])
    }

    /// Mesh losses: the direction of rolling power in every lossy mesh (the
    /// one search of `losses.rs`), then the power balance.
    fn power(&self, ws: &mut Workspace, s: &Scenario<'_>) -> Result<()> {
        let wscale = ws.speed.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (m, cols) in self.circuits.iter().enumerate() {
            ws.rolling[m] = Self::w(ws, cols[1]) - Self::w(ws, cols[2]);
        }
        // The search's buffers leave the workspace while it solves (moving
        // them allocates nothing).
        let mut directions = std::mem::replace(&mut ws.directions, Directions::new(0));
        let rolling = std::mem::take(&mut ws.rolling);
        let meshes = Meshes {
            ratios: s.ratios,
            efficiency: s.efficiency,
            rolling: &rolling,
            speed_scale: wscale,
        };
        let settled = directions.settle(
            &mut LossyScenario {
                plan: self,
                ws,
                meshes,
            },
            &meshes,
        );
        ws.rolling = rolling;
        ws.directions = directions;
        let iterations = settled?;
        // The balance.
        let (mut input, mut output, mut kinetic_rate) = (0.0, 0.0, 0.0);
        let c = self.constraints();
        let n = self.n;
        for k in 0..n {
            let mut torque = s.torques[k];
            if let Some(r) = self.driving.iter().position(|&d| d == k) {
                torque += ws.x[c + r];
            }
            let p = torque * ws.speed[k];
            if p > 0.0 {
                input += p;
            } else {
                output -= p;
            }
            kinetic_rate += ws.mw[k] * ws.speed[k];
        }
        let loss = (0..self.circuits.len())
            .map(|m| ws.x[m] * (s.ratios[m] - ws.tau[m]) * ws.rolling[m])
            .sum();
        ws.power = PowerSummary {
            input,
            output,
            loss,
            kinetic_rate,
            iterations,
        };
        Ok(())
    }

    /// max |M w' + psi~^T lambda - Q - D^T T_d| relative to the largest torque (eq. 6).
    fn residual_of_motion(&self, ws: &Workspace, s: &Scenario<'_>) -> f64 {
        let n = self.n;
        let c = self.constraints();
        let mut worst = 0.0_f64;
        let mut scale = 1e-300_f64;
        for k in 0..n {
            let mut r = ws.mw[k];
            r -= s.torques[k];
            scale = scale.max(s.torques[k].abs());
            for (m, cols) in self.circuits.iter().enumerate() {
                let t = ws.tau[m];
                for (col, v) in cols.iter().zip(willis_row(t)) {
                    if *col == Some(k) {
                        r += v * ws.x[m];
                        scale = scale.max((v * ws.x[m]).abs());
                    }
                }
            }
            for (e, row) in self.extras.iter().enumerate() {
                for &(col, v) in row {
                    if col == Some(k) {
                        r += v * ws.x[self.circuits.len() + e];
                    }
                }
            }
            if let Some(r_d) = self.driving.iter().position(|&d| d == k) {
                r -= ws.x[c + r_d];
                scale = scale.max(ws.x[c + r_d].abs());
            }
            worst = worst.max(r.abs());
        }
        worst / scale
    }
}

/// One scenario's force system as the direction search sees it.
struct LossyScenario<'a, 'b> {
    plan: &'a PreparedTrain,
    ws: &'a mut Workspace,
    meshes: Meshes<'b>,
}

impl LossySolver for LossyScenario<'_, '_> {
    fn solve_directions(&mut self, directions: &[Driver]) -> Result<()> {
        for (m, t) in self.ws.tau.iter_mut().enumerate() {
            *t = self.meshes.force_ratio(m, directions[m]);
        }
        self.plan.solve_forces(self.ws, false)
    }
}

/// The search reads the scenario's current solution as a [`Solved`] one.
impl ForceSolution for LossyScenario<'_, '_> {
    fn multiplier(&self, m: usize) -> f64 {
        self.solved().multiplier(m)
    }
    fn torque_scale(&self) -> f64 {
        self.solved().torque_scale()
    }
    fn condition(&self) -> f64 {
        self.solved().condition()
    }
}

impl LossyScenario<'_, '_> {
    fn solved(&self) -> Solved<'_> {
        Solved {
            plan: self.plan,
            ws: self.ws,
        }
    }
}

/// A solved scenario, read by the direction rule.
struct Solved<'a> {
    plan: &'a PreparedTrain,
    ws: &'a Workspace,
}

impl ForceSolution for Solved<'_> {
    fn multiplier(&self, m: usize) -> f64 {
        self.ws.x[m]
    }
    fn torque_scale(&self) -> f64 {
        self.plan.torque_scale(self.ws)
    }
    fn condition(&self) -> f64 {
        self.ws.cond[2]
    }
}

impl PreparedTrain {
    /// The train's torque scale in a solution: the largest right-hand side of
    /// eq. (10), driving torque or mesh torque.
    fn torque_scale(&self, ws: &Workspace) -> f64 {
        let c = self.constraints();
        let applied = ws.rhs.iter().chain(&ws.x[c..]);
        let meshes = (0..self.circuits.len()).map(|m| mesh_torque(ws.x[m], ws.tau[m]));
        applied.map(|v| v.abs()).chain(meshes).fold(0.0, f64::max)
    }

    /// Which gear drives each mesh in the carrier's frame in the last solution
    /// of `ws` for `s` (none where a mesh does not roll or is idle), by the
    /// rule of the direction search. Needs the rolling speeds of a
    /// [`Compute::Power`] solve.
    pub fn drivers(&self, ws: &Workspace, s: &Scenario<'_>) -> Vec<Driver> {
        let wscale = ws.speed.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let meshes = Meshes {
            ratios: s.ratios,
            efficiency: s.efficiency,
            rolling: &ws.rolling,
            speed_scale: wscale,
        };
        let solved = Solved { plan: self, ws };
        let tol = idle_tolerance(&solved);
        (0..self.circuits.len())
            .map(|m| meshes.implied_at(&solved, m, tol))
            .collect()
    }
}
