//! Concept search (`[concept]` in a search spec): the transmission's
//! structure is searched too. Every structure of the space (structures.rs),
//! each once up to relabelling interchangeable sets, has its element layouts
//! judged state by state over the whole box of basic ratios (layouts.rs);
//! the survivors' teeth are found by the tooth search (`design::search`),
//! and all candidates are ranked together.

mod layouts;
mod options;
mod structures;
mod train;

#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use serde::{Deserialize, Serialize};

use crate::design::search::{
    Candidate, Incumbent, MAX_LAYOUTS, Search, SetSpace, Stats, check_numbers, check_partition,
    merge, rank, write_teeth,
};
use crate::design::spec::{ConceptSpec, SynthSpec};
use crate::error::DesignError;
use crate::spec::{ElementKind, PlanetaryKind, Spec};

use layouts::{DimBox, Layouts, Problem};
pub use options::ToothOption;
pub use structures::Structure;
use structures::{SetSlot, Space, roles, willis_rows};

/// A layout as a candidate reports it: element -> links.
type Layout = Vec<(String, Vec<String>)>;

/// Most members (of all sets together) a concept may have.
pub const MAX_MEMBERS: usize = 24;

/// Most tooth options a concept may list (`concept.options`).
pub const MAX_OPTIONS: usize = 1000;

/// Most sets a concept may have (the relabellings are tried one by one).
pub const MAX_SETS: usize = 6;

/// A candidate's structure, as a concept search reports it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConceptInfo {
    /// The free shafts, each named by its members (`P1.carrier=P4.ring`;
    /// `input` for a separate input shaft).
    pub shafts: Vec<String>,
    /// Members held by the case.
    pub held: Vec<String>,
    /// The input and output shafts.
    pub input: String,
    /// The output shaft.
    pub output: String,
    /// Per element whose position has equivalents (a clutch joining another
    /// two members of a set it locks: the same transmission), those positions.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub equivalent_positions: Vec<(String, Vec<Vec<String>>)>,
    /// Other layouts of this structure that make the same shafts turn
    /// together (or held) in every gear state: the same transmission.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub equivalent_layouts: Vec<Vec<(String, Vec<String>)>>,
    /// This concept's other tooth sets meeting the targets (other basic
    /// ratios), best first, at most `concept.options`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tooth_options: Vec<ToothOption>,
    /// The search for `tooth_options` stopped at `concept.max_nodes`: the
    /// list may miss some.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub tooth_options_cut: bool,
    /// The structure itself (member ids), to rebuild the train.
    pub structure: Structure,
}

/// A prepared concept search.
#[derive(Debug, Clone)]
pub struct Concepts {
    spec: SynthSpec,
    concept: ConceptSpec,
    sets: Vec<SetSlot>,
    structures: Vec<Structure>,
    problem: Problem,
    cache: HashMap<String, SetSpace>,
    members: Vec<String>,
    cancel: Option<Arc<AtomicBool>>,
}

impl Concepts {
    /// Check a concept search spec and list its structures.
    ///
    /// # Errors
    /// [`DesignError`] naming the offending field.
    pub fn new(spec: SynthSpec) -> Result<Concepts, DesignError> {
        let bad = |field: &str, message: String| DesignError::Invalid {
            field: field.into(),
            message,
        };
        let concept = spec
            .concept
            .clone()
            .ok_or_else(|| bad("concept", "a concept search needs [concept]".into()))?;
        if !spec.base.is_empty() {
            return Err(bad(
                "base",
                "a concept search builds its own trains from [concept]; give no base".into(),
            ));
        }
        if !spec.layout.is_empty() {
            return Err(bad(
                "layout",
                "a concept search places every element itself; give no [layout]".into(),
            ));
        }
        check_numbers(&spec)?;
        if concept.options > MAX_OPTIONS {
            return Err(bad(
                "concept.options",
                format!("list at most {MAX_OPTIONS} tooth options per concept"),
            ));
        }
        if concept.sets.is_empty() || concept.sets.len() > MAX_SETS {
            return Err(bad("concept.sets", format!("give 1 to {MAX_SETS} sets")));
        }
        for name in spec.sets.keys() {
            if !concept.sets.contains_key(name) {
                return Err(DesignError::UnknownSet(name.clone()));
            }
        }
        let mut sets = Vec::new();
        let mut members = Vec::new();
        let mut cache = HashMap::new();
        let mut classes: Vec<(PlanetaryKind, &crate::design::SetRange)> = Vec::new();
        for (name, &kind) in &concept.sets {
            if !matches!(
                kind,
                PlanetaryKind::Simple
                    | PlanetaryKind::DoublePinion
                    | PlanetaryKind::Stepped
                    | PlanetaryKind::Ravigneaux
            ) {
                return Err(bad(
                    &format!("concept.sets.{name}"),
                    "a concept's sets are simple, double_pinion, stepped or ravigneaux".into(),
                ));
            }
            let range = spec.sets.get(name).ok_or_else(|| {
                bad(
                    &format!("sets.{name}"),
                    "give this set's tooth ranges (sun, ring; sun2 for a Ravigneaux set, planet for a stepped one)".into(),
                )
            })?;
            let class = classes
                .iter()
                .position(|&(k, r)| k == kind && r == range)
                .unwrap_or_else(|| {
                    classes.push((kind, range));
                    classes.len() - 1
                });
            sets.push(SetSlot {
                first: members.len(),
                kind,
                class,
            });
            for role in roles(kind) {
                members.push(format!("{name}.{role}"));
            }
            cache.insert(
                name.clone(),
                SetSpace::new(name, kind, range, &spec.constraints)?,
            );
        }
        if members.len() > MAX_MEMBERS {
            return Err(bad(
                "concept.sets",
                format!(
                    "{} members; a concept may have at most {MAX_MEMBERS}",
                    members.len()
                ),
            ));
        }
        let elements: Vec<(&String, ElementKind)> =
            concept.elements.iter().map(|(n, &k)| (n, k)).collect();
        if elements.is_empty() {
            return Err(bad("concept.elements", "give the shift elements".into()));
        }
        if concept.states.is_empty() {
            return Err(bad("concept.states", "give the gear states".into()));
        }
        let mut engaged_count = None;
        let mut states = Vec::new();
        for (state, engaged) in &concept.states {
            let field = format!("concept.states.{state}");
            let mut ids = Vec::new();
            for e in engaged {
                let id = elements.iter().position(|(n, _)| *n == e).ok_or_else(|| {
                    bad(
                        &field,
                        format!("`{e}` is not an element of concept.elements"),
                    )
                })?;
                if ids.contains(&id) {
                    return Err(bad(&field, format!("`{e}` is engaged twice")));
                }
                ids.push(id);
            }
            match engaged_count {
                None => engaged_count = Some(ids.len()),
                Some(k) if k != ids.len() => {
                    return Err(bad(
                        &field,
                        format!(
                            "engages {} elements where the first state engages {k}: each state of a concept engages as many, one per DOF above one",
                            ids.len()
                        ),
                    ));
                }
                Some(_) => {}
            }
            let window = spec.targets.ratios.get(state).and_then(|&t| {
                let tol = spec.targets.tolerance;
                let (a, b) = (t - tol, t + tol);
                if a <= 0.0 && b >= 0.0 {
                    return None;
                }
                let (lo, hi) = (1.0 / b, 1.0 / a);
                Some((lo.min(hi), lo.max(hi)))
            });
            states.push((ids, window));
        }
        for s in spec.targets.ratios.keys() {
            if !concept.states.contains_key(s) {
                return Err(DesignError::UnknownState(s.clone()));
            }
        }
        let [hmin, hmax] = concept.held;
        if hmin > hmax {
            return Err(bad(
                "concept.held",
                "need [min, max] with min <= max".into(),
            ));
        }
        // The searched dimensions and Willis rows, set by set.
        let mut dims = Vec::new();
        let mut willis = Vec::new();
        let mut set_of = Vec::new();
        for (i, (name, slot)) in concept.sets.keys().zip(&sets).enumerate() {
            let space = &cache[name];
            let f = slot.first;
            let d = dims.len();
            for dim in &space.dims {
                let ks = &dim.ks;
                let lo = ks.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = ks.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                if ks.is_empty() {
                    return Err(bad(
                        &format!("sets.{name}"),
                        "no tooth set in these ranges meets the constraints".into(),
                    ));
                }
                // Two generic values per dimension, different for each
                // (sets of one range must not get equal ratios: k_a = k_b
                // is where some states are singular), no tooth ratio.
                let at = |f: f64| lo + (0.2 + 0.6 * f.fract()) * (hi - lo);
                let i = dims.len() as f64;
                dims.push(DimBox {
                    lo,
                    hi,
                    sign: dim.sign,
                    picks: [at(0.381_966 + 0.618_034 * i), at(0.723_607 + 0.414_214 * i)],
                });
            }
            if slot.kind == PlanetaryKind::Ravigneaux {
                willis.push((f, f + 2, f + 3, d));
                willis.push((f + 1, f + 2, f + 3, d + 1));
            } else {
                willis.push((f, f + 1, f + 2, d));
            }
            set_of.extend(std::iter::repeat_n(i, roles(slot.kind).len()));
        }
        let dof = engaged_count.unwrap_or(0) + 1;
        let space = Space {
            sets: sets.clone(),
            members: members.len(),
            dof,
            input: concept.input,
            held: concept.held,
        };
        let structures = space.structures(concept.max_structures).ok_or_else(|| {
            DesignError::Egt(
                crate::AnalysisError::Budget {
                    what: "the concept search's structure space".into(),
                    estimate: format!("more than {} structures", concept.max_structures),
                    limit: format!("{} structures", concept.max_structures),
                    raise: "hold fewer members (`concept.held`), fix the input (`concept.input`), or raise `concept.max_structures`".into(),
                }
                .into(),
            )
        })?;
        if structures.is_empty() {
            let w: usize = sets.iter().map(|s| willis_rows(s.kind)).sum();
            return Err(bad(
                "concept",
                format!(
                    "no structure has {dof} DOF ({} engaged per state, plus one): {} members and {w} Willis rows, with held members in {hmin}..={hmax} and the input as {:?}",
                    dof - 1,
                    members.len(),
                    concept.input
                ),
            ));
        }
        let mut problem = Problem {
            elements: elements
                .iter()
                .map(|(_, k)| {
                    (
                        matches!(k, ElementKind::OneWayBrake | ElementKind::OneWayClutch),
                        matches!(k, ElementKind::Brake | ElementKind::OneWayBrake),
                    )
                })
                .collect(),
            states,
            dims,
            willis,
            set_of,
            order: Vec::new(),
            completes: Vec::new(),
        };
        problem.plan();
        Ok(Concepts {
            spec,
            concept,
            sets,
            structures,
            problem,
            cache,
            members,
            cancel: None,
        })
    }

    /// Stop runs soon after `flag` is set (as [`Search::with_cancel`]).
    #[must_use]
    pub fn with_cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }

    fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// The structures searched, in order.
    pub fn structures(&self) -> &[Structure] {
        &self.structures
    }

    /// How many of the best candidates a run keeps.
    pub fn top(&self) -> usize {
        self.spec.top
    }

    /// The sets, in the order of each candidate's lists.
    pub fn set_names(&self) -> Vec<String> {
        self.concept.sets.keys().cloned().collect()
    }

    /// The train of a candidate (its structure, layout and teeth).
    ///
    /// # Errors
    /// [`DesignError`] when the candidate has no structure.
    pub fn candidate_spec(&self, c: &Candidate) -> Result<Spec, DesignError> {
        let info = c.concept.as_ref().ok_or_else(|| DesignError::Invalid {
            field: "candidate".into(),
            message: "not a concept search's candidate".into(),
        })?;
        let mut spec = self.train(&info.structure, &c.layout);
        write_teeth(&mut spec, &self.set_names(), &c.teeth);
        Ok(spec)
    }

    /// Run structures `part`, `part + parts`, ... (disjoint, covering).
    ///
    /// # Errors
    /// [`DesignError::Invalid`] for a bad partition; a budget error.
    pub fn run_partition(
        &self,
        part: usize,
        parts: usize,
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        let (mut found, stats) = self.run_part(part, parts)?;
        self.add_tooth_options(&mut found)?;
        Ok((found, stats))
    }

    /// [`Concepts::run_partition`] without the tooth options.
    fn run_part(&self, part: usize, parts: usize) -> Result<(Vec<Candidate>, Stats), DesignError> {
        check_partition(part, parts)?;
        use rayon::prelude::*;
        let ids: Vec<usize> = (part..self.structures.len()).step_by(parts).collect();
        let incumbent = Arc::new(Incumbent::new(self.spec.top));
        let results: Vec<Result<(Vec<Candidate>, Stats), DesignError>> = ids
            .par_iter()
            .map(|&i| self.run_structure(i, &incumbent))
            .collect();
        let mut done = Vec::new();
        for r in results {
            done.push(r?);
        }
        let (found, mut stats) = merge(done, self.spec.top);
        self.space_counts(&mut stats);
        stats.interrupted = self.cancelled();
        Ok((found, stats))
    }

    /// Run the whole space as `parts` partitions one after another,
    /// calling `progress(done, parts, best)` after each (as
    /// [`Search::run_in_parts`]).
    ///
    /// # Errors
    /// As [`Concepts::run_partition`].
    pub fn run_in_parts(
        &self,
        parts: usize,
        mut progress: impl FnMut(usize, usize, &[Candidate]),
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        let parts = parts.clamp(1, self.structures.len().max(1));
        let mut best: Vec<Candidate> = Vec::new();
        let mut done = Vec::with_capacity(parts);
        // The options of the merged best only, once at the end.
        for part in 0..parts {
            let (found, stats) = self.run_part(part, parts)?;
            let stop = stats.interrupted;
            best.extend(found.iter().cloned());
            rank(&mut best, self.spec.top);
            done.push((found, stats));
            if stop {
                break;
            }
            progress(part + 1, parts, &best);
        }
        let (mut found, mut stats) = merge(done, self.spec.top);
        self.add_tooth_options(&mut found)?;
        self.space_counts(&mut stats);
        Ok((found, stats))
    }

    /// Run the whole space on all cores.
    ///
    /// # Errors
    /// As [`Concepts::run_partition`].
    pub fn run(&self) -> Result<(Vec<Candidate>, Stats), DesignError> {
        self.run_partition(0, 1)
    }

    /// The whole search's counts: its structures and each structure's tooth
    /// and ratio spaces (the same for all).
    fn space_counts(&self, stats: &mut Stats) {
        stats.structures = self.structures.len() as u64;
        stats.tooth_space = self
            .cache
            .values()
            .map(|s| s.teeth.values().map(|t| t.len() as f64).sum::<f64>())
            .product();
        stats.ratio_space = self.cache.values().map(|s| s.teeth.len() as f64).product();
    }

    /// One structure: its layouts judged, then the tooth search over the
    /// layouts left, each layout (a concept) reporting its best teeth.
    fn run_structure(
        &self,
        i: usize,
        incumbent: &Arc<Incumbent>,
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        // `structures` set marks a concept search's counts for `merge`.
        let mut stats = Stats {
            structures: 1,
            ..Stats::default()
        };
        if self.cancelled() {
            return Ok((Vec::new(), stats));
        }
        let s = &self.structures[i];
        let Some(j) = self.judge(s, &mut stats) else {
            return Ok((Vec::new(), stats));
        };
        stats.structures_searched = 1;
        let picks = j.picks.iter().map(|(p, _)| p.clone()).collect();
        let Some(search) = self.tooth_search(s, &j, picks, self.spec.top)? else {
            return Ok((Vec::new(), stats));
        };
        let (mut found, inner) = search
            .with_incumbent(incumbent.clone())
            .best_per_layout(i as u64)
            .run()?;
        stats.layouts = inner.layouts;
        stats.nodes = inner.nodes;
        stats.leaves = inner.leaves;
        stats.rejected = inner.rejected;
        stats.cut = inner.cut;
        let elements: Vec<&String> = self.concept.elements.keys().collect();
        for c in &mut found {
            let mut equivalent = Vec::new();
            for (e, name) in elements.iter().enumerate() {
                let Some(placed) = c.layout.iter().find(|(n, _)| n == *name) else {
                    continue;
                };
                let opt = j.lay.opts(e).iter().find(|o| j.link(o) == placed.1);
                if let Some(o) = opt
                    && !o.variants.is_empty()
                {
                    equivalent.push((
                        (*name).clone(),
                        o.variants
                            .iter()
                            .map(|&(a, b)| vec![j.names[a].clone(), j.names[b].clone()])
                            .collect(),
                    ));
                }
            }
            let equivalent_layouts = j
                .picks
                .iter()
                .find(|(p, _)| j.named(p) == c.layout)
                .map(|(_, same)| same.iter().map(|p| j.named(p)).collect())
                .unwrap_or_default();
            c.concept = Some(ConceptInfo {
                shafts: j.names.clone(),
                held: s
                    .held
                    .iter()
                    .map(|&m| self.members[m as usize].clone())
                    .collect(),
                input: j.names[s.input].clone(),
                output: j.names[s.output].clone(),
                equivalent_positions: equivalent,
                equivalent_layouts,
                tooth_options: Vec::new(),
                tooth_options_cut: false,
                structure: s.clone(),
            });
        }
        rank(&mut found, self.spec.top);
        Ok((found, stats))
    }

    /// A structure's layouts judged state by state (None: no layout left).
    fn judge<'a>(&'a self, s: &'a Structure, stats: &mut Stats) -> Option<Judged<'a>> {
        let mut lay = Layouts::new(&self.problem, s)?;
        let picks = lay.run(MAX_LAYOUTS);
        stats.skipped_layouts = lay.idle;
        stats.states_checked = lay.checked;
        if picks.is_empty() {
            return None;
        }
        let names = self.shaft_names(s);
        let choices = (0..self.problem.elements.len())
            .map(|e| lay.opts(e).iter().map(|o| link(&names, o)).collect())
            .collect();
        Some(Judged {
            lay,
            names,
            choices,
            elements: self.concept.elements.keys().cloned().collect(),
            picks,
        })
    }

    /// The tooth search over `picks` of a judged structure, keeping `top`
    /// (None: egt refuses the structure's train, e.g. a locked sub-chain
    /// for every layout).
    fn tooth_search(
        &self,
        s: &Structure,
        j: &Judged<'_>,
        picks: Vec<Vec<u32>>,
        top: usize,
    ) -> Result<Option<Search>, DesignError> {
        let Some(first) = picks.first() else {
            return Ok(None);
        };
        let mut sub = self.sub_spec(j.choices.clone());
        sub.top = top;
        let base = self.train(s, &j.named(first));
        let search = match Search::build(sub, base, Some(&self.cache), Some(picks)) {
            Ok(search) => search,
            Err(DesignError::Egt(_)) => return Ok(None),
            Err(e) => return Err(e),
        };
        let search = match &self.cancel {
            Some(f) => search.with_cancel(f.clone()),
            None => search,
        };
        Ok(Some(search.with_node_limit(self.concept.max_nodes)))
    }

    /// The search spec of one structure: the concept's sets, targets and
    /// constraints, every element free over `choices`.
    fn sub_spec(&self, choices: Vec<Vec<Vec<String>>>) -> SynthSpec {
        let mut sub = self.spec.clone();
        sub.concept = None;
        sub.layout = self
            .concept
            .elements
            .keys()
            .zip(choices)
            .map(|(n, c)| (n.clone(), crate::design::Placement::Choices(c)))
            .collect();
        sub
    }

    fn shaft_names(&self, s: &Structure) -> Vec<String> {
        train::shaft_names(s, &self.members)
    }

    fn train(&self, s: &Structure, layout: &[(String, Vec<String>)]) -> Spec {
        train::train(&self.concept, &self.sets, &self.members, s, layout)
    }
}

/// A structure's layouts left after the state checks, with their names.
struct Judged<'a> {
    lay: Layouts<'a>,
    /// The shafts' names.
    names: Vec<String>,
    /// Per element, its options' links.
    choices: Vec<Vec<Vec<String>>>,
    /// The elements' names.
    elements: Vec<String>,
    /// Each layout kept, with the layouts equivalent to it.
    picks: Vec<(Vec<u32>, Vec<Vec<u32>>)>,
}

impl Judged<'_> {
    /// A layout as a candidate names it.
    fn named(&self, pick: &[u32]) -> Layout {
        self.elements
            .iter()
            .zip(pick)
            .zip(&self.choices)
            .map(|((n, &k), c)| (n.clone(), c[k as usize].clone()))
            .collect()
    }

    fn link(&self, o: &layouts::Opt) -> Vec<String> {
        link(&self.names, o)
    }
}

/// An option's links by shaft name.
fn link(names: &[String], o: &layouts::Opt) -> Vec<String> {
    std::iter::once(o.a)
        .chain(o.b)
        .map(|x| names[x].clone())
        .collect()
}
