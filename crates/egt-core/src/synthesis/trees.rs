//! Non-isomorphic trees on `n` vertices: the turning-pair skeletons of all
//! geared kinematic chains with `n` links (paper §2, property 3: deleting the
//! gear edges leaves a spanning tree). Grown leaf by leaf from smaller trees and
//! de-duplicated by canonical code, so no tree list is pasted in.

use std::collections::BTreeMap;

use super::canon::{Extra, canonical};
use super::graph::{ChainGraph, Joint};

/// Every non-isomorphic tree on `n >= 1` vertices, in a fixed order (by canonical code).
pub fn trees(n: usize) -> Vec<ChainGraph> {
    let mut level: BTreeMap<Vec<u8>, ChainGraph> = BTreeMap::new();
    level.insert(Vec::new(), ChainGraph::empty(1));
    for k in 1..n {
        let mut next = BTreeMap::new();
        for t in level.values() {
            for v in 0..k {
                let mut g = ChainGraph::empty(k + 1);
                for (a, b) in t.pairs(Joint::Turning) {
                    g.set(a, b, Joint::Turning);
                }
                g.set(v, k, Joint::Turning);
                let (code, perm) = canonical(&g, Extra::None);
                next.entry(code).or_insert_with(|| g.permuted(&perm));
            }
        }
        level = next;
    }
    level.into_values().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tree_counts_match_oeis_a000055() {
        // Unlabelled trees on n = 0..8 vertices (OEIS A000055).
        let want = [1, 1, 1, 1, 2, 3, 6, 11, 23];
        for (n, &w) in want.iter().enumerate().skip(1) {
            assert_eq!(trees(n).len(), w, "n = {n}");
        }
    }
}
