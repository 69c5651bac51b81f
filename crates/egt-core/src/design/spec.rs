//! The design-search specification (`egt synth SPEC`): a base train with named
//! simple planetary sets and a transmission table, tooth ranges per unknown set,
//! the engineering constraints on each set, and the target ratios with their
//! tolerance. Serde only; validation happens when the search is prepared.

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};

use crate::spec::{exactly_two, optional_two};

/// A design search as written (TOML or JSON). See `docs/synth.md`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SynthSpec {
    /// Path of the base train spec, relative to the search spec's file.
    /// Absent in a concept search (`[concept]`), which builds its trains.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub base: String,
    /// A concept search: the sets, elements and gear states are given, the
    /// permanent connections between the sets' members are searched too.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub concept: Option<ConceptSpec>,
    /// Unknown sets: planetary set name -> tooth ranges. Sets not listed keep
    /// the base train's teeth.
    pub sets: IndexMap<String, SetRange>,
    /// Constraints applied to every unknown set.
    #[serde(default)]
    pub constraints: Constraints,
    /// Targets and tolerances.
    pub targets: Targets,
    /// How many of the best candidates to keep. Default 20.
    #[serde(default = "default_top")]
    pub top: usize,
    /// Most leaves (points of one k per set that teeth make) the bound may
    /// reach in one run or partition before the search is refused as too
    /// loose: each survivor is confirmed by an exact analysis. Default
    /// 10 000; `egt synth --max-leaves` overrides it.
    #[serde(default = "default_max_leaves")]
    pub max_leaves: u64,
    /// Shift elements whose position is free: element name -> where it may
    /// sit. Elements not listed keep the base train's links.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub layout: IndexMap<String, Placement>,
}

fn default_top() -> usize {
    20
}

/// [`SynthSpec::max_leaves`]'s default.
pub const DEFAULT_MAX_LEAVES: u64 = 10_000;

fn default_max_leaves() -> u64 {
    DEFAULT_MAX_LEAVES
}

/// A concept search's fixed parts (`[concept]`, docs/synth.md "Concept
/// search"): the kinds of the sets and elements and the gear states; the
/// permanent connections, the input and output members and the elements'
/// positions are searched.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConceptSpec {
    /// Set name -> kind: `simple`, `double_pinion`, `stepped` or `ravigneaux`. Each
    /// needs its tooth ranges under `[sets]`.
    pub sets: IndexMap<String, crate::spec::PlanetaryKind>,
    /// Element name -> kind: `brake`, `clutch`, `one_way_brake`, `one_way_clutch`.
    pub elements: IndexMap<String, crate::spec::ElementKind>,
    /// Gear state name -> the elements engaged in it (the same number in every state).
    pub states: IndexMap<String, Vec<String>>,
    /// Where the input is: `member` (on a member of a set, default),
    /// `shaft` (a shaft of its own, reaching the sets through clutches) or `any`.
    #[serde(default)]
    pub input: InputRule,
    /// How many members the case holds permanently, `[min, max]` (default `[0, 0]`).
    #[serde(default = "no_held", deserialize_with = "exactly_two")]
    pub held: [usize; 2],
    /// Most structures the search may list (default 1 000 000).
    #[serde(default = "default_max_structures")]
    pub max_structures: u64,
    /// Most nodes one structure's tooth search may visit (default 20 000);
    /// a structure stopped there is counted in the report's `cut`.
    #[serde(default = "default_max_nodes")]
    pub max_nodes: u64,
    /// How many other tooth sets each reported concept lists, best first
    /// (default 20; 0: none). `top` counts concepts, each once.
    #[serde(default = "default_options")]
    pub options: usize,
}

/// Where a concept's input may be.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InputRule {
    /// On a member of a set (a shaft that may join two members).
    #[default]
    Member,
    /// A shaft of its own that reaches the sets only through clutches.
    Shaft,
    /// Either.
    Any,
}

fn no_held() -> [usize; 2] {
    [0, 0]
}

fn default_options() -> usize {
    20
}

fn default_max_nodes() -> u64 {
    20_000
}

fn default_max_structures() -> u64 {
    1_000_000
}

/// Where a freed shift element may sit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Placement {
    /// `"any"`: a brake on any central link but the frame, the input and the
    /// output; a clutch between any two central links but the frame.
    Any(String),
    /// The alternatives, each the element's links (one for a brake, two for
    /// a clutch).
    Choices(Vec<Vec<String>>),
}

/// Inclusive tooth ranges of one unknown set (simple, double-pinion,
/// stepped or Ravigneaux).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetRange {
    /// Sun teeth `[min, max]` (the small, forward sun of a Ravigneaux set).
    #[serde(deserialize_with = "exactly_two")]
    pub sun: [i64; 2],
    /// Large sun teeth `[min, max]`: required for a Ravigneaux set, refused
    /// for a simple one.
    #[serde(
        default,
        deserialize_with = "optional_two",
        skip_serializing_if = "Option::is_none"
    )]
    pub sun2: Option<[i64; 2]>,
    /// Ring teeth `[min, max]`.
    #[serde(deserialize_with = "exactly_two")]
    pub ring: [i64; 2],
    /// Teeth `[min, max]` of a stepped planet's first step (meshing the
    /// sun): required for a stepped set, whose second step (meshing the
    /// ring) follows from the coaxial condition; refused for the other
    /// kinds, whose planets follow from sun and ring.
    #[serde(
        default,
        deserialize_with = "optional_two",
        skip_serializing_if = "Option::is_none"
    )]
    pub planet: Option<[i64; 2]>,
    /// Number of equally spaced planets (assembly and non-interference). Default 3.
    #[serde(default = "default_planets")]
    pub planets: i64,
}

fn default_planets() -> i64 {
    3
}

/// Engineering constraints on each unknown set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Constraints {
    /// Smallest planet tooth count. Default 13.
    #[serde(default = "default_min_planet")]
    pub min_planet: i64,
    /// Profile-shift allowance in teeth: |ring - sun - 2 planet| <= this
    /// (|ring - sun - planet - planet2| for a stepped set).
    /// 0 (default) is the coaxial condition of unshifted gears.
    #[serde(default)]
    pub profile_shift: i64,
    /// Require equally spaced planets to assemble: (sun + ring) / planets
    /// an integer for a simple set; (sun planet2 + ring planet) /
    /// (planets gcd(planet, planet2)) for a stepped one (docs/synth.md).
    /// Default true.
    #[serde(default = "yes")]
    pub assembly: bool,
    /// Require neighbouring planets' tip circles not to touch:
    /// (sun + planet) sin(pi / n) > planet + 2. Default true.
    #[serde(default = "yes")]
    pub non_interference: bool,
    /// Limits `[min, max]` of ring / sun.
    #[serde(
        default,
        deserialize_with = "optional_two",
        skip_serializing_if = "Option::is_none"
    )]
    pub ring_sun: Option<[f64; 2]>,
}

fn default_min_planet() -> i64 {
    13
}

fn yes() -> bool {
    true
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints {
            min_planet: default_min_planet(),
            profile_shift: 0,
            assembly: true,
            non_interference: true,
            ring_sun: None,
        }
    }
}

/// What the ratios must be.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Targets {
    /// Gear state name -> target ratio input/output speed (negative for reverse).
    pub ratios: IndexMap<String, f64>,
    /// Largest accepted |ratio - target|. Default 0.0005 (three decimals).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Accepted spread (largest / smallest forward ratio) `[min, max]`.
    #[serde(
        default,
        deserialize_with = "optional_two",
        skip_serializing_if = "Option::is_none"
    )]
    pub spread: Option<[f64; 2]>,
    /// Accepted step between adjacent forward gears `[min, max]` (every step).
    #[serde(
        default,
        deserialize_with = "optional_two",
        skip_serializing_if = "Option::is_none"
    )]
    pub steps: Option<[f64; 2]>,
    /// A progressive ratio set: no step larger than the one below it.
    #[serde(default)]
    pub progressive: bool,
    /// Every shift between adjacent forward gears releases one element and
    /// applies one.
    #[serde(default)]
    pub single_swap: bool,
    /// Lowest accepted efficiency of a targeted gear state (with the base
    /// train's mesh efficiencies; 1 where none are given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub efficiency: Option<f64>,
    /// Largest accepted |torque| of an engaged shift element, per unit input
    /// torque, in a targeted gear state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_element_torque: Option<f64>,
    /// Largest accepted |mesh torque| (a mesh's multiplier, eq. 7: the torque
    /// it puts on its gear i, all planets together), per unit input torque,
    /// in a targeted gear state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_mesh_torque: Option<f64>,
}

fn default_tolerance() -> f64 {
    5e-4
}

impl SynthSpec {
    /// Parse a search spec (TOML or JSON) with located errors.
    ///
    /// # Errors
    /// [`crate::Error::Syntax`] with line, column and field path.
    pub fn from_str(text: &str, format: crate::Format, source_name: &str) -> crate::Result<Self> {
        crate::spec::parse::parse_document(text, format, source_name)
    }

    /// Where the base train is: `base` relative to the directory of the
    /// search spec's file (`spec_file`), or as written when absolute or when
    /// the search spec has no file (standard input, a string).
    pub fn base_path(&self, spec_file: Option<&std::path::Path>) -> std::path::PathBuf {
        let base = std::path::Path::new(&self.base);
        match spec_file.and_then(std::path::Path::parent) {
            Some(dir) if base.is_relative() => dir.join(base),
            _ => base.to_path_buf(),
        }
    }
}
