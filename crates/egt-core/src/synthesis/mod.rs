//! Structural synthesis: the atlas of non-isomorphic geared kinematic chains
//! (epicyclic gear train graphs) with a given number of links and degree of
//! freedom, at two levels:
//!
//! - **rotation graphs** (r-graphs): links, turning pairs and gear pairs, axis
//!   levels left out; a graph is in the atlas when at least one level
//!   assignment makes it a valid chain;
//! - **displacement graphs** (d-graphs): the same with the axis levels, i.e.
//!   with the carrier (transfer vertex) of every gear pair chosen.
//!
//! Neither level distinguishes the frame. Each member is checked by egt's own
//! topology checks (`Train::from_spec`: tree of turning pairs, one transfer
//! vertex per circuit, planarity, no locked, redundant or fractionated
//! sub-chain, Gruebler-Kutzbach F, paper eq. (1)). See docs/atlas.md.

pub mod canon;
pub mod graph;
pub mod hypertree;
pub mod levels;
pub mod trees;
mod validity;

use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use crate::Train;
use crate::error::{Error, Result};
use canon::{Code, Extra, canonical};
use graph::{ChainGraph, Joint, MAX_LINKS};
use levels::{Candidate, Tree, bfs_tree, rotation_graph};
use validity::{checked_form, has_cut_link};
#[cfg(test)]
use validity::{egt_check, has_rigid_subchain};

/// Which graphs are counted as distinct.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GraphLevel {
    /// Rotation graphs: levels unlabelled.
    Rotation,
    /// Displacement graphs: with the axis levels.
    Displacement,
}

/// Which sense of "fractionated" rejects a chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Fractionation {
    /// As `egt check`: a link whose removal splits the graph of some bearing
    /// layout into moving parts; a chain passes when some layout passes.
    #[default]
    Layout,
    /// Kinematic (Tsai & Lin's non-fractionated trains): also reject a chain
    /// whose rotation graph has a cut link, whatever the bearings. Stricter
    /// for two or more DOF; the same for one DOF.
    Kinematic,
}

/// What to enumerate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AtlasRequest {
    /// Number of links (vertices), frame included.
    pub links: usize,
    /// Degree of freedom (Gruebler-Kutzbach, paper eq. (1)): gear pairs = links - 1 - dof.
    pub dof: usize,
    /// Rotation or displacement graphs.
    pub level: GraphLevel,
    /// Only turning-pair trees `part.0` of every `part.1` (0-based): partitions
    /// of the search that can run on separate machines; their outputs are
    /// disjoint and together make the whole atlas.
    pub part: Option<(usize, usize)>,
    /// Which sense of fractionation rejects a chain.
    pub fractionation: Fractionation,
}

/// One member of the atlas.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct AtlasMember {
    /// The compact adjacency form (`1-2:a 1-3:G ...`), links named 1..n, frame-free.
    pub adjacency: String,
    /// Number of links.
    pub links: usize,
    /// Degree of freedom.
    pub dof: usize,
    /// The level this member was counted at.
    pub level: GraphLevel,
    /// Number of gear pairs.
    pub gears: usize,
    /// Number of distinct carriers (transfer vertices) in the emitted level assignment.
    pub carriers: usize,
    /// Number of distinct axis levels in the emitted level assignment.
    pub axes: usize,
    /// Links on the main axis shared by the most links (coaxial shafts: candidate input/output/fixed links).
    pub coaxial: Vec<String>,
    /// Number of sets of three links on one axis: the candidate
    /// (input, output, fixed) triples of a one-DOF reducer, unordered.
    pub coaxial_triples: usize,
    /// For a rotation graph, how many displacement graphs it has.
    pub displacement_graphs: usize,
    /// The canonical code (hex), the key of the isomorphism class.
    pub code: String,
}

/// The atlas member a train is, at `level`: the same code, adjacency form
/// and classification `enumerate` gives it. The train's rotation graph is the
/// union of its gear pairs' rotation triangles (gear `i`, gear `j`, carrier
/// `k`: turning edges `i-k` and `j-k`), each edge on the axis of its side of
/// the fundamental circuit; which bearings join coaxial links does not matter.
/// Only the one tree that owns the train is searched (to count its rotation
/// graph's displacement graphs), not the whole atlas.
///
/// # Errors
/// More than `MAX_LINKS` links, or a link in no gear pair's triangle (a link
/// the atlas has no place for, e.g. a housing joined by a bearing only).
pub fn member(train: &Train, level: GraphLevel) -> Result<AtlasMember> {
    let n = train.links().len();
    if n > MAX_LINKS {
        return Err(Error::invalid(
            "links",
            format!("the atlas handles at most {MAX_LINKS} links, the train has {n}"),
        ));
    }
    let mut g = ChainGraph::empty(n);
    let mut legs: Vec<((usize, usize), usize)> = Vec::new();
    for c in train.circuits() {
        let (i, j, k) = (c.gear_i.index(), c.gear_j.index(), c.carrier.index());
        g.set(i, j, Joint::Gear);
        for (x, level) in [(i, c.level_i.index()), (j, c.level_j.index())] {
            g.set(x, k, Joint::Turning);
            legs.push(((x.min(k), x.max(k)), level));
        }
    }
    let turning = g.pairs(Joint::Turning);
    let mut touched = vec![false; n];
    for &(a, b) in &turning {
        touched[a] = true;
        touched[b] = true;
    }
    if let Some(free) = (0..n).find(|&a| !touched[a]) {
        return Err(Error::invalid(
            "links",
            format!(
                "link `{}` is in no gear pair's circuit as gear or carrier; the atlas has chains of gear pairs only",
                train.links()[free].name
            ),
        ));
    }
    // Axes: edges of one level name joined through a shared link (the same
    // letter on two separate carriers is two axes).
    let named: Vec<usize> = turning
        .iter()
        .map(|e| legs.iter().find(|(p, _)| p == e).expect("a leg").1)
        .collect();
    let mut axis: Vec<usize> = (0..turning.len()).collect();
    fn root(axis: &mut [usize], mut x: usize) -> usize {
        while axis[x] != x {
            axis[x] = axis[axis[x]];
            x = axis[x];
        }
        x
    }
    for e in 0..turning.len() {
        for f in e + 1..turning.len() {
            let ((a, b), (c, d)) = (turning[e], turning[f]);
            if named[e] == named[f] && (a == c || a == d || b == c || b == d) {
                let (re, rf) = (root(&mut axis, e), root(&mut axis, f));
                axis[re] = rf;
            }
        }
    }
    let levels = renamed(
        &(0..turning.len())
            .map(|e| root(&mut axis, e))
            .collect::<Vec<_>>(),
    );
    // The canonical labelling, and the tree that owns the rotation graph.
    let (rcode, perm) = canonical(&g, Extra::None);
    let gc = g.permuted(&perm);
    let lc = permuted_levels(&g, &levels, &gc, &perm);
    let (dcode, _) = canonical(&gc, Extra::Levels(&lc));
    let mut owner = ChainGraph::empty(n);
    for (a, b) in bfs_tree(&gc) {
        owner.set(a, b, Joint::Turning);
    }
    let req = AtlasRequest {
        links: n,
        dof: train.dof(),
        level,
        part: None,
        fractionation: Fractionation::Layout,
    };
    let (_, p) = canonical(&owner, Extra::None);
    let members = members_of_tree(&owner.permuted(&p), &req, &NEVER).unwrap_or_default();
    let code: String = match level {
        GraphLevel::Rotation => &rcode,
        GraphLevel::Displacement => &dcode,
    }
    .iter()
    .map(|b| format!("{b:02x}"))
    .collect();
    members.into_iter().find(|m| m.code == code).ok_or_else(|| {
        Error::invalid(
            "links",
            "the train's rotation graph fails egt's checks in every bearing layout".to_string(),
        )
    })
}

/// Number of partitionable units (turning-pair trees) for `links`.
pub fn units(links: usize) -> usize {
    trees::trees(links).len()
}

/// Enumerates the atlas; members come in a fixed order (by tree, then by canonical code).
///
/// # Errors
/// A bad request (fewer than 3 or more than `MAX_LINKS` links, a DOF that
/// leaves no gear pair, an empty partition) names the offending field.
pub fn enumerate(req: &AtlasRequest) -> Result<Vec<AtlasMember>> {
    let mut out = Vec::new();
    enumerate_with(req, |_, members| out.extend(members))?;
    Ok(out)
}

/// Like [`enumerate`], but hands the members of each unit (tree) to `sink`
/// as soon as they are known, in order, with the unit's index, so that a caller
/// can stream output and report progress.
///
/// # Errors
/// As [`enumerate`].
pub fn enumerate_with(req: &AtlasRequest, sink: impl FnMut(usize, Vec<AtlasMember>)) -> Result<()> {
    enumerate_until(req, &NEVER, sink).map(|_| ())
}

/// The request's fields, each in range, or an error that names the field.
fn validate(req: &AtlasRequest) -> Result<()> {
    if req.links < 3 || req.links > MAX_LINKS {
        return Err(Error::invalid(
            "links",
            format!("must be between 3 and {MAX_LINKS}, got {}", req.links),
        ));
    }
    if req.dof == 0 || req.dof.saturating_add(2) > req.links {
        return Err(Error::invalid(
            "dof",
            format!(
                "must be between 1 and {} for {} links (at least one gear pair)",
                req.links - 2,
                req.links
            ),
        ));
    }
    if let Some((i, k)) = req.part
        && (k == 0 || i >= k)
    {
        return Err(Error::invalid(
            "part",
            format!("part {i} of {k}: need 0 <= part < parts"),
        ));
    }
    Ok(())
}

/// A flag nothing sets: the search of a caller that does not cancel.
static NEVER: AtomicBool = AtomicBool::new(false);

/// Like [`enumerate_with`], but stops soon after `cancel` is set (by another
/// thread: a Ctrl-C handler, a time limit): it is read between units and,
/// within a unit, once per level partition and per candidate graph, never in
/// the canonical labelling itself. The units handed to `sink` before the stop
/// are whole and in order; the unit in progress is dropped, never handed on
/// in part. Returns `Ok(true)` when every unit was handed on, `Ok(false)`
/// when `cancel` stopped the enumeration first. The library sets no signal
/// handler: the flag is the caller's.
///
/// # Errors
/// As [`enumerate`].
pub fn enumerate_until(
    req: &AtlasRequest,
    cancel: &AtomicBool,
    mut sink: impl FnMut(usize, Vec<AtlasMember>),
) -> Result<bool> {
    validate(req)?;
    let all = trees::trees(req.links);
    let chosen: Vec<(usize, &ChainGraph)> = all
        .iter()
        .enumerate()
        .filter(|(i, _)| req.part.is_none_or(|(p, k)| i % k == p))
        .collect();
    // Parallel over trees in chunks, handing results on in order.
    let chunk = rayon::current_num_threads().max(1) * 2;
    for group in chosen.chunks(chunk) {
        if cancel.load(Ordering::Relaxed) {
            return Ok(false);
        }
        let results: Vec<(usize, Option<Vec<AtlasMember>>)> = group
            .par_iter()
            .map(|&(i, t)| (i, members_of_tree(t, req, cancel)))
            .collect();
        for (i, m) in results {
            // The trees before a cancelled one are whole: hand them on.
            let Some(m) = m else { return Ok(false) };
            sink(i, m);
        }
    }
    Ok(true)
}

/// Calls `f` with every choice of `k` candidates whose legs cover all the
/// tree's turning pairs (`full`): a turning pair that is no gear pair's leg
/// would be a bridge of the rotation graph, not a bearing of this tree form.
fn for_each_cover(cands: &[Candidate], k: usize, full: u32, f: &mut dyn FnMut(&[Candidate])) {
    fn rec(
        cands: &[Candidate],
        k: usize,
        full: u32,
        covered: u32,
        picked: &mut Vec<Candidate>,
        f: &mut dyn FnMut(&[Candidate]),
    ) {
        if picked.len() == k {
            if covered == full {
                f(picked);
            }
            return;
        }
        let left = k - picked.len();
        // each gear pair covers at most two turning pairs
        if (full & !covered).count_ones() as usize > 2 * left || cands.len() < left {
            return;
        }
        let (first, rest) = cands.split_first().expect("cands.len() >= left >= 1");
        picked.push(*first);
        rec(rest, k, full, covered | first.covers, picked, f);
        picked.pop();
        rec(rest, k, full, covered, picked, f);
    }
    rec(cands, k, full, 0, &mut Vec::with_capacity(k), f);
}

/// One displacement graph found from a tree: its rotation graph in canonical
/// labelling and the turning edges' levels in that labelling.
#[derive(Debug, Clone)]
struct Found {
    rcode: Code,
    graph: ChainGraph,
    levels: Vec<usize>,
}

/// The displacement graphs this tree owns: every valid level partition and
/// choice of gear pairs on `tree`, as rotation graphs (the union of the gear
/// pairs' rotation triangles) with levels, kept when the canonical rotation
/// graph's breadth-first spanning tree has the shape of `tree`. Every
/// displacement graph is owned by exactly one tree, so trees partition the
/// search with no de-duplication across them.
fn found_in_tree(
    tree_graph: &ChainGraph,
    req: &AtlasRequest,
    cancel: &AtomicBool,
) -> BTreeMap<Code, Found> {
    found_from_tree(tree_graph, req, true, cancel)
}

/// As [`found_in_tree`]; with `owned_only` false, every displacement graph
/// reachable from `tree` (for testing that ownership loses nothing). Once
/// `cancel` is set, the rest is skipped: the map is then partial, and the
/// caller drops it.
fn found_from_tree(
    tree_graph: &ChainGraph,
    req: &AtlasRequest,
    owned_only: bool,
    cancel: &AtomicBool,
) -> BTreeMap<Code, Found> {
    let n = req.links;
    let gears = n - 1 - req.dof;
    let tree = Tree::new(tree_graph);
    let tcode = canonical(tree_graph, Extra::None).0;
    let full: u32 = (1u32 << tree.turning.len()) - 1;
    let mut owner: HashMap<Code, bool> = HashMap::new();
    let mut seen: HashSet<(Code, Vec<usize>)> = HashSet::new();
    let mut out: BTreeMap<Code, Found> = BTreeMap::new();
    // Level partitions that a symmetry of the tree maps onto each other give
    // the same displacement graphs: one per orbit is enough.
    let mut orbits: HashSet<Code> = HashSet::new();
    tree.for_each_level_partition(|levels| {
        if cancel.load(Ordering::Relaxed)
            || !orbits.insert(canonical(tree_graph, Extra::Levels(levels)).0)
        {
            return;
        }
        let cands = tree.candidates(levels);
        for_each_cover(&cands, gears, full, &mut |picked| {
            if cancel.load(Ordering::Relaxed) {
                return;
            }
            let (g, lv) = rotation_graph(n, picked);
            let (rcode, perm) = canonical(&g, Extra::None);
            let owned = !owned_only
                || *owner.entry(rcode.clone()).or_insert_with(|| {
                    let gc = g.permuted(&perm);
                    let mut t = ChainGraph::empty(n);
                    for (a, b) in bfs_tree(&gc) {
                        t.set(a, b, Joint::Turning);
                    }
                    canonical(&t, Extra::None).0 == tcode
                });
            if !owned {
                return;
            }
            let gc = g.permuted(&perm);
            let lc = permuted_levels(&g, &lv, &gc, &perm);
            if !seen.insert((rcode.clone(), lc.clone())) {
                return;
            }
            let (dcode, _) = canonical(&gc, Extra::Levels(&lc));
            out.entry(dcode).or_insert(Found {
                rcode,
                graph: gc,
                levels: lc,
            });
        });
    });
    out
}

/// `levels` (of `g`'s turning pairs) re-indexed for `gc = g.permuted(perm)`
/// and renamed in order of first appearance.
fn permuted_levels(
    g: &ChainGraph,
    levels: &[usize],
    gc: &ChainGraph,
    perm: &[usize],
) -> Vec<usize> {
    let old = g.pairs(Joint::Turning);
    let raw: Vec<usize> = gc
        .pairs(Joint::Turning)
        .iter()
        .map(|&(a, b)| {
            let k = old
                .iter()
                .position(|&(x, y)| {
                    let (p, q) = (perm[x], perm[y]);
                    (p.min(q), p.max(q)) == (a, b)
                })
                .expect("same edges");
            levels[k]
        })
        .collect();
    renamed(&raw)
}

/// Level names renamed 0, 1, .. in order of first appearance.
fn renamed(levels: &[usize]) -> Vec<usize> {
    let mut map: Vec<(usize, usize)> = Vec::new();
    levels
        .iter()
        .map(|&l| {
            if let Some(&(_, r)) = map.iter().find(|(x, _)| *x == l) {
                r
            } else {
                map.push((l, map.len()));
                map.len() - 1
            }
        })
        .collect()
}

/// All atlas members this tree owns; None when `cancel` was set before
/// they were all found.
fn members_of_tree(
    tree: &ChainGraph,
    req: &AtlasRequest,
    cancel: &AtomicBool,
) -> Option<Vec<AtlasMember>> {
    let found = found_in_tree(tree, req, cancel);
    // Also right after the search: a cancelled search's map is partial.
    if cancel.load(Ordering::Relaxed) {
        return None;
    }
    let out = members_from(checked_members(found, req), req);
    // Set at any point, the flag drops the tree (even one just finished).
    (!cancel.load(Ordering::Relaxed)).then_some(out)
}

/// The displacement graphs `found` that pass egt's checks (and the
/// kinematic sense of fractionation when asked), by rotation graph: r-code
/// to its valid displacement graphs (d-code, emitted form), in d-code order.
fn checked_members(
    found: BTreeMap<Code, Found>,
    req: &AtlasRequest,
) -> BTreeMap<Code, Vec<(Code, Emitted)>> {
    let mut by_rotation: BTreeMap<Code, Vec<(Code, Emitted)>> = BTreeMap::new();
    for (dcode, f) in found {
        if req.fractionation == Fractionation::Kinematic && has_cut_link(&f.graph) {
            continue;
        }
        if let Some(emitted) = checked_form(&f.graph, &f.levels) {
            by_rotation
                .entry(f.rcode)
                .or_default()
                .push((dcode, emitted));
        }
    }
    by_rotation
}

/// The members at `req.level` of the valid displacement graphs grouped by
/// rotation graph: a rotation graph once (its first displacement graph's
/// form) or every displacement graph.
fn members_from(
    by_rotation: BTreeMap<Code, Vec<(Code, Emitted)>>,
    req: &AtlasRequest,
) -> Vec<AtlasMember> {
    let n = req.links;
    let gears = n - 1 - req.dof;
    let mut out = Vec::new();
    for (rcode, ds) in by_rotation {
        let count = ds.len();
        let member = |code: &Code, e: &Emitted| AtlasMember {
            adjacency: e.adjacency.clone(),
            links: n,
            dof: req.dof,
            level: req.level,
            gears,
            carriers: e.carriers,
            axes: e.axes,
            coaxial: e.coaxial.clone(),
            coaxial_triples: e.coaxial_triples,
            displacement_graphs: count,
            code: code.iter().map(|b| format!("{b:02x}")).collect(),
        };
        match req.level {
            GraphLevel::Rotation => {
                let (_, e) = &ds[0];
                out.push(member(&rcode, e));
            }
            GraphLevel::Displacement => {
                for (dcode, e) in &ds {
                    out.push(member(dcode, e));
                }
            }
        }
    }
    out
}

/// A displacement graph as egt prints it.
#[derive(Debug, Clone)]
struct Emitted {
    adjacency: String,
    carriers: usize,
    axes: usize,
    coaxial: Vec<String>,
    coaxial_triples: usize,
}

impl Emitted {
    /// The bearing tree `tree` (turning edges of the rotation graph `g`)
    /// with its levels, then the gear pairs.
    fn new(g: &ChainGraph, levels: &[usize], tree: &[(usize, usize)]) -> Self {
        let turning = g.pairs(Joint::Turning);
        let level_of =
            |e: (usize, usize)| levels[turning.iter().position(|&x| x == e).expect("edge")];
        let tree_levels: Vec<usize> = tree.iter().map(|&e| level_of(e)).collect();
        Self::with_layout(g, tree, &tree_levels)
    }

    /// The bearing tree `tree` with its levels `tree_levels` (any names),
    /// then the gear pairs of the rotation graph `g`.
    fn with_layout(g: &ChainGraph, tree: &[(usize, usize)], tree_levels: &[usize]) -> Self {
        let tree_levels = renamed(tree_levels);
        let mut parts: Vec<String> = tree
            .iter()
            .zip(&tree_levels)
            .map(|(&(a, b), &l)| format!("{}-{}:{}", a + 1, b + 1, level_name(l)))
            .collect();
        let gear_pairs = g.pairs(Joint::Gear);
        parts.extend(
            gear_pairs
                .iter()
                .map(|&(a, b)| format!("{}-{}:G", a + 1, b + 1)),
        );
        // carriers: the common turning neighbour of each gear pair
        let mut carriers: Vec<usize> = gear_pairs
            .iter()
            .filter_map(|&(a, b)| {
                (0..g.links())
                    .find(|&k| g.joint(a, k) == Joint::Turning && g.joint(b, k) == Joint::Turning)
            })
            .collect();
        carriers.sort_unstable();
        carriers.dedup();
        let axes = tree_levels.iter().max().map_or(0, |m| m + 1);
        // a level's pairs form a tree: pairs + 1 links on that axis
        let coaxial_triples = (0..axes)
            .map(|l| {
                let k = tree_levels.iter().filter(|&&x| x == l).count() + 1;
                k * k.saturating_sub(1) * k.saturating_sub(2) / 6
            })
            .sum();
        Emitted {
            adjacency: parts.join(" "),
            carriers: carriers.len(),
            axes,
            coaxial: coaxial(tree, &tree_levels),
            coaxial_triples,
        }
    }
}

fn level_name(l: usize) -> String {
    let letters = b"abcdefghijklmnopqrstuvwxyz";
    (letters[l % 26] as char).to_string() + &"'".repeat(l / 26)
}

/// The links of each level (sorted), level by level.
fn level_links(turning: &[(usize, usize)], levels: &[usize]) -> Vec<Vec<usize>> {
    (0..levels.iter().max().map_or(0, |m| m + 1))
        .map(|l| {
            let mut links: Vec<usize> = turning
                .iter()
                .zip(levels)
                .filter(|&(_, &x)| x == l)
                .flat_map(|(&(a, b), _)| [a, b])
                .collect();
            links.sort_unstable();
            links.dedup();
            links
        })
        .collect()
}

/// Links on the most populated axis: those joined by turning pairs of the level used most.
fn coaxial(turning: &[(usize, usize)], levels: &[usize]) -> Vec<String> {
    let mut best: Vec<usize> = Vec::new();
    for links in level_links(turning, levels) {
        if links.len() > best.len() {
            best = links;
        }
    }
    best.iter().map(|l| (l + 1).to_string()).collect()
}

/// Calls `f` with every `k`-subset of `0..m` (as sorted indices).
#[cfg(test)]
fn for_each_subset(m: usize, k: usize, mut f: impl FnMut(&[usize])) {
    if k > m {
        return;
    }
    let mut idx: Vec<usize> = (0..k).collect();
    loop {
        f(&idx);
        let Some(i) = (0..k).rev().find(|&i| idx[i] != i + m - k) else {
            return;
        };
        idx[i] += 1;
        for j in i + 1..k {
            idx[j] = idx[j - 1] + 1;
        }
    }
}

#[cfg(test)]
mod tests;
