//! The small graph the enumeration works on: links 0..n, a spanning tree of
//! turning pairs (paper §2, property 3) and gear pairs, stored as an
//! adjacency matrix so that permutations and canonical codes are cheap.

/// Largest number of links the enumeration handles (codes are `u8`, sets `u16`).
pub const MAX_LINKS: usize = 12;

/// What joins two links.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Joint {
    /// Nothing.
    None,
    /// A turning (revolute) pair.
    Turning,
    /// A gear pair.
    Gear,
}

/// A geared kinematic chain's graph: `n` links, turning pairs forming a tree, gear pairs.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct ChainGraph {
    n: usize,
    adj: Vec<Joint>,
}

impl ChainGraph {
    /// `n` links and no pairs.
    pub fn empty(n: usize) -> Self {
        assert!(n <= MAX_LINKS, "at most {MAX_LINKS} links");
        ChainGraph {
            n,
            adj: vec![Joint::None; n * n],
        }
    }

    /// The number of links.
    pub fn links(&self) -> usize {
        self.n
    }

    /// The joint between links `a` and `b`.
    pub fn joint(&self, a: usize, b: usize) -> Joint {
        self.adj[a * self.n + b]
    }

    /// Sets the joint between `a` and `b` (both directions).
    pub fn set(&mut self, a: usize, b: usize, j: Joint) {
        self.adj[a * self.n + b] = j;
        self.adj[b * self.n + a] = j;
    }

    /// Pairs `(a, b)`, `a < b`, joined by `j`.
    pub fn pairs(&self, j: Joint) -> Vec<(usize, usize)> {
        let mut v = Vec::new();
        for a in 0..self.n {
            for b in a + 1..self.n {
                if self.joint(a, b) == j {
                    v.push((a, b));
                }
            }
        }
        v
    }

    /// Number of pairs of kind `j` at link `a`.
    pub fn degree(&self, a: usize, j: Joint) -> usize {
        (0..self.n).filter(|&b| self.joint(a, b) == j).count()
    }

    /// The graph with link `i` renamed `perm[i]`.
    pub fn permuted(&self, perm: &[usize]) -> ChainGraph {
        let mut g = ChainGraph::empty(self.n);
        for a in 0..self.n {
            for b in 0..self.n {
                g.adj[perm[a] * self.n + perm[b]] = self.adj[a * self.n + b];
            }
        }
        g
    }

    /// The tree path of turning pairs from `a` to `b`, as the list of links.
    pub fn tree_path(&self, a: usize, b: usize) -> Vec<usize> {
        // Depth-first search over turning pairs; the tree makes the path unique.
        let mut prev = vec![usize::MAX; self.n];
        let mut stack = vec![a];
        prev[a] = a;
        while let Some(u) = stack.pop() {
            if u == b {
                break;
            }
            for (v, p) in prev.iter_mut().enumerate() {
                if self.adj[u * self.n + v] == Joint::Turning && *p == usize::MAX {
                    *p = u;
                    stack.push(v);
                }
            }
        }
        let mut path = vec![b];
        let mut u = b;
        while u != a {
            u = prev[u];
            path.push(u);
        }
        path.reverse();
        path
    }
}
