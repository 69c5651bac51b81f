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
pub mod levels;
pub mod trees;

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::{Format, Train};
use canon::{Code, Extra, canonical};
use graph::{ChainGraph, Joint, MAX_LINKS};
use levels::Circuits;

/// Which graphs are counted as distinct.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GraphLevel {
    /// Rotation graphs: levels unlabelled.
    Rotation,
    /// Displacement graphs: with the axis levels.
    Displacement,
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
    /// For a rotation graph, how many displacement graphs it has.
    pub displacement_graphs: usize,
    /// The canonical code (hex), the key of the isomorphism class.
    pub code: String,
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
pub fn enumerate_with(
    req: &AtlasRequest,
    mut sink: impl FnMut(usize, Vec<AtlasMember>),
) -> Result<()> {
    if req.links < 3 || req.links > MAX_LINKS {
        return Err(Error::invalid(
            "links",
            format!("must be between 3 and {MAX_LINKS}, got {}", req.links),
        ));
    }
    if req.dof == 0 || req.dof + 2 > req.links {
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
    let all = trees::trees(req.links);
    let chosen: Vec<(usize, &ChainGraph)> = all
        .iter()
        .enumerate()
        .filter(|(i, _)| req.part.is_none_or(|(p, k)| i % k == p))
        .collect();
    // Parallel over trees in chunks, handing results on in order.
    let chunk = rayon::current_num_threads().max(1) * 2;
    for group in chosen.chunks(chunk) {
        let results: Vec<(usize, Vec<AtlasMember>)> = group
            .par_iter()
            .map(|&(i, t)| (i, members_of_tree(t, req)))
            .collect();
        for (i, m) in results {
            sink(i, m);
        }
    }
    Ok(())
}

/// Calls `f` with every `k`-subset of `0..m` (as sorted indices).
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

/// All atlas members whose turning pairs form `tree`.
fn members_of_tree(tree: &ChainGraph, req: &AtlasRequest) -> Vec<AtlasMember> {
    let n = req.links;
    let gears = n - 1 - req.dof;
    // Gear pairs can only join links not already joined by a turning pair.
    let free = tree.pairs(Joint::None);
    // r-code -> (graph, list of its d-graph candidates by d-code)
    let mut classes: BTreeMap<Code, ChainGraph> = BTreeMap::new();
    for_each_subset(free.len(), gears, |pick| {
        let mut g = tree.clone();
        for &i in pick {
            g.set(free[i].0, free[i].1, Joint::Gear);
        }
        if Circuits::new(&g).triangular() {
            let (code, perm) = canonical(&g, Extra::None);
            classes.entry(code).or_insert_with(|| g.permuted(&perm));
        }
    });
    let mut out = Vec::new();
    for (rcode, g) in classes {
        let circuits = Circuits::new(&g);
        // d-code -> (carriers, levels), valid by egt's checks
        let mut ds: BTreeMap<Code, (Vec<usize>, Vec<usize>)> = BTreeMap::new();
        circuits.for_each_level_partition(|carriers, levels| {
            let (code, _) = canonical(&g, Extra::Levels(levels));
            ds.entry(code)
                .or_insert_with(|| (carriers.to_vec(), levels.to_vec()));
        });
        ds.retain(|_, (_, levels)| passes_egt_check(&adjacency(&circuits, levels)));
        if ds.is_empty() {
            continue;
        }
        let count = ds.len();
        let member = |code: &Code, carriers: &[usize], levels: &[usize]| AtlasMember {
            adjacency: adjacency(&circuits, levels),
            links: n,
            dof: req.dof,
            level: req.level,
            gears,
            carriers: {
                let mut c = carriers.to_vec();
                c.sort_unstable();
                c.dedup();
                c.len()
            },
            axes: levels.iter().max().map_or(0, |m| m + 1),
            coaxial: coaxial(&circuits, levels),
            displacement_graphs: count,
            code: code.iter().map(|b| format!("{b:02x}")).collect(),
        };
        match req.level {
            GraphLevel::Rotation => {
                let (carriers, levels) = ds.values().next().expect("non-empty");
                out.push(member(&rcode, carriers, levels));
            }
            GraphLevel::Displacement => {
                for (dcode, (carriers, levels)) in &ds {
                    out.push(member(dcode, carriers, levels));
                }
            }
        }
    }
    out
}

fn level_name(l: usize) -> String {
    let letters = b"abcdefghijklmnopqrstuvwxyz";
    (letters[l % 26] as char).to_string() + &"'".repeat(l / 26)
}

/// The compact adjacency form: turning pairs with their level, then gear pairs.
fn adjacency(c: &Circuits, levels: &[usize]) -> String {
    let mut parts: Vec<String> = c
        .turning
        .iter()
        .zip(levels)
        .map(|(&(a, b), &l)| format!("{}-{}:{}", a + 1, b + 1, level_name(l)))
        .collect();
    parts.extend(
        c.gears
            .iter()
            .map(|&(a, b)| format!("{}-{}:G", a + 1, b + 1)),
    );
    parts.join(" ")
}

/// Links on the most populated axis: those joined by turning pairs of the level used most.
fn coaxial(c: &Circuits, levels: &[usize]) -> Vec<String> {
    let axes = levels.iter().max().map_or(0, |m| m + 1);
    let mut best: Vec<usize> = Vec::new();
    for l in 0..axes {
        let mut links: Vec<usize> = c
            .turning
            .iter()
            .zip(levels)
            .filter(|&(_, &x)| x == l)
            .flat_map(|(&(a, b), _)| [a, b])
            .collect();
        links.sort_unstable();
        links.dedup();
        if links.len() > best.len() {
            best = links;
        }
    }
    best.iter().map(|l| (l + 1).to_string()).collect()
}

/// egt's own topology checks, exactly as `egt check` applies them.
fn passes_egt_check(adjacency: &str) -> bool {
    let text = format!("frame = \"1\"\nadjacency = \"{adjacency}\"\n");
    Train::from_str(&text, Format::Toml, "atlas").is_ok()
}

#[cfg(test)]
mod tests;
