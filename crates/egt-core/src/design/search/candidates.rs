//! Candidates and their ranking: what a search returns, its counts, and
//! the merge of partitions' results.

use serde::{Deserialize, Serialize};

use super::space::Teeth;

/// One candidate returned by the search (it reads back from its serde form,
/// so that partitions run elsewhere can be merged by [`merge`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Candidate {
    /// Per unknown set (in spec order): the basic ratio ring/sun as a fraction.
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
    /// Leaves (full ratio vectors) evaluated.
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
        total.layouts = s.layouts;
        total.skipped_layouts = s.skipped_layouts;
        total.nodes += s.nodes;
        total.leaves += s.leaves;
        total.rejected += s.rejected;
        total.interrupted |= s.interrupted;
    }
    rank(&mut found, top);
    (found, total)
}

/// Sort by score (then by the teeth, so that the order is canonical) and keep `top`.
pub fn rank(c: &mut Vec<Candidate>, top: usize) {
    c.sort_by(|a, b| {
        a.score.total_cmp(&b.score).then_with(|| {
            let ka: Vec<_> = a.teeth.iter().map(|t| (t.sun, t.sun2, t.ring)).collect();
            let kb: Vec<_> = b.teeth.iter().map(|t| (t.sun, t.sun2, t.ring)).collect();
            ka.cmp(&kb).then_with(|| a.layout.cmp(&b.layout))
        })
    });
    c.truncate(top);
}
