//! Mesh losses: the direction of rolling power in every lossy mesh, found by
//! one search that every solver uses (the single-scenario power flow in
//! `power.rs` and the prepared, allocation-free path in `prepared.rs`).
//!
//! A lossy mesh of basic efficiency eta loses (1 - eta) of its rolling power
//! (the power in the carrier's frame) in the direction that power flows, so
//! its force row is psi~_m = (1, -tau', tau' - 1) with tau' = eta tau when
//! gear i drives and tau' = tau / eta when gear j drives. The direction
//! depends on the solution: it is found by iteration, falling back to
//! enumeration; when no assignment is consistent the train self-locks.
//!
//! A mesh is *idle* when it rolls but carries no torque. Its multiplier is
//! then zero in exact arithmetic and a few units of round-off in floating
//! point; the sign of that round-off is not a direction of power. The test
//! is relative to the train's own torque scale (the largest applied,
//! driving or mesh torque) and to the condition of the force system, never
//! to the mesh's own multiplier. An idle mesh has no loss and no direction.

use serde::Serialize;

use crate::error::{AnalysisError, Result};

/// Which gear drives a mesh in the carrier's frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Driver {
    /// Gear i gives the rolling power.
    GearI,
    /// Gear j gives the rolling power.
    GearJ,
    /// No rolling power (no relative motion or no load).
    None,
}

/// Relative size under which a rolling speed counts as zero (against the
/// largest link speed).
pub(crate) const ROLLING_ZERO_REL: f64 = 1e-12;
/// Largest number of lossy meshes whose directions are enumerated when iteration fails.
pub(crate) const MAX_ENUMERATED_MESHES: usize = 16;
/// A mesh torque at or below `IDLE_ROUNDING * max(1, condition)` times the
/// train's torque scale is round-off: the mesh is idle.
pub(crate) const IDLE_ROUNDING: f64 = 256.0 * f64::EPSILON;

/// The largest torque a mesh's multiplier puts on one of its three members:
/// |lambda| max(1, |tau|, |tau - 1|) (the row of eq. 2 scaled by lambda).
pub(crate) fn mesh_torque(lambda: f64, tau: f64) -> f64 {
    lambda.abs() * 1f64.max(tau.abs()).max((tau - 1.0).abs())
}

/// A solution of eq. (10) as the direction rule reads it.
pub(crate) trait ForceSolution {
    /// Multiplier of mesh `m`.
    fn multiplier(&self, m: usize) -> f64;
    /// The train's torque scale: the largest applied, driving or mesh torque.
    fn torque_scale(&self) -> f64;
    /// Condition estimate of the force system solved.
    fn condition(&self) -> f64;
}

/// A force solver whose lossy meshes need directions: eq. (10) re-solved for
/// given force ratios.
pub(crate) trait LossySolver: ForceSolution {
    /// Re-solve eq. (10) with the force ratios of `directions` (tau eta when
    /// gear i drives, tau / eta when gear j does, tau when idle).
    ///
    /// # Errors
    /// A singular or refused force system for these ratios.
    fn solve_directions(&mut self, directions: &[Driver]) -> Result<()>;
}

/// The meshes' data for the search: Willis ratios, basic efficiencies and
/// rolling speeds w_j - w_k, with the largest link speed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Meshes<'a> {
    pub ratios: &'a [f64],
    pub efficiency: &'a [f64],
    pub rolling: &'a [f64],
    pub speed_scale: f64,
}

impl Meshes<'_> {
    fn rolls(&self, m: usize) -> bool {
        self.rolling[m].abs() > ROLLING_ZERO_REL * self.speed_scale
    }

    /// Force ratio of mesh `m` when `driver` drives.
    pub(crate) fn force_ratio(&self, m: usize, driver: Driver) -> f64 {
        let (tau, eta) = (self.ratios[m], self.efficiency[m]);
        match driver {
            Driver::GearI => tau * eta,
            Driver::GearJ => tau / eta,
            Driver::None => tau,
        }
    }

    /// The driver the solution in `sys` implies for mesh `m`: gear i drives
    /// when lambda tau (w_j - w_k) > 0; none when the mesh does not roll or
    /// is idle (its torque is round-off against the train's torque scale).
    /// (`tol` is the [`idle_tolerance`] of the solution, computed once per solution.)
    pub(crate) fn implied_at(&self, sys: &impl ForceSolution, m: usize, tol: f64) -> Driver {
        let lam = sys.multiplier(m);
        if !self.rolls(m) || mesh_torque(lam, self.ratios[m]) <= tol {
            Driver::None
        } else if lam * self.ratios[m] * self.rolling[m] > 0.0 {
            Driver::GearI
        } else {
            Driver::GearJ
        }
    }
}

/// The torque below which a mesh of the solution in `sys` is idle.
pub(crate) fn idle_tolerance(sys: &impl ForceSolution) -> f64 {
    IDLE_ROUNDING * sys.condition().max(1.0) * sys.torque_scale()
}

/// Buffers of the search, sized once per train (one per workspace).
#[derive(Debug, Clone)]
pub(crate) struct Directions {
    /// The direction of each mesh in the accepted solution.
    pub dirs: Vec<Driver>,
    next: Vec<Driver>,
    lossy: Vec<usize>,
}

impl Directions {
    /// Buffers for `gears` meshes.
    pub(crate) fn new(gears: usize) -> Self {
        Directions {
            dirs: vec![Driver::None; gears],
            next: vec![Driver::None; gears],
            lossy: Vec::with_capacity(gears),
        }
    }

    /// Find consistent directions, starting from the ideal solution that `sys`
    /// holds on entry; on success `sys` holds the lossy solution for
    /// `self.dirs`. Returns the number of direction iterations (0 when no
    /// mesh is lossy). Allocates nothing.
    ///
    /// # Errors
    /// [`AnalysisError::SelfLocking`] when no assignment of directions is
    /// consistent; [`AnalysisError::DirectionsUndecided`] when iteration does
    /// not settle and too many meshes are lossy to enumerate; the force
    /// system's errors.
    pub(crate) fn settle(
        &mut self,
        sys: &mut impl LossySolver,
        meshes: &Meshes<'_>,
    ) -> Result<usize> {
        let g = meshes.ratios.len();
        self.lossy.clear();
        let tol = idle_tolerance(sys);
        for m in 0..g {
            self.dirs[m] = Driver::None;
            if meshes.efficiency[m] < 1.0 && meshes.implied_at(sys, m, tol) != Driver::None {
                self.lossy.push(m);
            }
        }
        if self.lossy.is_empty() {
            return Ok(0);
        }
        let mut iterations = 0;
        // The solution in `sys` always belongs to `dirs`: it is consistent
        // when the directions it implies are those it was solved with.
        for _ in 0..(2 * self.lossy.len() + 4) {
            iterations += 1;
            let tol = idle_tolerance(sys);
            for m in 0..g {
                self.next[m] = if meshes.efficiency[m] < 1.0 {
                    meshes.implied_at(sys, m, tol)
                } else {
                    Driver::None
                };
            }
            if self.next == self.dirs {
                return Ok(iterations);
            }
            self.dirs.copy_from_slice(&self.next);
            sys.solve_directions(&self.dirs)?;
        }
        self.enumerate(sys, meshes)?;
        Ok(iterations)
    }

    /// Try every assignment of directions to the meshes loaded in the ideal
    /// solution; keep the first consistent one.
    fn enumerate(&mut self, sys: &mut impl LossySolver, meshes: &Meshes<'_>) -> Result<()> {
        let k = self.lossy.len();
        if k > MAX_ENUMERATED_MESHES {
            return Err(AnalysisError::DirectionsUndecided {
                meshes: k,
                limit: MAX_ENUMERATED_MESHES,
            }
            .into());
        }
        for bits in 0..(1u32 << k) {
            self.dirs.iter_mut().for_each(|d| *d = Driver::None);
            for (b, &m) in self.lossy.iter().enumerate() {
                self.dirs[m] = if bits >> b & 1 == 1 {
                    Driver::GearJ
                } else {
                    Driver::GearI
                };
            }
            if sys.solve_directions(&self.dirs).is_err() {
                continue;
            }
            let tol = idle_tolerance(sys);
            let consistent = self.lossy.iter().all(|&m| {
                let d = meshes.implied_at(sys, m, tol);
                d == self.dirs[m] || d == Driver::None
            });
            if consistent {
                return Ok(());
            }
        }
        Err(AnalysisError::SelfLocking.into())
    }
}
