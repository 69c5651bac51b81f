//! Canonical forms of chain graphs, so that isomorphic graphs get equal codes.
//!
//! No maintained Rust crate offers canonical labelling of small vertex- and
//! edge-coloured graphs (nauty/Traces have no maintained Rust binding;
//! petgraph only tests isomorphism pairwise, which does not give a hashable
//! form for de-duplicating a stream). The graphs here have at most a dozen
//! links, so the form is the least code over all relabellings that keep an
//! iso-invariant vertex colouring (turning degree, gear degree, refined by the
//! neighbours' colours to a fixed point) in order, found by branch and bound
//! (a partial relabelling is dropped as soon as its code prefix exceeds the
//! best). That is exact (every relabelling an isomorphism could induce is
//! considered) and is tested against the plain minimum over all `n!`
//! permutations in this module's tests.

use super::graph::{ChainGraph, Joint, MAX_LINKS};

/// A canonical code: equal codes iff isomorphic (for the same `n`).
pub type Code = Vec<u8>;

/// What besides the graph takes part in the isomorphism.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Extra<'a> {
    /// Rotation graph: turning and gear pairs only.
    None,
    /// Displacement graph: each turning pair (listed as in
    /// `ChainGraph::pairs(Joint::Turning)`) with its axis level; levels are
    /// names only, so they are renamed in order of first appearance.
    Levels(&'a [usize]),
}

/// The pairs of `g` as a matrix of small codes: 0 none, 1 gear pair, 2 + level
/// (levels renamed in order of first appearance among the turning pairs; every
/// turning pair is level 0 without `Extra::Levels`).
fn matrix(g: &ChainGraph, extra: Extra<'_>) -> Vec<u8> {
    let n = g.links();
    let mut m = vec![0u8; n * n];
    let mut names: Vec<usize> = Vec::new();
    for (k, (a, b)) in g.pairs(Joint::Turning).into_iter().enumerate() {
        let level = match extra {
            Extra::None => 0,
            Extra::Levels(levels) => {
                let l = levels[k];
                names.iter().position(|&x| x == l).unwrap_or_else(|| {
                    names.push(l);
                    names.len() - 1
                })
            }
        };
        let code = 2 + u8::try_from(level).expect("fewer levels than links");
        m[a * n + b] = code;
        m[b * n + a] = code;
    }
    for (a, b) in g.pairs(Joint::Gear) {
        m[a * n + b] = 1;
        m[b * n + a] = 1;
    }
    m
}

#[cfg(test)]
/// The code of `g` relabelled by `perm` (old -> new): column by column, the
/// pairs `(p, q)`, `p < q`, of the new labels, with levels renamed in order of
/// first appearance. The reference definition the search below must match.
fn code_of(g: &ChainGraph, extra: Extra<'_>, perm: &[usize]) -> Code {
    let n = g.links();
    let m = matrix(g, extra);
    let mut inv = vec![0; n];
    for (old, &new) in perm.iter().enumerate() {
        inv[new] = old;
    }
    let mut rename = [u8::MAX; 16];
    let mut next = 0u8;
    let mut code = Vec::with_capacity(n * n.saturating_sub(1) / 2);
    for q in 1..n {
        for p in 0..q {
            code.push(renamed(m[inv[p] * n + inv[q]], &mut rename, &mut next));
        }
    }
    code
}

/// A pair code with its level renamed in order of first appearance.
fn renamed(x: u8, rename: &mut [u8; 16], next: &mut u8) -> u8 {
    if x < 2 {
        return x;
    }
    let l = usize::from(x - 2);
    if rename[l] == u8::MAX {
        rename[l] = *next;
        *next += 1;
    }
    2 + rename[l]
}

/// Iso-invariant vertex colours: (turning degree, gear degree), refined by
/// the multiset of (pair kind, neighbour colour) until stable (1-WL). Colours
/// are ranks of sorted signatures, so relabelling the graph permutes them.
fn colours(g: &ChainGraph) -> Vec<usize> {
    // A signature: own colour, neighbour count, then the sorted
    // (kind, colour) codes of the neighbours; fixed size, no allocation.
    type Sig = [u16; MAX_LINKS + 2];
    let n = g.links();
    let kind = |a: usize, b: usize| match g.joint(a, b) {
        Joint::None => 0u16,
        Joint::Turning => 1,
        Joint::Gear => 2,
    };
    let rank = |sigs: &[Sig], out: &mut [usize]| -> usize {
        let mut sorted: Vec<Sig> = sigs.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        for (o, s) in out.iter_mut().zip(sigs) {
            *o = sorted.binary_search(s).expect("present");
        }
        sorted.len()
    };
    let mut sigs: Vec<Sig> = (0..n)
        .map(|a| {
            let mut s = [0u16; MAX_LINKS + 2];
            s[0] = g.degree(a, Joint::Turning) as u16;
            s[1] = g.degree(a, Joint::Gear) as u16;
            s
        })
        .collect();
    let mut col = vec![0usize; n];
    let mut classes = rank(&sigs, &mut col);
    loop {
        for (a, s) in sigs.iter_mut().enumerate() {
            *s = [0u16; MAX_LINKS + 2];
            s[0] = col[a] as u16;
            let mut k = 2;
            for (b, &c) in col.iter().enumerate() {
                let j = kind(a, b);
                if j != 0 {
                    s[k] = j * (MAX_LINKS as u16 + 1) + c as u16;
                    k += 1;
                }
            }
            s[1] = (k - 2) as u16;
            s[2..k].sort_unstable();
        }
        let mut next = vec![0usize; n];
        let more = rank(&sigs, &mut next);
        col = next;
        if more == classes {
            return col;
        }
        classes = more;
    }
}

/// Branch and bound over the relabellings that keep the colour classes in
/// order: positions are filled one by one, each from its colour class, and a
/// branch stops as soon as its code prefix (the columns filled so far)
/// exceeds the best complete code.
struct Search<'a> {
    n: usize,
    m: &'a [u8],
    /// Colour class of each position.
    class_at: Vec<usize>,
    /// Links of each colour class.
    members: Vec<Vec<usize>>,
    /// The least link each link is a twin of (same pairs with every other
    /// link): swapping twins is an automorphism, so at each position only
    /// one twin of a kind need be tried.
    twin: Vec<usize>,
    used: Vec<bool>,
    /// Link at each filled position.
    placed: Vec<usize>,
    cur: Vec<u8>,
    best: Option<(Code, Vec<usize>)>,
}

impl Search<'_> {
    /// Fills position `q`. `below` says the prefix so far is already less than
    /// the best code's (so no comparison is needed); returns whether the best
    /// code was replaced (after which the prefix equals the new best's).
    fn fill(&mut self, q: usize, rename: [u8; 16], next: u8, mut below: bool) -> bool {
        let n = self.n;
        if q == n {
            let mut perm = vec![0; n];
            for (pos, &old) in self.placed.iter().enumerate() {
                perm[old] = pos;
            }
            match &mut self.best {
                Some((b, p)) => {
                    b.copy_from_slice(&self.cur);
                    *p = perm;
                }
                None => self.best = Some((self.cur.clone(), perm)),
            }
            return true;
        }
        let start = q * q.saturating_sub(1) / 2;
        let end = start + q;
        let class = self.class_at[q];
        let mut replaced = false;
        let mut tried = 0u32;
        for i in 0..self.members[class].len() {
            let v = self.members[class][i];
            if self.used[v] || tried & (1 << self.twin[v]) != 0 {
                continue;
            }
            tried |= 1 << self.twin[v];
            let (mut r, mut nx) = (rename, next);
            for p in 0..q {
                self.cur[start + p] = renamed(self.m[self.placed[p] * n + v], &mut r, &mut nx);
            }
            let child_below = below
                || match &self.best {
                    None => true,
                    Some((b, _)) => match self.cur[start..end].cmp(&b[start..end]) {
                        std::cmp::Ordering::Greater => continue,
                        std::cmp::Ordering::Less => true,
                        std::cmp::Ordering::Equal => false,
                    },
                };
            self.used[v] = true;
            self.placed[q] = v;
            if self.fill(q + 1, r, nx, child_below) {
                replaced = true;
                below = false;
            }
            self.used[v] = false;
        }
        replaced
    }
}

/// The canonical code and one relabelling (old -> new) that attains it.
pub fn canonical(g: &ChainGraph, extra: Extra<'_>) -> (Code, Vec<usize>) {
    let n = g.links();
    let m = matrix(g, extra);
    let col = colours(g);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&a| col[a]);
    let classes = col.iter().max().map_or(0, |m| m + 1);
    let mut members = vec![Vec::new(); classes];
    for &a in &order {
        members[col[a]].push(a);
    }
    let twin: Vec<usize> = (0..n)
        .map(|v| {
            (0..v)
                .find(|&w| (0..n).all(|x| x == v || x == w || m[v * n + x] == m[w * n + x]))
                .unwrap_or(v)
        })
        .collect();
    let mut search = Search {
        n,
        m: &m,
        twin,
        class_at: order.iter().map(|&a| col[a]).collect(),
        members,
        used: vec![false; n],
        placed: vec![0; n],
        cur: vec![0; n * n.saturating_sub(1) / 2],
        best: None,
    };
    search.fill(0, [u8::MAX; 16], 0, false);
    search.best.expect("at least one relabelling")
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The reference: least code over all n! permutations.
    fn brute(g: &ChainGraph, extra: Extra<'_>) -> Code {
        let n = g.links();
        let mut perm: Vec<usize> = (0..n).collect();
        let mut best = code_of(g, extra, &perm);
        // Lexicographic next-permutation.
        while let Some(i) = (0..n.saturating_sub(1))
            .rev()
            .find(|&i| perm[i] < perm[i + 1])
        {
            let j = (i + 1..n).rev().find(|&j| perm[j] > perm[i]).unwrap();
            perm.swap(i, j);
            perm[i + 1..].reverse();
            best = best.min(code_of(g, extra, &perm));
        }
        best
    }

    /// A deterministic pseudo-random source (xorshift) for test graphs.
    fn rng(seed: &mut u64) -> u64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        *seed
    }

    #[test]
    fn canonical_codes_separate_exactly_like_brute_force_minima() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut seen = Vec::new();
        for trial in 0..400 {
            let n = 3 + trial % 5;
            let mut g = ChainGraph::empty(n);
            for v in 1..n {
                let p = (rng(&mut seed) as usize) % v;
                g.set(p, v, Joint::Turning);
            }
            for a in 0..n {
                for b in a + 1..n {
                    if g.joint(a, b) == Joint::None {
                        match rng(&mut seed) % 6 {
                            0 | 1 => g.set(a, b, Joint::Gear),
                            // rotation graphs have cycles of turning pairs
                            2 => g.set(a, b, Joint::Turning),
                            _ => {}
                        }
                    }
                }
            }
            let turning = g.pairs(Joint::Turning);
            let levels: Vec<usize> = turning
                .iter()
                .map(|_| rng(&mut seed) as usize % 3)
                .collect();
            // the same graph relabelled at random, levels renamed too
            let mut perm: Vec<usize> = (0..n).collect();
            for i in (1..n).rev() {
                perm.swap(i, rng(&mut seed) as usize % (i + 1));
            }
            let h = g.permuted(&perm);
            let shift = rng(&mut seed) as usize % 3;
            let h_levels: Vec<usize> = h
                .pairs(Joint::Turning)
                .iter()
                .map(|&(a, b)| {
                    let inv = |x| perm.iter().position(|&p| p == x).unwrap();
                    let (x, y) = (inv(a), inv(b));
                    let k = turning
                        .iter()
                        .position(|&e| e == (x.min(y), x.max(y)))
                        .unwrap();
                    (levels[k] + shift) % 3
                })
                .collect();
            for (eg, eh) in [
                (Extra::None, Extra::None),
                (Extra::Levels(&levels), Extra::Levels(&h_levels)),
            ] {
                let (c, p) = canonical(&g, eg);
                assert_eq!(c, code_of(&g, eg, &p));
                assert_eq!(c, canonical(&h, eh).0, "relabelled, trial {trial}");
                seen.push((c, brute(&g, eg)));
            }
        }
        // Equal canonical codes exactly when equal brute-force minima.
        for (c1, b1) in &seen {
            for (c2, b2) in &seen {
                assert_eq!(c1 == c2, b1 == b2);
            }
        }
    }
}
