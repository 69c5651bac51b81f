//! Candidates and their ranking: what a search returns, its counts, and
//! the merge of partitions' results.

use serde::{Deserialize, Serialize};

use super::space::Teeth;

/// One candidate returned by the search (it reads back from its serde form,
/// so that partitions run elsewhere can be merged by [`merge`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Candidate {
    /// Per unknown set (in spec order): the basic ratio k as a fraction
    /// ([`Teeth::basic`]: ring/sun, or ring planet/(sun planet2) for a stepped planet).
    pub basic: Vec<String>,
    /// Per unknown set: ring/large sun of a Ravigneaux set (None for a simple set).
    pub basic2: Vec<Option<String>>,
    /// Per unknown set: the smallest-sun teeth giving those basic ratios.
    pub teeth: Vec<Teeth>,
    /// Per unknown set: how many admissible tooth sets give the same basic
    /// ratios (and so the same gear ratios).
    pub alternatives: Vec<usize>,
    /// Per gear state (base order): name, ratio (float), exact ratio.
    pub ratios: Vec<(String, f64, String)>,
    /// Spread of the forward ratios.
    pub spread: Option<f64>,
    /// Freed elements' links in this candidate's layout (empty without `[layout]`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layout: Vec<(String, Vec<String>)>,
    /// Score: root mean square of (ratio - target) / target over the targeted states. Lower is better.
    pub score: f64,
    /// Per unknown set: every admissible tooth set with the same basic
    /// ratios (the first is `teeth`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub same_ratio_teeth: Vec<Vec<Teeth>>,
    /// Lowest efficiency over the targeted states (the mesh efficiencies
    /// given; 1 where none), from the exact analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub efficiency: Option<f64>,
    /// Largest |engaged element torque| per unit input torque over the
    /// targeted states, from the exact analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub element_torque: Option<f64>,
    /// Largest |mesh multiplier| (the torque on a mesh's first gear) per
    /// unit input torque over the targeted states, from the exact analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_torque: Option<f64>,
    /// Largest |planet speed relative to its carrier| per unit input speed
    /// over the targeted states (the planet bearings' duty), from the exact
    /// analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet_speed: Option<f64>,
    /// A concept search's structure of this candidate (None in a tooth search).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub concept: Option<crate::design::concept::ConceptInfo>,
}

/// Counts of a finished search.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Stats {
    /// Product of the per-set counts of admissible tooth triples (the naive space).
    pub tooth_space: f64,
    /// Product of the per-set counts of distinct basic ratios (pairs of them
    /// for a Ravigneaux set): the searched space.
    pub ratio_space: f64,
    /// Branch-and-bound nodes visited.
    pub nodes: u64,
    /// Leaves (full ratio vectors) that passed the float check, each then
    /// confirmed by an exact analysis (what `max_leaves` bounds).
    pub leaves: u64,
    /// Leaves that met the ratio targets but failed a target only the exact
    /// analysis can check (steps, progression, efficiency, element or mesh torque).
    #[serde(default)]
    pub rejected: u64,
    /// Element layouts searched (1 without `[layout]`).
    #[serde(default)]
    pub layouts: u64,
    /// Layouts skipped before the search (see `egt synth` docs: doubled
    /// elements, states that are not one DOF, singular states).
    #[serde(default)]
    pub skipped_layouts: u64,
    /// The run was stopped before it searched the whole space
    /// ([`Search::with_cancel`](super::Search::with_cancel)): the candidates
    /// are exact but the best of the part searched only. Absent from the
    /// serde form when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub interrupted: bool,
    /// A concept search: structures in the space (each once, up to
    /// relabelling interchangeable sets).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub structures: u64,
    /// A concept search: structures with a layout left to search after
    /// the gear states were checked over the whole box of ratios.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub structures_searched: u64,
    /// Searches stopped at their node limit (a concept search's structures
    /// whose tooth search took more than `concept.max_nodes` nodes): their
    /// candidates are exact, but their spaces were not all searched.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub cut: u64,
    /// A concept search: distinct gear-state systems checked.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub states_checked: u64,
}

fn is_zero(x: &u64) -> bool {
    *x == 0
}

/// Partitions' results as one search's: the candidates ranked together
/// ([`rank`]) and the counts summed (the spaces are the whole search's).
pub fn merge(parts: Vec<(Vec<Candidate>, Stats)>, top: usize) -> (Vec<Candidate>, Stats) {
    let mut found = Vec::new();
    let mut total = Stats::default();
    for (c, s) in parts {
        found.extend(c);
        // The spaces and layouts are the whole search's in every partition.
        total.tooth_space = s.tooth_space;
        total.ratio_space = s.ratio_space;
        if s.structures > 0 || s.structures_searched > 0 {
            // A concept search's parts count their own structures' layouts.
            total.layouts += s.layouts;
            total.skipped_layouts += s.skipped_layouts;
        } else {
            total.layouts = s.layouts;
            total.skipped_layouts = s.skipped_layouts;
        }
        total.structures = s.structures;
        total.structures_searched += s.structures_searched;
        total.states_checked += s.states_checked;
        total.cut += s.cut;
        total.nodes += s.nodes;
        total.leaves += s.leaves;
        total.rejected += s.rejected;
        total.interrupted |= s.interrupted;
    }
    rank(&mut found, top);
    (found, total)
}

/// `x` to 9 significant digits: the analysis keys of one concept computed
/// through different but equivalent trains differ in the last bits (the
/// 8HP's three concepts' mesh torques 1.4454946439823564, ..566, ..568),
/// which must not decide their order. Rounding keeps the order total.
fn key9(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(8 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// Sort and keep `top`: by the ratio error (score), then the higher lowest
/// efficiency, the smaller largest element torque, the smaller largest mesh
/// torque, the slower fastest planet (each to 9 significant digits), the
/// fewer shafts (a concept), then by the teeth, layout and structure, so
/// that the order is canonical.
pub fn rank(c: &mut Vec<Candidate>, top: usize) {
    let shafts = |x: &Candidate| x.concept.as_ref().map_or(0, |k| k.shafts.len());
    let keys = |x: &Candidate| {
        [
            -key9(x.efficiency.unwrap_or(1.0)),
            key9(x.element_torque.unwrap_or(0.0)),
            key9(x.mesh_torque.unwrap_or(0.0)),
            key9(x.planet_speed.unwrap_or(0.0)),
        ]
    };
    c.sort_by(|a, b| {
        a.score
            .total_cmp(&b.score)
            .then_with(|| {
                let (ka, kb) = (keys(a), keys(b));
                ka.iter()
                    .zip(&kb)
                    .map(|(x, y)| x.total_cmp(y))
                    .find(|o| o.is_ne())
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .then_with(|| shafts(a).cmp(&shafts(b)))
            .then_with(|| {
                let key = |x: &Candidate| -> Vec<_> {
                    x.teeth
                        .iter()
                        .map(|t| (t.sun, t.sun2, t.ring, t.planet, t.planet2))
                        .collect()
                };
                let (ka, kb) = (key(a), key(b));
                ka.cmp(&kb)
            })
            .then_with(|| a.layout.cmp(&b.layout))
            .then_with(|| {
                let k = |x: &Candidate| x.concept.as_ref().map(|k| k.structure.clone());
                k(a).cmp(&k(b))
            })
    });
    c.truncate(top);
}
