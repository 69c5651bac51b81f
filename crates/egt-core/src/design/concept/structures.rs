//! The structure space of a concept search: every way to join the sets'
//! members into shafts, hold some on the case and pick the input and output
//! shafts that leaves the right number of DOF, each listed once up to a
//! relabelling of interchangeable sets (its canonical form).

use serde::{Deserialize, Serialize};

use crate::design::spec::InputRule;
use crate::spec::PlanetaryKind;

/// The members of a set of this kind, in the order of its member ids.
pub(crate) fn roles(kind: PlanetaryKind) -> &'static [&'static str] {
    match kind {
        PlanetaryKind::Ravigneaux => &["sun", "sun2", "ring", "carrier"],
        _ => &["sun", "ring", "carrier"],
    }
}

/// Willis rows a set of this kind adds (its members less its DOF).
pub(crate) fn willis_rows(kind: PlanetaryKind) -> usize {
    if kind == PlanetaryKind::Ravigneaux {
        2
    } else {
        1
    }
}

/// A set as the structure space sees it.
#[derive(Debug, Clone)]
pub(crate) struct SetSlot {
    /// Its first member id (members are numbered set by set).
    pub(crate) first: usize,
    pub(crate) kind: PlanetaryKind,
    /// Sets of one class (kind and tooth ranges alike) are interchangeable.
    pub(crate) class: usize,
}

/// One structure: the shafts (each the member ids on it; a separate input
/// shaft has none), the held members, and which shafts are the input and
/// the output.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Structure {
    /// The free shafts, each its member ids (at most two, of two sets).
    pub shafts: Vec<Vec<u8>>,
    /// Members held by the case.
    pub held: Vec<u8>,
    /// The input shaft.
    pub input: usize,
    /// The output shaft.
    pub output: usize,
}

/// A skeleton: the joined pairs and the held members.
type Skeleton = (Vec<(u8, u8)>, Vec<u8>);

/// What the enumeration needs: the sets, the DOF the base train must have
/// (one per engaged element, plus one), and the limits of the space.
#[derive(Debug, Clone)]
pub(crate) struct Space {
    pub(crate) sets: Vec<SetSlot>,
    pub(crate) members: usize,
    pub(crate) dof: usize,
    pub(crate) input: InputRule,
    pub(crate) held: [usize; 2],
}

impl Space {
    fn set_of(&self, m: usize) -> usize {
        self.sets.iter().rposition(|s| s.first <= m).unwrap_or(0)
    }

    /// Every permutation of the sets that maps each set to one of its class,
    /// as a map of member ids.
    fn relabellings(&self) -> Vec<Vec<u8>> {
        let n = self.sets.len();
        let mut out = Vec::new();
        let mut perm: Vec<usize> = (0..n).collect();
        permute(&mut perm, 0, &mut |p| {
            if (0..n).all(|i| self.sets[p[i]].class == self.sets[i].class) {
                let mut map = vec![0_u8; self.members];
                for (i, &j) in p.iter().enumerate() {
                    let len = roles(self.sets[i].kind).len();
                    for r in 0..len {
                        map[self.sets[i].first + r] = (self.sets[j].first + r) as u8;
                    }
                }
                out.push(map);
            }
        });
        out
    }

    /// Every structure once, in a fixed order. `limit`: most structures to
    /// list; None past it.
    pub(crate) fn structures(&self, limit: u64) -> Option<Vec<Structure>> {
        let maps = self.relabellings();
        let willis: usize = self.sets.iter().map(|s| willis_rows(s.kind)).sum();
        let mut out = Vec::new();
        for separate in [false, true] {
            let allowed = match self.input {
                InputRule::Member => !separate,
                InputRule::Shaft => separate,
                InputRule::Any => true,
            };
            // Free shafts = members - joins - held (+ the separate input),
            // and the base train's DOF = free shafts - Willis rows.
            let Some(merges) =
                (self.members + usize::from(separate)).checked_sub(willis + self.dof)
            else {
                continue;
            };
            if !allowed {
                continue;
            }
            for held in self.held[0]..=self.held[1].min(merges) {
                let joins = merges - held;
                let mut skeletons = Vec::new();
                let mut partner = vec![None; self.members];
                let mut held_flags = vec![false; self.members];
                self.skeletons(
                    0,
                    joins,
                    held,
                    &mut partner,
                    &mut held_flags,
                    &mut skeletons,
                );
                for (pairs, held_list) in skeletons {
                    let key = skeleton_key(&pairs, &held_list);
                    // Canonical skeletons only; keep their stabiliser.
                    let mut stab = Vec::new();
                    let mut smallest = true;
                    for map in &maps {
                        let k =
                            skeleton_key(&relabel_pairs(&pairs, map), &relabel(&held_list, map));
                        match k.cmp(&key) {
                            std::cmp::Ordering::Less => {
                                smallest = false;
                                break;
                            }
                            std::cmp::Ordering::Equal => stab.push(map),
                            std::cmp::Ordering::Greater => {}
                        }
                    }
                    if !smallest {
                        continue;
                    }
                    let shafts = shafts_of(self.members, &pairs, &held_list, separate);
                    let n = shafts.len();
                    for input in 0..n {
                        if separate && input != n - 1 {
                            continue;
                        }
                        for output in 0..n {
                            if output == input || (separate && output == n - 1) {
                                continue;
                            }
                            let s = Structure {
                                shafts: shafts.clone(),
                                held: held_list.clone(),
                                input,
                                output,
                            };
                            let key = io_key(&s, None);
                            if stab.iter().all(|m| io_key(&s, Some(m)) >= key) {
                                if out.len() as u64 >= limit {
                                    return None;
                                }
                                out.push(s);
                            }
                        }
                    }
                }
            }
        }
        Some(out)
    }

    /// Every choice of `joins` pairs of members of different sets and `held`
    /// held members (no member twice), from member `m` on.
    fn skeletons(
        &self,
        m: usize,
        joins: usize,
        held: usize,
        partner: &mut Vec<Option<usize>>,
        held_flags: &mut Vec<bool>,
        out: &mut Vec<Skeleton>,
    ) {
        if joins == 0 && held == 0 {
            let pairs = (0..self.members)
                .filter_map(|a| partner[a].filter(|&b| b > a).map(|b| (a as u8, b as u8)))
                .collect();
            let h = (0..self.members)
                .filter(|&a| held_flags[a])
                .map(|a| a as u8)
                .collect();
            out.push((pairs, h));
            return;
        }
        if m >= self.members {
            return;
        }
        if partner[m].is_some() {
            self.skeletons(m + 1, joins, held, partner, held_flags, out);
            return;
        }
        // Alone.
        self.skeletons(m + 1, joins, held, partner, held_flags, out);
        // At most one held member per set: two would hold the whole set.
        let set = self.set_of(m);
        if held > 0 && !(0..self.members).any(|b| held_flags[b] && self.set_of(b) == set) {
            held_flags[m] = true;
            self.skeletons(m + 1, joins, held - 1, partner, held_flags, out);
            held_flags[m] = false;
        }
        if joins > 0 {
            for b in m + 1..self.members {
                if partner[b].is_none() && !held_flags[b] && self.set_of(b) != set {
                    partner[m] = Some(b);
                    partner[b] = Some(m);
                    self.skeletons(m + 1, joins - 1, held, partner, held_flags, out);
                    partner[m] = None;
                    partner[b] = None;
                }
            }
        }
    }
}

fn permute(p: &mut Vec<usize>, k: usize, f: &mut impl FnMut(&[usize])) {
    if k == p.len() {
        f(p);
        return;
    }
    for i in k..p.len() {
        p.swap(k, i);
        permute(p, k + 1, f);
        p.swap(k, i);
    }
}

fn relabel(list: &[u8], map: &[u8]) -> Vec<u8> {
    let mut v: Vec<u8> = list.iter().map(|&m| map[m as usize]).collect();
    v.sort_unstable();
    v
}

fn relabel_pairs(pairs: &[(u8, u8)], map: &[u8]) -> Vec<(u8, u8)> {
    pairs
        .iter()
        .map(|&(a, b)| {
            let (a, b) = (map[a as usize], map[b as usize]);
            (a.min(b), a.max(b))
        })
        .collect()
}

fn skeleton_key(pairs: &[(u8, u8)], held: &[u8]) -> Vec<u8> {
    let mut p = pairs.to_vec();
    p.sort_unstable();
    let mut key: Vec<u8> = p.iter().flat_map(|&(a, b)| [a, b]).collect();
    key.push(u8::MAX);
    let mut h = held.to_vec();
    h.sort_unstable();
    key.extend(h);
    key
}

/// The input and output of a structure as the smallest member of their
/// shafts (a separate input: `u8::MAX`), under a relabelling.
fn io_key(s: &Structure, map: Option<&Vec<u8>>) -> (u8, u8) {
    let tag = |shaft: &Vec<u8>| {
        shaft
            .iter()
            .map(|&m| map.map_or(m, |map| map[m as usize]))
            .min()
            .unwrap_or(u8::MAX)
    };
    (tag(&s.shafts[s.input]), tag(&s.shafts[s.output]))
}

/// The free shafts of a skeleton: the joined pairs, then the members alone
/// (held ones excepted), then the separate input shaft.
fn shafts_of(members: usize, pairs: &[(u8, u8)], held: &[u8], separate: bool) -> Vec<Vec<u8>> {
    let mut shafts: Vec<Vec<u8>> = Vec::new();
    for m in 0..members as u8 {
        if held.contains(&m) {
            continue;
        }
        if let Some(&(a, b)) = pairs.iter().find(|p| p.0 == m || p.1 == m) {
            if a == m {
                shafts.push(vec![a, b]);
            }
        } else {
            shafts.push(vec![m]);
        }
    }
    if separate {
        shafts.push(Vec::new());
    }
    shafts
}

/// The canonical form of any structure of this space (relabelled copies
/// give the same): the smallest key over the relabellings. The enumeration
/// keeps the structures that are their own; the tests check it against this.
#[cfg(test)]
pub(crate) fn canonical_key(space: &Space, s: &Structure) -> (Vec<u8>, (u8, u8)) {
    let pairs: Vec<(u8, u8)> = s
        .shafts
        .iter()
        .filter(|sh| sh.len() == 2)
        .map(|sh| (sh[0].min(sh[1]), sh[0].max(sh[1])))
        .collect();
    space
        .relabellings()
        .iter()
        .map(|map| {
            (
                skeleton_key(&relabel_pairs(&pairs, map), &relabel(&s.held, map)),
                io_key(s, Some(map)),
            )
        })
        .min()
        .unwrap_or_default()
}
