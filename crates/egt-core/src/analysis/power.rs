//! Power flow through every mesh, circulating power, and the torque balance
//! with mesh losses.
//!
//! Link s spends the torque lambda_m psi~[m, s] on mesh m (eq. 7), so the power
//! it sends into the mesh is lambda_m psi~[m, s] w_s. For an ideal mesh the
//! three members' powers sum to lambda_m psi_m(w) = 0. A lossy mesh of basic
//! efficiency eta loses (1 - eta) of the rolling power, the power in the
//! carrier's frame, in the direction it actually flows. That is modelled by
//! the force row psi~_m = (1, -tau', tau' - 1) with tau' = eta tau when gear i
//! drives in the carrier frame and tau' = tau / eta when gear j drives; the
//! mesh then dissipates lambda_m (tau - tau') (w_j - w_k) >= 0. The drive
//! direction depends on the solution, so it is found by iteration, falling back
//! to enumeration; when no assignment is consistent the train self-locks.

use serde::Serialize;

pub use crate::solve::losses::Driver;

use crate::analysis::dynamics::{DynamicsRequest, InverseDynamics};
use crate::error::Result;
use crate::model::mass::MassMatrix;
use crate::model::train::{GearId, LinkId, Train};
use crate::solve::kinematics::{SpeedInput, Speeds};
use crate::solve::prepared::{Compute, PreparedTrain, Scenario};

/// Power in one mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshPower {
    /// The gear pair.
    pub gear: GearId,
    /// Power sent into the mesh by gear i, gear j and the carrier (absolute frame).
    pub absolute: [f64; 3],
    /// Rolling power: the power the driving gear sends in the carrier's frame.
    pub rolling: f64,
    /// Which gear drives in the carrier's frame.
    pub driver: Driver,
    /// Basic efficiency used.
    pub efficiency: f64,
    /// Power lost in the mesh.
    pub loss: f64,
}

/// Power of one link.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkPower {
    /// The link.
    pub link: LinkId,
    /// Power received from its external torque, Q_l w_l.
    pub external: f64,
    /// Power stored in its inertia, w_l (M w')_l.
    pub inertial: f64,
}

/// A power flow.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PowerFlow {
    /// Speeds of all links.
    pub speeds: Speeds,
    /// The torque solution (with losses, if asked).
    pub dynamics: InverseDynamics,
    /// Per mesh.
    pub meshes: Vec<MeshPower>,
    /// Per link.
    pub links: Vec<LinkPower>,
    /// The balance, efficiency and circulation (their fields stand in this
    /// struct's serde form, as in `egt power --format json`).
    #[serde(flatten)]
    pub totals: PowerTotals,
    /// The meshes and shafts carrying more than the input power, when power circulates.
    pub circulating: Option<(Vec<GearId>, Vec<LinkId>)>,
    /// Direction iterations used (0 for ideal meshes).
    pub iterations: usize,
    /// Notes.
    pub notes: Vec<String>,
}

/// The totals of a power flow: its balance, efficiency and circulation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PowerTotals {
    /// Sum of positive external powers.
    pub input_power: f64,
    /// Minus the sum of negative external powers.
    pub output_power: f64,
    /// Sum of mesh losses.
    pub loss: f64,
    /// dK/dt = w^T M w'.
    pub kinetic_rate: f64,
    /// output / input, when there is input power.
    pub efficiency: Option<f64>,
    /// Largest branch power (a shaft's exchange with one planetary unit or one
    /// fixed-axis mesh) over the input power.
    pub circulation_ratio: f64,
}

/// What a power-flow analysis asks.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PowerRequest {
    /// Input speeds (one per DOF).
    pub speeds: Vec<SpeedInput>,
    /// Loads, accelerations, driving links.
    pub dynamics: DynamicsRequest,
    /// Apply the gear pairs' basic efficiencies.
    pub losses: bool,
}

impl Train {
    /// Speeds under brakes/clutches as well as the Willis equations:
    /// w = [V] w_in with [V] from eq. (23).
    pub(crate) fn constrained_speeds(
        &self,
        inputs: &[SpeedInput],
        extras: &[crate::solve::rows::Extra],
    ) -> Result<Speeds> {
        let links: Vec<LinkId> = inputs.iter().map(|i| i.link).collect();
        let (v, condition) = self.velocity_matrix_cond(&links, extras)?;
        let mut speed = vec![0.0; self.links().len()];
        for (r, l) in self.coordinates().iter().enumerate() {
            speed[l.index()] = inputs
                .iter()
                .enumerate()
                .map(|(c, i)| v[(r, c)] * i.speed)
                .sum();
        }
        let ratios = self.ratios()?;
        let residual = crate::solve::kinematics::willis_residual(self, &ratios, &speed);
        Ok(Speeds {
            known: self.links().iter().map(|l| l.sized).collect(),
            speed,
            exact: None,
            relative: Vec::new(),
            residual,
            condition,
            warnings: Vec::new(),
        })
    }

    /// Power flow at an operating point, ideal or with mesh losses.
    ///
    /// # Errors
    /// As kinematics and inverse dynamics; \[`AnalysisError::SelfLocking`\] when no
    /// consistent direction of power flow exists.
    pub fn power_flow(&self, req: &PowerRequest, mass: Option<&MassMatrix>) -> Result<PowerFlow> {
        // One prepared train and workspace: the speeds (eq. 2) first, then
        // from the same factorisation the accelerations (eq. 8), the forces
        // (eq. 10) and, with losses, the direction search.
        let dyn_req = &req.dynamics;
        let inputs: Vec<LinkId> = req.speeds.iter().map(|i| i.link).collect();
        if dyn_req.extras.is_empty() {
            self.ratios()?;
            self.check_speed_inputs(&inputs)?;
        }
        let accelerated = Self::accelerated_links(dyn_req);
        let plan = PreparedTrain::for_analysis(
            self,
            &inputs,
            &accelerated,
            &dyn_req.driving,
            &dyn_req.extras,
        )?;
        let mut ws = plan.workspace();
        let speeds = if dyn_req.extras.is_empty() {
            self.kinematics_on(&plan, &mut ws, &req.speeds)?
        } else {
            self.constrained_speeds(&req.speeds, &dyn_req.extras)?
        };
        let w = &speeds.speed;
        let taus = self.ratios()?;
        let etas: Vec<f64> = self
            .gears()
            .iter()
            .map(|g| if req.losses { g.efficiency } else { 1.0 })
            .collect();
        let rolling: Vec<f64> = self
            .circuits()
            .iter()
            .map(|c| w[c.gear_j.index()] - w[c.carrier.index()])
            .collect();
        let alpha = Self::prescribed_accelerations(dyn_req)?;
        let (q, velocity) = self.generalized_forces(dyn_req, mass, Some(w))?;
        let input_speeds: Vec<f64> = req.speeds.iter().map(|i| i.speed).collect();
        let scenario = Scenario {
            ratios: &taus,
            speeds: &input_speeds,
            accelerations: &alpha,
            torques: &q,
            inertia: &[],
            mass: &[],
            efficiency: &etas,
            mass_matrix: mass,
        };
        plan.solve(&mut ws, &scenario, Compute::Power)?;
        let dynamics = self.dynamics_result(dyn_req, mass, &plan, &ws, &velocity);
        let dirs = ws.directions().to_vec();
        let tp = ws.force_ratios().to_vec();
        let implied = plan.drivers(&ws, &scenario);
        let iterations = ws.power().iterations;
        let notes: Vec<String> = Vec::new();

        let mut meshes = Vec::with_capacity(taus.len());
        for (m, c) in self.circuits().iter().enumerate() {
            let lam = dynamics.multipliers[m];
            let absolute = [
                lam * w[c.gear_i.index()],
                -tp[m] * lam * w[c.gear_j.index()],
                (tp[m] - 1.0) * lam * w[c.carrier.index()],
            ];
            let driver = if dirs[m] != Driver::None {
                dirs[m]
            } else {
                implied[m]
            };
            let p_i = lam * taus[m] * rolling[m];
            meshes.push(MeshPower {
                gear: GearId::from_index(m),
                absolute,
                rolling: p_i.abs(),
                driver,
                efficiency: etas[m],
                loss: lam * (taus[m] - tp[m]) * rolling[m],
            });
        }

        let mw: Vec<f64> = match mass {
            Some(mm) => {
                let wd: Vec<f64> = self
                    .coordinates()
                    .iter()
                    .map(|l| dynamics.acceleration[l.index()])
                    .collect();
                mm.mul_vec(&wd)
            }
            None => vec![0.0; self.coordinates().len()],
        };
        let mut links = Vec::new();
        let (mut input_power, mut output_power, mut kinetic_rate) = (0.0, 0.0, 0.0);
        for (k, &l) in self.coordinates().iter().enumerate() {
            let external = dynamics.torque[l.index()] * w[l.index()];
            // w (M w' - velocity torques) = dK/dt, with d/dt M when [M] varies.
            let inertial = (mw[k] - dynamics.velocity_torque[l.index()]) * w[l.index()];
            kinetic_rate += inertial;
            if external > 0.0 {
                input_power += external;
            } else {
                output_power -= external;
            }
            links.push(LinkPower {
                link: l,
                external,
                inertial,
            });
        }
        let loss: f64 = meshes.iter().map(|m| m.loss).sum();
        let efficiency = (input_power > 0.0).then(|| efficiency(input_power, loss, kinetic_rate));

        // Branch powers: what each shaft (a link turning about a frame axis)
        // exchanges with each planetary unit. A unit is a set of meshes joined
        // through floating links (planets, and carriers that ride on other
        // carriers): its meshes share bodies whose bearing forces pass power
        // between them. Sets that only share a shaft (a common carrier, sun or
        // ring turning about a frame axis) are distinct units, so power that
        // circulates through that shaft between them is seen.
        let shaft = |l: LinkId| {
            self.tree()
                .parent(l)
                .is_some_and(|(p, _)| p == self.frame())
        };
        let units = self.planetary_units(&shaft);
        let mut circ_ratio: f64 = 0.0;
        let (mut hot_meshes, mut hot_links) = (Vec::new(), Vec::new());
        let threshold = input_power * (1.0 + 1e-9);
        for unit in &units {
            let mut members: Vec<LinkId> = Vec::new();
            for &m in unit {
                let c = &self.circuits()[m];
                for l in [c.gear_i, c.gear_j, c.carrier] {
                    if shaft(l) && !members.contains(&l) {
                        members.push(l);
                    }
                }
            }
            for &l in &members {
                let p: f64 = unit
                    .iter()
                    .map(|&m| {
                        let c = &self.circuits()[m];
                        [c.gear_i, c.gear_j, c.carrier]
                            .iter()
                            .zip(meshes[m].absolute)
                            .filter(|(x, _)| **x == l)
                            .map(|(_, p)| p)
                            .sum::<f64>()
                    })
                    .sum::<f64>()
                    .abs();
                if input_power > 0.0 {
                    circ_ratio = circ_ratio.max(p / input_power);
                    if p > threshold {
                        hot_meshes.extend(
                            unit.iter()
                                .map(|&m| GearId::from_index(m))
                                .filter(|g| !hot_meshes.contains(g))
                                .collect::<Vec<_>>(),
                        );
                        if !hot_links.contains(&l) {
                            hot_links.push(l);
                        }
                    }
                }
            }
        }
        let circulating = (!hot_meshes.is_empty()).then_some((hot_meshes, hot_links));
        crate::error::finite_results(
            "the power flow",
            [input_power, output_power, loss, kinetic_rate]
                .iter()
                .chain(&dynamics.multipliers),
        )?;
        Ok(PowerFlow {
            speeds,
            dynamics,
            meshes,
            links,
            totals: PowerTotals {
                input_power,
                output_power,
                loss,
                kinetic_rate,
                efficiency,
                circulation_ratio: circ_ratio,
            },
            circulating,
            iterations,
            notes,
        })
    }
}

/// Output power over input power, written as 1 - (loss + dK/dt) / input
/// (equal by the power balance): a train that loses nothing and stores
/// nothing has exactly 1, not 1 + round-off, and a high efficiency keeps its
/// digits instead of the difference of two nearly equal powers.
pub fn efficiency(input: f64, loss: f64, kinetic_rate: f64) -> f64 {
    1.0 - (loss + kinetic_rate) / input
}

impl Train {
    /// The meshes grouped into planetary units: two meshes are in one unit
    /// when they share a floating link (neither the frame nor a shaft). A
    /// fixed-axis mesh whose members are all shafts is a unit of its own.
    fn planetary_units(&self, shaft: &impl Fn(LinkId) -> bool) -> Vec<Vec<usize>> {
        let g = self.circuits().len();
        let mut root: Vec<usize> = (0..g).collect();
        fn find(root: &mut [usize], mut m: usize) -> usize {
            while root[m] != m {
                root[m] = root[root[m]];
                m = root[m];
            }
            m
        }
        let mut holder: Vec<Option<usize>> = vec![None; self.links().len()];
        for (m, c) in self.circuits().iter().enumerate() {
            for l in [c.gear_i, c.gear_j, c.carrier] {
                if l == self.frame() || shaft(l) {
                    continue;
                }
                match holder[l.index()] {
                    Some(other) => {
                        let (a, b) = (find(&mut root, m), find(&mut root, other));
                        root[a] = b;
                    }
                    None => holder[l.index()] = Some(m),
                }
            }
        }
        let mut units: Vec<Vec<usize>> = Vec::new();
        let mut unit_of: Vec<Option<usize>> = vec![None; g];
        for m in 0..g {
            let r = find(&mut root, m);
            match unit_of[r] {
                Some(u) => units[u].push(m),
                None => {
                    unit_of[r] = Some(units.len());
                    units.push(vec![m]);
                }
            }
        }
        units
    }
}
