//! The gear-train spec as a user writes it (TOML or JSON, one serde model).
//!
//! This is the input format, kept exactly as written: names, not ids; optional
//! data left optional. [`crate::Train::from_spec`] validates it into a typed
//! graph, and nothing downstream reads the spec again. The whole format is
//! described for users in `docs/spec.md`; `egt schema` prints its JSON Schema.

pub(crate) mod expand;
pub mod parse;

use indexmap::IndexMap;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A whole gear-train spec: the graph (links, turning pairs, gear pairs, written
/// out or through the shorthands), optional physical data, optional shift
/// elements and gear states, and optional analysis settings.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// A title for reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Name of the frame (ground) link. It need not be listed in `links`.
    pub frame: String,
    /// Links (bodies) with their optional physical data. Links created by
    /// `planetary` sets or by `adjacency` need not be listed, but may be, to
    /// give them data.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub links: Vec<LinkSpec>,
    /// Revolute (turning) pairs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub revolutes: Vec<RevoluteSpec>,
    /// Gear pairs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gears: Vec<GearSpec>,
    /// Planetary sets written as engineers draw them; each expands into links,
    /// turning pairs and gear pairs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub planetary: Vec<PlanetarySpec>,
    /// The compact adjacency-list form printed by enumeration programs, e.g.
    /// `"1-2:a 2-3:b 1-4:a 1-3:G 3-4:G=-5/2"`: `A-B:x` is a turning pair at
    /// level `x`, `A-B:G` a gear pair, optionally with its Willis ratio after `=`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adjacency: Option<String>,
    /// Distances between adjacent axis levels (the paper's delta_ab, ...), for
    /// the kinetic energy of floating links. Derived from pitch radii when absent.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub offsets: Vec<OffsetSpec>,
    /// Shift elements: brakes, clutches and one-way clutches.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub elements: Vec<ElementSpec>,
    /// Input, output and gear states of an automatic transmission.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission: Option<TransmissionSpec>,
    /// Operating data for the analyses (speeds, loads, accelerations, curves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub analysis: Option<AnalysisSpec>,
    /// Mesh stiffnesses, torsional springs and compliant shift elements: the
    /// data of the lumped torsional model (`egt modes`, docs/vibration.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compliance: Option<ComplianceSpec>,
    /// Named gear changes in time (`[[shift]]`), run by `egt shift-sim
    /// --shift NAME`: the spec's alternative to the command's shift flags.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shift: Vec<ShiftSpec>,
}

/// A gear change in time between two gear states of `[transmission]`, with
/// the operating point and each changing element's capacity (`egt shift-sim
/// --shift NAME`; each field is the flag of the same name). The integration
/// settings (tolerances, method, step budget) stay on the command line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ShiftSpec {
    /// Unique name, e.g. `"2-3 power-on"`.
    pub name: String,
    /// The gear before (a state of `[transmission.states]`).
    pub from: String,
    /// The gear after. The elements of `from` not in `to` release, those of
    /// `to` not in `from` apply; every one of them needs a capacity in `ramps`.
    pub to: String,
    /// Input speed at t = 0 (rad/s); the train starts in `from`'s steady motion.
    pub input_speed: f64,
    /// Constant input torque (N m) (or `torque_table`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_torque: Option<f64>,
    /// Input torque over input speed, `[[w, T], ...]` (rad/s, N m), linear between points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_table: Option<Vec<[f64; 2]>>,
    /// Road load at the output `[c0, c1, c2]`: c0 sgn(w) + c1 w + c2 w|w| (N m). Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub road_load: Option<[f64; 3]>,
    /// Vehicle inertia reflected to the output link (kg m^2). Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vehicle_inertia: Option<f64>,
    /// Friction coefficients `[static, kinetic]`. Default `[0.15, 0.12]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<[f64; 2]>,
    /// Slip speed (rad/s) over which the coefficient falls from static to
    /// kinetic; default: a step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_decay: Option<f64>,
    /// Each changing element's capacity (N m per unit friction coefficient)
    /// by name: a number, or a ramp `[t0, t1, from, to]`.
    #[serde(default)]
    pub ramps: IndexMap<String, CapacitySpec>,
    /// End time (s). Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_end: Option<f64>,
    /// A compliant shaft from the output link to the vehicle inertia;
    /// default: rigid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_shaft: Option<OutputShaftSpec>,
    /// Mesh losses: the gear pairs' `efficiency` on the meshing forces, as
    /// `egt power` applies them (`--losses`). Default false (ideal meshes).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub losses: bool,
}

/// A torsional shaft from the output link to the vehicle, reduced to the
/// output link.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputShaftSpec {
    /// Stiffness (N m/rad).
    pub stiffness: f64,
    /// Damping (N m s/rad). Default 0.
    #[serde(default)]
    pub damping: f64,
}

/// A shift element's capacity as written: constant, or a linear ramp.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(
    untagged,
    expecting = "a capacity: a number C, or a ramp [t0, t1, from, to] (linear from `from` at t0 to `to` at t1)"
)]
pub enum CapacitySpec {
    /// Constant capacity.
    Constant(f64),
    /// `[t0, t1, from, to]`.
    Ramp([f64; 4]),
}

/// One link (rigid body). All physical data is optional: each analysis asks
/// only for what it uses.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// Unique name.
    pub name: String,
    /// Moment of inertia of one copy about its own axis [kg m^2].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<f64>,
    /// Mass of one copy \[kg\] (enters the kinetic energy of floating links, eq. 4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Number of identical satellites this link stands for (the paper's n_s).
    /// Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub copies: Option<u32>,
    /// Angular positions of the copies \[degrees\] about the axis of the carrier
    /// they ride on, measured from its offset arm, one per copy. Default:
    /// evenly spaced. Only the kinetic energy of links on nested carriers
    /// depends on them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phases: Option<Vec<f64>>,
    /// Number of gear wheels rigidly joined on this link. When it is 1, every
    /// mesh of the link uses the same wheel, so its tooth counts and pitch radii
    /// must agree. Default: one wheel per gear pair.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wheels: Option<u32>,
}

/// A revolute (turning) pair between two links, about an axis at `level`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RevoluteSpec {
    /// The two links.
    #[serde(deserialize_with = "exactly_two")]
    pub links: [String; 2],
    /// The axis level label (`a`, `b`, `c`, ... or any name).
    pub level: String,
}

/// Internal or external mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum MeshKind {
    /// Both wheels external: the carrier-relative speeds have opposite signs.
    External,
    /// One wheel is a ring (annulus): the carrier-relative speeds have equal signs.
    Internal,
}

/// A gear ratio as written: a number, or an exact fraction as a string (`"-162/77"`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum RatioSpec {
    /// A decimal number.
    Number(f64),
    /// An exact rational `"p/q"` or decimal `"-2.5"`.
    Text(String),
}

/// A gear pair between links `links[0]` (gear i) and `links[1]` (gear j).
///
/// The ratio is the paper's Willis ratio tau = (w_i - w_k) / (w_j - w_k), where
/// k is the carrier (transfer vertex); from teeth, tau = -z_j/z_i for an
/// external mesh and +z_j/z_i for an internal one.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GearSpec {
    /// Optional name (default `G<m>`, m counting from 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Gear i and gear j.
    #[serde(deserialize_with = "exactly_two")]
    pub links: [String; 2],
    /// Tooth counts [z_i, z_j]; needs `mesh`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "optional_two")]
    pub teeth: Option<[i64; 2]>,
    /// Mesh kind, with `teeth`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshKind>,
    /// The Willis ratio, instead of teeth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ratio: Option<RatioSpec>,
    /// Module \[m\]: pitch radius = module * z / 2 (needs `teeth`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub module: Option<f64>,
    /// Pitch radii [r_i, r_j] \[m\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "optional_two")]
    pub radii: Option<[f64; 2]>,
    /// Basic mesh efficiency (power ratio in the carrier frame), in (0, 1]. Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub efficiency: Option<f64>,
}

/// Kinds of planetary set understood by the shorthand.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PlanetaryKind {
    /// Sun, planet, ring, carrier.
    #[default]
    Simple,
    /// Sun meshes the inner planet, which meshes the outer planet, which meshes the ring.
    DoublePinion,
    /// A stepped (compound) planet: wheel `planet` meshes the sun, wheel `planet2`
    /// meshes the ring (or the second sun `sun2`).
    Stepped,
    /// Ravigneaux: small sun - short pinion (`planet`) - long pinion (`planet2`),
    /// and large sun `sun2` - long pinion - ring, on one carrier.
    Ravigneaux,
}

/// Tooth counts of a planetary set. Only the central members are needed for
/// the speeds of the central members; planets without teeth are created with
/// an unknown size, and their own speeds are then reported as unknown.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanetaryTeeth {
    /// Sun (the small sun of a Ravigneaux set).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun: Option<i64>,
    /// Ring (annulus).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ring: Option<i64>,
    /// Second sun (large sun of a Ravigneaux set; second sun of a stepped set).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun2: Option<i64>,
    /// Planet meshing the sun (inner planet, short pinion, first step).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet: Option<i64>,
    /// Outer planet / long pinion / second step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet2: Option<i64>,
}

/// A planetary set in engineering terms. Central members name links, which may
/// be shared with other sets or be the frame (a fixed ring: `ring = "frame"`).
/// Central members turn about the main axis `axis`; planets turn on the carrier,
/// each at its own level (named after the planet link).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanetarySpec {
    /// Name of the set; planets default to `<name>.planet` and `<name>.planet2`.
    pub name: String,
    /// Kind of set. Default `simple`.
    #[serde(default)]
    pub kind: PlanetaryKind,
    /// Sun link.
    pub sun: String,
    /// Ring link (absent only for a stepped set with two suns).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ring: Option<String>,
    /// Second sun link (Ravigneaux large sun, or stepped set with two suns).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun2: Option<String>,
    /// Carrier link.
    pub carrier: String,
    /// Planet link name (default `<name>.planet`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet: Option<String>,
    /// Second planet link name (default `<name>.planet2`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet2: Option<String>,
    /// Tooth counts.
    pub teeth: PlanetaryTeeth,
    /// Module \[m\] for every wheel of the set (gives pitch radii and axis offsets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub module: Option<f64>,
    /// Basic efficiency of every mesh of the set. Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub efficiency: Option<f64>,
    /// Level of the main axis. Default `a`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<String>,
}

/// Distance between two axis levels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OffsetSpec {
    /// The two levels.
    #[serde(deserialize_with = "exactly_two")]
    pub levels: [String; 2],
    /// Distance between the axes \[m\].
    pub distance: f64,
}

/// Kind of shift element.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// Holds one link to the frame.
    Brake,
    /// Joins two links.
    Clutch,
    /// Holds one link against turning backwards (negative speed).
    OneWayBrake,
    /// Joins two links when the first would turn slower than the second.
    OneWayClutch,
}

/// A shift element.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ElementSpec {
    /// Name used in the gear states (e.g. `A`).
    pub name: String,
    /// Kind of element.
    pub kind: ElementKind,
    /// One link for a brake, two for a clutch.
    pub links: Vec<String>,
}

/// Input, output and gear states of a transmission.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransmissionSpec {
    /// Input link.
    pub input: String,
    /// Output link.
    pub output: String,
    /// Gear states in shift order: state name -> engaged elements, e.g. `1 = ["A", "B", "C"]`.
    #[serde(default)]
    pub states: IndexMap<String, Vec<String>>,
}

/// A linearised torque-speed curve T = torque + slope * (w - speed) acting on
/// a link (eq. 13-15). Torques are applied torques, positive along positive
/// rotation; a motor whose torque falls as it speeds up has a negative slope.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CurveSpec {
    /// Link the torque acts on.
    pub link: String,
    /// Torque at the operating speed [N m].
    pub torque: f64,
    /// dT/dw at the operating point [N m s].
    #[serde(default)]
    pub slope: f64,
    /// Operating speed [rad/s].
    #[serde(default)]
    pub speed: f64,
}

/// Settings for time simulation.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SimulateSpec {
    /// End time \[s\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_end: Option<f64>,
    /// Step \[s\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Integrator name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// Initial speeds of the driving coordinates, link -> rad/s.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub initial: IndexMap<String, f64>,
}

/// Operating data for the analyses. Every field is optional; each analysis
/// reads only what it needs.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalysisSpec {
    /// Prescribed speeds, link -> rad/s (as many as the train has DOF).
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub speeds: IndexMap<String, RatioSpec>,
    /// Known external torques, link -> N m (applied, positive along positive rotation).
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub torques: IndexMap<String, f64>,
    /// Prescribed angular accelerations, link -> rad/s^2 (as many as DOF).
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub accelerations: IndexMap<String, f64>,
    /// Links whose driving torque is unknown and solved for (as many as DOF).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub driving: Vec<String>,
    /// Angles of carriers, link -> rad: the direction of each carrier's
    /// offset arm. Asked for only when the mass matrix depends on them (a
    /// single planet, or unevenly loaded arms, on nested carriers).
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub angles: IndexMap<String, f64>,
    /// Link to which the equivalent inertia is reduced.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reduce_to: Option<String>,
    /// Linearised torque-speed curves of motors and loads.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub curves: Vec<CurveSpec>,
    /// Time-simulation settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simulate: Option<SimulateSpec>,
}

/// The compliance of the train for its lumped torsional model (Kahraman 1994;
/// Lin & Parker 1999): a spring along the line of action of each gear pair,
/// torsional springs between links, and engaged shift elements as springs.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComplianceSpec {
    /// Pressure angle \[degrees\] of every mesh without its own; default 20.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure_angle: Option<f64>,
    /// One entry per gear pair: its mesh stiffness along the line of action.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub meshes: Vec<MeshStiffnessSpec>,
    /// Torsional springs between two links, or from one link to the frame.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub springs: Vec<TorsionSpringSpec>,
    /// Shift elements that are springs, not rigid constraints, when engaged.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub elements: Vec<ElementStiffnessSpec>,
}

/// The mesh stiffness of one gear pair (of each planet's mesh, for planets
/// with copies), along its line of action.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshStiffnessSpec {
    /// The gear pair's name (`G1`, `P/sun-planet`, ...).
    pub gear: String,
    /// Mesh stiffness along the line of action \[N/m\].
    pub stiffness: f64,
    /// Mesh damping along the line of action \[N s/m\]. Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Pressure angle \[degrees\]; default `compliance.pressure_angle`, else 20.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure_angle: Option<f64>,
    /// Base radii [r_bi, r_bj] \[m\]; default: the pitch radii times the
    /// cosine of the pressure angle.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "optional_two")]
    pub base_radii: Option<[f64; 2]>,
}

/// A torsional spring (a shaft, a coupling, a compliant output).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TorsionSpringSpec {
    /// Optional name; default `S<n>`, n counting from 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Two links, or one: a spring from that link to the frame.
    pub links: Vec<String>,
    /// Torsional stiffness \[N m/rad\].
    pub stiffness: f64,
    /// Torsional damping \[N m s/rad\]. Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

/// An engaged shift element as a torsional spring.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ElementStiffnessSpec {
    /// The element's name.
    pub element: String,
    /// Torsional stiffness \[N m/rad\] when engaged.
    pub stiffness: f64,
    /// Torsional damping \[N m s/rad\]. Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

/// A pair written as an array of exactly two elements. (TOML's reader would
/// otherwise take the first two of a longer array and drop the rest.)
pub(crate) fn exactly_two<'de, D, T>(d: D) -> std::result::Result<[T; 2], D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v: Vec<T> = Vec::deserialize(d)?;
    let n = v.len();
    <[T; 2]>::try_from(v)
        .map_err(|_| serde::de::Error::invalid_length(n, &"an array of exactly two elements"))
}

/// [`exactly_two`] for an optional pair.
pub(crate) fn optional_two<'de, D, T>(d: D) -> std::result::Result<Option<[T; 2]>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    exactly_two(d).map(Some)
}
