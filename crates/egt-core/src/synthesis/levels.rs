//! Axis levels of the turning pairs (paper §2, property 5): every gear pair's
//! fundamental circuit (the gear edge plus the tree path between its gears)
//! has exactly one transfer vertex, the carrier, with all turning pairs on one
//! side at one level and all on the other side at one different level.
//!
//! In the rotation-graph form every circuit is a triangle (gear i, gear j,
//! carrier k: each gear joined to the link about whose axis it turns), as in
//! the paper's displacement graph construction (§2). A displacement graph
//! adds the levels: a partition of the turning pairs into axes, each axis a
//! connected set of coaxial links, with the two pairs at each carrier apart.

use super::graph::{ChainGraph, Joint};

#[derive(Debug)]
/// The gear pairs' tree paths (as link lists) and the turning pairs (as in `ChainGraph::pairs`).
pub struct Circuits {
    /// Turning pairs `(a, b)`, `a < b`.
    pub turning: Vec<(usize, usize)>,
    /// Gear pairs `(a, b)`, `a < b`.
    pub gears: Vec<(usize, usize)>,
    /// For each gear pair, its tree path from `a` to `b`.
    pub paths: Vec<Vec<usize>>,
}

impl Circuits {
    /// The circuits of `g`.
    pub fn new(g: &ChainGraph) -> Self {
        let gears = g.pairs(Joint::Gear);
        let paths = gears.iter().map(|&(a, b)| g.tree_path(a, b)).collect();
        Circuits {
            turning: g.pairs(Joint::Turning),
            gears,
            paths,
        }
    }

    fn edge(&self, a: usize, b: usize) -> usize {
        let key = (a.min(b), a.max(b));
        self.turning
            .iter()
            .position(|&e| e == key)
            .expect("tree edge")
    }

    /// Whether every gear pair's circuit is a triangle (gear, gear, carrier):
    /// the rotation-graph form, in which each gear is joined to its carrier.
    pub fn triangular(&self) -> bool {
        self.paths.iter().all(|p| p.len() == 3)
    }

    /// Calls `f(carriers, levels)` for every level assignment of a triangular
    /// graph: `levels[e]` is the axis level (0, 1, .. in order of first use)
    /// of turning pair e, each level's pairs form a connected set of coaxial
    /// links, and each circuit's two turning pairs at its carrier differ.
    pub fn for_each_level_partition(&self, mut f: impl FnMut(&[usize], &[usize])) {
        let m = self.turning.len();
        let carriers: Vec<usize> = self.paths.iter().map(|p| p[1]).collect();
        let sides: Vec<(usize, usize)> = self
            .paths
            .iter()
            .map(|p| (self.edge(p[0], p[1]), self.edge(p[1], p[2])))
            .collect();
        // restricted-growth strings = set partitions of the turning pairs
        let mut rgs = vec![0usize; m];
        loop {
            if sides.iter().all(|&(x, y)| rgs[x] != rgs[y]) && self.classes_connected(&rgs) {
                f(&carriers, &rgs);
            }
            let Some(i) = (1..m)
                .rev()
                .find(|&i| rgs[i] <= *rgs[..i].iter().max().expect("i >= 1"))
            else {
                return;
            };
            rgs[i] += 1;
            for r in &mut rgs[i + 1..] {
                *r = 0;
            }
        }
    }

    /// Whether the turning pairs of each level join a connected set of links.
    fn classes_connected(&self, levels: &[usize]) -> bool {
        let k = levels.iter().max().map_or(0, |x| x + 1);
        (0..k).all(|l| {
            let edges: Vec<(usize, usize)> = self
                .turning
                .iter()
                .zip(levels)
                .filter(|&(_, &x)| x == l)
                .map(|(&e, _)| e)
                .collect();
            // a forest is connected iff links = edges + 1
            let mut links: Vec<usize> = edges.iter().flat_map(|&(a, b)| [a, b]).collect();
            links.sort_unstable();
            links.dedup();
            links.len() == edges.len() + 1
        })
    }
}
