//! One mode of a whole train during a shift: which elements are locked (the
//! changing elements' phases), the mode's matrices (its null-space basis `N`, the Cholesky of `N^T M N`, the
//! rows and their Gram inverse), and what the mode gives at a state: the
//! forces, the accelerations, the locked elements' torques (Lagrange
//! multipliers), the event functions and the lock-up projection.

use nalgebra::{Cholesky, DMatrix, DVector, DVectorView, Dyn};

use super::compliance::OutputShaft;
use super::friction::Capacity;
use super::mesh_loss::{Lossy, MeshLosses};
use super::mode::mode_basis;
use super::shift::ShiftSim;
use crate::error::{AnalysisError, Error, Result};
use crate::model::train::{ElementId, Train};

#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Phase {
    Locked,
    /// Slipping with the sign its slip had when the phase began.
    Slipping(f64),
}

/// One mode: the changing elements' phases and the mode's constant matrices.
pub(super) struct Mode {
    /// The changing elements' phases, which make the mode.
    pub(super) phases: Vec<Phase>,
    pub(super) basis: DMatrix<f64>,
    /// Cholesky of `N^T M N`.
    pub(super) reduced: Cholesky<f64, Dyn>,
    pub(super) rows: DMatrix<f64>,
    /// `(A A^T)^-1 A`: the multipliers are this map of `M v' - f`.
    pub(super) lambda_map: DMatrix<f64>,
    /// Row index of each changing element when locked.
    pub(super) row_of: Vec<Option<usize>>,
    /// Row index of the first kept element (held rigidly, always locked):
    /// they follow the Willis rows, in the order of [`Setup::kept`].
    pub(super) kept_row0: usize,
    /// With mesh losses: the meshes' directions and the lossy system
    /// (`mesh_loss.rs`); `None` for ideal meshes.
    pub(super) lossy: Option<Lossy>,
    /// The row holding the output at rest by the road load's Coulomb term
    /// (`rest.rs`), when the vehicle is parked.
    pub(super) park_row: Option<usize>,
}

pub(super) struct Setup<'a> {
    pub(super) train: &'a Train,
    pub(super) sim: &'a ShiftSim,
    pub(super) m: DMatrix<f64>,
    pub(super) input: usize,
    pub(super) output: usize,
    /// The elements engaged in both gears without a capacity: held rigidly.
    pub(super) kept: Vec<ElementId>,
    /// The elements with a capacity: the off-going ones, the on-coming ones,
    /// then the held ones (engaged in both gears, given a capacity).
    pub(super) elements: Vec<ElementId>,
    pub(super) rows: Vec<DVector<f64>>,
    pub(super) one_way: Vec<bool>,
    pub(super) capacity: Vec<Capacity>,
    pub(super) n: usize,
    /// The meshes' efficiencies when the shift has mesh losses.
    pub(super) losses: Option<MeshLosses>,
    /// A torque the surroundings apply against the output's motion whatever
    /// its direction (N m; a co-simulation unit's load input), added to the
    /// road load; 0 in `run`.
    pub(super) load: f64,
}

impl Setup<'_> {
    /// The number of changing elements (off-going and on-coming).
    pub(super) fn k(&self) -> usize {
        self.elements.len()
    }

    pub(super) fn mode(&self, phases: &[Phase]) -> Result<Mode> {
        self.mode_with(phases, false)
    }

    /// `phases` as a mode of a train at rest: a tie-up (no DOF) is allowed
    /// (`rest.rs`).
    pub(super) fn rest_mode(&self, phases: &[Phase]) -> Result<Mode> {
        self.mode_with(phases, true)
    }

    fn mode_with(&self, phases: &[Phase], rest: bool) -> Result<Mode> {
        let mut locked = self.kept.clone();
        let mut row_of = vec![None; phases.len()];
        let willis = mode_basis(self.train, &[])?.rows.nrows();
        for (i, p) in phases.iter().enumerate() {
            if *p == Phase::Locked {
                row_of[i] = Some(willis + locked.len());
                locked.push(self.elements[i]);
            }
        }
        let mb = mode_basis(self.train, &locked)?;
        // The locked elements, named, for a refusal.
        let listed = || {
            (locked.iter())
                .map(|&e| format!("`{}`", self.train.elements()[e.index()].name))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if mb.dof() == 0 && !rest {
            return Err(refuse(format!(
                "tie-up: with {} locked the train cannot move",
                listed()
            )));
        }
        let basis = mb.basis.clone();
        let reduced = Cholesky::new(basis.transpose() * &self.m * &basis).ok_or_else(|| {
            Error::Analysis(AnalysisError::MissingData {
                what: "inertia on every moving part of the mode".into(),
                analysis: "a shift simulation (the reduced mass matrix is singular)".into(),
                hint: "give `inertia` to the links (and planets) of the gear sets".into(),
            })
        })?;
        let lambda_map = (&mb.rows * mb.rows.transpose())
            .try_inverse()
            .map(|g| g * &mb.rows)
            .ok_or_else(|| {
                refuse(format!(
                    "the rows of the mode with {} locked are dependent (an element that repeats another's constraint), so its torques are not determined",
                    listed()
                ))
            })?;
        Ok(Mode {
            phases: phases.to_vec(),
            basis,
            reduced,
            rows: mb.rows,
            lambda_map,
            row_of,
            kept_row0: willis,
            lossy: None,
            park_row: None,
        })
    }

    /// The applied torques at state `y`: the input torque, and at the
    /// output the road load (or, with a compliant output, the shaft's torque).
    pub(super) fn applied(&self, y: &[f64]) -> DVector<f64> {
        let v = &y[..self.n];
        let mut f = DVector::zeros(self.n);
        f[self.input] += self.sim.input_torque.at(v[self.input]);
        f[self.output] -= match self.shaft_state(y) {
            Some((shaft, w_v, phi)) => shaft.torque(v[self.output], w_v, phi),
            None => self.road(v[self.output]),
        };
        f
    }

    /// With a compliant output: the shaft, the vehicle's speed and the
    /// shaft's twist (the states after the applied work).
    fn shaft_state(&self, y: &[f64]) -> Option<(&OutputShaft, f64, f64)> {
        let at = self.n + self.k() + 1;
        self.sim
            .output_shaft
            .as_ref()
            .map(|shaft| (shaft, y[at], y[at + 1]))
    }

    /// The energy the balance follows: the train's kinetic energy, and with a
    /// compliant output the vehicle's and the shaft's.
    pub(super) fn energy(&self, y: &[f64]) -> f64 {
        let train = self.kinetic(&y[..self.n]);
        match self.shaft_state(y) {
            Some((shaft, w_v, phi)) => {
                train
                    + 0.5 * self.sim.vehicle_inertia * w_v * w_v
                    + 0.5 * shaft.stiffness * phi * phi
            }
            None => train,
        }
    }

    /// The road load at output speed `w`, resisting motion, and the load
    /// torque.
    pub(super) fn road(&self, w: f64) -> f64 {
        let [c0, c1, c2] = self.sim.road_load;
        c0 * w.signum() * f64::from(u8::from(w != 0.0)) + c1 * w + c2 * w * w.abs() + self.load
    }

    pub(super) fn slip(&self, i: usize, v: &[f64]) -> f64 {
        self.rows[i].iter().zip(v).map(|(a, b)| a * b).sum()
    }

    /// Torque of a slipping element on its first link.
    pub(super) fn friction(&self, i: usize, dir: f64, t: f64, v: &[f64]) -> f64 {
        if self.one_way[i] {
            0.0
        } else {
            -dir * self.sim.law.mu(self.slip(i, v)) * self.capacity[i].at(t)
        }
    }

    /// All generalised forces in `phases` at state `y` (applied plus slipping friction).
    pub(super) fn forces(&self, phases: &[Phase], t: f64, y: &[f64]) -> (DVector<f64>, Vec<f64>) {
        let v = &y[..self.n];
        let mut f = self.applied(y);
        let mut tf = vec![0.0; phases.len()];
        for (i, p) in phases.iter().enumerate() {
            if let Phase::Slipping(dir) = *p {
                tf[i] = self.friction(i, dir, t, v);
                f.axpy(tf[i], &self.rows[i], 1.0);
            }
        }
        (f, tf)
    }

    /// The state derivative: speeds, each changing element's dissipation, applied work.
    pub(super) fn rhs(&self, mode: &Mode, t: f64, y: &[f64]) -> Vec<f64> {
        let n = self.n;
        let v = &y[..n];
        let (f, tf) = self.forces(&mode.phases, t, y);
        let mut d = Vec::with_capacity(y.len());
        let mesh = match (&mode.lossy, &self.losses) {
            (Some(lossy), Some(losses)) => {
                let (a, mu) = self.lossy_solve(lossy, mode, &f);
                d.extend_from_slice(a.as_slice());
                Some(losses.power(lossy, v, &mu))
            }
            _ => {
                // v' = N (N^T M N)^-1 N^T f, the reduced solve in place and
                // N q written straight into the derivative (no temporaries
                // but q: this runs at every stage of every step).
                let mut q = mode.basis.tr_mul(&f);
                mode.reduced.solve_mut(&mut q);
                d.extend((0..n).map(|i| {
                    mode.basis
                        .row(i)
                        .iter()
                        .zip(q.iter())
                        .map(|(b, x)| b * x)
                        .sum::<f64>()
                }));
                None
            }
        };
        for (i, t) in tf.iter().enumerate() {
            d.push(-t * self.slip(i, v));
        }
        match self.shaft_state(y) {
            // The applied torques' power: the input's and the road's (as
            // `applied`, without a vector).
            None => d.push(
                self.sim.input_torque.at(v[self.input]) * v[self.input]
                    - self.road(v[self.output]) * v[self.output],
            ),
            Some((shaft, w_v, phi)) => {
                // The input's work, the road's on the vehicle, the damper's loss.
                let w_out = v[self.output];
                let (t_s, road) = (shaft.torque(w_out, w_v, phi), self.road(w_v));
                let slip = w_out - w_v;
                d.push(
                    self.sim.input_torque.at(v[self.input]) * v[self.input]
                        - road * w_v
                        - shaft.damping * slip * slip,
                );
                d.push((t_s - road) / self.sim.vehicle_inertia);
                d.push(slip);
            }
        }
        // the meshes' loss, the last state
        d.extend(mesh);
        d
    }

    /// The index of the mesh-loss energy in the state (the last one), with losses.
    pub(super) fn mesh_at(&self) -> Option<usize> {
        let shaft = if self.sim.output_shaft.is_some() {
            2
        } else {
            0
        };
        self.losses.as_ref().map(|_| self.n + self.k() + 1 + shaft)
    }

    /// The multipliers of `mode` at state `y` with derivative `dy`: one per
    /// row (Willis rows, kept, locked changing elements), in the sign of
    /// `M v' - f = A^T lambda`.
    pub(super) fn multipliers(&self, mode: &Mode, t: f64, y: &[f64], dy: &[f64]) -> Vec<f64> {
        let (f, _) = self.forces(&mode.phases, t, y);
        self.multipliers_of(mode, f, dy)
    }

    /// [`Setup::multipliers`] from the generalised forces `f` at the state.
    fn multipliers_of(&self, mode: &Mode, mut f: DVector<f64>, dy: &[f64]) -> Vec<f64> {
        if let Some(lossy) = &mode.lossy {
            return self.lossy_solve(lossy, mode, &f).1;
        }
        // f <- M v' - f in place, then one product with the mode's map
        f.gemv(
            1.0,
            &self.m,
            &DVectorView::from_slice(&dy[..self.n], self.n),
            -1.0,
        );
        (&mode.lambda_map * f).data.into()
    }

    /// The locked elements' torques on their first links: each changing
    /// element's (`0` where slipping), then each kept element's.
    pub(super) fn locked_torques(
        &self,
        mode: &Mode,
        t: f64,
        y: &[f64],
        dy: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let lambda = self.multipliers(mode, t, y, dy);
        let changing = mode
            .row_of
            .iter()
            .map(|k| k.map_or(0.0, |k| lambda[k]))
            .collect();
        let kept = (0..self.kept.len())
            .map(|j| lambda[mode.kept_row0 + j])
            .collect();
        (changing, kept)
    }

    /// Event functions of the current phases: each crosses zero at a change.
    pub(super) fn events(&self, mode: &Mode, t: f64, y: &[f64], dy: &[f64]) -> Vec<f64> {
        let phases = &mode.phases;
        let (lam, _) = self.locked_torques(mode, t, y, dy);
        let mut g: Vec<f64> = (phases.iter().enumerate())
            .map(|(i, &p)| match p {
                Phase::Slipping(_) => self.element_event(i, p, t, 0.0, self.slip(i, &y[..self.n])),
                Phase::Locked => self.element_event(i, p, t, lam[i], 0.0),
            })
            .collect();
        // With losses, then each mesh's rolling power in its driver's sense.
        if let (Some(lossy), Some(losses)) = (&mode.lossy, &self.losses) {
            let mu = self.multipliers(mode, t, y, dy);
            g.extend(losses.events(lossy, &y[..self.n], &mu));
        }
        // Parked, last: the road load's static margin.
        if let Some(r) = mode.park_row {
            g.push(self.stopping() - self.multipliers(mode, t, y, dy)[r].abs());
        }
        g
    }

    /// [`Setup::events`] from `q`, [`Setup::observe`]'s quantities at the
    /// same point (each element's torque and slip are the ones `events`
    /// computes): no multiplier solve of its own for an ideal mode that is
    /// not parked (the others take `events`).
    pub(super) fn events_observed(
        &self,
        mode: &Mode,
        t: f64,
        y: &[f64],
        dy: &[f64],
        q: &Observed,
    ) -> Vec<f64> {
        if mode.lossy.is_some() || mode.park_row.is_some() {
            return self.events(mode, t, y, dy);
        }
        let k = mode.phases.len();
        (mode.phases.iter().enumerate())
            .map(|(i, &p)| self.element_event(i, p, t, q[1 + i], q[1 + k + i]))
            .collect()
    }

    /// Element `i`'s event function in phase `p` from its torque on its
    /// first link and its slip: the slip in its direction while slipping; a
    /// locked one-way element's torque; a locked element's margin to its
    /// static limit.
    fn element_event(&self, i: usize, p: Phase, t: f64, torque: f64, slip: f64) -> f64 {
        match p {
            Phase::Slipping(dir) => dir * slip,
            Phase::Locked if self.one_way[i] => torque,
            Phase::Locked => self.sim.law.static_limit(self.capacity[i].at(t)) - torque.abs(),
        }
    }

    /// The lock-up: `v` projected onto `mode`'s speeds in the metric of
    /// \[M\] (the speeds a constraint impulse leaves: `M (v+ - v)` lies in the
    /// row space of the mode's rows), and the kinetic energy it removes. The
    /// same map as [`super::lockup::lock_projection`], computed in the mode's
    /// coordinates so that links without inertia do no harm.
    pub(super) fn project(&self, mode: &Mode, v: &[f64]) -> (DVector<f64>, f64) {
        let v = DVector::from_column_slice(v);
        let q = mode
            .reduced
            .solve(&(mode.basis.transpose() * (&self.m * &v)));
        let plus = &mode.basis * q;
        let lost = self.kinetic(v.as_slice()) - self.kinetic(plus.as_slice());
        (plus, lost.max(0.0))
    }

    pub(super) fn kinetic(&self, v: &[f64]) -> f64 {
        let v = DVector::from_column_slice(v);
        0.5 * v.dot(&(&self.m * &v))
    }

    /// What the report follows at a state with derivative `dy`: the output
    /// torque (vehicle inertia times output acceleration plus the road load),
    /// each changing element's torque on its first link (the multiplier where
    /// locked, the friction torque where slipping), then each one's slip,
    /// then each kept element's torque (its multiplier).
    pub(super) fn observe(&self, mode: &Mode, t: f64, y: &[f64], dy: &[f64]) -> Observed {
        let (v, phases) = (&y[..self.n], &mode.phases);
        // One evaluation of the forces serves the multipliers and the
        // slipping elements' torques.
        let (f, friction) = self.forces(phases, t, y);
        let lambda = self.multipliers_of(mode, f, dy);
        let k = phases.len();
        let mut q = Vec::with_capacity(1 + 2 * k + self.kept.len());
        q.push(match (self.shaft_state(y), mode.park_row) {
            (Some((shaft, w_v, phi)), _) => shaft.torque(v[self.output], w_v, phi),
            // Parked: the road load's static reaction holds the vehicle.
            (None, Some(r)) => -lambda[r],
            (None, None) => self.sim.vehicle_inertia * dy[self.output] + self.road(v[self.output]),
        });
        q.extend((0..k).map(|i| match (phases[i], mode.row_of[i]) {
            (Phase::Locked, Some(r)) => lambda[r],
            (Phase::Locked, None) => 0.0,
            (Phase::Slipping(_), _) => friction[i],
        }));
        q.extend((0..k).map(|i| self.slip(i, v)));
        q.extend((0..self.kept.len()).map(|j| lambda[mode.kept_row0 + j]));
        q
    }

    /// An element's name.
    pub(super) fn name(&self, i: usize) -> &str {
        &self.train.elements()[self.elements[i].index()].name
    }
}

/// The quantities a shift report follows, in the order of
/// [`Setup::observe`]: the output torque, the `k` changing elements'
/// torques, their `k` slips, the kept elements' torques.
pub(super) type Observed = Vec<f64>;

pub(super) fn refuse(detail: String) -> Error {
    Error::Analysis(AnalysisError::Singular {
        what: "shift simulation".into(),
        detail,
    })
}
