//! Which candidate graphs are atlas members: egt's own checks (`egt
//! check`) in some bearing layout, the kinematic sense of fractionation,
//! and the rigid sub-chain that makes a candidate degenerate (docs/atlas.md,
//! "Validity").

use super::graph::{ChainGraph, Joint};
use super::levels::bfs_tree;
use super::{Emitted, level_links};
use crate::error::{Error, Result, TopologyError};
use crate::{Format, Train};

/// egt's own topology checks, exactly as `egt check` applies them.
pub(super) fn egt_check(adjacency: &str) -> Result<Train> {
    let text = format!("frame = \"1\"\nadjacency = \"{adjacency}\"\n");
    Train::from_str(&text, Format::Toml, "atlas")
}

/// Whether removing one link disconnects the rest of `g` (turning and gear
/// pairs alike): a cut link of the rotation graph.
pub(super) fn has_cut_link(g: &ChainGraph) -> bool {
    let n = g.links();
    (0..n).any(|cut| {
        let start = usize::from(cut == 0);
        let mut seen = vec![false; n];
        seen[cut] = true;
        seen[start] = true;
        let mut stack = vec![start];
        let mut count = 2;
        while let Some(a) = stack.pop() {
            for (b, s) in seen.iter_mut().enumerate() {
                if !*s && g.joint(a, b) != Joint::None {
                    *s = true;
                    count += 1;
                    stack.push(b);
                }
            }
        }
        count < n
    })
}

/// The displacement graph `(g, levels)` in the first bearing layout that
/// passes egt's checks, or `None` when none does.
///
/// A level is a set of coaxial links; any tree of bearings inside each level
/// gives the same train (the same rotation graph and Willis equations). Two
/// of egt's checks read the bearing graph itself: planarity, and
/// fractionation (a link whose removal splits the graph into moving parts).
/// The breadth-first spanning tree of `g` is tried first; when it fails one
/// of those two, every other layout (every tree on each level's links, by
/// Prüfer sequences) in a fixed order. So a member is a train that some
/// bearing layout makes acceptable to `egt check`.
pub(super) fn checked_form(g: &ChainGraph, levels: &[usize]) -> Option<Emitted> {
    let bfs = bfs_tree(g);
    let first = Emitted::new(g, levels, &bfs);
    match egt_check(&first.adjacency) {
        Ok(_) => return Some(first),
        // A rigid sub-chain (eq. 1 leaves it no motion) is not tried in
        // other layouts, a saving only: its Willis rows are dependent
        // (redundant) or hold its links together (locked). At 6-9 links
        // egt's checks reject every such candidate in every layout; at 10,
        // the 9 that another layout let through are refused by the locked
        // test of a gear pair that never turns (docs/atlas.md).
        Err(Error::Topology(
            TopologyError::NonPlanar { .. } | TopologyError::Fractionated { .. },
        )) if !has_rigid_subchain(g, levels) => {}
        Err(_) => return None,
    }
    let classes = level_links(&g.pairs(Joint::Turning), levels);
    // one Prüfer sequence per level: digit i of level c runs over its links
    let digits: Vec<(usize, usize)> = classes
        .iter()
        .enumerate()
        .flat_map(|(c, links)| (0..links.len().saturating_sub(2)).map(move |_| (c, links.len())))
        .collect();
    let mut seq = vec![0usize; digits.len()];
    loop {
        let mut layout: Vec<(usize, usize)> = Vec::new();
        let mut layout_levels: Vec<usize> = Vec::new();
        for (c, links) in classes.iter().enumerate() {
            let code: Vec<usize> = digits
                .iter()
                .zip(&seq)
                .filter(|((dc, _), _)| *dc == c)
                .map(|(_, &x)| x)
                .collect();
            for (a, b) in pruefer_tree(links.len(), &code) {
                let (x, y) = (links[a], links[b]);
                layout.push((x.min(y), x.max(y)));
                layout_levels.push(c);
            }
        }
        let form = Emitted::with_layout(g, &layout, &layout_levels);
        if egt_check(&form.adjacency).is_ok() {
            return Some(form);
        }
        // next sequence (mixed radix)
        let i = (0..seq.len()).find(|&i| seq[i] + 1 < digits[i].1)?;
        seq[i] += 1;
        for x in &mut seq[..i] {
            *x = 0;
        }
    }
}

/// Whether some `k >= 3` links hold `k - 1` or more gear pairs with both
/// gears and the carrier among them: a sub-chain whose Gruebler count
/// (paper eq. (1)) leaves it no motion relative to itself. The carrier of a
/// gear pair is the link joined to both gears by turning pairs of two
/// different levels (`levels` of `g`'s turning pairs, in order).
pub(super) fn has_rigid_subchain(g: &ChainGraph, levels: &[usize]) -> bool {
    let n = g.links();
    let turning = g.pairs(Joint::Turning);
    let level = |a: usize, b: usize| {
        let e = (a.min(b), a.max(b));
        turning.iter().position(|&x| x == e).map(|i| levels[i])
    };
    let masks: Vec<u32> = g
        .pairs(Joint::Gear)
        .iter()
        .filter_map(|&(a, b)| {
            let k = (0..n)
                .find(|&k| matches!((level(a, k), level(b, k)), (Some(x), Some(y)) if x != y))?;
            Some((1u32 << a) | (1 << b) | (1 << k))
        })
        .collect();
    (1u32..1 << n).any(|s| {
        let k = s.count_ones() as usize;
        k >= 3 && masks.iter().filter(|&&m| m & s == m).count() + 1 >= k
    })
}

/// The labelled tree on `0..m` with Prüfer sequence `code` (length `m - 2`).
fn pruefer_tree(m: usize, code: &[usize]) -> Vec<(usize, usize)> {
    if m < 2 {
        return Vec::new();
    }
    let mut degree = vec![1usize; m];
    for &x in code {
        degree[x] += 1;
    }
    let mut edges = Vec::with_capacity(m - 1);
    for &x in code {
        let leaf = (0..m).find(|&v| degree[v] == 1).expect("a leaf");
        edges.push((leaf, x));
        degree[leaf] -= 1;
        degree[x] -= 1;
    }
    let last: Vec<usize> = (0..m).filter(|&v| degree[v] == 1).collect();
    edges.push((last[0], last[1]));
    edges
}
