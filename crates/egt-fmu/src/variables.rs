//! The unit's variables, made from a transmission spec once: their names (the
//! spec's link and element names), value references, causalities, units and
//! start values. The model description lists them and an instance reads and
//! writes its values by them, so the two cannot disagree.

use egt_core::Train;
use egt_core::shift_dynamics::{DEFAULT_MU, DEFAULT_TOLERANCE};

/// The capacity an element of the initial gear starts with when the importer
/// sets none (N m per unit friction coefficient): far above any torque the
/// bundled transmissions carry, so the default unit holds its first gear.
pub const HELD_CAPACITY: f64 = 1e5;

/// The input speed a unit starts at by default (rad/s).
pub const DEFAULT_INPUT_SPEED: f64 = 100.0;

/// What a real variable is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Input speed at `t = 0` (rad/s).
    InitialSpeed,
    /// Static friction coefficient.
    MuStatic,
    /// Kinetic friction coefficient.
    MuKinetic,
    /// Road load `c0`, `c1`, `c2`.
    RoadLoad(usize),
    /// Vehicle inertia at the output (kg m^2).
    VehicleInertia,
    /// Relative tolerance of the integrator.
    Rtol,
    /// Absolute tolerance of the integrator.
    Atol,
    /// The torque on the input link (input).
    InputTorque,
    /// An element's capacity (input).
    Capacity(usize),
    /// A moving link's speed: its coordinate index (output).
    Speed(usize),
    /// The output torque to the vehicle (output).
    OutputTorque,
    /// An element's slip speed (output).
    Slip(usize),
    /// An element's torque on its first link (output).
    ElementTorque(usize),
    /// The energy an element has dissipated (output).
    Energy(usize),
    /// The last time an element locked, -1 before any (output).
    LockTime(usize),
}

/// FMI causality.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialisation.
    Parameter,
    /// Set by the importer before every step.
    Input,
    /// Read by the importer.
    Output,
}

/// One real variable.
#[derive(Debug, Clone, PartialEq)]
pub struct RealVariable {
    /// Its name in the model description.
    pub name: String,
    /// What it is.
    pub role: Role,
    /// Parameter, input or output.
    pub causality: Causality,
    /// Its unit (declared in the model description), if it has one.
    pub unit: Option<&'static str>,
    /// Its start value (parameters and inputs).
    pub start: Option<f64>,
    /// One line for the model description.
    pub description: String,
}

/// The unit's variables. Reals have value references `0..reals.len()`;
/// the two integers are [`INITIAL_GEAR`] and [`LOCKED_ELEMENTS`].
#[derive(Debug, Clone, PartialEq)]
pub struct Variables {
    /// Every real, its value reference its index.
    pub reals: Vec<RealVariable>,
    /// The gear states, for `initial_gear` (1-based).
    pub gears: Vec<String>,
    /// The shift elements, in the spec's order.
    pub elements: Vec<String>,
}

/// Value reference of the integer parameter `initial_gear`.
pub const INITIAL_GEAR: u32 = 0;
/// Value reference of the integer output `locked_elements`.
pub const LOCKED_ELEMENTS: u32 = 1;

/// Why a spec cannot be a unit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NotAUnit(pub String);

impl std::fmt::Display for NotAUnit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for NotAUnit {}

impl Variables {
    /// The variables of a transmission (a spec with shift elements and gear
    /// states).
    ///
    /// # Errors
    /// A spec without a transmission, or two variables with one name (an
    /// element named like a link).
    pub fn of(train: &Train) -> Result<Variables, NotAUnit> {
        let t = train
            .checked_transmission()
            .map_err(|e| NotAUnit(format!("an FMU needs a transmission: {e}")))?;
        let link = |l: egt_core::LinkId| train.link(l).name.clone();
        let (input, output) = (link(t.input), link(t.output));
        let elements: Vec<String> = train.elements().iter().map(|e| e.name.clone()).collect();
        let first = &t.states[0];
        let param = |name: &str, role, unit, start: f64, description: &str| RealVariable {
            name: name.into(),
            role,
            causality: Causality::Parameter,
            unit,
            start: Some(start),
            description: description.into(),
        };
        let mut reals = vec![
            param(
                "initial_input_speed",
                Role::InitialSpeed,
                Some("rad/s"),
                DEFAULT_INPUT_SPEED,
                "input speed at the start, in the initial gear's steady motion",
            ),
            param(
                "mu_static",
                Role::MuStatic,
                None,
                DEFAULT_MU[0],
                "static friction coefficient of every element",
            ),
            param(
                "mu_kinetic",
                Role::MuKinetic,
                None,
                DEFAULT_MU[1],
                "kinetic friction coefficient of every element",
            ),
        ];
        for (i, unit) in [(0, "N.m"), (1, "N.m.s/rad"), (2, "N.m.s2/rad2")] {
            reals.push(param(
                &format!("road_load_c{i}"),
                Role::RoadLoad(i),
                Some(unit),
                0.0,
                "road load at the output: c0 sgn(w) + c1 w + c2 w |w|",
            ));
        }
        reals.extend([
            param(
                "vehicle_inertia",
                Role::VehicleInertia,
                Some("kg.m2"),
                0.0,
                "vehicle inertia reflected to the output link",
            ),
            param(
                "rtol",
                Role::Rtol,
                None,
                DEFAULT_TOLERANCE,
                "relative tolerance of egt's integrator",
            ),
            param(
                "atol",
                Role::Atol,
                None,
                DEFAULT_TOLERANCE,
                "absolute tolerance of egt's integrator",
            ),
        ]);
        reals.push(RealVariable {
            name: format!("{input}.torque"),
            role: Role::InputTorque,
            causality: Causality::Input,
            unit: Some("N.m"),
            start: Some(0.0),
            description: format!("torque applied to `{input}` (held over a step)"),
        });
        for (i, e) in elements.iter().enumerate() {
            let engaged = first.engaged.iter().any(|x| x.index() == i);
            reals.push(RealVariable {
                name: format!("{e}.capacity"),
                role: Role::Capacity(i),
                causality: Causality::Input,
                unit: Some("N.m"),
                start: Some(if engaged { HELD_CAPACITY } else { 0.0 }),
                description: format!(
                    "capacity of `{e}` per unit friction coefficient (torque limit mu C), >= 0"
                ),
            });
        }
        let out = |name: String, role, unit, description: String| RealVariable {
            name,
            role,
            causality: Causality::Output,
            unit,
            start: None,
            description,
        };
        for (c, &l) in train.coordinates().iter().enumerate() {
            let name = link(l);
            reals.push(out(
                format!("{name}.speed"),
                Role::Speed(c),
                Some("rad/s"),
                format!("speed of `{name}`"),
            ));
        }
        reals.push(out(
            format!("{output}.torque"),
            Role::OutputTorque,
            Some("N.m"),
            format!("torque `{output}` delivers to the vehicle"),
        ));
        for (i, e) in elements.iter().enumerate() {
            reals.extend([
                out(
                    format!("{e}.slip"),
                    Role::Slip(i),
                    Some("rad/s"),
                    format!("slip speed of `{e}`"),
                ),
                out(
                    format!("{e}.torque"),
                    Role::ElementTorque(i),
                    Some("N.m"),
                    format!("torque of `{e}` on its first link"),
                ),
                out(
                    format!("{e}.energy"),
                    Role::Energy(i),
                    Some("J"),
                    format!("energy `{e}` has dissipated"),
                ),
                out(
                    format!("{e}.lock_time"),
                    Role::LockTime(i),
                    Some("s"),
                    format!("the last time `{e}` locked (-1 before any)"),
                ),
            ]);
        }
        let mut names: Vec<&str> = reals.iter().map(|r| r.name.as_str()).collect();
        names.extend(["initial_gear", "locked_elements"]);
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(NotAUnit(format!(
                "two variables are named `{}` (an element named like a link?)",
                w[0]
            )));
        }
        Ok(Variables {
            reals,
            gears: t.states.iter().map(|s| s.name.clone()).collect(),
            elements,
        })
    }

    /// The value reference of the real with `role`.
    pub fn real(&self, role: Role) -> Option<u32> {
        (self.reals.iter().position(|r| r.role == role)).and_then(|i| u32::try_from(i).ok())
    }
}
