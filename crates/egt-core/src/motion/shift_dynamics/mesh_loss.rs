//! Optional mesh losses in a shift (`egt shift-sim --losses`): each gear
//! pair's basic efficiency (the spec's `efficiency`, as `egt power` reads
//! it) acting on the meshing forces of every mode, with the direction rule
//! of `egt power` (`solve/losses.rs`, the one direction search).
//!
//! A lossy mesh keeps its kinematic Willis row `A_m = (1, -tau, tau - 1)`
//! (the speeds still obey eq. 2) but its force row is
//! `A~_m = (1, -tau', tau' - 1)`, `tau' = eta tau` when gear i drives in the
//! carrier's frame and `tau / eta` when gear j does. The motion is
//! `M v' = f + A~^T mu`, `A v = 0`; with `v' = N q'` (`N` the mode's
//! null-space basis) that is the square system `[M N, -A~^T] [q'; mu] = f`
//! (order `n`: the mode's DOF plus its rows), factored once per mode and
//! set of directions. Ideal meshes give `A~ = A`, and the system is the
//! reduced `N^T M N q' = N^T f` with its multipliers.
//!
//! Power: `v^T A~^T mu = sum mu_m (tau - tau'_m) (w_j - w_k)` since
//! `A v = 0`, so `dKE/dt = f.v - P_mesh` with
//! `P_mesh = -sum mu_m (tau - tau'_m) (w_j - w_k) >= 0`, the mesh-loss term
//! of the energy balance (its own state, integrated like the friction work).
//! The multiplier `egt power` reads is `-mu_m`.
//!
//! Directions are part of a mode: found by [`Directions::settle`] at `t = 0`
//! and after every mode change, and kept while each lossy mesh's rolling
//! power `-mu_m tau (w_j - w_k)` keeps its sign. Its zero is an event,
//! located like the others: the mesh's driver flips there (the loss is zero
//! at that instant either way). A lossy mesh that is idle when its mode
//! begins (not rolling, or carrying round-off) has an event too: its power
//! reaching [`IDLE_POWER`] of the train's power scale, where the search
//! gives it its direction (a mesh that starts to roll when an element lets
//! go).

use nalgebra::DVector;

use super::train_mode::{Mode, Setup};
use crate::error::Result;
use crate::model::train::Train;
use crate::numerics::linalg::Lu;
use crate::solve::losses::{
    Directions, Driver, ForceSolution, LossySolver, Meshes, idle_tolerance, mesh_torque,
};

/// The power, relative to the train's (its torque scale times its largest
/// speed when the directions were found), at which an idle lossy mesh is
/// given a direction.
pub(super) const IDLE_POWER: f64 = 1e-9;

/// The train's meshes as the time model needs them: ratio, basic
/// efficiency, and the coordinates of gear j and the carrier (for the
/// rolling speed `w_j - w_k` and the force row's change).
pub(super) struct MeshLosses {
    pub(super) ratios: Vec<f64>,
    pub(super) efficiency: Vec<f64>,
    gear_j: Vec<Option<usize>>,
    carrier: Vec<Option<usize>>,
}

/// A mode's lossy force rows: the directions and the factored square system.
pub(super) struct Lossy {
    /// The driver of each mesh.
    pub(super) drivers: Vec<Driver>,
    /// `tau'` of each mesh under `drivers`.
    force_ratio: Vec<f64>,
    lu: Lu,
    /// [`IDLE_POWER`] times the train's power scale.
    idle_power: f64,
}

impl MeshLosses {
    pub(super) fn new(train: &Train) -> Result<Self> {
        let ratios = train.ratios()?;
        Ok(MeshLosses {
            ratios,
            efficiency: train.gears().iter().map(|g| g.efficiency).collect(),
            gear_j: (train.circuits().iter())
                .map(|c| train.coordinate(c.gear_j))
                .collect(),
            carrier: (train.circuits().iter())
                .map(|c| train.coordinate(c.carrier))
                .collect(),
        })
    }

    /// The rolling speed `w_j - w_k` of every mesh at speeds `v`.
    pub(super) fn rolling(&self, v: &[f64]) -> Vec<f64> {
        let at = |k: Option<usize>| k.map_or(0.0, |k| v[k]);
        (0..self.ratios.len())
            .map(|m| at(self.gear_j[m]) - at(self.carrier[m]))
            .collect()
    }

    fn meshes<'a>(&'a self, rolling: &'a [f64], v: &[f64]) -> Meshes<'a> {
        Meshes {
            ratios: &self.ratios,
            efficiency: &self.efficiency,
            rolling,
            speed_scale: v.iter().fold(0.0f64, |m, x| m.max(x.abs())),
        }
    }

    /// The power the meshes lose at speeds `v` with multipliers `mu`.
    pub(super) fn power(&self, lossy: &Lossy, v: &[f64], mu: &[f64]) -> f64 {
        let rolling = self.rolling(v);
        (0..self.ratios.len())
            .map(|m| -mu[m] * (self.ratios[m] - lossy.force_ratio[m]) * rolling[m])
            .sum()
    }

    /// Event functions of the lossy meshes: each one's rolling power in the
    /// sense of its driver, positive while the driver holds; for an idle
    /// lossy mesh, the idle power less the size of its power (`INFINITY`
    /// for an ideal mesh).
    pub(super) fn events(&self, lossy: &Lossy, v: &[f64], mu: &[f64]) -> Vec<f64> {
        let rolling = self.rolling(v);
        (0..self.ratios.len())
            .map(|m| {
                let p = -mu[m] * self.ratios[m] * rolling[m];
                match lossy.drivers[m] {
                    _ if self.efficiency[m] >= 1.0 => f64::INFINITY,
                    Driver::GearI => p,
                    Driver::GearJ => -p,
                    Driver::None => lossy.idle_power - p.abs(),
                }
            })
            .collect()
    }
}

/// The square system of a mode for given directions, and its solution:
/// what [`Directions::settle`] iterates on.
struct System<'a> {
    setup: &'a Setup<'a>,
    losses: &'a MeshLosses,
    mode: &'a Mode,
    f: &'a DVector<f64>,
    force_ratio: Vec<f64>,
    lu: Lu,
    condition: f64,
    /// `[q'; mu]`.
    x: Vec<f64>,
}

impl<'a> System<'a> {
    fn new(
        setup: &'a Setup<'a>,
        losses: &'a MeshLosses,
        mode: &'a Mode,
        f: &'a DVector<f64>,
    ) -> Result<Self> {
        let n = setup.n;
        let mut s = System {
            setup,
            losses,
            mode,
            f,
            force_ratio: Vec::new(),
            lu: Lu::new(n),
            condition: 1.0,
            x: vec![0.0; n],
        };
        s.solve_directions(&vec![Driver::None; losses.ratios.len()])?;
        Ok(s)
    }
}

impl ForceSolution for System<'_> {
    fn multiplier(&self, m: usize) -> f64 {
        -self.x[self.mode.basis.ncols() + m]
    }

    fn torque_scale(&self) -> f64 {
        let d = self.mode.basis.ncols();
        let ratios = &self.losses.ratios;
        let meshes = (0..ratios.len()).map(|m| mesh_torque(self.x[d + m], ratios[m]));
        let others = self.x[d + ratios.len()..].iter().map(|x| x.abs());
        (self.f.iter().map(|x| x.abs()))
            .chain(meshes)
            .chain(others)
            .fold(0.0, f64::max)
    }

    fn condition(&self) -> f64 {
        self.condition
    }
}

impl LossySolver for System<'_> {
    fn solve_directions(&mut self, directions: &[Driver]) -> Result<()> {
        let losses = self.losses;
        let meshes = Meshes {
            ratios: &losses.ratios,
            efficiency: &losses.efficiency,
            rolling: &[],
            speed_scale: 0.0,
        };
        self.force_ratio = (0..directions.len())
            .map(|m| meshes.force_ratio(m, directions[m]))
            .collect();
        let (n, basis, rows) = (self.setup.n, &self.mode.basis, &self.mode.rows);
        let d = basis.ncols();
        let mn = &self.setup.m * basis;
        let a = self.lu.matrix_mut();
        for i in 0..n {
            for c in 0..d {
                a[i * n + c] = mn[(i, c)];
            }
            for r in 0..rows.nrows() {
                a[i * n + d + r] = -rows[(r, i)];
            }
        }
        // The force rows: tau' for tau at gear j and the carrier.
        for (m, &tp) in self.force_ratio.iter().enumerate() {
            let dt = losses.ratios[m] - tp;
            if let Some(j) = losses.gear_j[m] {
                a[j * n + d + m] -= dt;
            }
            if let Some(k) = losses.carrier[m] {
                a[k * n + d + m] += dt;
            }
        }
        self.condition = self.lu.factor_checked(
            "the lossy equations of motion of a shift mode",
            "the mode's rows are dependent or an inertia is missing",
        )?;
        self.x.copy_from_slice(self.f.as_slice());
        self.lu.solve(&mut self.x);
        Ok(())
    }
}

impl Setup<'_> {
    /// `mode` with its lossy force rows: the directions at time `t`, state
    /// `y` from `prior` when they are consistent there (every lossy mesh's
    /// implied driver is its own, idle ones included, so that a mesh that
    /// stops rolling loses its direction; mesh `flipped` is not checked: it
    /// sits at its zero), else from the one direction search.
    /// Without losses, `mode` as it is.
    ///
    /// # Errors
    /// A singular lossy system; no consistent directions (self-locking).
    pub(super) fn directed(
        &self,
        mut mode: Mode,
        t: f64,
        y: &[f64],
        prior: Option<&[Driver]>,
        flipped: Option<usize>,
    ) -> Result<Mode> {
        let Some(losses) = &self.losses else {
            return Ok(mode);
        };
        let v = &y[..self.n];
        let (f, _) = self.forces(&mode.phases, t, y);
        let rolling = losses.rolling(v);
        let meshes = losses.meshes(&rolling, v);
        let mut sys = System::new(self, losses, &mode, &f)?;
        let mut drivers = None;
        if let Some(prior) = prior {
            sys.solve_directions(prior)?;
            let tol = idle_tolerance(&sys);
            let holds = (0..prior.len()).all(|m| {
                let d = meshes.implied_at(&sys, m, tol);
                flipped == Some(m) || losses.efficiency[m] >= 1.0 || d == prior[m]
            });
            if holds {
                drivers = Some(prior.to_vec());
            } else {
                sys.solve_directions(&vec![Driver::None; prior.len()])?;
            }
        }
        let drivers = match drivers {
            Some(d) => d,
            None => {
                let mut search = Directions::new(losses.ratios.len());
                search.settle(&mut sys, &meshes)?;
                search.dirs
            }
        };
        let idle_power = IDLE_POWER * sys.torque_scale() * meshes.speed_scale;
        let (force_ratio, lu) = (sys.force_ratio, sys.lu);
        mode.lossy = Some(Lossy {
            drivers,
            force_ratio,
            lu,
            idle_power,
        });
        Ok(mode)
    }

    /// The lossy mode's accelerations and multipliers (`mu`, one per row of
    /// the mode) under forces `f`.
    pub(super) fn lossy_solve(
        &self,
        lossy: &Lossy,
        mode: &Mode,
        f: &DVector<f64>,
    ) -> (DVector<f64>, Vec<f64>) {
        let d = mode.basis.ncols();
        let mut x = f.as_slice().to_vec();
        lossy.lu.solve(&mut x);
        let a = &mode.basis * DVector::from_column_slice(&x[..d]);
        (a, x[d..].to_vec())
    }
}

impl Lossy {
    /// The drivers to try after mesh `m`'s event, and the mesh not to
    /// check: a driving mesh's power crossed zero, so its driver flips (it
    /// sits at its zero, unchecked); an idle one's power grew, so it is
    /// checked and gets its direction from the search.
    pub(super) fn after_event(&self, m: usize) -> (Vec<Driver>, Option<usize>) {
        let mut d = self.drivers.clone();
        let flipped = match d[m] {
            Driver::GearI => Driver::GearJ,
            Driver::GearJ => Driver::GearI,
            Driver::None => return (d, None),
        };
        d[m] = flipped;
        (d, Some(m))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::super::shift::tests::{
        APPLY, RELEASE, rel, simpson, upshift, zf, zf_2_3, zf_change,
    };
    use super::super::shift::{ShiftResult, ShiftSim};
    use crate::analysis::dynamics::DynamicsRequest;
    use crate::analysis::power::PowerRequest;
    use crate::analysis::transmission::element_constraint;
    use crate::model::train::Train;
    use crate::solve::kinematics::SpeedInput;

    /// The 8HP 2-3 upshift with losses, a linear road load only and a light
    /// vehicle: it settles in third where the output torque meets the load.
    fn settling() -> ShiftSim {
        ShiftSim {
            road_load: [0.0, 4.0, 0.0],
            vehicle_inertia: 0.5,
            t_end: 12.0,
            losses: true,
            ..zf_2_3()
        }
    }

    /// `egt power` in `state` at the run's last input speed, with the run's
    /// input torque and the output torque unknown (static: no acceleration).
    fn power_of(
        train: &Train,
        state: &str,
        r: &ShiftResult,
        torque: f64,
    ) -> crate::analysis::power::PowerFlow {
        let t = train.checked_transmission().unwrap();
        let gear = t.states.iter().find(|s| s.name == state).unwrap();
        let extras = (gear.engaged.iter())
            .map(|e| element_constraint(&train.elements()[e.index()]))
            .collect();
        let last = r.samples.last().unwrap();
        let req = PowerRequest {
            speeds: vec![SpeedInput {
                link: t.input,
                speed: last.speed[t.input.index()],
                exact: None,
            }],
            dynamics: DynamicsRequest {
                torques: vec![(t.input, torque)],
                accelerations: Vec::new(),
                driving: vec![t.output],
                extras,
            },
            losses: true,
        };
        train.power_flow(&req, None).unwrap()
    }

    #[test]
    fn the_steady_state_after_a_lossy_shift_is_egt_powers_power_flow() {
        let train = zf();
        let sim = settling();
        let r = sim.run(&train).unwrap();
        assert!(r.lock_time.is_some());
        let pf = power_of(&train, "3", &r, 300.0);
        let t = train.checked_transmission().unwrap();
        let (i, o) = (t.input.index(), t.output.index());
        let last = r.samples.last().unwrap();
        // The output torque the load meets is egt power's output torque.
        let t_out = -pf.dynamics.torque[o];
        assert!(
            rel(last.output_torque, t_out) < 1e-7,
            "{} vs {t_out}",
            last.output_torque
        );
        // Every link turns as egt power says (its speeds from the input's).
        for (l, &w) in pf.speeds.speed.iter().enumerate() {
            assert!(
                (last.speed[l] - w).abs() < 1e-9 * last.speed[i].abs(),
                "link {l}"
            );
        }
        // The efficiency: output over input power, against egt power's.
        let eff = last.output_torque * last.speed[o] / (300.0 * last.speed[i]);
        let pf_eff = pf.totals.efficiency.unwrap();
        assert!(pf_eff < 0.999, "{pf_eff}: the meshes lose");
        assert!(rel(eff, pf_eff) < 1e-7, "{eff} vs {pf_eff}");
        // The on-coming clutch C carries egt power's element torque (the
        // element applies minus the multiplier egt power reports).
        let c = r.elements.iter().position(|e| e == "C").unwrap();
        let gear = t.states.iter().find(|s| s.name == "3").unwrap();
        let at = (gear.engaged.iter())
            .position(|e| train.elements()[e.index()].name == "C")
            .unwrap();
        let pf_c = -pf.dynamics.element_torques[at];
        assert!(
            rel(last.element_torque[c], pf_c) < 1e-7,
            "{} vs {pf_c}",
            last.element_torque[c]
        );
        // The loss rate at the end is egt power's loss.
        let n = r.samples.len();
        let (a, b) = (&r.samples[n - 2], &r.samples[n - 1]);
        let rate = (b.mesh_loss.unwrap() - a.mesh_loss.unwrap()) / (b.t - a.t);
        assert!(
            rel(rate, pf.totals.loss) < 1e-6,
            "{rate} vs {}",
            pf.totals.loss
        );
        // Losses cost output: the ideal run ends with more output torque.
        let ideal = ShiftSim {
            losses: false,
            ..settling()
        }
        .run(&train)
        .unwrap();
        assert!(ideal.samples.last().unwrap().output_torque > last.output_torque * 1.001);
        assert!(ideal.mesh_loss.is_none());
    }

    #[test]
    fn the_energy_balance_with_mesh_losses_closes_at_a_tight_tolerance() {
        let train = zf();
        let sim = ShiftSim {
            losses: true,
            rtol: 1e-10,
            atol: 1e-10,
            ..zf_2_3()
        };
        let r = sim.run(&train).unwrap();
        let mesh = r.mesh_loss.unwrap();
        let dissipated = r.dissipated.iter().sum::<f64>() + mesh + r.lock_loss;
        assert!(mesh > 1.0, "{mesh}");
        assert!(
            r.max_energy_residual < 1e-7 * dissipated,
            "{} of {dissipated}",
            r.max_energy_residual
        );
        // The mesh loss never falls.
        let m: Vec<f64> = r.samples.iter().map(|s| s.mesh_loss.unwrap()).collect();
        assert!(m.windows(2).all(|w| w[1] >= w[0]));
        assert!(r.samples.iter().all(|s| s.energy_residual.is_finite()));
    }

    #[test]
    fn losses_on_ideal_meshes_give_the_ideal_run() {
        // The C4 gives its gear pairs no efficiency (1): with the option on,
        // the lossy system is the ideal one and no mesh loses anything.
        let train = simpson();
        let ideal = upshift().run(&train).unwrap();
        let lossy = ShiftSim {
            losses: true,
            ..upshift()
        }
        .run(&train)
        .unwrap();
        assert_eq!(lossy.mesh_loss, Some(0.0));
        assert_eq!(ideal.changes.len(), lossy.changes.len());
        assert!(rel(lossy.lock_time.unwrap(), ideal.lock_time.unwrap()) < 1e-9);
        for (a, b) in lossy.dissipated.iter().zip(&ideal.dissipated) {
            assert!(rel(*a, *b) < 1e-7, "{a} vs {b}");
        }
    }

    #[test]
    fn a_lossy_double_swap_ends_in_fourth_with_its_energy_balanced() {
        // The 8HP 1-4 (A, C off; D, E on) with losses: the kinematics stay
        // the ideal train's, so it ends in fourth's ratio (egt shift).
        let train = zf();
        let sim = ShiftSim {
            losses: true,
            ..zf_change(
                "1",
                "4",
                &[("A", RELEASE), ("C", RELEASE), ("D", APPLY), ("E", APPLY)],
            )
        };
        let r = sim.run(&train).unwrap();
        assert!(r.lock_time.is_some());
        let t = train.checked_transmission().unwrap();
        let last = r.samples.last().unwrap();
        let ratio = last.speed[t.input.index()] / last.speed[t.output.index()];
        let fourth = train.analyse_gear("4").unwrap().ratio;
        assert!(rel(ratio, fourth) < 1e-9, "{ratio} vs {fourth}");
        let mesh = r.mesh_loss.unwrap();
        let dissipated = r.dissipated.iter().sum::<f64>() + mesh;
        assert!(mesh > 0.0);
        assert!(
            r.max_energy_residual < 1e-7 * dissipated,
            "{} of {dissipated}",
            r.max_energy_residual
        );
    }
}
