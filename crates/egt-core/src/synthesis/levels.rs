//! Axis levels on a turning-pair tree (paper §2, property 5), and the gear
//! pairs they allow.
//!
//! A *level partition* of a tree's turning pairs puts each pair on an axis;
//! the pairs of one level form a connected set of coaxial links. A gear pair
//! `(i, j)` is allowed when the tree path from `i` to `j` changes level exactly
//! once: the link where it changes is the carrier `k` (the transfer vertex),
//! `i` turns about one of its axes and `j` about another. The gear pair's
//! *rotation triangle* is `i-k`, `j-k`, `i-j`: the two relative rotations the
//! gear pair needs, whether or not `i` and `k` are joined directly by a
//! bearing (they may be joined through other coaxial links).

use super::graph::{ChainGraph, Joint};

/// A gear pair a level partition allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Candidate {
    /// The gears `(i, j)`, `i < j`.
    pub gears: (usize, usize),
    /// The carrier (transfer vertex) `k`.
    pub carrier: usize,
    /// The axis levels of the legs `i-k` and `j-k`.
    pub leg_levels: (usize, usize),
    /// Bit `e` set when tree pair `e` is one of the legs.
    pub covers: u32,
}

/// A turning-pair tree with every link-to-link path precomputed.
#[derive(Debug)]
pub struct Tree {
    /// Number of links.
    pub n: usize,
    /// Turning pairs `(a, b)`, `a < b`, as in `ChainGraph::pairs(Joint::Turning)`.
    pub turning: Vec<(usize, usize)>,
    /// `paths[a * n + b]`: the tree pairs (by index) on the path from `a` to `b`, in order.
    paths: Vec<Vec<usize>>,
    /// `links[a * n + b]`: the links on that path, `a` first.
    links: Vec<Vec<usize>>,
}

impl Tree {
    /// The tree of `g`'s turning pairs.
    pub fn new(g: &ChainGraph) -> Self {
        let n = g.links();
        let turning = g.pairs(Joint::Turning);
        let edge = |a: usize, b: usize| {
            let key = (a.min(b), a.max(b));
            turning.iter().position(|&e| e == key).expect("tree edge")
        };
        let mut paths = vec![Vec::new(); n * n];
        let mut links = vec![Vec::new(); n * n];
        for a in 0..n {
            for b in 0..n {
                if a != b {
                    let p = g.tree_path(a, b);
                    paths[a * n + b] = p.windows(2).map(|w| edge(w[0], w[1])).collect();
                    links[a * n + b] = p;
                }
            }
        }
        Tree {
            n,
            turning,
            paths,
            links,
        }
    }

    /// Calls `f(levels)` for every level partition: `levels[e]` is the level
    /// (0, 1, .. in order of first use) of turning pair `e`, and each level's
    /// pairs join a connected set of links.
    pub fn for_each_level_partition(&self, mut f: impl FnMut(&[usize])) {
        let m = self.turning.len();
        if m == 0 {
            return;
        }
        // restricted-growth strings = set partitions of the turning pairs
        let mut rgs = vec![0usize; m];
        loop {
            if self.classes_connected(&rgs) {
                f(&rgs);
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
            // a forest is connected iff links = pairs + 1
            let mut seen = 0u32;
            let mut pairs = 0;
            for (&(a, b), &x) in self.turning.iter().zip(levels) {
                if x == l {
                    pairs += 1;
                    seen |= (1 << a) | (1 << b);
                }
            }
            seen.count_ones() as usize == pairs + 1
        })
    }

    /// The gear pairs `levels` allows, in a fixed order.
    pub fn candidates(&self, levels: &[usize]) -> Vec<Candidate> {
        let n = self.n;
        let mut out = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let path = &self.paths[i * n + j];
                if path.len() < 2 {
                    continue; // joined by a turning pair
                }
                let changes: Vec<usize> = (1..path.len())
                    .filter(|&t| levels[path[t - 1]] != levels[path[t]])
                    .collect();
                let [t] = changes[..] else {
                    continue;
                };
                let carrier = self.links[i * n + j][t];
                let mut covers = 0u32;
                if t == 1 {
                    covers |= 1 << path[0];
                }
                if path.len() - t == 1 {
                    covers |= 1 << path[t];
                }
                out.push(Candidate {
                    gears: (i, j),
                    carrier,
                    leg_levels: (levels[path[0]], levels[path[path.len() - 1]]),
                    covers,
                });
            }
        }
        out
    }
}

/// The rotation graph of a set of gear pairs: their rotation triangles
/// (turning edges `i-k`, `j-k`, gear edge `i-j`), and each turning edge's level.
pub fn rotation_graph(n: usize, picked: &[Candidate]) -> (ChainGraph, Vec<usize>) {
    let mut g = ChainGraph::empty(n);
    let mut leg = Vec::with_capacity(2 * picked.len());
    for c in picked {
        let (i, j) = c.gears;
        g.set(i, j, Joint::Gear);
        for (x, l) in [(i, c.leg_levels.0), (j, c.leg_levels.1)] {
            g.set(x, c.carrier, Joint::Turning);
            leg.push(((x.min(c.carrier), x.max(c.carrier)), l));
        }
    }
    let levels = g
        .pairs(Joint::Turning)
        .iter()
        .map(|e| leg.iter().find(|(p, _)| p == e).expect("a leg").1)
        .collect();
    (g, levels)
}

/// A spanning tree of `g`'s turning edges, by breadth-first search from link
/// 0 taking neighbours in label order: the bearing layout egt emits.
pub fn bfs_tree(g: &ChainGraph) -> Vec<(usize, usize)> {
    let n = g.links();
    let mut seen = vec![false; n];
    seen[0] = true;
    let mut queue = std::collections::VecDeque::from([0]);
    let mut tree = Vec::with_capacity(n.saturating_sub(1));
    while let Some(a) = queue.pop_front() {
        for (b, s) in seen.iter_mut().enumerate() {
            if !*s && g.joint(a, b) == Joint::Turning {
                *s = true;
                tree.push((a.min(b), a.max(b)));
                queue.push_back(b);
            }
        }
    }
    tree
}
