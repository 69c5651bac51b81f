//! Shift dynamics (issue 14): the pieces of a gear-change simulation with
//! friction elements that slip, stick and lock.
//!
//! - [`friction`]: the friction law of a clutch or brake (Coulomb, static >
//!   kinetic, optional speed-dependent coefficient) times a capacity that is a
//!   function of time (a pressure ramp).
//! - [`lockup`]: the momentum-consistent projection applied when an element
//!   locks (kinetic energy never rises).
//! - [`engagement`]: a clutch joining two inertias, integrated with event
//!   location of the slip-speed zero crossing on the step's dense output; the
//!   reference case whose slip time, lock-up speed and dissipated energy have
//!   closed forms.
//!
//! - [`mode`]: the reduced coordinates of a mode, the null space of the Willis
//!   rows plus the locked-element rows (a gear: 1 DOF; mid-shift: 2).
//!
//! - [`shift`]: a whole train's gear change (`egt shift-sim`): the off-going
//!   element releases, the on-coming one slips and locks, one-way elements
//!   overrun and engage; modes of [`mode`], events located on the dense
//!   output of [`ode`], lock-ups by momentum-consistent projection. Private
//!   pieces: `request` (the shift asked for, checked: numbers, budgets,
//!   each changing element's ramp), `train_mode` (one mode of the train: forces, multipliers,
//!   events), `consistent` (the consistent mode at `t = 0` and after every
//!   event: release what cannot hold, lock what can), `extremes` (the
//!   reported ranges, over both sides of every event and between samples)
//!   `named` (a spec's `[[shift]]` made into a [`ShiftSim`]), `compliance`
//!   (an optional compliant output shaft to the vehicle, [`OutputShaft`]),
//!   `mesh_loss` (optional mesh losses: the gear pairs' efficiencies on
//!   each mode's meshing forces with `egt power`'s direction rule, the loss
//!   in the energy balance) and `rest` (a train braked to a standstill
//!   rests, held by its elements or parked by the road load, instead of
//!   being refused as a tie-up).
//! - [`stepping`]: the same model advanced piece by piece over `[t, t + h]`
//!   with capacities set by the caller ([`ShiftStepper`], the FMU's step).
//! - [`quality`]: the torque and inertia phases of a finished shift and its
//!   quality measures (output-torque dip and overshoot, oscillation after the
//!   lock, jerk, steps at events, each element's energy and peak power),
//!   read from the samples.
//!
//! Not built yet: a vehicle parked behind a compliant output shaft, and a
//! stop of the output while other links still move (two DOF or more). See
//! docs/shift_dynamics.md.

mod compliance;
mod consistent;
pub mod engagement;
mod extremes;
pub mod friction;
pub mod lockup;
mod mesh_loss;
pub mod mode;
mod named;
pub mod ode;
pub mod quality;
mod request;
mod rest;
mod result;
pub mod shift;
pub mod stepping;
mod train_mode;

pub use compliance::OutputShaft;
pub use engagement::{Engagement, EngagementResult, EngagementSample, Phase};
pub use friction::{Capacity, FrictionLaw};
pub use lockup::{LockUp, lock_projection};
pub use mode::{ModeBasis, mode_basis};
pub use named::{DEFAULT_MU, DEFAULT_T_END, DEFAULT_TOLERANCE};
pub use quality::{AtTime, ElementQuality, ShiftQuality};
pub use shift::{
    DEFAULT_MAX_STEPS, InputTorque, MAX_STEP, MIN_RTOL, ModeChange, ShiftMethod, ShiftResult,
    ShiftSample, ShiftSim, Stiffness,
};
pub use stepping::{ShiftStepper, StepInputs};
