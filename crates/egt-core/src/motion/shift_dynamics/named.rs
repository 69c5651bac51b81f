//! A shift the spec names (`[[shift]]`, `egt shift-sim --shift NAME`) made
//! into a [`ShiftSim`]: the spec's fields, the command line's defaults for
//! those it leaves out, and the integration settings the caller gives.

use super::compliance::OutputShaft;
use super::friction::{Capacity, FrictionLaw};
use super::shift::{DEFAULT_MAX_STEPS, InputTorque, ShiftMethod, ShiftSim};
use crate::error::{Error, Result, suggest};
use crate::model::train::Train;
use crate::spec::CapacitySpec;

/// Friction coefficients `[static, kinetic]` when a shift gives none (a wet clutch).
pub const DEFAULT_MU: [f64; 2] = [0.15, 0.12];
/// End time (s) when a shift gives none.
pub const DEFAULT_T_END: f64 = 1.0;
/// Relative and absolute tolerance of the adaptive steps by default.
pub const DEFAULT_TOLERANCE: f64 = 1e-8;

impl ShiftSim {
    /// The spec's shift `name` (`[[shift]]`), with the default integration
    /// settings ([`DEFAULT_TOLERANCE`], [`ShiftMethod::Auto`],
    /// [`DEFAULT_MAX_STEPS`]); set the fields to change them. The fields
    /// the spec leaves out take `egt shift-sim`'s defaults (no road load or
    /// vehicle inertia, [`DEFAULT_MU`], a step from static to kinetic
    /// friction, [`DEFAULT_T_END`]).
    ///
    /// # Errors
    /// `shift` (invalid) when the spec names no such shift, listing those it
    /// names; the numbers themselves are checked by [`ShiftSim::run`].
    pub fn named(train: &Train, name: &str) -> Result<ShiftSim> {
        let shifts = train.transmission().map_or(&[][..], |t| &t.shifts[..]);
        let Some(s) = shifts.iter().find(|s| s.name == name) else {
            let names: Vec<&str> = shifts.iter().map(|s| s.name.as_str()).collect();
            let hint = suggest(name, names.iter().copied())
                .map(|s| format!(" (did you mean `{s}`?)"))
                .unwrap_or_default();
            return Err(Error::invalid(
                "shift",
                if names.is_empty() {
                    format!("unknown shift `{name}`: the spec has no [[shift]]")
                } else {
                    format!(
                        "unknown shift `{name}`{hint}; the spec's: `{}`",
                        names.join("`, `")
                    )
                },
            ));
        };
        let input_torque = match (&s.torque_table, s.input_torque) {
            (Some(table), None) => InputTorque::Table(table.iter().map(|p| (p[0], p[1])).collect()),
            (None, Some(t)) => InputTorque::Constant(t),
            _ => {
                return Err(Error::invalid(
                    "shift.input_torque",
                    "give exactly one of `input_torque` and `torque_table`",
                ));
            }
        };
        let mu = s.mu.unwrap_or(DEFAULT_MU);
        Ok(ShiftSim {
            from: s.from.clone(),
            to: s.to.clone(),
            input_speed: s.input_speed,
            input_torque,
            road_load: s.road_load.unwrap_or_default(),
            vehicle_inertia: s.vehicle_inertia.unwrap_or_default(),
            law: FrictionLaw {
                mu_static: mu[0],
                mu_kinetic: mu[1],
                decay: s.mu_decay,
            },
            off_going: None,
            on_coming: None,
            ramps: s
                .ramps
                .iter()
                .map(|(element, c)| (element.clone(), capacity(*c)))
                .collect(),
            t_end: s.t_end.unwrap_or(DEFAULT_T_END),
            output_shaft: s.output_shaft.map(|o| OutputShaft {
                stiffness: o.stiffness,
                damping: o.damping,
            }),
            rtol: DEFAULT_TOLERANCE,
            atol: DEFAULT_TOLERANCE,
            method: ShiftMethod::Auto,
            max_steps: DEFAULT_MAX_STEPS,
            losses: s.losses,
        })
    }
}

fn capacity(c: CapacitySpec) -> Capacity {
    match c {
        CapacitySpec::Constant(c) => Capacity::Constant(c),
        CapacitySpec::Ramp([t0, t1, from, to]) => Capacity::Ramp { t0, t1, from, to },
    }
}
