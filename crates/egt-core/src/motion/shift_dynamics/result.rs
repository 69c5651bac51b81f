//! What a shift run reports: its samples (both sides of every event), mode
//! changes, ranges, energies, lock and rest times, stiffness switch and
//! quality measures ([`super::shift::ShiftSim::run`] fills them).

use serde::Serialize;

use super::quality::ShiftQuality;

/// Where the explicit method's steps became limited by stability.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stiffness {
    /// Time (s).
    pub t: f64,
    /// The explicit step there (s).
    pub h: f64,
    /// The estimated stiffness (largest decay rate, 1/s): the explicit method
    /// needs `h <= 2.5 / rate` whatever the accuracy asked.
    pub rate: f64,
}

/// A mode change.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeChange {
    /// Time (s).
    pub t: f64,
    /// The element that changed.
    pub element: String,
    /// `locked`, `slipping` or `overrunning` (a one-way element).
    pub now: String,
    /// The mode's degrees of freedom after the change.
    pub dof: usize,
}

/// One output sample.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShiftSample {
    /// Time (s).
    pub t: f64,
    /// Speed of every link, by link index (rad/s; 0 for the frame).
    pub speed: Vec<f64>,
    /// Slip of each changing element (`a_e . v`), in the order of
    /// [`ShiftResult::elements`].
    pub slip: Vec<f64>,
    /// Torque of each changing element on its first link.
    pub element_torque: Vec<f64>,
    /// Torque the output shaft delivers to the vehicle: vehicle inertia times
    /// output acceleration plus the road load.
    pub output_torque: f64,
    /// Energy dissipated so far by each changing element (J).
    pub dissipated: Vec<f64>,
    /// `W_applied - dKE - E_friction - E_lock - E_mesh` (J).
    pub energy_residual: f64,
    /// With mesh losses: the energy the meshes lost so far (J).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh_loss: Option<f64>,
    /// Degrees of freedom of the mode.
    pub dof: usize,
    /// Torque of each kept element on its first link (its Lagrange
    /// multiplier), in the order of [`ShiftResult::kept`].
    pub kept_torque: Vec<f64>,
}

/// The result of a shift.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShiftResult {
    /// The elements with a capacity: the off-going ones, the on-coming
    /// ones, then the held ones (the columns of every per-element array).
    pub elements: Vec<String>,
    /// The off-going elements (released: in the old gear, not the new).
    pub off_going: Vec<String>,
    /// The on-coming elements (applied: in the new gear, not the old).
    pub on_coming: Vec<String>,
    /// The elements engaged in both gears and given no capacity: held
    /// rigidly throughout, their torques in [`ShiftSample::kept_torque`].
    pub kept: Vec<String>,
    /// The elements engaged in both gears and given a capacity (`ramps`):
    /// locked while their torque stays within it, slipping (and
    /// dissipating) when it does not, like the changing elements.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub held: Vec<String>,
    /// Samples at every accepted step and on both sides of every mode
    /// change: two samples share the change's time, the first the old mode's
    /// state there (the left limit), the second the new mode's (a change at
    /// `t = 0` has only the second).
    pub samples: Vec<ShiftSample>,
    /// Mode changes in time order.
    pub changes: Vec<ModeChange>,
    /// Time an on-coming element first carries capacity (start of the torque phase).
    pub shift_start: Option<f64>,
    /// Time the on-coming elements are first all locked (end of the inertia phase).
    pub lock_time: Option<f64>,
    /// `lock_time - shift_start`.
    pub shift_time: Option<f64>,
    /// Largest and smallest output torque over the run: over both sides of
    /// every mode change and the turning points between samples.
    pub output_torque_range: [f64; 2],
    /// Largest and smallest torque of each changing element, as
    /// `output_torque_range`.
    pub element_torque_range: Vec<[f64; 2]>,
    /// Largest and smallest slip of each changing element, as
    /// `output_torque_range`.
    pub slip_range: Vec<[f64; 2]>,
    /// Largest and smallest torque of each kept element, as
    /// `output_torque_range`.
    pub kept_torque_range: Vec<[f64; 2]>,
    /// Energy each changing element dissipated (J).
    pub dissipated: Vec<f64>,
    /// When the train came to rest (every link stopped, held by its locked
    /// elements: `rest.rs`), if it did and stayed at rest; `None` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rest_time: Option<f64>,
    /// Energy removed by the lock-up projections (J).
    pub lock_loss: f64,
    /// With mesh losses: the energy the meshes lost (J).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh_loss: Option<f64>,
    /// Largest |energy residual| over the run (J).
    pub max_energy_residual: f64,
    /// Accepted steps.
    pub steps: usize,
    /// The method each part of the run used: `explicit`, `implicit`, or
    /// `explicit, then implicit`.
    pub method: String,
    /// When the explicit steps became limited by stability (a stiff mode),
    /// if they did: with `auto` the run went on implicitly from there; with
    /// `explicit` it kept taking steps of about `h`.
    pub stiff: Option<Stiffness>,
    /// The torque and inertia phases and the shift-quality measures (dip,
    /// overshoot, oscillation after the lock, jerk, steps at events, each
    /// element's energy and peak power), from the samples (`quality.rs`).
    pub quality: ShiftQuality,
}
