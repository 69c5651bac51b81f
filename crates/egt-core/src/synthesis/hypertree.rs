//! The atlas generated levels first (issue 46): every displacement graph has
//! one hypertree of axis levels, so the search runs over non-isomorphic
//! hypertrees and never meets a graph from two of them.
//!
//! A level is a set of coaxial links; in a displacement graph the levels
//! meet in at most one link and form a tree (docs/atlas.md, "Definitions"):
//! a *hypertree* on the links. A gear pair `i-j` is allowed on a hypertree
//! when `i` lies on a level `A` and `j` on a level `B` that meet in the
//! carrier `k`; its legs `i-k` (on `A`) and `j-k` (on `B`) are its turning
//! pairs. A displacement graph is a choice of `N - 1 - F` allowed gear pairs
//! whose legs join every level's links. Its levels are read back from it, so
//! an isomorphism between two graphs on one hypertree is a symmetry of that
//! hypertree, and graphs on non-isomorphic hypertrees are never isomorphic:
//! de-duplication is per hypertree, and hypertrees partition the search.
//!
//! The tree-first search (`mod.rs`) finds each graph from every bearing tree
//! that reaches it and keeps it in one (its owner), after a canonical
//! labelling each time; at ten links that waste dominates. This search
//! shares only the canonical form and egt's checks with it, and the tests
//! compare the two at 3 to 9 links.

use std::collections::{BTreeMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::canon::{Code, Extra, canonical};
use super::graph::{ChainGraph, Joint};
use super::{AtlasMember, AtlasRequest, Found, checked_members, members_from, permuted_levels};
use crate::error::{Error, Result};

/// Every non-isomorphic hypertree of levels on `n >= 2` links, as level
/// masks (bit `x` for link `x`), in a fixed order (by canonical code). Grown
/// link by link: a hypertree's leaf link (on one level only) removed leaves a
/// hypertree on one link fewer (its level dropped if two links were left),
/// so adding a link to a level, or as a new two-link level with any link,
/// reaches them all.
pub fn hypertrees(n: usize) -> Vec<Vec<u16>> {
    let mut level: BTreeMap<Code, Vec<u16>> = BTreeMap::new();
    level.insert(Vec::new(), vec![0b11]);
    for m in 2..n {
        let mut next = BTreeMap::new();
        for h in level.values() {
            let mut grown: Vec<Vec<u16>> = (0..h.len())
                .map(|a| {
                    let mut g = h.clone();
                    g[a] |= 1 << m;
                    g
                })
                .collect();
            grown.extend((0..m).map(|x| {
                let mut g = h.clone();
                g.push((1 << x) | (1 << m));
                g
            }));
            for g in grown {
                let (code, canon) = canonical_hypertree(m + 1, &g);
                next.entry(code).or_insert(canon);
            }
        }
        level = next;
    }
    level.into_values().collect()
}

/// The canonical code of a hypertree (each level a clique of turning pairs
/// of its own level: two levels share at most one link, so the cliques give
/// the levels back) and the hypertree relabelled to it.
fn canonical_hypertree(n: usize, h: &[u16]) -> (Code, Vec<u16>) {
    let mut g = ChainGraph::empty(n);
    for &mask in h {
        for a in links(mask) {
            for b in links(mask).filter(|&b| b > a) {
                g.set(a, b, Joint::Turning);
            }
        }
    }
    let levels: Vec<usize> = g
        .pairs(Joint::Turning)
        .iter()
        .map(|&(a, b)| level_of(h, a, b).expect("a clique's level"))
        .collect();
    let (code, perm) = canonical(&g, Extra::Levels(&levels));
    let mut canon: Vec<u16> = h
        .iter()
        .map(|&mask| links(mask).fold(0, |m, x| m | (1 << perm[x])))
        .collect();
    canon.sort_unstable();
    (code, canon)
}

/// The links of a mask, in order.
fn links(mask: u16) -> impl Iterator<Item = usize> + Clone {
    (0..16).filter(move |&x| mask >> x & 1 == 1)
}

/// The level holding both `a` and `b` (two levels share at most one link).
fn level_of(h: &[u16], a: usize, b: usize) -> Option<usize> {
    let both = (1u16 << a) | (1 << b);
    h.iter().position(|&m| m & both == both)
}

/// A gear pair a hypertree allows: gears `i < j`, carrier `k`, and the
/// (link, level) incidences its legs `i-k` and `j-k` touch.
#[derive(Debug, Clone, Copy)]
struct Allowed {
    i: usize,
    j: usize,
    k: usize,
    touches: u32,
}

/// The gear pairs hypertree `h` allows, with the incidence bit numbering.
fn allowed(h: &[u16]) -> (Vec<Allowed>, u32) {
    let mut bit = BTreeMap::new();
    for (a, &mask) in h.iter().enumerate() {
        for x in links(mask) {
            let next = bit.len();
            bit.insert((x, a), 1u32 << next);
        }
    }
    let full = bit.values().fold(0, |m, b| m | b);
    let mut out = Vec::new();
    for (a, &ma) in h.iter().enumerate() {
        for (b, &mb) in h.iter().enumerate() {
            let common = ma & mb;
            if a == b || common.count_ones() != 1 {
                continue;
            }
            let k = common.trailing_zeros() as usize;
            for i in links(ma & !common) {
                for j in links(mb & !common).filter(|&j| j > i) {
                    out.push(Allowed {
                        i,
                        j,
                        k,
                        touches: bit[&(i, a)] | bit[&(k, a)] | bit[&(j, b)] | bit[&(k, b)],
                    });
                }
            }
        }
    }
    (out, full)
}

/// Whether the legs of `picked` join every level's links.
fn levels_joined(h: &[u16], picked: &[Allowed]) -> bool {
    h.iter().all(|&mask| {
        // the legs inside this level, as neighbour masks
        let mut adj = [0u16; 16];
        for p in picked {
            for x in [p.i, p.j] {
                let pair = (1u16 << x) | (1 << p.k);
                if mask & pair == pair {
                    adj[x] |= 1 << p.k;
                    adj[p.k] |= 1 << x;
                }
            }
        }
        let mut reach = mask & mask.wrapping_neg();
        loop {
            let grown = links(reach).fold(reach, |m, x| m | adj[x]);
            if grown == reach {
                return reach == mask;
            }
            reach = grown;
        }
    })
}

/// The rotation graph of `picked` and its turning pairs' levels.
fn graph_of(n: usize, h: &[u16], picked: &[Allowed]) -> (ChainGraph, Vec<usize>) {
    let mut g = ChainGraph::empty(n);
    for p in picked {
        g.set(p.i, p.j, Joint::Gear);
        g.set(p.i, p.k, Joint::Turning);
        g.set(p.j, p.k, Joint::Turning);
    }
    let levels = g
        .pairs(Joint::Turning)
        .iter()
        .map(|&(a, b)| level_of(h, a, b).expect("a leg lies on a level"))
        .collect();
    (g, levels)
}

/// Every displacement graph on hypertree `h`, once each, keyed by its
/// canonical code; partial once `cancel` is set (the caller drops it).
fn found_on(n: usize, gears: usize, h: &[u16], cancel: &AtomicBool) -> BTreeMap<Code, Found> {
    let (cands, full) = allowed(h);
    let mut seen: HashSet<Code> = HashSet::new();
    let mut out = BTreeMap::new();
    let mut picked: Vec<Allowed> = Vec::with_capacity(gears);
    let mut visit = |picked: &[Allowed]| {
        if cancel.load(Ordering::Relaxed) || !levels_joined(h, picked) {
            return;
        }
        let (g, lv) = graph_of(n, h, picked);
        let dcode = canonical(&g, Extra::Levels(&lv)).0;
        if !seen.insert(dcode.clone()) {
            return;
        }
        let (rcode, perm) = canonical(&g, Extra::None);
        let gc = g.permuted(&perm);
        let lc = permuted_levels(&g, &lv, &gc, &perm);
        out.insert(
            dcode,
            Found {
                rcode,
                graph: gc,
                levels: lc,
            },
        );
    };
    covers(&cands, gears, full, 0, 0, &mut picked, &mut visit);
    out
}

/// Calls `f` with every choice of `k` allowed pairs from `cands[start..]`
/// that touches every incidence in `full`.
fn covers(
    cands: &[Allowed],
    k: usize,
    full: u32,
    start: usize,
    covered: u32,
    picked: &mut Vec<Allowed>,
    f: &mut dyn FnMut(&[Allowed]),
) {
    let left = k - picked.len();
    if left == 0 {
        if covered == full {
            f(picked);
        }
        return;
    }
    // a gear pair touches at most four incidences
    if (full & !covered).count_ones() as usize > 4 * left {
        return;
    }
    for p in start..cands.len().saturating_sub(left - 1) {
        picked.push(cands[p]);
        covers(cands, k, full, p + 1, covered | cands[p].touches, picked, f);
        picked.pop();
    }
}

/// The atlas by the levels-first search: the same members as
/// [`super::enumerate`] (the tests compare their codes), in the order of
/// their rotation graphs' codes, then their own. `req.part` splits the
/// hypertrees (`i % k == part`), which splits the displacement graphs; a
/// rotation graph's displacement graphs may lie on several hypertrees, so
/// the rotation level takes no part, and a part's members count in
/// `displacement_graphs` only the part's own.
///
/// # Errors
/// As [`super::enumerate`]; a part at the rotation level names `part`.
pub fn enumerate_by_levels(req: &AtlasRequest) -> Result<Vec<AtlasMember>> {
    Ok(enumerate_by_levels_until(req, &super::NEVER, &|_| {})?.unwrap_or_default())
}

/// Like [`enumerate_by_levels`], but stops soon after `cancel` is set (read
/// between hypertrees and between candidate graphs), and calls `done` with
/// the number of valid displacement graphs of each hypertree finished (from
/// the worker threads, in no particular order). Returns `Ok(None)` when
/// `cancel` stopped it: the members are grouped by rotation graph only at
/// the end, so none are handed on.
///
/// # Errors
/// As [`enumerate_by_levels`].
pub fn enumerate_by_levels_until(
    req: &AtlasRequest,
    cancel: &AtomicBool,
    done: &(dyn Fn(usize) + Sync),
) -> Result<Option<Vec<AtlasMember>>> {
    super::validate(req)?;
    if req.part.is_some() && req.level == super::GraphLevel::Rotation {
        return Err(Error::invalid(
            "part",
            "the levels-first search splits displacement graphs only: a rotation graph's may lie in several parts"
                .to_string(),
        ));
    }
    let n = req.links;
    let gears = n - 1 - req.dof;
    let all = hypertrees(n);
    let chosen: Vec<&Vec<u16>> = all
        .iter()
        .enumerate()
        .filter(|(i, _)| req.part.is_none_or(|(p, k)| i % k == p))
        .map(|(_, h)| h)
        .collect();
    let parts: Vec<_> = chosen
        .par_iter()
        .map(|h| {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let found = found_on(n, gears, h, cancel);
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let valid = checked_members(found, req);
            done(valid.values().map(Vec::len).sum());
            Some(valid)
        })
        .collect();
    let Some(parts) = parts.into_iter().collect::<Option<Vec<_>>>() else {
        return Ok(None);
    };
    let mut by_rotation = BTreeMap::new();
    for part in parts {
        for (rcode, ds) in part {
            by_rotation.entry(rcode).or_insert_with(Vec::new).extend(ds);
        }
    }
    for ds in by_rotation.values_mut() {
        ds.sort_by(|a: &(Code, _), b| a.0.cmp(&b.0));
    }
    Ok(Some(members_from(by_rotation, req)))
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::super::{Fractionation, GraphLevel, enumerate};
    use super::*;

    fn request(links: usize, dof: usize, level: GraphLevel) -> AtlasRequest {
        AtlasRequest {
            links,
            dof,
            level,
            part: None,
            fractionation: Fractionation::Layout,
        }
    }

    /// Each member's code with its displacement-graph count, and how many members.
    fn keyed(members: &[AtlasMember]) -> (BTreeSet<(String, usize)>, usize) {
        let set = members
            .iter()
            .map(|m| (m.code.clone(), m.displacement_graphs))
            .collect();
        (set, members.len())
    }

    /// The two searches give the same members (codes, and each rotation
    /// graph's count of displacement graphs), each once.
    fn same_atlas(links: usize, dof: usize) {
        for level in [GraphLevel::Rotation, GraphLevel::Displacement] {
            let req = request(links, dof, level);
            let (trees_first, n1) = keyed(&enumerate(&req).expect("tree-first"));
            let (levels_first, n2) = keyed(&enumerate_by_levels(&req).expect("levels-first"));
            assert_eq!(n1, trees_first.len());
            assert_eq!(
                n2,
                levels_first.len(),
                "{links} links, {dof} DOF: a member twice"
            );
            assert_eq!(
                trees_first, levels_first,
                "{links} links, {dof} DOF, {level:?}"
            );
        }
    }

    #[test]
    fn the_levels_first_search_finds_the_tree_first_atlas() {
        for links in 3..=7 {
            same_atlas(links, 1);
        }
        for links in 5..=7 {
            same_atlas(links, 2);
        }
        same_atlas(7, 3);
    }

    #[test]
    fn a_fixed_part_of_the_ten_link_atlas_recounts() {
        // docs/atlas.md: the ten-link one-DOF atlas, 903 812 displacement
        // graphs in all; this part of 400 holds 1420 of them.
        let req = AtlasRequest {
            part: Some((2, 400)),
            ..request(10, 1, GraphLevel::Displacement)
        };
        let members = enumerate_by_levels(&req).expect("a valid part");
        assert_eq!(members.len(), 1420);
        assert!(members.iter().all(|m| m.links == 10 && m.gears == 8));
    }

    /// By hand in release: `ATLAS_LINKS=9 cargo test --release -p egt-core
    /// --lib levels_first_agrees -- --ignored` (docs/atlas.md).
    #[test]
    #[ignore = "seconds to minutes in release; run by hand (docs/atlas.md)"]
    fn levels_first_agrees_beyond_ci_sizes() {
        let links: usize =
            std::env::var("ATLAS_LINKS").map_or(8, |s| s.parse().expect("ATLAS_LINKS"));
        let dof: usize = std::env::var("ATLAS_DOF").map_or(1, |s| s.parse().expect("ATLAS_DOF"));
        let t = std::time::Instant::now();
        same_atlas(links, dof);
        eprintln!(
            "{links} links, {dof} DOF: the same atlas ({:.1} s)",
            t.elapsed().as_secs_f64()
        );
    }

    #[test]
    fn hypertree_counts_are_the_free_trees_two_coloured() {
        // scripts/atlas_gen.py's counts (networkx's free trees on n + L
        // vertices, two-coloured into n links and L levels of two or more).
        let want = [(3, 2), (4, 4), (5, 9), (6, 22), (7, 59), (8, 165), (9, 496)];
        for (n, w) in want {
            assert_eq!(hypertrees(n).len(), w, "n = {n}");
        }
    }
}
