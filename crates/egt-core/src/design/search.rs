//! The tooth-count search: branch and bound over the basic ratios k = z_ring /
//! z_sun of the unknown sets, then exact confirmation of every survivor.
//!
//! Per gear state the Willis rows (eq. 2 of the paper, one per simple set:
//! w_s - w_c + k (w_r - w_c) = 0), the engaged elements' rows and w_in = 1 form
//! a square system A(k) w = e. Each k_i sits in one row, so det A and the
//! Cramer numerator of w_out are affine in each k_i: on a box of k values, if
//! det A keeps one sign at every vertex it has no zero inside, and w_out is
//! monotone in each k_i, so its range over the box is spanned by the vertex
//! values. A box whose w_out range misses a target's window is dropped whole;
//! the others are halved along the set with the most candidate ratios. Leaves
//! (one k per set) are checked in floats, then rebuilt as a train and solved
//! exactly by the transmission analysis (`Train::shift_table`), which gives
//! the reported ratios as fractions.

use std::collections::HashMap;

use nalgebra::{DMatrix, DVector};
use num_rational::Ratio;
use serde::Serialize;

use super::spec::{Constraints, SetRange, SynthSpec};
use crate::model::train::Train;
use crate::spec::{PlanetaryKind, Spec};

/// Why a search cannot run. Each variant names the offending field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DesignError {
    /// `sets.<name>` is not a planetary set of the base train.
    #[error("sets.{0}: no simple planetary set of that name in the base train")]
    UnknownSet(String),
    /// `targets.ratios.<state>` is not a gear state of the base train.
    #[error("targets.ratios.{0}: no gear state of that name in the base train")]
    UnknownState(String),
    /// A field has an impossible value.
    #[error("{field}: {message}")]
    Invalid {
        /// The field.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The base train or a candidate failed egt's own analysis.
    #[error(transparent)]
    Egt(#[from] crate::Error),
}

/// A design error as one of egt's typed errors (so the CLI's exit codes,
/// JSON error codes and Python's exceptions cover it): the base train's and
/// candidates' own errors as they are; a field, set or state of the search
/// spec as a spec error naming it (exit 2).
impl From<DesignError> for crate::Error {
    fn from(e: DesignError) -> Self {
        match e {
            DesignError::Egt(e) => e,
            DesignError::UnknownSet(name) => crate::Error::invalid(
                format!("sets.{name}"),
                "no simple planetary set of that name in the base train",
            ),
            DesignError::UnknownState(name) => crate::Error::invalid(
                format!("targets.ratios.{name}"),
                "no gear state of that name in the base train",
            ),
            DesignError::Invalid { field, message } => crate::Error::invalid(field, message),
        }
    }
}

/// One way to build a set: sun, ring and planet teeth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Teeth {
    /// Sun.
    pub sun: i64,
    /// Ring.
    pub ring: i64,
    /// Planet.
    pub planet: i64,
}

/// A basic ratio k = ring / sun (reduced) and every admissible tooth triple giving it.
#[derive(Debug, Clone)]
struct Basic {
    k: f64,
    teeth: Vec<Teeth>,
}

/// A gear state's square system with the unknown sets' rows marked.
#[derive(Debug, Clone)]
struct StateSystem {
    matrix: DMatrix<f64>,
    /// Per unknown set: (row, sun col, ring col, carrier col).
    rows: Vec<(usize, usize, usize, usize)>,
    output: usize,
    input_row: usize,
    target: Option<f64>,
}

/// A prepared search: the per-set candidate ratios and the per-state systems.
#[derive(Debug, Clone)]
pub struct Search {
    spec: SynthSpec,
    base: Spec,
    set_names: Vec<String>,
    basics: Vec<Vec<Basic>>,
    states: Vec<StateSystem>,
}

/// One candidate returned by the search.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// Per unknown set (in spec order): the basic ratio ring/sun as a fraction.
    pub basic: Vec<String>,
    /// Per unknown set: the smallest-sun tooth triple giving that ratio.
    pub teeth: Vec<Teeth>,
    /// Per unknown set: every admissible triple with the same ratio (same gear ratios).
    pub alternatives: Vec<usize>,
    /// Per gear state (base order): name, ratio (float), exact ratio.
    pub ratios: Vec<(String, f64, String)>,
    /// Spread of the forward ratios.
    pub spread: Option<f64>,
    /// Score: root mean square of (ratio - target) / target over the targeted states. Lower is better.
    pub score: f64,
}

/// Counts of a finished search.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Stats {
    /// Product of the per-set counts of admissible tooth triples (the naive space).
    pub tooth_space: f64,
    /// Product of the per-set counts of distinct basic ratios (the searched space).
    pub ratio_space: f64,
    /// Branch-and-bound nodes visited.
    pub nodes: u64,
    /// Leaves (full ratio vectors) evaluated.
    pub leaves: u64,
}

/// Most (sun, ring) pairs one set's ranges may span (each is visited once).
pub const MAX_SET_PAIRS: i64 = 10_000_000;

/// Admissible tooth triples of one set, grouped by reduced ring/sun, sorted by k.
fn basics(name: &str, r: &SetRange, c: &Constraints) -> Result<Vec<Basic>, DesignError> {
    let bad = |f: &str, m: &str| DesignError::Invalid {
        field: format!("sets.{name}.{f}"),
        message: m.into(),
    };
    if r.sun[0] < 3 || r.sun[0] > r.sun[1] {
        return Err(bad("sun", "need 3 <= min <= max"));
    }
    if r.ring[0] > r.ring[1] || r.ring[1] <= r.sun[0] {
        return Err(bad(
            "ring",
            "need min <= max and max above the smallest sun",
        ));
    }
    if r.planets < 1 {
        return Err(bad("planets", "need at least one planet"));
    }
    // Bounded work per set: every (sun, ring) pair of the ranges is visited once.
    let max = crate::error::MAX_TEETH;
    if r.sun[1] > max || r.ring[1] > max {
        return Err(bad(
            "sun",
            &format!("tooth counts above {max} are not searched"),
        ));
    }
    let pairs = (r.sun[1] - r.sun[0] + 1).saturating_mul(r.ring[1] - r.ring[0] + 1);
    if pairs > MAX_SET_PAIRS {
        return Err(bad(
            "ring",
            &format!(
                "{pairs} (sun, ring) pairs in this set; at most {MAX_SET_PAIRS} are searched per set"
            ),
        ));
    }
    let mut map: HashMap<Ratio<i64>, Vec<Teeth>> = HashMap::new();
    for sun in r.sun[0]..=r.sun[1] {
        for ring in r.ring[0]..=r.ring[1] {
            let diff = ring - sun;
            if diff <= 0 {
                continue;
            }
            // Planet from the coaxial condition, within the profile-shift allowance.
            let planet = diff / 2;
            if (diff - 2 * planet).abs() > c.profile_shift || planet < c.min_planet {
                continue;
            }
            if c.assembly && (sun + ring) % r.planets != 0 {
                continue;
            }
            if c.non_interference && r.planets > 1 {
                let s = (std::f64::consts::PI / r.planets as f64).sin();
                if (sun + planet) as f64 * s <= (planet + 2) as f64 {
                    continue;
                }
            }
            let k = ring as f64 / sun as f64;
            if let Some([lo, hi]) = c.ring_sun
                && (k < lo || k > hi)
            {
                continue;
            }
            map.entry(Ratio::new(ring, sun))
                .or_default()
                .push(Teeth { sun, ring, planet });
        }
    }
    let mut out: Vec<Basic> = map
        .into_iter()
        .map(|(q, mut teeth)| {
            teeth.sort_by_key(|t| (t.sun, t.ring));
            Basic {
                k: *q.numer() as f64 / *q.denom() as f64,
                teeth,
            }
        })
        .collect();
    out.sort_by(|a, b| a.k.total_cmp(&b.k));
    if out.is_empty() {
        return Err(bad(
            "sun",
            "no tooth counts in these ranges meet the constraints",
        ));
    }
    Ok(out)
}

impl Search {
    /// Prepare a search: check names against the base train, list each set's
    /// admissible teeth, and build each gear state's system once.
    ///
    /// # Errors
    /// [`DesignError`] naming the offending field, set or state.
    pub fn new(spec: SynthSpec, base: Spec) -> Result<Search, DesignError> {
        let tx = base
            .transmission
            .clone()
            .ok_or_else(|| DesignError::Invalid {
                field: "base".into(),
                message: "the base train has no [transmission] section".into(),
            })?;
        if !(spec.targets.tolerance > 0.0 && spec.targets.tolerance.is_finite()) {
            return Err(DesignError::Invalid {
                field: "targets.tolerance".into(),
                message: "must be positive".into(),
            });
        }
        for s in spec.targets.ratios.keys() {
            if !tx.states.contains_key(s) {
                return Err(DesignError::UnknownState(s.clone()));
            }
        }
        let mut links: Vec<String> = Vec::new();
        let col = |name: &str, links: &mut Vec<String>| -> usize {
            if let Some(i) = links.iter().position(|l| l == name) {
                i
            } else {
                links.push(name.to_string());
                links.len() - 1
            }
        };
        // Willis rows of every simple set: known sets get their k now.
        let mut willis = Vec::new();
        for p in &base.planetary {
            let ring = p.ring.clone().ok_or_else(|| DesignError::Invalid {
                field: format!("planetary.{}", p.name),
                message: "synth handles simple sets (sun, ring, carrier) only".into(),
            })?;
            if p.kind != PlanetaryKind::Simple {
                return Err(DesignError::Invalid {
                    field: format!("planetary.{}", p.name),
                    message: "synth handles simple sets only".into(),
                });
            }
            let (s, r, c) = (
                col(&p.sun, &mut links),
                col(&ring, &mut links),
                col(&p.carrier, &mut links),
            );
            let k = match (p.teeth.sun, p.teeth.ring) {
                (Some(zs), Some(zr)) => zr as f64 / zs as f64,
                _ => f64::NAN,
            };
            willis.push((p.name.clone(), s, r, c, k));
        }
        let set_names: Vec<String> = spec.sets.keys().cloned().collect();
        let mut unknown_of = Vec::new();
        for n in &set_names {
            let i = willis
                .iter()
                .position(|w| &w.0 == n)
                .ok_or_else(|| DesignError::UnknownSet(n.clone()))?;
            unknown_of.push(i);
        }
        for (i, w) in willis.iter().enumerate() {
            if w.4.is_nan() && !unknown_of.contains(&i) {
                return Err(DesignError::Invalid {
                    field: format!("planetary.{}.teeth", w.0),
                    message: "give sun and ring teeth, or list the set under [sets]".into(),
                });
            }
        }
        for e in &base.elements {
            for l in &e.links {
                col(l, &mut links);
            }
        }
        let input = col(&tx.input, &mut links);
        let output = col(&tx.output, &mut links);
        let frame = links.iter().position(|l| l == &base.frame);
        let n = links.len();
        let mut states = Vec::new();
        for (name, engaged) in &tx.states {
            let mut rows: Vec<Vec<f64>> = Vec::new();
            let mut marks = Vec::new();
            for (i, &(_, s, r, c, k)) in willis.iter().enumerate() {
                let mut row = vec![0.0; n];
                row[s] += 1.0;
                row[r] += if k.is_nan() { 0.0 } else { k };
                row[c] -= 1.0 + if k.is_nan() { 0.0 } else { k };
                if let Some(u) = unknown_of.iter().position(|&j| j == i) {
                    marks.push((u, rows.len(), s, r, c));
                }
                rows.push(row);
            }
            for el in engaged {
                let e = base
                    .elements
                    .iter()
                    .find(|e| &e.name == el)
                    .ok_or_else(|| DesignError::Invalid {
                        field: format!("transmission.states.{name}"),
                        message: format!("unknown element `{el}`"),
                    })?;
                let mut row = vec![0.0; n];
                let a = col(&e.links[0], &mut links);
                row[a] += 1.0;
                if let Some(b) = e.links.get(1) {
                    let b = col(b, &mut links);
                    row[b] -= 1.0;
                }
                rows.push(row);
            }
            if let Some(f) = frame {
                let mut row = vec![0.0; n];
                row[f] = 1.0;
                rows.push(row);
            }
            let input_row = rows.len();
            let mut row = vec![0.0; n];
            row[input] = 1.0;
            rows.push(row);
            if rows.len() != n {
                return Err(DesignError::Invalid {
                    field: format!("transmission.states.{name}"),
                    message: format!(
                        "{} constraint rows for {} links: synth needs one-DOF states of a one-DOF-per-element train",
                        rows.len(),
                        n
                    ),
                });
            }
            let matrix = DMatrix::from_fn(n, n, |i, j| rows[i][j]);
            marks.sort_by_key(|m| m.0);
            let rows = marks
                .iter()
                .map(|&(_, row, s, r, c)| (row, s, r, c))
                .collect();
            states.push(StateSystem {
                matrix,
                rows,
                output,
                input_row,
                target: spec.targets.ratios.get(name).copied(),
            });
        }
        let mut basics_all = Vec::new();
        for (name, r) in &spec.sets {
            basics_all.push(basics(name, r, &spec.constraints)?);
        }
        Ok(Search {
            spec,
            base,
            set_names,
            basics: basics_all,
            states,
        })
    }

    /// How many of the best candidates a run keeps (the spec's `top`).
    pub fn top(&self) -> usize {
        self.spec.top
    }

    /// The unknown sets, in the order of each candidate's lists.
    pub fn set_names(&self) -> &[String] {
        &self.set_names
    }

    /// Number of partitions the first unknown set's ratios can be split into.
    pub fn max_partitions(&self) -> usize {
        self.basics[0].len()
    }

    /// Run partition `part` of `parts` (contiguous slices of the first set's
    /// sorted ratios). Partitions are disjoint and cover the space, so their
    /// candidates can be merged and re-ranked in any order.
    ///
    /// # Errors
    /// [`DesignError::Invalid`] for a bad partition, or an exact-analysis failure.
    pub fn run_partition(
        &self,
        part: usize,
        parts: usize,
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        if parts == 0 || part >= parts {
            return Err(DesignError::Invalid {
                field: "partition".into(),
                message: format!("{part} of {parts}"),
            });
        }
        // In u128: part and parts come from the command line and may be huge.
        let len = self.basics[0].len() as u128;
        let slice =
            |p: usize| usize::try_from(len * p as u128 / parts as u128).unwrap_or(usize::MAX);
        let (lo, hi) = (slice(part), slice(part + 1));
        let mut stats = Stats {
            tooth_space: self
                .basics
                .iter()
                .map(|b| b.iter().map(|x| x.teeth.len() as f64).sum::<f64>())
                .product(),
            ratio_space: self.basics.iter().map(|b| b.len() as f64).product(),
            ..Stats::default()
        };
        if lo >= hi {
            return Ok((Vec::new(), stats));
        }
        let mut bounds: Vec<(usize, usize)> = self.basics.iter().map(|b| (0, b.len())).collect();
        bounds[0] = (lo, hi);
        let nodes = std::sync::atomic::AtomicU64::new(0);
        let leaves = std::sync::atomic::AtomicU64::new(0);
        let found = self.branch(&bounds, &nodes, &leaves);
        stats.nodes = nodes.into_inner();
        stats.leaves = leaves.into_inner();
        let mut out = Vec::new();
        for ks in found {
            out.push(self.confirm(&ks)?);
        }
        rank(&mut out, self.spec.top);
        Ok((out, stats))
    }

    /// Run the whole space as `parts` partitions one after another (each on
    /// all cores), calling `progress(done, parts)` after each: what a
    /// progress bar and an ETA need. Merged and ranked, the result is
    /// [`Search::run`]'s.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run_in_parts(
        &self,
        parts: usize,
        mut progress: impl FnMut(usize, usize),
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        let parts = parts.clamp(1, self.max_partitions().max(1));
        let mut found = Vec::new();
        let mut total = Stats::default();
        for part in 0..parts {
            let (c, s) = self.run_partition(part, parts)?;
            found.extend(c);
            total.tooth_space = s.tooth_space;
            total.ratio_space = s.ratio_space;
            total.nodes += s.nodes;
            total.leaves += s.leaves;
            progress(part + 1, parts);
        }
        rank(&mut found, self.spec.top);
        Ok((found, total))
    }

    /// Run the whole space (one partition) on all cores.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run(&self) -> Result<(Vec<Candidate>, Stats), DesignError> {
        self.run_partition(0, 1)
    }

    /// Output speeds at the vertices of a box; None if det A changes sign (no bound).
    fn state_range(&self, st: &StateSystem, bounds: &[(usize, usize)]) -> Option<(f64, f64)> {
        let m = bounds.len();
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut sign = 0.0f64;
        let mut a = st.matrix.clone();
        for v in 0..(1usize << m) {
            for (u, &(row, s, r, c)) in st.rows.iter().enumerate() {
                let (b0, b1) = bounds[u];
                let idx = if v >> u & 1 == 1 { b1 - 1 } else { b0 };
                let k = self.basics[u][idx].k;
                for j in 0..a.ncols() {
                    a[(row, j)] = 0.0;
                }
                a[(row, s)] += 1.0;
                a[(row, r)] += k;
                a[(row, c)] -= 1.0 + k;
            }
            let lu = a.clone().lu();
            let det = lu.determinant();
            if det == 0.0 || (sign != 0.0 && det.signum() != sign) {
                return None;
            }
            sign = det.signum();
            let mut e = DVector::zeros(a.nrows());
            e[st.input_row] = 1.0;
            let w = lu.solve(&e)?[st.output];
            lo = lo.min(w);
            hi = hi.max(w);
        }
        Some((lo, hi))
    }

    /// Does the box possibly hold a solution? (false = every state's window missed by some state.)
    fn feasible(&self, bounds: &[(usize, usize)]) -> bool {
        let tol = self.spec.targets.tolerance;
        for st in &self.states {
            let Some(t) = st.target else { continue };
            let (a, b) = (t - tol, t + tol);
            if a <= 0.0 && b >= 0.0 {
                continue;
            }
            // Output speed window 1/ratio.
            let (wlo, whi) = (1.0 / b, 1.0 / a);
            let (wlo, whi) = (wlo.min(whi), wlo.max(whi));
            if let Some((lo, hi)) = self.state_range(st, bounds)
                && (hi < wlo || lo > whi)
            {
                return false;
            }
        }
        true
    }

    fn branch(
        &self,
        bounds: &[(usize, usize)],
        nodes: &std::sync::atomic::AtomicU64,
        leaves: &std::sync::atomic::AtomicU64,
    ) -> Vec<Vec<usize>> {
        use std::sync::atomic::Ordering::Relaxed;
        nodes.fetch_add(1, Relaxed);
        if !self.feasible(bounds) {
            return Vec::new();
        }
        let widest = (0..bounds.len())
            .max_by_key(|&u| bounds[u].1 - bounds[u].0)
            .unwrap_or(0);
        let (b0, b1) = bounds[widest];
        if b1 - b0 <= 1 {
            leaves.fetch_add(1, Relaxed);
            // A single point: the box test above was exact up to round-off; check spread.
            return if self.leaf_ok(bounds) {
                vec![bounds.iter().map(|b| b.0).collect()]
            } else {
                Vec::new()
            };
        }
        let mid = b0 + (b1 - b0) / 2;
        let mut left = bounds.to_vec();
        left[widest] = (b0, mid);
        let mut right = bounds.to_vec();
        right[widest] = (mid, b1);
        let (mut l, r) = rayon::join(
            || self.branch(&left, nodes, leaves),
            || self.branch(&right, nodes, leaves),
        );
        l.extend(r);
        l
    }

    fn leaf_ok(&self, bounds: &[(usize, usize)]) -> bool {
        let tol = self.spec.targets.tolerance;
        let mut fwd = Vec::new();
        for st in &self.states {
            let Some((w, _)) = self.state_range(st, bounds) else {
                return false;
            };
            let ratio = 1.0 / w;
            if let Some(t) = st.target
                && (ratio - t).abs() > tol
            {
                return false;
            }
            if ratio > 0.0 && ratio.is_finite() {
                fwd.push(ratio);
            }
        }
        if let Some([lo, hi]) = self.spec.targets.spread {
            let mx = fwd.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let mn = fwd.iter().copied().fold(f64::INFINITY, f64::min);
            let s = mx / mn;
            if !(s >= lo && s <= hi) {
                return false;
            }
        }
        true
    }

    /// The base spec with the candidate's teeth written in.
    pub fn candidate_spec(&self, teeth: &[Teeth]) -> Spec {
        let mut spec = self.base.clone();
        for (name, t) in self.set_names.iter().zip(teeth) {
            if let Some(p) = spec.planetary.iter_mut().find(|p| &p.name == name) {
                p.teeth.sun = Some(t.sun);
                p.teeth.ring = Some(t.ring);
                p.teeth.planet = Some(t.planet);
            }
        }
        spec
    }

    /// Rebuild the train with the candidate's teeth and solve it exactly.
    fn confirm(&self, ks: &[usize]) -> Result<Candidate, DesignError> {
        let teeth: Vec<Teeth> = ks
            .iter()
            .enumerate()
            .map(|(u, &i)| self.basics[u][i].teeth[0])
            .collect();
        let train = Train::from_spec(&self.candidate_spec(&teeth))?;
        let table = train.shift_table()?;
        let mut ratios = Vec::new();
        let mut err2 = 0.0;
        let mut nt = 0;
        for g in &table.gears {
            let exact = g
                .ratio_exact
                .as_ref()
                .map(crate::numerics::exact::display)
                .unwrap_or_default();
            if let Some(t) = self.spec.targets.ratios.get(&g.state) {
                err2 += ((g.ratio - t) / t).powi(2);
                nt += 1;
            }
            ratios.push((g.state.clone(), g.ratio, exact));
        }
        Ok(Candidate {
            basic: ks
                .iter()
                .enumerate()
                .map(|(u, &i)| {
                    let t = self.basics[u][i].teeth[0];
                    crate::numerics::exact::display(&crate::numerics::exact::frac(t.ring, t.sun))
                })
                .collect(),
            teeth,
            alternatives: ks
                .iter()
                .enumerate()
                .map(|(u, &i)| self.basics[u][i].teeth.len())
                .collect(),
            ratios,
            spread: table.spread.as_ref().map(|s| s.value),
            score: if nt > 0 {
                (err2 / nt as f64).sqrt()
            } else {
                0.0
            },
        })
    }
}

/// Sort by score (then by the teeth, so that the order is canonical) and keep `top`.
pub fn rank(c: &mut Vec<Candidate>, top: usize) {
    c.sort_by(|a, b| {
        a.score.total_cmp(&b.score).then_with(|| {
            let ka: Vec<_> = a.teeth.iter().map(|t| (t.sun, t.ring)).collect();
            let kb: Vec<_> = b.teeth.iter().map(|t| (t.sun, t.ring)).collect();
            ka.cmp(&kb)
        })
    });
    c.truncate(top);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::parse::{Format, parse_spec};

    const ZF: &str = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/zf_8hp70.toml"
    ));

    fn zf_search(sets: &str) -> Search {
        let text = format!(
            "base = \"zf_8hp70.toml\"\ntop = 5\n{sets}\n[targets]\nratios = {{ \"1\" = 4.696, \"2\" = 3.130, \"3\" = 2.104, \"4\" = 1.667, \"5\" = 1.285, \"6\" = 1.000, \"7\" = 0.839, \"8\" = 0.667, \"R\" = -3.297 }}\n"
        );
        let spec: SynthSpec = toml::from_str(&text).expect("test input");
        Search::new(
            spec,
            parse_spec(ZF, Format::Toml, "zf").expect("test input"),
        )
        .expect("test input")
    }

    /// Rediscovery of the 8HP teeth from the published ratios (to three
    /// decimals) within small ranges around them; every candidate's ratios
    /// come from the exact analysis and meet the targets.
    #[test]
    fn rediscovers_8hp_teeth() {
        let s = zf_search(
            "[sets]\nP1 = { sun = [44, 52], ring = [90, 100] }\nP2 = { sun = [44, 52], ring = [90, 100] }\nP3 = { sun = [64, 72], ring = [106, 114] }\nP4 = { sun = [20, 26], ring = [80, 88] }",
        );
        let (found, stats) = s.run().expect("test input");
        assert!(stats.leaves as f64 <= stats.ratio_space);
        let real = [(48, 96), (48, 96), (69, 111), (23, 85)];
        // The real set or one with identical basic ratios (ring/sun).
        assert!(found.iter().any(|c| {
            c.teeth
                .iter()
                .zip(real)
                .all(|(t, (zs, zr))| t.ring * zs == zr * t.sun)
        }));
        for c in &found {
            for (state, ratio, exact) in &c.ratios {
                let q = crate::numerics::exact::parse_rational(exact).expect("test input");
                assert!((crate::numerics::exact::to_f64(&q) - ratio).abs() < 1e-12);
                let t = s.spec.targets.ratios[state];
                assert!((ratio - t).abs() <= 5e-4, "{state}: {ratio} vs {t}");
            }
        }
    }

    /// Partitions are disjoint and cover the space: their merged candidates
    /// equal the one-partition run.
    #[test]
    fn partitions_merge_to_the_whole() {
        let s = zf_search(
            "[sets]\nP3 = { sun = [60, 76], ring = [100, 120] }\nP4 = { sun = [20, 28], ring = [76, 92] }",
        );
        let (whole, _) = s.run().expect("test input");
        let mut merged = Vec::new();
        for p in 0..3 {
            merged.extend(s.run_partition(p, 3).expect("test input").0);
        }
        rank(&mut merged, 5);
        let key = |c: &Vec<Candidate>| c.iter().map(|x| x.teeth.clone()).collect::<Vec<_>>();
        assert_eq!(key(&whole), key(&merged));
        assert!(!whole.is_empty());
    }

    /// Sequential parts with progress give the one-partition result.
    #[test]
    fn run_in_parts_reports_progress_and_equals_run() {
        let s = zf_search(
            "[sets]\nP3 = { sun = [60, 76], ring = [100, 120] }\nP4 = { sun = [20, 28], ring = [76, 92] }",
        );
        let (whole, ws) = s.run().expect("test input");
        let mut seen = Vec::new();
        let (parts, ps) = s
            .run_in_parts(4, |done, of| seen.push((done, of)))
            .expect("test input");
        assert_eq!(seen, [(1, 4), (2, 4), (3, 4), (4, 4)]);
        let key = |c: &Vec<Candidate>| c.iter().map(|x| x.teeth.clone()).collect::<Vec<_>>();
        assert_eq!(key(&whole), key(&parts));
        assert_eq!(ws.tooth_space, ps.tooth_space);
    }

    #[test]
    fn unknown_names_are_errors() {
        let spec: SynthSpec = toml::from_str(
            "base = \"x\"\n[sets]\nP9 = { sun = [20, 30], ring = [60, 80] }\n[targets]\nratios = { \"1\" = 4.7 }",
        )
        .expect("test input");
        let err = Search::new(
            spec,
            parse_spec(ZF, Format::Toml, "zf").expect("test input"),
        )
        .expect_err("must fail");
        assert!(err.to_string().contains("sets.P9"), "{err}");
    }

    /// Ranges that would take minutes or exhaust memory are refused by name
    /// before any pair is visited.
    #[test]
    fn huge_ranges_are_refused_by_field() {
        let err = Search::new(
            toml::from_str(
                "base = \"x\"\n[sets]\nP1 = { sun = [20, 100000], ring = [60, 200000] }\n[targets]\nratios = { \"1\" = 4.7 }",
            )
            .expect("test input"),
            parse_spec(ZF, Format::Toml, "zf").expect("test input"),
        )
        .expect_err("must refuse");
        assert!(
            err.to_string().contains("sets.P1.ring") && err.to_string().contains("10000000"),
            "{err}"
        );
        let err = Search::new(
            toml::from_str(
                "base = \"x\"\n[sets]\nP1 = { sun = [20, 30], ring = [60, 2000000] }\n[targets]\nratios = { \"1\" = 4.7 }",
            )
            .expect("test input"),
            parse_spec(ZF, Format::Toml, "zf").expect("test input"),
        )
        .expect_err("must refuse");
        assert!(err.to_string().contains("1000000"), "{err}");
    }

    /// The ranges (suns 20-80, rings 60-130, all four sets unknown,
    /// 8.9e10 tooth combinations): the bound leaves one candidate, the 8HP's
    /// basic ratios 2, 2, 111/69, 85/23.
    #[test]
    fn rediscovers_8hp_full_ranges() {
        let r = "{ sun = [20, 80], ring = [60, 130] }";
        let s = zf_search(&format!("[sets]\nP1 = {r}\nP2 = {r}\nP3 = {r}\nP4 = {r}"));
        let (found, stats) = s.run().expect("test input");
        assert!(stats.tooth_space > 1e10);
        assert_eq!(found[0].basic, ["2", "2", "37/23", "85/23"]);
    }
}
