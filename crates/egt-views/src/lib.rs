//! # egt-views
//!
//! The named JSON documents of egt's results, built from results computed
//! elsewhere. The `egt` command prints them with `--format json` and the
//! Python module's `to_dict()` returns them, so that a result has one shape
//! whichever front end produced it: `egt kinematics --format json` and
//! `Train.kinematics().to_dict()` give the same document for the same train
//! and inputs (the `source` is the name the spec was read under).
//!
//! Every function only formats: the analysis has been run by the caller.
//! Each analysis's document is one module (its serde structs and `build`);
//! the functions here give it as a JSON value with the `version` field.

pub mod circuits;
pub mod dynamics;
pub mod format;
pub mod kinematics;
pub mod modes;
pub mod power;
pub mod shift;
pub mod simulation;
pub mod stability;

use egt_core::analysis::power::PowerFlow;
use egt_core::model::train::Curve;
use egt_core::motion::simulate::Simulation;
use egt_core::{
    DynamicsRequest, GearAnalysis, InverseDynamics, LinkId, ShiftTable, SpeedInput, Speeds,
    StabilityReport, Train,
};
use serde_json::Value;

/// `egt kinematics --format json`.
///
/// # Errors
/// None in practice (serde cannot fail on the report's types).
pub fn kinematics(
    train: &Train,
    source: &str,
    inputs: &[SpeedInput],
    speeds: &Speeds,
) -> serde_json::Result<Value> {
    format::value_of(&kinematics::build(train, source, inputs, speeds))
}

/// `egt dynamics --format json` (`reduce_to`: the link the equivalent
/// inertia is reduced to; None: the spec's, else the first driving link).
///
/// # Errors
/// None in practice.
pub fn dynamics(
    train: &Train,
    source: &str,
    req: &DynamicsRequest,
    r: &InverseDynamics,
    reduce_to: Option<LinkId>,
) -> serde_json::Result<Value> {
    let reduce_to = reduce_to.or(train.analysis().reduce_to);
    format::value_of(&dynamics::build(train, source, req, r, reduce_to))
}

/// `egt power --format json` (`--ideal` is `losses = false`).
///
/// # Errors
/// None in practice.
pub fn power(
    train: &Train,
    source: &str,
    pf: &PowerFlow,
    losses: bool,
) -> serde_json::Result<Value> {
    format::value_of(&power::build(train, source, pf, losses))
}

/// `egt stability --format json`.
///
/// # Errors
/// None in practice.
pub fn stability(train: &Train, source: &str, rep: &StabilityReport) -> serde_json::Result<Value> {
    format::value_of(&stability::build(train, source, rep))
}

/// `egt modes --format json`.
///
/// # Errors
/// None in practice.
pub fn modes(train: &Train, source: &str, m: &egt_core::NaturalModes) -> serde_json::Result<Value> {
    format::value_of(&modes::build(train, source, m))
}

/// `egt shift --format json`.
///
/// # Errors
/// None in practice.
pub fn shift(train: &Train, source: &str, table: &ShiftTable) -> serde_json::Result<Value> {
    format::value_of(&shift::build(train, source, table))
}

/// `egt simulate --format json` without `--reactions`. `curves`: the
/// torque-speed curves the run used (None when the torques came from
/// elsewhere, e.g. a Python function: then there is no equilibrium).
///
/// # Errors
/// None in practice.
pub fn simulation(
    train: &Train,
    source: &str,
    sim: &Simulation,
    t_end: f64,
    curves: Option<&[Curve]>,
) -> serde_json::Result<Value> {
    let (equilibrium, observed_rate) =
        curves.map_or((None, None), |c| simulation::equilibrium(train, c, sim));
    format::value_of(&simulation::build(
        train,
        source,
        sim,
        t_end,
        equilibrium,
        observed_rate,
        None,
    ))
}

/// One gear state as a row of `egt shift --format json`'s `gears`.
/// `forward`: whether its ratio has the sign most of the states share
/// (`ShiftTable::forward`).
///
/// # Errors
/// None in practice.
pub fn gear(train: &Train, gear: &GearAnalysis, forward: bool) -> serde_json::Result<Value> {
    serde_json::to_value(shift::gear_row(train, gear, forward))
}

/// `egt shift-sim --format json`: the run as it is (it names its links and
/// elements already).
///
/// # Errors
/// None in practice.
pub fn shift_simulation(run: &egt_core::shift_dynamics::ShiftResult) -> serde_json::Result<Value> {
    format::value_of(run)
}
