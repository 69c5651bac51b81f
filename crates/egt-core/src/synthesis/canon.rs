//! Canonical forms of chain graphs, so that isomorphic graphs get equal codes.
//!
//! No maintained Rust crate offers canonical labelling of small vertex- and
//! edge-coloured graphs (nauty/Traces have no maintained Rust binding;
//! petgraph only tests isomorphism pairwise, which does not give a hashable
//! form for de-duplicating a stream). The graphs here have at most a dozen
//! links, so the form is the least code over all relabellings that keep an
//! iso-invariant vertex colouring (turning degree, gear degree, refined once by
//! the neighbours' colours) in order. That is exact (every relabelling an
//! isomorphism could induce is tried) and is tested against the plain
//! minimum over all `n!` permutations in this module's tests.

use super::graph::{ChainGraph, Joint};

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

fn code_of(g: &ChainGraph, extra: Extra<'_>, perm: &[usize]) -> Code {
    let n = g.links();
    // new label -> old label
    let mut inv = vec![0; n];
    for (old, &new) in perm.iter().enumerate() {
        inv[new] = old;
    }
    let turning = g.pairs(Joint::Turning);
    let mut rename = vec![u8::MAX; n];
    let mut next = 0u8;
    let mut code = Vec::with_capacity(n * (n - 1) / 2);
    for p in 0..n {
        for q in p + 1..n {
            let (a, b) = (inv[p], inv[q]);
            code.push(match g.joint(a, b) {
                Joint::None => 0,
                Joint::Gear => 1,
                Joint::Turning => match extra {
                    Extra::None => 2,
                    Extra::Levels(levels) => {
                        let k = turning
                            .iter()
                            .position(|&(x, y)| (x, y) == (a.min(b), a.max(b)))
                            .expect("turning pair listed");
                        if rename[levels[k]] == u8::MAX {
                            rename[levels[k]] = next;
                            next += 1;
                        }
                        2 + rename[levels[k]]
                    }
                },
            });
        }
    }
    code
}

/// Iso-invariant vertex colours: degrees, refined once by neighbour colours.
fn colours(g: &ChainGraph) -> Vec<Vec<usize>> {
    let n = g.links();
    let base: Vec<(usize, usize)> = (0..n)
        .map(|a| (g.degree(a, Joint::Turning), g.degree(a, Joint::Gear)))
        .collect();
    (0..n)
        .map(|a| {
            let mut c = vec![base[a].0, base[a].1];
            for j in [Joint::Turning, Joint::Gear] {
                let mut nb: Vec<(usize, usize)> = (0..n)
                    .filter(|&b| g.joint(a, b) == j)
                    .map(|b| base[b])
                    .collect();
                nb.sort_unstable();
                c.push(usize::MAX);
                for (x, y) in nb {
                    c.push(x);
                    c.push(y);
                }
            }
            c
        })
        .collect()
}

/// Calls `f` with every permutation (old -> new) that keeps the colour classes in order.
fn for_each_class_perm(g: &ChainGraph, mut f: impl FnMut(&[usize])) {
    let n = g.links();
    let col = colours(g);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| col[a].cmp(&col[b]));
    // classes as ranges of `order`
    let mut classes = Vec::new();
    let mut s = 0;
    for i in 1..=n {
        if i == n || col[order[i]] != col[order[s]] {
            classes.push((s, i));
            s = i;
        }
    }
    let mut perm = vec![0; n];
    fn rec(
        classes: &[(usize, usize)],
        order: &mut Vec<usize>,
        perm: &mut Vec<usize>,
        f: &mut dyn FnMut(&[usize]),
    ) {
        let Some((&(s, e), rest)) = classes.split_first() else {
            f(perm);
            return;
        };
        // Heap-free: iterate permutations of order[s..e] by swapping.
        permute(s, s, e, order, perm, rest, f);
    }
    fn permute(
        k: usize,
        s: usize,
        e: usize,
        order: &mut Vec<usize>,
        perm: &mut Vec<usize>,
        rest: &[(usize, usize)],
        f: &mut dyn FnMut(&[usize]),
    ) {
        if k == e {
            for (pos, &old) in order.iter().enumerate().take(e).skip(s) {
                perm[old] = pos;
            }
            rec(rest, order, perm, f);
            return;
        }
        for i in k..e {
            order.swap(k, i);
            permute(k + 1, s, e, order, perm, rest, f);
            order.swap(k, i);
        }
    }
    rec(&classes, &mut order, &mut perm, &mut f);
}

/// The canonical code and one relabelling (old -> new) that attains it.
pub fn canonical(g: &ChainGraph, extra: Extra<'_>) -> (Code, Vec<usize>) {
    let mut best: Option<(Code, Vec<usize>)> = None;
    for_each_class_perm(g, |perm| {
        let c = code_of(g, extra, perm);
        if best.as_ref().is_none_or(|(b, _)| c < *b) {
            best = Some((c, perm.to_vec()));
        }
    });
    best.expect("at least the identity-ordered permutation")
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
        for trial in 0..300 {
            let n = 3 + trial % 4;
            let mut g = ChainGraph::empty(n);
            for v in 1..n {
                let p = (rng(&mut seed) as usize) % v;
                g.set(p, v, Joint::Turning);
            }
            for a in 0..n {
                for b in a + 1..n {
                    if g.joint(a, b) == Joint::None && rng(&mut seed).is_multiple_of(3) {
                        g.set(a, b, Joint::Gear);
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
