//! The element layouts of one structure that can meet the targets: the
//! elements placed one at a time, each gear state checked as soon as its
//! engaged elements are placed (one DOF for generic teeth, and its target
//! within the output speed's range over the whole box of basic ratios), so a
//! layout is dropped at its first impossible state, not at the end.

use std::collections::HashMap;

use crate::design::search::{misses, same_speed, searched_willis};

use super::structures::Structure;

/// Largest free shaft count the dense state solve holds.
pub(crate) const MAX_SHAFTS: usize = 32;

/// One searched dimension (a basic ratio): its range, sign and two generic picks.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DimBox {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
    pub(crate) sign: f64,
    pub(crate) picks: [f64; 2],
}

/// A gear state's engaged element ids and, if targeted, its output-speed window.
pub(crate) type StateGoal = (Vec<usize>, Option<(f64, f64)>);

/// What every structure's layouts are checked against.
#[derive(Debug, Clone)]
pub(crate) struct Problem {
    /// Per element: one-way or not, brake or clutch.
    pub(crate) elements: Vec<(bool, bool)>,
    /// Per gear state: engaged element ids, output-speed window if targeted.
    pub(crate) states: Vec<StateGoal>,
    pub(crate) dims: Vec<DimBox>,
    /// Willis rows: (sun, ring, carrier member ids, dimension).
    pub(crate) willis: Vec<(usize, usize, usize, usize)>,
    /// Member id -> set index.
    pub(crate) set_of: Vec<usize>,
    /// The order elements are placed in, and per element the states it completes.
    pub(crate) order: Vec<usize>,
    pub(crate) completes: Vec<Vec<usize>>,
}

impl Problem {
    /// Place elements first that complete the most states.
    pub(crate) fn plan(&mut self) {
        let n = self.elements.len();
        let mut placed = vec![false; n];
        let mut order = Vec::new();
        let mut done = vec![false; self.states.len()];
        let mut completes = vec![Vec::new(); n];
        for _ in 0..n {
            let best = (0..n)
                .filter(|&e| !placed[e])
                .max_by_key(|&e| {
                    let now = self
                        .states
                        .iter()
                        .enumerate()
                        .filter(|(s, st)| !done[*s] && st.0.iter().all(|&x| placed[x] || x == e))
                        .count();
                    // Most states completed, then most states touched; lowest id.
                    let touched = self.states.iter().filter(|st| st.0.contains(&e)).count();
                    (now, touched, usize::MAX - e)
                })
                .unwrap_or(0);
            placed[best] = true;
            order.push(best);
            for (s, st) in self.states.iter().enumerate() {
                if !done[s] && st.0.iter().all(|&x| placed[x]) {
                    done[s] = true;
                    completes[best].push(s);
                }
            }
        }
        self.order = order;
        self.completes = completes;
    }
}

/// Where an element may sit in a structure: its row (a brake's shaft, or a
/// clutch's two shafts) and the shafts (and the case, bit `n`) it makes turn
/// together, which is what it does: options with the same closure are one.
#[derive(Debug, Clone)]
pub(crate) struct Opt {
    pub(crate) a: usize,
    pub(crate) b: Option<usize>,
    pub(crate) mask: u64,
    /// Other placements of the same closure (a clutch joining another two
    /// members of a set it locks).
    pub(crate) variants: Vec<(usize, usize)>,
}

/// The options of brakes and of clutches in a structure.
pub(crate) fn options(p: &Problem, s: &Structure) -> (Vec<Opt>, Vec<Opt>) {
    let n = s.shafts.len();
    let mut shaft_of = vec![n; p.set_of.len()];
    for (i, sh) in s.shafts.iter().enumerate() {
        for &m in sh {
            shaft_of[m as usize] = i;
        }
    }
    let sets = p.set_of.iter().max().map_or(0, |m| m + 1);
    let closure = |mut mask: u64| {
        loop {
            let before = mask;
            for set in 0..sets {
                let on: Vec<usize> = (0..p.set_of.len())
                    .filter(|&m| p.set_of[m] == set)
                    .map(|m| shaft_of[m])
                    .collect();
                if on.iter().filter(|&&x| mask >> x & 1 == 1).count() >= 2 {
                    for x in on {
                        mask |= 1 << x;
                    }
                }
            }
            if mask == before {
                return mask;
            }
        }
    };
    let case = 1_u64 << n;
    let brakes = (0..n)
        .filter(|&x| x != s.input && x != s.output)
        .map(|x| Opt {
            a: x,
            b: None,
            mask: closure(1 << x | case),
            variants: Vec::new(),
        })
        .collect();
    let mut clutches: Vec<Opt> = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            let mask = closure(1 << a | 1 << b);
            if let Some(o) = clutches.iter_mut().find(|o| o.mask == mask) {
                o.variants.push((a, b));
            } else {
                clutches.push(Opt {
                    a,
                    b: Some(b),
                    mask,
                    variants: Vec::new(),
                });
            }
        }
    }
    (brakes, clutches)
}

/// A state's verdict, kept per set of engaged closures.
#[derive(Debug, Clone)]
struct Verdict {
    regular: bool,
    /// The dimensions w_out depends on (bit d), at the generic picks.
    depends: u64,
    /// w_out where it depends on no dimension: the same for all teeth
    /// (N = w D), so its window is met or missed whatever the teeth. The
    /// vertex test cannot say so where D changes sign in the box, and a
    /// tooth search of such a state would follow D's zero surface.
    constant: Option<f64>,
    /// w_out at all the first picks and at all the second: two states
    /// with the same are taken to have the same ratio for all teeth (their
    /// difference, a rational function, vanishing at generic points).
    sig: Option<[f64; 2]>,
    /// (N, D) of w_out = N / D at the vertices of the whole box of ratios
    /// (halving the box was tried: on a sample of the 8HP's space two
    /// halvings pruned no more layouts and took three times as long).
    vertices: Vec<(f64, f64)>,
}

/// The per-structure search of layouts.
pub(crate) struct Layouts<'a> {
    p: &'a Problem,
    s: &'a Structure,
    n: usize,
    col: Vec<Option<usize>>,
    pub(crate) brakes: Vec<Opt>,
    pub(crate) clutches: Vec<Opt>,
    memo: HashMap<Vec<u64>, Verdict>,
    pick: Vec<u32>,
    /// Per layout kept: what it does in every state, and its index in the output.
    seen: HashMap<Vec<Vec<u64>>, usize>,
    /// Set id -> the shafts of its members (bit n: the case).
    set_masks: Vec<u64>,
    /// Per state, the dimensions its ratio depends on (targeted states).
    depends: Vec<u64>,
    /// The targeted states passed under the current picks, with their
    /// signatures and windows: a state with the same ratio as one of them
    /// must share part of its window.
    live: Vec<([f64; 2], (f64, f64))>,
    /// Layouts dropped because some basic ratio moves no targeted ratio.
    pub(crate) idle: u64,
    /// States checked (memo misses), for the counts.
    pub(crate) checked: u64,
    /// Picks refused because a state's ratio, the same for all teeth,
    /// misses its target, or because a state has another's ratio for all
    /// teeth and a window apart from it.
    pub(crate) constant_missed: u64,
    pub(crate) shared_apart: u64,
}

impl<'a> Layouts<'a> {
    pub(crate) fn new(p: &'a Problem, s: &'a Structure) -> Option<Self> {
        let n = s.shafts.len();
        if n + 1 > MAX_SHAFTS {
            return None;
        }
        let mut col = vec![None; p.set_of.len()];
        for (i, sh) in s.shafts.iter().enumerate() {
            for &m in sh {
                col[m as usize] = Some(i);
            }
        }
        let (brakes, clutches) = options(p, s);
        let sets = p.set_of.iter().max().map_or(0, |m| m + 1);
        let set_masks = (0..sets)
            .map(|set| {
                (0..p.set_of.len())
                    .filter(|&m| p.set_of[m] == set)
                    .map(|m| col[m].map_or(1_u64 << n, |c| 1 << c))
                    .fold(0, |a, b| a | b)
            })
            .collect();
        Some(Layouts {
            p,
            s,
            n,
            col,
            brakes,
            clutches,
            memo: HashMap::new(),
            pick: vec![0; p.elements.len()],
            seen: HashMap::new(),
            set_masks,
            depends: vec![0; p.states.len()],
            live: Vec::new(),
            idle: 0,
            checked: 0,
            constant_missed: 0,
            shared_apart: 0,
        })
    }

    pub(crate) fn opts(&self, e: usize) -> &[Opt] {
        if self.p.elements[e].1 {
            &self.brakes
        } else {
            &self.clutches
        }
    }

    /// Every layout (an option index per element) whose states all pass,
    /// each with the layouts that do the same in every gear state (the same
    /// shafts turn together, or are held, in each): one transmission.
    pub(crate) fn run(&mut self, limit: usize) -> Vec<(Vec<u32>, Vec<Vec<u32>>)> {
        let mut out = Vec::new();
        self.place(0, &mut out, limit);
        out
    }

    /// What the engaged elements of each state make turn together: per
    /// state, the groups of shafts (bit n: the case), each set with two
    /// members in a group locking the set into it.
    fn effect(&self) -> Vec<Vec<u64>> {
        self.p
            .states
            .iter()
            .map(|(engaged, _)| {
                let mut groups: Vec<u64> = engaged
                    .iter()
                    .map(|&e| self.opts(e)[self.pick[e] as usize].mask)
                    .collect();
                loop {
                    let mut merged = false;
                    'outer: for i in 0..groups.len() {
                        for j in i + 1..groups.len() {
                            if groups[i] & groups[j] != 0 {
                                groups[i] |= groups[j];
                                groups.swap_remove(j);
                                merged = true;
                                break 'outer;
                            }
                        }
                        for &m in &self.set_masks {
                            let g = groups[i];
                            if g & m != m && (g & m).count_ones() >= 2 {
                                groups[i] |= m;
                                merged = true;
                            }
                        }
                    }
                    if !merged {
                        break;
                    }
                }
                groups.sort_unstable();
                groups
            })
            .collect()
    }

    fn place(&mut self, depth: usize, out: &mut Vec<(Vec<u32>, Vec<Vec<u32>>)>, limit: usize) {
        if out.len() >= limit {
            return;
        }
        if depth == self.p.order.len() {
            // A set whose ratio moves no targeted state idles in every
            // gear: a concept with fewer sets, not this one (and its teeth
            // would all be solutions).
            let all = (1_u64 << self.p.dims.len()) - 1;
            let targeted = self.p.states.iter().any(|s| s.1.is_some());
            if targeted && self.depends.iter().fold(0, |a, b| a | b) != all {
                self.idle += 1;
                return;
            }
            let key = self.effect();
            if let Some(&i) = self.seen.get(&key) {
                out[i].1.push(self.pick.clone());
            } else {
                self.seen.insert(key, out.len());
                out.push((self.pick.clone(), Vec::new()));
            }
            return;
        }
        let e = self.p.order[depth];
        let count = self.opts(e).len();
        'next: for o in 0..count {
            // Two elements of one way-ness with the same closure waste one.
            let mask = self.opts(e)[o].mask;
            for &f in &self.p.order[..depth] {
                if self.p.elements[f].0 == self.p.elements[e].0
                    && self.opts(f)[self.pick[f] as usize].mask == mask
                {
                    continue 'next;
                }
            }
            self.pick[e] = o as u32;
            let live = self.live.len();
            for si in 0..self.p.completes[e].len() {
                let s = self.p.completes[e][si];
                if !self.state_ok(s) {
                    self.live.truncate(live);
                    continue 'next;
                }
            }
            self.place(depth + 1, out, limit);
            self.live.truncate(live);
        }
    }

    fn state_ok(&mut self, s: usize) -> bool {
        let (engaged, window) = &self.p.states[s];
        let mut key: Vec<u64> = engaged
            .iter()
            .map(|&e| self.opts(e)[self.pick[e] as usize].mask)
            .collect();
        key.sort_unstable();
        if !self.memo.contains_key(&key) {
            let v = self.verdict(engaged);
            self.checked += 1;
            self.memo.insert(key.clone(), v);
        }
        let v = &self.memo[&key];
        if !v.regular {
            return false;
        }
        if window.is_some() {
            self.depends[s] = v.depends;
        }
        let Some((lo, hi)) = *window else {
            return true;
        };
        let eps = 1e-9 * lo.abs().max(hi.abs());
        let ok = match v.constant {
            Some(w) => {
                let met = w >= lo - eps && w <= hi + eps;
                self.constant_missed += u64::from(!met);
                met
            }
            None => !misses(&v.vertices, lo, hi),
        };
        if !ok {
            return false;
        }
        // A state with another's ratio for all teeth needs a window that
        // meets the other's (the 8HP space has layouts where five states
        // of five targets share one ratio).
        if let Some(sig) = v.sig {
            let apart = self.live.iter().any(|&(other, (olo, ohi))| {
                same_speed(sig[0], other[0])
                    && same_speed(sig[1], other[1])
                    && (lo > ohi + eps || olo > hi + eps)
            });
            if apart {
                self.shared_apart += 1;
                return false;
            }
            self.live.push((sig, (lo, hi)));
        }
        true
    }

    /// The state's system without its Willis coefficients: element rows and
    /// the input row, then the Willis rows' places.
    fn verdict(&self, engaged: &[usize]) -> Verdict {
        let n = self.n;
        let mut base = [0.0_f64; MAX_SHAFTS * MAX_SHAFTS];
        let w = self.p.willis.len();
        for (i, &e) in engaged.iter().enumerate() {
            let o = &self.opts(e)[self.pick[e] as usize];
            let r = (w + i) * n;
            base[r + o.a] += 1.0;
            if let Some(b) = o.b {
                base[r + b] -= 1.0;
            }
        }
        let input_row = w + engaged.len();
        base[input_row * n + self.s.input] = 1.0;
        if input_row + 1 != n {
            return Verdict {
                regular: false,
                depends: 0,
                constant: None,
                sig: None,
                vertices: Vec::new(),
            };
        }
        let dims = &self.p.dims;
        let regular = (0..2).any(|q| {
            let ks: Vec<f64> = dims.iter().map(|d| d.picks[q]).collect();
            self.solve(&base, &ks, input_row).2
        });
        if !regular {
            return Verdict {
                regular,
                depends: 0,
                constant: None,
                sig: None,
                vertices: Vec::new(),
            };
        }
        // Which basic ratios move w_out: each changed alone from one pick to the other.
        let at = |ks: &[f64]| self.solve(&base, ks, input_row).1;
        let k0: Vec<f64> = dims.iter().map(|d| d.picks[0]).collect();
        let w0 = at(&k0);
        let mut depends = 0_u64;
        for d in 0..dims.len() {
            let mut k = k0.clone();
            k[d] = dims[d].picks[1];
            let w = at(&k);
            let same = same_speed(w, w0);
            if !same {
                depends |= 1 << d;
            }
        }
        // The box of the dimensions w_out depends on; the others at their
        // generic pick (N and D may share a factor in them that changes
        // sign inside the box, which the vertex test cannot see past).
        let bx: Vec<(f64, f64)> = dims
            .iter()
            .enumerate()
            .map(|(i, d)| {
                if depends >> i & 1 == 1 {
                    (d.lo, d.hi)
                } else {
                    (d.picks[0], d.picks[0])
                }
            })
            .collect();
        Verdict {
            regular,
            depends,
            constant: (depends == 0 && w0.is_finite()).then_some(w0),
            sig: {
                let k1: Vec<f64> = dims.iter().map(|d| d.picks[1]).collect();
                let w1 = at(&k1);
                (w0.is_finite() && w1.is_finite()).then_some([w0, w1])
            },
            vertices: self.vertices(&base, input_row, &bx),
        }
    }

    /// (N, D) of w_out = N / D at the vertices of the box `bx`.
    fn vertices(&self, base: &[f64], input_row: usize, bx: &[(f64, f64)]) -> Vec<(f64, f64)> {
        let m = bx.len();
        let mut ks = vec![0.0; m];
        let mut out = Vec::with_capacity(1 << m);
        for v in 0..1_usize << m {
            for (u, k) in ks.iter_mut().enumerate() {
                *k = if v >> u & 1 == 1 { bx[u].1 } else { bx[u].0 };
            }
            let (det, wout, _) = self.solve(base, &ks, input_row);
            if det != 0.0 && wout.is_finite() {
                out.push((wout * det, det));
            } else {
                // Singular here: N by Cramer (w_out's column replaced by
                // the right-hand side), D = 0.
                out.push((self.numerator(base, &ks, input_row), 0.0));
            }
        }
        out
    }

    /// The Cramer numerator of w_out: det A with the output's column
    /// replaced by the right-hand side (the unit input row).
    fn numerator(&self, base: &[f64], ks: &[f64], input_row: usize) -> f64 {
        let n = self.n;
        let mut a = [0.0_f64; MAX_SHAFTS * MAX_SHAFTS];
        self.fill(&mut a, base, ks);
        let out = self.s.output;
        for i in 0..n {
            a[i * n + out] = if i == input_row { 1.0 } else { 0.0 };
        }
        let mut det = 1.0;
        for k in 0..n {
            let p = (k..n)
                .max_by(|&x, &y| a[x * n + k].abs().total_cmp(&a[y * n + k].abs()))
                .unwrap_or(k);
            let piv = a[p * n + k];
            if piv == 0.0 {
                return 0.0;
            }
            if p != k {
                for j in 0..n {
                    a.swap(p * n + j, k * n + j);
                }
                det = -det;
            }
            det *= piv;
            for i in k + 1..n {
                let f = a[i * n + k] / piv;
                for j in k..n {
                    a[i * n + j] -= f * a[k * n + j];
                }
            }
        }
        det
    }

    /// The state's matrix at `ks`: `base` with the Willis rows written in.
    fn fill(&self, a: &mut [f64], base: &[f64], ks: &[f64]) {
        let n = self.n;
        a[..n * n].copy_from_slice(&base[..n * n]);
        for (i, &(s, r, c, d)) in self.p.willis.iter().enumerate() {
            let coef = searched_willis(self.p.dims[d].sign * ks[d]);
            for (m, x) in [s, r, c].into_iter().zip(coef) {
                if let Some(j) = self.col[m] {
                    a[i * n + j] += x;
                }
            }
        }
    }

    /// det A, w_out and whether A is regular (smallest pivot above round-off
    /// of the largest), for basic ratios `ks` (unsigned; the sign is the
    /// dimension's).
    fn solve(&self, base: &[f64], ks: &[f64], input_row: usize) -> (f64, f64, bool) {
        let n = self.n;
        let mut a = [0.0_f64; MAX_SHAFTS * MAX_SHAFTS];
        self.fill(&mut a, base, ks);
        let mut rhs = [0.0_f64; MAX_SHAFTS];
        rhs[input_row] = 1.0;
        let mut det = 1.0;
        let (mut pmin, mut pmax) = (f64::INFINITY, 0.0_f64);
        for k in 0..n {
            let p = (k..n)
                .max_by(|&x, &y| a[x * n + k].abs().total_cmp(&a[y * n + k].abs()))
                .unwrap_or(k);
            let piv = a[p * n + k];
            pmin = pmin.min(piv.abs());
            pmax = pmax.max(piv.abs());
            if piv == 0.0 {
                return (0.0, f64::NAN, false);
            }
            if p != k {
                for j in 0..n {
                    a.swap(p * n + j, k * n + j);
                }
                rhs.swap(p, k);
                det = -det;
            }
            det *= piv;
            for i in k + 1..n {
                let f = a[i * n + k] / piv;
                if f != 0.0 {
                    for j in k..n {
                        a[i * n + j] -= f * a[k * n + j];
                    }
                    rhs[i] -= f * rhs[k];
                }
            }
        }
        // Back substitution for the output column only needs the whole solve.
        let mut w = [0.0_f64; MAX_SHAFTS];
        for i in (0..n).rev() {
            let mut acc = rhs[i];
            for j in i + 1..n {
                acc -= a[i * n + j] * w[j];
            }
            w[i] = acc / a[i * n + i];
        }
        (det, w[self.s.output], pmin > 1e-10 * pmax)
    }
}
