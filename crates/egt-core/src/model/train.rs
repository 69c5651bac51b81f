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
use crate::spec::{ElementKind, MeshKind, RatioSpec, Spec};

/// The names ids serialize as inside [`Train::named`] (by kind: links, gear
/// pairs, turning pairs, levels, elements); outside it, ids serialize as
/// their indices.
#[derive(Debug, Default)]
struct NameTable([Vec<String>; 5]);

thread_local! {
    static NAMES: std::cell::RefCell<Option<NameTable>> = const { std::cell::RefCell::new(None) };
}

macro_rules! id_type {
    ($(#[$m:meta])* $name:ident, $kind:expr) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub(crate) u32);

        impl $name {
            /// The index of this id in its table.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }

            /// The id with index `i` (for iteration; ids are dense from 0).
            #[inline]
            pub fn from_index(i: usize) -> Self {
                Self(u32::try_from(i).unwrap_or(u32::MAX))
            }
        }

        /// The index, or inside [`Train::named`] the name.
        impl Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                let name = NAMES.with(|n| {
                    n.borrow()
                        .as_ref()
                        .and_then(|t| t.0[$kind].get(self.index()).cloned())
                });
                match name {
                    Some(name) => s.serialize_str(&name),
                    None => s.serialize_u32(self.0),
                }
            }
        }
    };
}

id_type!(
    /// A link (vertex of the graph).
    LinkId,
    0
);
id_type!(
    /// A gear pair (geared edge); gear pair m is fundamental circuit m.
    GearId,
    1
);
id_type!(
    /// A turning (revolute) pair.
    RevoluteId,
    2
);
id_type!(
    /// An axis level (a, b, c, ...).
    LevelId,
    3
);
id_type!(
    /// A shift element.
    ElementId,
    4
);

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
    /// `value` (any result of this train) as JSON with every id replaced by
    /// its name: links, gear pairs and elements by name, levels by letter,
    /// turning pairs as `a-b`. The named view for serde output; outside this
    /// call ids serialize as indices (what the Python conversion reads).
    ///
    /// # Errors
    /// A value that does not serialize (it never happens for egt's results).
    pub fn named<T: Serialize>(&self, value: &T) -> Result<serde_json::Value> {
        let table = NameTable([
            self.links().iter().map(|l| l.name.clone()).collect(),
            self.gears().iter().map(|g| g.name.clone()).collect(),
            self.revolutes()
                .iter()
                .map(|r| {
                    format!(
                        "{}-{}",
                        self.link_name(r.links[0]),
                        self.link_name(r.links[1])
                    )
                })
                .collect(),
            self.levels().to_vec(),
            self.elements().iter().map(|e| e.name.clone()).collect(),
        ]);
        let previous = NAMES.with(|n| n.borrow_mut().replace(table));
        let out = serde_json::to_value(value);
        NAMES.with(|n| *n.borrow_mut() = previous);
        out.map_err(|e| Error::invalid("named view", e.to_string()))
    }
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
    /// Operating data from the spec.
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

pub(crate) fn missing_ratio(g: &GearPair, analysis: &str) -> Error {
    crate::AnalysisError::MissingData {
        what: format!("the ratio of gear pair `{}`", g.name),
        analysis: analysis.to_string(),
        hint: format!("give `teeth` and `mesh`, or `ratio`, at {}", g.path),
    }
    .into()
}

fn finite(path: String, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::spec(path, SpecErrorKind::NonFinite { value: v }))
    }
}

fn positive(path: String, v: f64) -> Result<f64> {
    bounded(path, v, v > 0.0, "must be > 0")
}

fn non_negative(path: String, v: f64) -> Result<f64> {
    bounded(path, v, v >= 0.0, "must be >= 0")
}

/// `v`, finite and within the bound `ok` (else an out-of-range error saying `expected`).
fn bounded(path: String, v: f64, ok: bool, expected: &str) -> Result<f64> {
    let v = finite(path.clone(), v)?;
    if ok {
        Ok(v)
    } else {
        Err(Error::spec(
            path,
            SpecErrorKind::OutOfRange {
                value: v,
                expected: expected.into(),
            },
        ))
    }
}

fn teeth_value(path: String, z: i64) -> Result<u32> {
    u32::try_from(z)
        .ok()
        .filter(|&z| z > 0 && i64::from(z) <= crate::error::MAX_TEETH)
        .ok_or_else(|| Error::spec(path, SpecErrorKind::InvalidTeeth { value: z }))
}

impl Train {
    /// The mesh kind ratios from tooth counts use for gear pair `g`: as
    /// given, else the kind the sign of its given ratio implies (negative:
    /// external); None when neither is known.
    pub fn mesh_kind(&self, g: GearId) -> Option<MeshKind> {
        let gear = &self.gears()[g.index()];
        gear.mesh.or_else(|| {
            gear.ratio.as_ref().map(|r| {
                if r.value < 0.0 {
                    MeshKind::External
                } else {
                    MeshKind::Internal
                }
            })
        })
    }

    /// The ratios of every gear pair from one set of tooth counts
    /// (`teeth[m] = [z_i, z_j]` in gear-pair order) into `out`, by
    /// [`ratio_from_teeth`]; `row` names the set in errors (a batch row).
    ///
    /// # Errors
    /// Wrong counts of pairs; a pair without a known mesh kind; bad tooth
    /// counts, named by row and gear pair.
    pub fn ratios_from_teeth(&self, row: &str, teeth: &[[i64; 2]], out: &mut [f64]) -> Result<()> {
        let n = self.gears().len();
        if teeth.len() != n || out.len() != n {
            return Err(Error::invalid(
                row,
                format!(
                    "tooth counts for {n} gear pairs are needed, got {}",
                    teeth.len()
                ),
            ));
        }
        for (m, (z, o)) in teeth.iter().zip(out.iter_mut()).enumerate() {
            let name = &self.gears()[m].name;
            let path = format!("{row}[{m}] (gear pair `{name}`)");
            let mesh = self.mesh_kind(GearId::from_index(m)).ok_or_else(|| {
                Error::spec(
                    format!("gear pair `{name}`.mesh"),
                    SpecErrorKind::Missing {
                        what:
                            "the mesh kind (`external` or `internal`) that ratios from teeth need"
                                .into(),
                    },
                )
            })?;
            *o = exact::to_f64(&ratio_from_teeth(&path, mesh, *z)?);
        }
        Ok(())
    }
}

/// The Willis ratio of a gear pair from its tooth counts `[z_i, z_j]`:
/// tau = -z_j / z_i for an external mesh, +z_j / z_i for an internal one
/// (eq. 2), exactly. The one rule for specs and for batches of tooth counts;
/// `path` names the counts in errors.
///
/// # Errors
/// A count that is not a positive integer up to [`crate::error::MAX_TEETH`];
/// equal counts on an internal mesh (tau = 1 would lock the pair).
pub fn ratio_from_teeth(path: &str, mesh: MeshKind, teeth: [i64; 2]) -> Result<Q> {
    let zi = teeth_value(format!("{path}[0]"), teeth[0])?;
    let zj = teeth_value(format!("{path}[1]"), teeth[1])?;
    if mesh == MeshKind::Internal && zi == zj {
        return Err(Error::invalid(
            path,
            "an internal mesh needs different tooth counts (tau = 1 would lock the pair)",
        ));
    }
    let tau = exact::frac(i64::from(zj), i64::from(zi));
    Ok(if mesh == MeshKind::External {
        -tau
    } else {
        tau
    })
}

/// Validate one gear pair's numbers into a [`GearPair`].
fn gear_pair(g: &DraftGear, ids: &HashMap<&str, LinkId>) -> Result<GearPair> {
    let p = &g.path;
    let s = &g.spec;
    let gear_i = ids[s.links[0].as_str()];
    let gear_j = ids[s.links[1].as_str()];
    let teeth = match s.teeth {
        Some([zi, zj]) => Some([
            teeth_value(format!("{p}.teeth[0]"), zi)?,
            teeth_value(format!("{p}.teeth[1]"), zj)?,
        ]),
        None => None,
    };
    let ratio = match (&teeth, &s.ratio) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                p.clone(),
                "give either `teeth` (with `mesh`) or `ratio`, not both",
            ));
        }
        (Some([zi, zj]), None) => {
            let mesh = s.mesh.ok_or_else(|| {
                Error::spec(
                    format!("{p}.mesh"),
                    SpecErrorKind::Missing {
                        what: "mesh kind (`external` or `internal`) for `teeth`".into(),
                    },
                )
            })?;
            let tau = ratio_from_teeth(&format!("{p}.teeth"), mesh, [(*zi).into(), (*zj).into()])?;
            Some(Ratio {
                value: exact::to_f64(&tau),
                exact: Some(tau),
            })
        }
        (None, Some(RatioSpec::Number(v))) => {
            let v = finite(format!("{p}.ratio"), *v)?;
            Some(Ratio {
                value: v,
                exact: None,
            })
        }
        (None, Some(RatioSpec::Text(t))) => {
            let (q, value) = exact::parse_finite(t)
                .map_err(|e| Error::invalid(format!("{p}.ratio"), format!("`{t}`: {e}")))?;
            Some(Ratio {
                value,
                exact: Some(q),
            })
        }
        (None, None) => {
            if s.mesh.is_some() {
                return Err(Error::spec(
                    format!("{p}.teeth"),
                    SpecErrorKind::Missing {
                        what: "`teeth` for `mesh`".into(),
                    },
                ));
            }
            None
        }
    };
    if let Some(r) = &ratio
        && r.value == 0.0
    {
        return Err(Error::spec(
            format!("{p}.ratio"),
            SpecErrorKind::OutOfRange {
                value: 0.0,
                expected: "a Willis ratio is never 0".into(),
            },
        ));
    }
    let mut radii = match s.radii {
        Some([ri, rj]) => Some([
            positive(format!("{p}.radii[0]"), ri)?,
            positive(format!("{p}.radii[1]"), rj)?,
        ]),
        None => None,
    };
    if let Some(m) = s.module {
        let m = positive(format!("{p}.module"), m)?;
        let [zi, zj] = teeth.ok_or_else(|| {
            Error::spec(
                format!("{p}.teeth"),
                SpecErrorKind::Missing {
                    what: "`teeth` for `module`".into(),
                },
            )
        })?;
        let from_module = [m * f64::from(zi) / 2.0, m * f64::from(zj) / 2.0];
        if let Some(r) = radii
            && (0..2).any(|k| (r[k] - from_module[k]).abs() > 1e-9 * from_module[k])
        {
            return Err(Error::invalid(
                p.clone(),
                format!("`radii` {r:?} disagree with `module` x `teeth` / 2 = {from_module:?}"),
            ));
        }
        radii = Some(from_module);
    }
    let efficiency = match s.efficiency {
        Some(e) => {
            let e = finite(format!("{p}.efficiency"), e)?;
            if !(e > 0.0 && e <= 1.0) {
                return Err(Error::spec(
                    format!("{p}.efficiency"),
                    SpecErrorKind::OutOfRange {
                        value: e,
                        expected: "efficiency must be in (0, 1]".into(),
                    },
                ));
            }
            e
        }
        None => 1.0,
    };
    Ok(GearPair {
        name: g.name.clone(),
        gear_i,
        gear_j,
        ratio,
        teeth,
        mesh: s.mesh,
        radii,
        efficiency,
        path: p.clone(),
    })
}

/// The most memory the dense matrices of one analysis may take. The
/// analyses other than the topology check and the kinematics (dynamics,
/// power, stability, simulation, gear states, exact speeds) hold a few dense
/// n x n matrices (f64 or rationals) for n links; [`Train::require_dense`]
/// estimates them with [`dense_bytes`] before any is allocated, so a huge
/// train is refused by name instead of aborting on a failed allocation (or
/// running for minutes, the work being cubic in n). The topology check and
/// the float kinematics are sparse and take any train up to [`MAX_TRAIN_LINKS`].
pub const MAX_DENSE_BYTES: usize = 64 << 20;

/// The most links a train may have: about 5 KB of memory a link while it is
/// read and checked (a 10^5-link spec takes 0.5 GB), so 2^20 links stay
/// within a few GB.
pub const MAX_TRAIN_LINKS: usize = 1 << 20;

/// Estimated bytes of the dense matrices of a train of `links` links: about
/// eight n x n matrices of 8-byte entries (see [`MAX_DENSE_BYTES`]).
pub fn dense_bytes(links: usize) -> usize {
    links.saturating_mul(links).saturating_mul(64)
}

/// The largest train whose dense matrices fit in [`MAX_DENSE_BYTES`].
pub fn most_dense_links() -> usize {
    // dense_bytes is increasing: the largest n with 64 n^2 <= limit.
    let mut n = ((MAX_DENSE_BYTES / 64) as f64).sqrt() as usize + 1;
    while dense_bytes(n) > MAX_DENSE_BYTES {
        n -= 1;
    }
    n
}

impl Train {
    /// Refuse `analysis` when its dense matrices for this train would pass
    /// [`MAX_DENSE_BYTES`]; called before any is allocated.
    ///
    /// # Errors
    /// [`AnalysisError::TooLarge`] naming the analysis, the size and the limit.
    pub fn require_dense(&self, analysis: &str) -> Result<()> {
        require_dense_links(self.links.len(), analysis)
    }
}

/// [`Train::require_dense`] for a train of `links` links (the one rule and
/// message, also for a [`MassMatrix`](crate::MassMatrix) of `links - 1`
/// coordinates).
pub(crate) fn require_dense_links(links: usize, analysis: &str) -> Result<()> {
    if dense_bytes(links) <= MAX_DENSE_BYTES {
        return Ok(());
    }
    Err(AnalysisError::TooLarge {
        analysis: analysis.to_string(),
        links,
        mib: dense_bytes(links) >> 20,
        limit_mib: MAX_DENSE_BYTES >> 20,
        most: most_dense_links(),
        what: "the topology check, the float kinematics, inverse dynamics and power flow are sparse and take it".into(),
    }
    .into())
}

fn build(spec: &Spec, draft: &Draft) -> Result<Train> {
    let n = draft.links.len();
    if n > MAX_TRAIN_LINKS {
        #[allow(clippy::cast_precision_loss)]
        return Err(Error::spec(
            "links",
            SpecErrorKind::OutOfRange {
                value: n as f64,
                expected: format!("at most {MAX_TRAIN_LINKS} links in a train"),
            },
        ));
    }
    // Links.
    let mut links = Vec::with_capacity(draft.links.len());
    let written: HashMap<&str, usize> = spec
        .links
        .iter()
        .enumerate()
        .map(|(k, l)| (l.name.as_str(), k))
        .collect();
    for (n, (name, dl)) in draft.links.iter().enumerate() {
        let path = written
            .get(name.as_str())
            .map_or_else(|| format!("link `{name}`"), |k| format!("links[{k}]"));
        let d = &dl.data;
        let inertia = d
            .inertia
            .map(|v| non_negative(format!("{path}.inertia"), v))
            .transpose()?;
        let mass = d
            .mass
            .map(|v| non_negative(format!("{path}.mass"), v))
            .transpose()?;
        let copies = match d.copies {
            Some(0) => {
                return Err(Error::spec(
                    format!("{path}.copies"),
                    SpecErrorKind::OutOfRange {
                        value: 0.0,
                        expected: "at least 1".into(),
                    },
                ));
            }
            Some(c) => c,
            None => 1,
        };
        if d.wheels == Some(0) {
            return Err(Error::spec(
                format!("{path}.wheels"),
                SpecErrorKind::OutOfRange {
                    value: 0.0,
                    expected: "at least 1".into(),
                },
            ));
        }
        let phases = match &d.phases {
            None => None,
            Some(p) if p.len() != copies as usize => {
                return Err(Error::invalid(
                    format!("{path}.phases"),
                    format!(
                        "{} phases given for {copies} copies: give one angle per copy",
                        p.len()
                    ),
                ));
            }
            Some(p) => Some(
                p.iter()
                    .enumerate()
                    .map(|(k, &v)| finite(format!("{path}.phases[{k}]"), v).map(f64::to_radians))
                    .collect::<Result<Vec<f64>>>()?,
            ),
        };
        debug_assert!(n > 0 || name == &spec.frame);
        links.push(Link {
            name: name.clone(),
            inertia,
            mass,
            copies,
            phases,
            wheels: d.wheels,
            sized: dl.sized,
        });
    }
    let ids: HashMap<&str, LinkId> = draft
        .links
        .keys()
        .enumerate()
        .map(|(i, k)| (k.as_str(), LinkId::from_index(i)))
        .collect();
    let frame = ids[spec.frame.as_str()];

    // Levels, interned in first-appearance order.
    let mut levels: Vec<String> = Vec::new();
    let mut level_ids: HashMap<String, LevelId> = HashMap::new();
    let mut level_id = |name: &str| -> LevelId {
        if let Some(&id) = level_ids.get(name) {
            return id;
        }
        let id = LevelId::from_index(levels.len());
        levels.push(name.to_string());
        level_ids.insert(name.to_string(), id);
        id
    };

    // Turning pairs: no self-loops, no duplicates.
    let mut seen: HashMap<(LinkId, LinkId), String> = HashMap::new();
    let key = |a: LinkId, b: LinkId| if a < b { (a, b) } else { (b, a) };
    let mut revolutes = Vec::with_capacity(draft.revolutes.len());
    for r in &draft.revolutes {
        let a = ids[r.links[0].as_str()];
        let b = ids[r.links[1].as_str()];
        if a == b {
            return Err(Error::spec(
                format!("{}.links", r.path),
                SpecErrorKind::SelfLoop {
                    link: r.links[0].clone(),
                },
            ));
        }
        if let Some(first) = seen.insert(key(a, b), r.path.clone()) {
            return Err(Error::spec(
                r.path.clone(),
                SpecErrorKind::Duplicate {
                    first,
                    what: format!(
                        "a second turning pair between `{}` and `{}`",
                        r.links[0], r.links[1]
                    ),
                },
            ));
        }
        revolutes.push(Revolute {
            links: [a, b],
            level: level_id(&r.level),
        });
    }

    // Gear pairs.
    let mut seen_gear: HashMap<(LinkId, LinkId), String> = HashMap::new();
    let mut seen_name: HashMap<&str, &str> = HashMap::new();
    let mut gears = Vec::with_capacity(draft.gears.len());
    for g in &draft.gears {
        let gp = gear_pair(g, &ids)?;
        if gp.gear_i == gp.gear_j {
            return Err(Error::spec(
                format!("{}.links", g.path),
                SpecErrorKind::SelfLoop {
                    link: g.spec.links[0].clone(),
                },
            ));
        }
        if let Some(first) = seen_gear.insert(key(gp.gear_i, gp.gear_j), g.path.clone()) {
            return Err(Error::spec(
                g.path.clone(),
                SpecErrorKind::Duplicate {
                    first,
                    what: format!(
                        "a second gear pair between `{}` and `{}`",
                        g.spec.links[0], g.spec.links[1]
                    ),
                },
            ));
        }
        if let Some(first) = seen_name.insert(g.name.as_str(), g.path.as_str()) {
            return Err(Error::spec(
                format!("{}.name", g.path),
                SpecErrorKind::Duplicate {
                    first: first.to_string(),
                    what: format!("gear pair name `{}`", g.name),
                },
            ));
        }
        for (side, l) in [gp.gear_i, gp.gear_j].into_iter().enumerate() {
            if !links[l.index()].sized && !g.path.starts_with("planetary") {
                return Err(Error::invalid(
                    format!("{}.links[{side}]", g.path),
                    format!(
                        "planet `{}` has no tooth count in its planetary set; give `teeth.planet` there to mesh it elsewhere",
                        links[l.index()].name
                    ),
                ));
            }
        }
        gears.push(gp);
    }
    check_single_wheels(&links, &gears)?;

    // Offsets between levels.
    let mut offsets = Vec::new();
    for (n, o) in spec.offsets.iter().enumerate() {
        let path = format!("offsets[{n}]");
        let mut lv = [LevelId(0); 2];
        for (s, name) in o.levels.iter().enumerate() {
            lv[s] = match level_ids.get(name.as_str()) {
                Some(&id) => id,
                None => {
                    return Err(Error::invalid(
                        format!("{path}.levels[{s}]"),
                        format!(
                            "unknown axis level `{name}` (levels in use: {})",
                            levels.join(", ")
                        ),
                    ));
                }
            };
        }
        if lv[0] == lv[1] {
            return Err(Error::invalid(
                format!("{path}.levels"),
                "an offset joins two different levels",
            ));
        }
        offsets.push((
            lv[0],
            lv[1],
            positive(format!("{path}.distance"), o.distance)?,
        ));
    }

    // The typed graph: node i is link i.
    let mut graph =
        UnGraph::<LinkId, Edge>::with_capacity(links.len(), revolutes.len() + gears.len());
    for i in 0..links.len() {
        graph.add_node(LinkId::from_index(i));
    }
    for (i, r) in revolutes.iter().enumerate() {
        graph.add_edge(
            node(r.links[0]),
            node(r.links[1]),
            Edge::Revolute(RevoluteId::from_index(i)),
        );
    }
    for (i, g) in gears.iter().enumerate() {
        graph.add_edge(
            node(g.gear_i),
            node(g.gear_j),
            Edge::Gear(GearId::from_index(i)),
        );
    }

    // Clutches as pairs of links (a malformed element is reported later, by name).
    let clutches: Vec<[LinkId; 2]> = spec
        .elements
        .iter()
        .filter(|e| matches!(e.kind, ElementKind::Clutch | ElementKind::OneWayClutch))
        .filter_map(|e| match e.links.as_slice() {
            [a, b] => Some([*ids.get(a.as_str())?, *ids.get(b.as_str())?]),
            _ => None,
        })
        .collect();
    let topo = topology::analyse(
        &links, frame, &levels, &revolutes, &gears, &graph, &clutches,
    )?;

    let coordinates: Vec<LinkId> = (0..links.len())
        .map(LinkId::from_index)
        .filter(|&l| l != frame)
        .collect();
    let mut coord_of = vec![None; links.len()];
    for (c, l) in coordinates.iter().enumerate() {
        coord_of[l.index()] = Some(c);
    }

    let link_ids = links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.clone(), LinkId::from_index(i)))
        .collect();
    let mut train = Train {
        name: spec.name.clone(),
        links,
        link_ids,
        frame,
        levels,
        revolutes,
        gears,
        offsets,
        graph,
        tree: topo.tree,
        circuits: topo.circuits,
        dof: topo.dof,
        coordinates,
        coord_of,
        elements: Vec::new(),
        transmission: None,
        analysis: Analysis::default(),
        checks: topo.checks,
        design_warnings: Vec::new(),
    };
    resolve_extras(spec, &mut train)?;
    train.design_warnings = planetary_warnings(spec, &train);
    Ok(train)
}

/// The design warnings of the simple planetary sets of `spec` (see
/// [`Train::design_warnings`]).
fn planetary_warnings(spec: &Spec, train: &Train) -> Vec<String> {
    let mut out = Vec::new();
    for (i, set) in spec.planetary.iter().enumerate() {
        if set.kind != crate::spec::PlanetaryKind::Simple {
            continue;
        }
        let (Some(zs), Some(zr)) = (set.teeth.sun, set.teeth.ring) else {
            continue;
        };
        let at = format!("planetary[{i}] (`{}`)", set.name);
        if zr <= zs {
            out.push(format!(
                "{at}: the ring ({zr} teeth) is not larger than the sun ({zs}): no planet fits between them"
            ));
            continue;
        }
        if let Some(zp) = set.teeth.planet
            && zr != zs + 2 * zp
        {
            out.push(format!(
                "{at}: z_ring = {zr} differs from z_sun + 2 z_planet = {}: the planets are not coaxial unless the gears are profile-shifted",
                zs + 2 * zp
            ));
        }
        let planet = set
            .planet
            .clone()
            .unwrap_or_else(|| format!("{}.planet", set.name));
        let copies = train.link_id(&planet).map_or(1, |l| train.link(l).copies);
        if copies >= 2 && (zs + zr) % i64::from(copies) != 0 {
            out.push(format!(
                "{at}: (z_sun + z_ring) / n = ({zs} + {zr}) / {copies} is not an integer: {copies} equally spaced planets cannot be assembled"
            ));
        }
    }
    out
}

fn node(l: LinkId) -> NodeIndex {
    NodeIndex::new(l.index())
}

/// A link declared with a single wheel meshes with that one wheel everywhere.
fn check_single_wheels(links: &[Link], gears: &[GearPair]) -> Result<()> {
    for (li, link) in links.iter().enumerate() {
        if link.wheels != Some(1) {
            continue;
        }
        let mut first: Option<(&GearPair, Option<u32>, Option<f64>)> = None;
        for g in gears {
            let side = if g.gear_i.index() == li {
                0
            } else if g.gear_j.index() == li {
                1
            } else {
                continue;
            };
            let z = g.teeth.map(|t| t[side]);
            let r = g.radii.map(|r| r[side]);
            if let Some((g0, z0, r0)) = first {
                let z_clash = matches!((z0, z), (Some(a), Some(b)) if a != b);
                let r_clash =
                    matches!((r0, r), (Some(a), Some(b)) if (a - b).abs() > 1e-9 * a.abs());
                if z_clash || r_clash {
                    return Err(Error::invalid(
                        g.path.clone(),
                        format!(
                            "link `{}` has one wheel, but it has different teeth or radius here than in {}",
                            link.name, g0.path
                        ),
                    ));
                }
            } else {
                first = Some((g, z, r));
            }
        }
    }
    Ok(())
}

/// Resolve the names in shift elements, transmission and analysis data.
fn resolve_extras(spec: &Spec, train: &mut Train) -> Result<()> {
    let mut elements: Vec<ShiftElement> = Vec::new();
    for (n, e) in spec.elements.iter().enumerate() {
        let path = format!("elements[{n}]");
        if let Some(k) = elements.iter().position(|x| x.name == e.name) {
            return Err(Error::spec(
                format!("{path}.name"),
                SpecErrorKind::Duplicate {
                    first: format!("elements[{k}]"),
                    what: format!("element name `{}`", e.name),
                },
            ));
        }
        let want = match e.kind {
            ElementKind::Brake | ElementKind::OneWayBrake => 1,
            ElementKind::Clutch | ElementKind::OneWayClutch => 2,
        };
        if e.links.len() != want {
            return Err(Error::invalid(
                format!("{path}.links"),
                format!("a {:?} takes {want} link(s), got {}", e.kind, e.links.len()),
            ));
        }
        let links = e
            .links
            .iter()
            .enumerate()
            .map(|(s, l)| train.resolve(l, &format!("{path}.links[{s}]")))
            .collect::<Result<Vec<_>>>()?;
        if links.contains(&train.frame) {
            return Err(Error::invalid(
                format!("{path}.links"),
                "name the held link; the frame is implied for a brake",
            ));
        }
        if want == 2 && links[0] == links[1] {
            return Err(Error::spec(
                format!("{path}.links"),
                SpecErrorKind::SelfLoop {
                    link: e.links[0].clone(),
                },
            ));
        }
        elements.push(ShiftElement {
            name: e.name.clone(),
            kind: e.kind,
            links,
        });
    }
    train.elements = elements;

    if let Some(t) = &spec.transmission {
        let input = train.resolve(&t.input, "transmission.input")?;
        let output = train.resolve(&t.output, "transmission.output")?;
        let mut states = Vec::new();
        for (name, engaged) in &t.states {
            let path = format!("transmission.states.{name}");
            let mut ids = Vec::new();
            for (s, e) in engaged.iter().enumerate() {
                let id = train
                    .elements
                    .iter()
                    .position(|x| &x.name == e)
                    .ok_or_else(|| {
                        Error::invalid(
                            format!("{path}[{s}]"),
                            format!(
                                "unknown shift element `{e}`{}",
                                suggest(e, train.elements.iter().map(|x| x.name.as_str()))
                                    .map(|s| format!(" (did you mean `{s}`?)"))
                                    .unwrap_or_default()
                            ),
                        )
                    })?;
                let id = ElementId::from_index(id);
                if ids.contains(&id) {
                    return Err(Error::invalid(
                        format!("{path}[{s}]"),
                        format!("element `{e}` is listed twice"),
                    ));
                }
                ids.push(id);
            }
            states.push(GearState {
                name: name.clone(),
                engaged: ids,
            });
        }
        train.transmission = Some(Transmission {
            input,
            output,
            states,
        });
    }

    if let Some(a) = &spec.analysis {
        let mut out = Analysis::default();
        for (name, v) in &a.speeds {
            let path = format!("analysis.speeds.{name}");
            let l = train.resolve(name, &path)?;
            let (value, exact) = match v {
                // A decimal written in the spec is read as the decimal the user
                // wrote (its shortest round-trip form), not as the binary value
                // of the double: 0.1 is 1/10, not 3602879701896397/2^55.
                RatioSpec::Number(x) => (
                    finite(path, *x)?,
                    exact::parse_rational(&x.to_string())
                        .ok()
                        .or_else(|| exact::from_f64(*x)),
                ),
                RatioSpec::Text(t) => {
                    let (q, value) = exact::parse_finite(t)
                        .map_err(|e| Error::invalid(&path, format!("`{t}`: {e}")))?;
                    (value, Some(q))
                }
            };
            out.speeds.push((l, value, exact));
        }
        for (name, v) in &a.torques {
            let path = format!("analysis.torques.{name}");
            out.torques
                .push((train.resolve(name, &path)?, finite(path, *v)?));
        }
        for (name, v) in &a.accelerations {
            let path = format!("analysis.accelerations.{name}");
            out.accelerations
                .push((train.resolve(name, &path)?, finite(path, *v)?));
        }
        for (k, name) in a.driving.iter().enumerate() {
            out.driving
                .push(train.resolve(name, &format!("analysis.driving[{k}]"))?);
        }
        for (name, v) in &a.angles {
            let path = format!("analysis.angles.{name}");
            out.angles
                .push((train.resolve(name, &path)?, finite(path, *v)?));
        }
        if let Some(r) = &a.reduce_to {
            out.reduce_to = Some(train.resolve(r, "analysis.reduce_to")?);
        }
        for (k, c) in a.curves.iter().enumerate() {
            let path = format!("analysis.curves[{k}]");
            out.curves.push(Curve {
                link: train.resolve(&c.link, &format!("{path}.link"))?,
                torque: finite(format!("{path}.torque"), c.torque)?,
                slope: finite(format!("{path}.slope"), c.slope)?,
                speed: finite(format!("{path}.speed"), c.speed)?,
            });
        }
        if let Some(s) = &a.simulate {
            let mut initial = Vec::new();
            for (name, v) in &s.initial {
                let path = format!("analysis.simulate.initial.{name}");
                initial.push((train.resolve(name, &path)?, finite(path, *v)?));
            }
            out.simulate = Some(Simulate {
                t_end: s
                    .t_end
                    .map(|v| positive("analysis.simulate.t_end".into(), v))
                    .transpose()?,
                dt: s
                    .dt
                    .map(|v| positive("analysis.simulate.dt".into(), v))
                    .transpose()?,
                method: s.method.clone(),
                initial,
            });
        }
        train.analysis = out;
    }
    Ok(())
}
