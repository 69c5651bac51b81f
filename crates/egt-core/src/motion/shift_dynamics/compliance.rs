//! An optional compliant output: a torsional shaft (stiffness, damping)
//! between the train's output link and the vehicle inertia, so that the
//! shuffle after a tip-in or a lock-up can be seen. Without it the vehicle
//! inertia sits rigidly on the output link, as before.
//!
//! With the shaft the state gains the vehicle's speed `w_v` and the shaft's
//! twist `phi` (output minus vehicle angle). The shaft carries
//! `T_s = k phi + c (w_out - w_v)`: it loads the output link with `-T_s`
//! and drives the vehicle, `J_v w_v' = T_s - road(w_v)`, `phi' = w_out - w_v`.
//! The energy the balance follows adds `1/2 J_v w_v^2 + 1/2 k phi^2`, and the
//! damper's `c (w_out - w_v)^2` counts as dissipation in the applied work.

use serde::Serialize;

use crate::error::{Error, Result};

/// A compliant shaft from the output link to the vehicle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OutputShaft {
    /// Torsional stiffness (N m/rad), reduced to the output link.
    pub stiffness: f64,
    /// Torsional damping (N m s/rad), reduced to the output link.
    pub damping: f64,
}

impl OutputShaft {
    pub(super) fn validate(&self, vehicle_inertia: f64) -> Result<()> {
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return Err(Error::invalid(
                "shift.output_shaft.stiffness",
                format!("{} must be finite and > 0", self.stiffness),
            ));
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return Err(Error::invalid(
                "shift.output_shaft.damping",
                format!("{} must be finite and >= 0", self.damping),
            ));
        }
        if vehicle_inertia <= 0.0 {
            return Err(Error::invalid(
                "shift.vehicle_inertia",
                "a compliant output shaft drives the vehicle inertia: give it (> 0)",
            ));
        }
        Ok(())
    }

    /// The shaft torque at output speed `w_out`, vehicle speed `w_v` and twist `phi`.
    pub(super) fn torque(&self, w_out: f64, w_v: f64, phi: f64) -> f64 {
        self.stiffness * phi + self.damping * (w_out - w_v)
    }

    /// The twist at which the shaft, turning with the train at one speed,
    /// carries `torque`.
    pub(super) fn twist_for(&self, torque: f64) -> f64 {
        torque / self.stiffness
    }
}
