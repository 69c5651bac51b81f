//! The unit's variables, made from a spec once (a transmission's, or a
//! train's without shift elements): their names (the spec's link and element
//! names), value references, causalities, units and start values. The model
//! description lists them and an instance reads and writes its values by
//! them, so the two cannot disagree.

use egt_core::shift_dynamics::{DEFAULT_MU, DEFAULT_TOLERANCE};
use egt_core::{LinkId, Train};

/// The capacity an element of the initial gear starts with when the importer
/// sets none (N m per unit friction coefficient): far above any torque the
/// bundled transmissions carry, so the default unit holds its first gear.
pub const HELD_CAPACITY: f64 = 1e5;

/// The input speed a unit starts at by default (rad/s).
pub const DEFAULT_INPUT_SPEED: f64 = 100.0;

/// A train's largest integration step when its spec gives neither `dt` nor
/// `t_end` (s).
pub const DEFAULT_DT: f64 = 1e-4;

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
    /// The torque the surroundings apply against the output (input).
    LoadTorque,
    /// A link's speed at `t = 0`, by link index (a train's parameter).
    InitialLinkSpeed(usize),
    /// The largest integration step (a train's parameter, s).
    Dt,
    /// The torque applied to a link, by link index (a train's input).
    LinkTorque(usize),
    /// A link's speed, by link index (a train's output).
    LinkSpeed(usize),
    /// The applied torques' work since `t = 0` (a train's output, J).
    Work,
    /// The kinetic energy (a train's output, J).
    KineticEnergy,
}

/// What a unit simulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A transmission's shift dynamics (`ShiftStepper`).
    Transmission,
    /// A train without shift elements under its curves and applied torques
    /// (`SimulationStepper`).
    Train,
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
/// a transmission's two integers are [`INITIAL_GEAR`] and
/// [`LOCKED_ELEMENTS`] (a train has none).
#[derive(Debug, Clone, PartialEq)]
pub struct Variables {
    /// What the unit simulates.
    pub kind: Kind,
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
    /// states), or of a train without shift elements ([`Kind::Train`]).
    ///
    /// # Errors
    /// Shift elements without a valid transmission, or two variables with
    /// one name (an element named like a link).
    pub fn of(train: &Train) -> Result<Variables, NotAUnit> {
        if train.transmission().is_none() && train.elements().is_empty() {
            return Variables::of_train(train);
        }
        let t = train.checked_transmission().map_err(|e| {
            NotAUnit(format!(
                "a spec with shift elements is a unit as a transmission: {e}"
            ))
        })?;
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
        reals.push(RealVariable {
            name: format!("{output}.load_torque"),
            role: Role::LoadTorque,
            causality: Causality::Input,
            unit: Some("N.m"),
            start: Some(0.0),
            description: format!(
                "torque against `{output}`'s motion whatever its direction, on top of the road load (held over a step)"
            ),
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
        distinct(&reals, &["initial_gear", "locked_elements"])?;
        Ok(Variables {
            kind: Kind::Transmission,
            reals,
            gears: t.states.iter().map(|s| s.name.clone()).collect(),
            elements,
        })
    }

    /// The variables of a train without shift elements: the initial speeds
    /// of its independent links (the spec's `[analysis.simulate] initial`,
    /// else its `speeds`, else its automatic coordinates at rest) and the
    /// step as parameters, a torque on every moving link as inputs (on top
    /// of the spec's curves), every moving link's speed, the work and the
    /// kinetic energy as outputs.
    fn of_train(train: &Train) -> Result<Variables, NotAUnit> {
        let refuse = |e: egt_core::Error| NotAUnit(format!("the train cannot be a unit: {e}"));
        // A unit that could not step is refused now, not at initialisation.
        let curves =
            egt_core::LinearCurves::new(train, &train.analysis().curves).map_err(refuse)?;
        egt_core::ReducedDynamics::new(train, &curves).map_err(refuse)?;
        let name = |l: LinkId| train.link(l).name.clone();
        let sim = train.analysis().simulate.clone().unwrap_or_default();
        let initial: Vec<(LinkId, f64)> = if !sim.initial.is_empty() {
            sim.initial.clone()
        } else if !train.analysis().speeds.is_empty() {
            train.analysis().speeds.iter().map(|s| (s.0, s.1)).collect()
        } else {
            let links = train.automatic_coordinates().map_err(refuse)?;
            links.into_iter().map(|l| (l, 0.0)).collect()
        };
        let dt = sim
            .dt
            .or(sim.t_end.map(|t| t / 1000.0))
            .unwrap_or(DEFAULT_DT);
        let mut reals: Vec<RealVariable> = initial
            .iter()
            .map(|&(l, w)| RealVariable {
                name: format!("{}.initial_speed", name(l)),
                role: Role::InitialLinkSpeed(l.index()),
                causality: Causality::Parameter,
                unit: Some("rad/s"),
                start: Some(w),
                description: format!("speed of `{}` at the start", name(l)),
            })
            .collect();
        reals.push(RealVariable {
            name: "dt".into(),
            role: Role::Dt,
            causality: Causality::Parameter,
            unit: Some("s"),
            start: Some(dt),
            description: "the largest integration step (a communication step is cut into equal steps no longer)".into(),
        });
        let moving: Vec<LinkId> = (0..train.links().len())
            .map(LinkId::from_index)
            .filter(|&l| l != train.frame())
            .collect();
        for &l in &moving {
            reals.push(RealVariable {
                name: format!("{}.torque", name(l)),
                role: Role::LinkTorque(l.index()),
                causality: Causality::Input,
                unit: Some("N.m"),
                start: Some(0.0),
                description: format!(
                    "torque applied to `{}` on top of the spec's curves (held over a step)",
                    name(l)
                ),
            });
        }
        let out = |name: String, role, unit, description: String| RealVariable {
            name,
            role,
            causality: Causality::Output,
            unit: Some(unit),
            start: None,
            description,
        };
        for &l in &moving {
            reals.push(out(
                format!("{}.speed", name(l)),
                Role::LinkSpeed(l.index()),
                "rad/s",
                format!("speed of `{}`", name(l)),
            ));
        }
        reals.push(out(
            "work".into(),
            Role::Work,
            "J",
            "work of the applied torques (the curves' and the inputs') since the start".into(),
        ));
        reals.push(out(
            "kinetic_energy".into(),
            Role::KineticEnergy,
            "J",
            "the train's kinetic energy".into(),
        ));
        distinct(&reals, &[])?;
        Ok(Variables {
            kind: Kind::Train,
            reals,
            gears: Vec::new(),
            elements: Vec::new(),
        })
    }

    /// The value reference of the real with `role`.
    pub fn real(&self, role: Role) -> Option<u32> {
        (self.reals.iter().position(|r| r.role == role)).and_then(|i| u32::try_from(i).ok())
    }
}

/// Refuses two variables with one name.
fn distinct(reals: &[RealVariable], integers: &[&str]) -> Result<(), NotAUnit> {
    let mut names: Vec<&str> = reals.iter().map(|r| r.name.as_str()).collect();
    names.extend(integers);
    names.sort_unstable();
    match names.windows(2).find(|w| w[0] == w[1]) {
        Some(w) => Err(NotAUnit(format!(
            "two variables are named `{}` (an element named like a link?)",
            w[0]
        ))),
        None => Ok(()),
    }
}
