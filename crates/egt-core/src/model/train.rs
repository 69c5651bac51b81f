//! The validated gear train: links, turning pairs and gear pairs behind typed
//! ids, the typed graph, the turning-pair tree rooted at the frame, the
//! fundamental-circuit table and the degree of freedom.
//!
//! A [`Train`] is built once from a [`Spec`] (all field and topology checks
//! happen here) and is then read by every analysis; nothing downstream
//! re-parses or re-validates.

use std::collections::HashMap;

use petgraph::graph::{NodeIndex, UnGraph};
use serde::Serialize;

use crate::error::{AnalysisError, Error, Result, SpecErrorKind, suggest};
use crate::model::circuits::FundamentalCircuit;
use crate::model::topology::{self, Tree};
use crate::numerics::exact::{self, Q};
use crate::spec::expand::{self, Draft, DraftGear};
use crate::spec::parse::{self, Format};
use crate::spec::{ElementKind, MeshKind, RatioSpec, ShiftSpec, Spec};

mod build;
mod compliance;
mod extras;
mod ids;
mod size;
mod teeth;

use build::build;

pub use compliance::{
    Compliance, DEFAULT_PRESSURE_ANGLE_DEG, ElementStiffness, MeshStiffness, TorsionSpring,
};
pub use ids::{ElementId, GearId, LevelId, LinkId, RevoluteId};
pub(crate) use size::require_dense_links;
pub use size::{MAX_DENSE_BYTES, MAX_TRAIN_LINKS, dense_bytes, most_dense_links};
pub(crate) use teeth::missing_ratio;
pub use teeth::ratio_from_teeth;

/// A link with its optional physical data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Link {
    /// Name.
    pub name: String,
    /// Moment of inertia of one copy about its own axis.
    pub inertia: Option<f64>,
    /// Mass of one copy.
    pub mass: Option<f64>,
    /// Number of identical satellites (n_s). 1 for a single body.
    pub copies: u32,
    /// Angular positions of the copies \[rad\] about their carrier's axis, from
    /// its arm, when not evenly spaced.
    pub phases: Option<Vec<f64>>,
    /// Gear wheels rigidly joined on it, when given.
    pub wheels: Option<u32>,
    /// False for a planet whose tooth count was not given: its own speed is unknown.
    pub sized: bool,
}

/// A turning pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Revolute {
    /// The two links, as written.
    pub links: [LinkId; 2],
    /// The axis level.
    pub level: LevelId,
}

/// A Willis ratio: always as a float, and exactly when it came from teeth or a fraction.
#[derive(Debug, Clone, PartialEq)]
pub struct Ratio {
    /// The value.
    pub value: f64,
    /// The exact value, when known.
    pub exact: Option<Q>,
}

/// A gear pair.
#[derive(Debug, Clone, PartialEq)]
pub struct GearPair {
    /// Name (e.g. `G1` or `P1/sun-planet`).
    pub name: String,
    /// Gear i.
    pub gear_i: LinkId,
    /// Gear j.
    pub gear_j: LinkId,
    /// Willis ratio tau = (w_i - w_k)/(w_j - w_k), if given.
    pub ratio: Option<Ratio>,
    /// Tooth counts [z_i, z_j], when given.
    pub teeth: Option<[u32; 2]>,
    /// Mesh kind, when given.
    pub mesh: Option<MeshKind>,
    /// Pitch radii [r_i, r_j], given or from the module.
    pub radii: Option<[f64; 2]>,
    /// Basic efficiency in the carrier frame (1 when not given).
    pub efficiency: f64,
    /// Where it was written in the spec.
    pub path: String,
}

/// A shift element, resolved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShiftElement {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: ElementKind,
    /// The held link (brakes) or the two joined links (clutches).
    pub links: Vec<LinkId>,
}

/// A gear state: the engaged shift elements.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GearState {
    /// Name (e.g. `1`, `R`).
    pub name: String,
    /// Engaged elements.
    pub engaged: Vec<ElementId>,
}

/// Transmission data, resolved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Transmission {
    /// Input link.
    pub input: LinkId,
    /// Output link.
    pub output: LinkId,
    /// Gear states in shift order.
    pub states: Vec<GearState>,
    /// The spec's named shifts (`[[shift]]`), as written: names unique,
    /// `from` and `to` known states; the rest is checked when one runs.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub shifts: Vec<ShiftSpec>,
}

/// A linearised torque-speed curve on a link, resolved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Curve {
    /// Link.
    pub link: LinkId,
    /// Torque at the operating point.
    pub torque: f64,
    /// Slope dT/dw.
    pub slope: f64,
    /// Operating speed.
    pub speed: f64,
}

/// Operating data from the spec's `[analysis]` section, resolved to ids.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Analysis {
    /// Prescribed speeds.
    pub speeds: Vec<(LinkId, f64, Option<Q>)>,
    /// Known applied torques.
    pub torques: Vec<(LinkId, f64)>,
    /// Prescribed accelerations.
    pub accelerations: Vec<(LinkId, f64)>,
    /// Links with unknown driving torque.
    pub driving: Vec<LinkId>,
    /// Carrier angles (rad), for a mass matrix that depends on them.
    pub angles: Vec<(LinkId, f64)>,
    /// Link for the equivalent inertia.
    pub reduce_to: Option<LinkId>,
    /// Torque-speed curves.
    pub curves: Vec<Curve>,
    /// Simulation settings, as written (initial speeds resolved).
    pub simulate: Option<Simulate>,
}

/// Simulation settings, resolved.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Simulate {
    /// End time.
    pub t_end: Option<f64>,
    /// Step.
    pub dt: Option<f64>,
    /// Integrator name.
    pub method: Option<String>,
    /// Initial speeds.
    pub initial: Vec<(LinkId, f64)>,
}

/// A validated geared kinematic chain.
#[derive(Debug, Clone)]
pub struct Train {
    pub(crate) name: Option<String>,
    pub(crate) links: Vec<Link>,
    /// Link ids by name (a train may have many thousands of links).
    pub(crate) link_ids: HashMap<String, LinkId>,
    pub(crate) frame: LinkId,
    pub(crate) levels: Vec<String>,
    pub(crate) revolutes: Vec<Revolute>,
    pub(crate) gears: Vec<GearPair>,
    pub(crate) offsets: Vec<(LevelId, LevelId, f64)>,
    pub(crate) graph: UnGraph<LinkId, Edge>,
    pub(crate) tree: Tree,
    pub(crate) circuits: Vec<FundamentalCircuit>,
    pub(crate) dof: usize,
    pub(crate) coordinates: Vec<LinkId>,
    pub(crate) coord_of: Vec<Option<usize>>,
    pub(crate) elements: Vec<ShiftElement>,
    pub(crate) transmission: Option<Transmission>,
    pub(crate) analysis: Analysis,
    pub(crate) compliance: Option<Compliance>,
    pub(crate) checks: Vec<String>,
    pub(crate) design_warnings: Vec<String>,
}

/// An edge of the typed graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    /// A turning pair.
    Revolute(RevoluteId),
    /// A gear pair.
    Gear(GearId),
}

impl Train {
    /// Run the topology phase of [`Train::from_spec`] again on this validated
    /// train (eq. 1 checks, the turning-pair tree, the circuit table of
    /// Table 1) and return the number of fundamental circuits. Validation does
    /// this once; the benchmarks time it apart from parsing.
    ///
    /// # Errors
    /// None for a train that was valid when built; the [`crate::TopologyError`] otherwise.
    pub fn reanalyse_topology(&self) -> Result<usize> {
        let clutches: Vec<[LinkId; 2]> = self
            .elements
            .iter()
            .filter(|e| matches!(e.kind, ElementKind::Clutch | ElementKind::OneWayClutch))
            .filter_map(|e| match e.links.as_slice() {
                &[a, b] => Some([a, b]),
                _ => None,
            })
            .collect();
        let topo = topology::analyse(
            &self.links,
            self.frame,
            &self.levels,
            &self.revolutes,
            &self.gears,
            &self.graph,
            &clutches,
        )?;
        Ok(topo.circuits.len())
    }

    /// Parse and validate a spec from text.
    ///
    /// # Errors
    /// Syntax, spec or topology errors, each naming the place or the links involved.
    pub fn from_str(text: &str, format: Format, source_name: &str) -> Result<Train> {
        Train::from_spec(&parse::parse_spec(text, format, source_name)?)
    }

    /// Validate a parsed spec into a train.
    ///
    /// # Errors
    /// [`Error::Spec`] for invalid fields (with their path) and
    /// [`Error::Topology`] when the graph is not a valid geared kinematic chain.
    pub fn from_spec(spec: &Spec) -> Result<Train> {
        let draft = expand::expand(spec)?;
        build(spec, &draft)
    }

    /// Title from the spec.
    pub fn name(&self) -> Option<&str> {
        self.name.as_deref()
    }
    /// All links; `LinkId::index()` indexes this slice.
    pub fn links(&self) -> &[Link] {
        &self.links
    }
    /// All links with their ids, in id order.
    pub fn links_with_ids(&self) -> impl Iterator<Item = (LinkId, &Link)> {
        (self.links.iter().enumerate()).map(|(i, l)| (LinkId::from_index(i), l))
    }
    /// A link by id.
    pub fn link(&self, id: LinkId) -> &Link {
        &self.links[id.index()]
    }
    /// A link's name.
    pub fn link_name(&self, id: LinkId) -> &str {
        &self.links[id.index()].name
    }
    /// The frame.
    pub fn frame(&self) -> LinkId {
        self.frame
    }
    /// Look up a link by name.
    pub fn link_id(&self, name: &str) -> Option<LinkId> {
        self.link_ids.get(name).copied()
    }
    /// Look up a link by name, with a spec error naming `path` when it is unknown.
    ///
    /// # Errors
    /// [`SpecErrorKind::UnknownLink`] with a suggestion.
    pub fn resolve(&self, name: &str, path: &str) -> Result<LinkId> {
        self.link_id(name).ok_or_else(|| {
            Error::spec(
                path,
                SpecErrorKind::UnknownLink {
                    name: name.to_string(),
                    suggestion: suggest(name, self.links.iter().map(|l| l.name.as_str())),
                },
            )
        })
    }
    /// Axis level names; `LevelId::index()` indexes this slice.
    pub fn levels(&self) -> &[String] {
        &self.levels
    }
    /// A level's name.
    pub fn level_name(&self, id: LevelId) -> &str {
        &self.levels[id.index()]
    }
    /// Turning pairs.
    pub fn revolutes(&self) -> &[Revolute] {
        &self.revolutes
    }
    /// Gear pairs (gear pair m is fundamental circuit m).
    pub fn gears(&self) -> &[GearPair] {
        &self.gears
    }
    /// The fundamental-circuit table (Table 1), one per gear pair in gear-pair order.
    pub fn circuits(&self) -> &[FundamentalCircuit] {
        &self.circuits
    }
    /// Degree of freedom (Gruebler-Kutzbach, confirmed by the generic rank of the Willis equations).
    pub fn dof(&self) -> usize {
        self.dof
    }
    /// The turning-pair tree rooted at the frame.
    pub fn tree(&self) -> &Tree {
        &self.tree
    }
    /// The typed graph (node weights are link ids, edge weights pair ids).
    pub fn graph(&self) -> &UnGraph<LinkId, Edge> {
        &self.graph
    }
    /// The speed coordinates: every link but the frame, in link order.
    pub fn coordinates(&self) -> &[LinkId] {
        &self.coordinates
    }
    /// Column of a link among the coordinates (None for the frame).
    pub fn coordinate(&self, link: LinkId) -> Option<usize> {
        self.coord_of[link.index()]
    }
    /// Offsets between axis levels given in the spec.
    pub fn offsets(&self) -> &[(LevelId, LevelId, f64)] {
        &self.offsets
    }
    /// Shift elements.
    pub fn elements(&self) -> &[ShiftElement] {
        &self.elements
    }
    /// Transmission data, if the spec has any.
    pub fn transmission(&self) -> Option<&Transmission> {
        self.transmission.as_ref()
    }
    /// The `[compliance]` data (mesh stiffnesses, springs), when given.
    pub fn compliance(&self) -> Option<&Compliance> {
        self.compliance.as_ref()
    }

    /// Operating data from the spec's `[analysis]` section.
    pub fn analysis(&self) -> &Analysis {
        &self.analysis
    }
    /// The topology checks that passed, in words.
    pub fn checks(&self) -> &[String] {
        &self.checks
    }
    /// Tooth counts that a valid train may have but that a designer should
    /// see: a ring smaller than its sun, planets that fail the coaxial
    /// condition of unshifted gears, or equally spaced planets that cannot
    /// be assembled. Warnings, not errors (profile shift and unequal spacing
    /// are legitimate).
    pub fn design_warnings(&self) -> &[String] {
        &self.design_warnings
    }
    /// True when every gear pair has an exact ratio.
    pub fn has_exact_ratios(&self) -> bool {
        self.gears
            .iter()
            .all(|g| g.ratio.as_ref().is_some_and(|r| r.exact.is_some()))
    }
    /// Float Willis ratios in gear-pair order.
    ///
    /// # Errors
    /// [`crate::AnalysisError::MissingData`] naming the first pair without a ratio.
    pub fn ratios(&self) -> Result<Vec<f64>> {
        self.gears
            .iter()
            .map(|g| {
                g.ratio
                    .as_ref()
                    .map(|r| r.value)
                    .ok_or_else(|| missing_ratio(g, "kinematics"))
            })
            .collect()
    }
}
