//! The tooth-count search: branch and bound over the basic ratios k = z_ring /
//! z_sun of the unknown sets, then exact confirmation of every survivor.
//!
//! Per gear state the Willis rows (eq. 2 of the paper: w_s - w_c + s k (w_r -
//! w_c) = 0 with s = +1 for a simple set and a Ravigneaux set's large sun, -1
//! for its small sun and a double-pinion set), the engaged elements' rows and
//! w_in = 1 form a square system A(k) w = e. A simple set has one searched k, a
//! Ravigneaux set two (ring/small sun, ring/large sun: one ring, so not every
//! pair is made of teeth; the pairs that are, are checked at the leaves).
//! Each k_i sits in one row, so det A and the
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
use serde::{Deserialize, Serialize};

use super::spec::{Constraints, SetRange, SynthSpec};
pub use crate::error::DesignError;
use crate::model::equations::willis_row;
use crate::model::train::Train;
use crate::spec::{PlanetaryKind, Spec};

/// One way to build a set: sun, ring and planet teeth (and for a Ravigneaux
/// set the large sun and the short pinion).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Teeth {
    /// Sun (the small, forward sun of a Ravigneaux set).
    pub sun: i64,
    /// Ring.
    pub ring: i64,
    /// Planet meshing the sun (the short pinion of a Ravigneaux set), as the spec's `planet`.
    pub planet: i64,
    /// Large sun of a Ravigneaux set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun2: Option<i64>,
    /// Long pinion of a Ravigneaux set (meshing the short pinion, the large
    /// sun and the ring), as the spec's `planet2`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet2: Option<i64>,
}

/// A basic ratio k = ring / sun (reduced) and every admissible tooth triple giving it.
#[derive(Debug, Clone)]
struct Basic {
    k: f64,
    teeth: Vec<Teeth>,
}

/// One searched basic ratio: its distinct values, ascending, and the sign of
/// its Willis row w_s + sign k w_r - (1 + sign k) w_c = 0.
#[derive(Debug, Clone)]
struct Dim {
    ks: Vec<f64>,
    sign: f64,
}

/// An unknown set: its dimensions (one, or two for a Ravigneaux set) and the
/// admissible teeth of every combination of their indices that teeth can make.
#[derive(Debug, Clone)]
struct Unknown {
    dims: Vec<usize>,
    teeth: HashMap<Vec<usize>, Vec<Teeth>>,
}

/// A gear state's square system with the searched rows marked.
#[derive(Debug, Clone)]
struct StateSystem {
    matrix: DMatrix<f64>,
    /// Per dimension: (row, sun col, ring col, carrier col).
    rows: Vec<(usize, usize, usize, usize)>,
    output: usize,
    input_row: usize,
    target: Option<f64>,
}

/// The freed shift elements and where each may sit (`[layout]`). A layout
/// is one pick per freed element (empty: the base train's layout).
#[derive(Debug, Clone, Default)]
struct Layouts {
    names: Vec<String>,
    choices: Vec<Vec<Vec<String>>>,
}

impl Layouts {
    fn count(&self) -> usize {
        self.choices.iter().map(Vec::len).product()
    }

    /// The `i`-th layout (mixed radix over the freed elements).
    fn pick(&self, mut i: usize) -> Vec<u32> {
        self.choices
            .iter()
            .map(|c| {
                let k = i % c.len();
                i /= c.len();
                u32::try_from(k).unwrap_or(u32::MAX)
            })
            .collect()
    }

    /// Element -> links of a layout, as a candidate reports it.
    fn named(&self, pick: &[u32]) -> Vec<(String, Vec<String>)> {
        self.names
            .iter()
            .zip(&self.choices)
            .zip(pick)
            .map(|((n, c), &k)| (n.clone(), c[k as usize].clone()))
            .collect()
    }
}

/// What the gear states' systems are built from (kept so that each layout's
/// systems are rebuilt when it is searched instead of stored for all).
#[derive(Debug, Clone)]
struct Rows {
    tx: crate::spec::TransmissionSpec,
    willis: Vec<WillisRow>,
    dim_of: Vec<Option<usize>>,
    links: Vec<String>,
}

/// A prepared search: the per-set candidate ratios and, per element layout,
/// the per-state systems.
#[derive(Debug, Clone)]
pub struct Search {
    spec: SynthSpec,
    base: Spec,
    set_names: Vec<String>,
    dims: Vec<Dim>,
    unknowns: Vec<Unknown>,
    rows: Rows,
    layouts: Layouts,
    /// The layouts searched (one pick per freed element; one empty pick
    /// without `[layout]`).
    variants: Vec<Vec<u32>>,
    /// Layouts skipped before the search: an element doubled, a gear state
    /// that is not one DOF, or one whose system is singular for any teeth.
    skipped_layouts: u64,
}

/// Most element layouts one search may list.
pub const MAX_LAYOUTS: usize = 1_000_000;

/// The Willis rows of the sets: (set, sun col, ring col, carrier col, k, sign).
type WillisRow = (String, usize, usize, usize, f64, f64);

/// A column of `links`, added when new.
fn col(name: &str, links: &mut Vec<String>) -> usize {
    if let Some(i) = links.iter().position(|l| l == name) {
        i
    } else {
        links.push(name.to_string());
        links.len() - 1
    }
}

/// One candidate returned by the search (it reads back from its serde form,
/// so that partitions run elsewhere can be merged by [`merge`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Candidate {
    /// Per unknown set (in spec order): the basic ratio ring/sun as a fraction.
    pub basic: Vec<String>,
    /// Per unknown set: ring/large sun of a Ravigneaux set (None for a simple set).
    pub basic2: Vec<Option<String>>,
    /// Per unknown set: the smallest-sun teeth giving those basic ratios.
    pub teeth: Vec<Teeth>,
    /// Per unknown set: how many admissible tooth sets give the same basic
    /// ratios (and so the same gear ratios).
    pub alternatives: Vec<usize>,
    /// Per gear state (base order): name, ratio (float), exact ratio.
    pub ratios: Vec<(String, f64, String)>,
    /// Spread of the forward ratios.
    pub spread: Option<f64>,
    /// Freed elements' links in this candidate's layout (empty without `[layout]`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layout: Vec<(String, Vec<String>)>,
    /// Score: root mean square of (ratio - target) / target over the targeted states. Lower is better.
    pub score: f64,
}

/// Counts of a finished search.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Stats {
    /// Product of the per-set counts of admissible tooth triples (the naive space).
    pub tooth_space: f64,
    /// Product of the per-set counts of distinct basic ratios (pairs of them
    /// for a Ravigneaux set): the searched space.
    pub ratio_space: f64,
    /// Branch-and-bound nodes visited.
    pub nodes: u64,
    /// Leaves (full ratio vectors) evaluated.
    pub leaves: u64,
    /// Leaves that met the ratio targets but failed a target only the exact
    /// analysis can check (steps, progression, efficiency, element or mesh torque).
    #[serde(default)]
    pub rejected: u64,
    /// Element layouts searched (1 without `[layout]`).
    #[serde(default)]
    pub layouts: u64,
    /// Layouts skipped before the search (see `egt synth` docs: doubled
    /// elements, states that are not one DOF, singular states).
    #[serde(default)]
    pub skipped_layouts: u64,
}

/// Most (sun, ring) pairs one set's ranges may span (each is visited once).
pub const MAX_SET_PAIRS: i64 = 10_000_000;

/// The planet between a sun and a ring on one axis (the coaxial condition,
/// within the profile-shift allowance), if the constraints admit it; the
/// non-interference and assembly tests of `planets` equally spaced copies.
fn coaxial_planet(sun: i64, ring: i64, planets: i64, c: &Constraints) -> Option<i64> {
    let diff = ring - sun;
    if diff <= 0 {
        return None;
    }
    let planet = diff / 2;
    if (diff - 2 * planet).abs() > c.profile_shift || planet < c.min_planet {
        return None;
    }
    if c.assembly && (sun + ring) % planets != 0 {
        return None;
    }
    if c.non_interference && planets > 1 {
        let s = (std::f64::consts::PI / planets as f64).sin();
        if (sun + planet) as f64 * s <= (planet + 2) as f64 {
            return None;
        }
    }
    Some(planet)
}

/// The checks every unknown set's ranges share; `bad(field, message)` names the field.
fn check_ranges(r: &SetRange, bad: &dyn Fn(&str, &str) -> DesignError) -> Result<(), DesignError> {
    for (field, range) in [("sun", Some(r.sun)), ("sun2", r.sun2)] {
        if let Some([lo, hi]) = range
            && (lo < 3 || lo > hi)
        {
            return Err(bad(field, "need 3 <= min <= max"));
        }
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
    let max = crate::error::MAX_TEETH;
    if r.sun[1] > max || r.ring[1] > max || r.sun2.is_some_and(|s| s[1] > max) {
        return Err(bad(
            "sun",
            &format!("tooth counts above {max} are not searched"),
        ));
    }
    // Bounded work per set: every tooth combination of the ranges is visited once.
    let span = |x: [i64; 2]| x[1] - x[0] + 1;
    let combos = span(r.sun)
        .saturating_mul(span(r.ring))
        .saturating_mul(r.sun2.map_or(1, span));
    if combos > MAX_SET_PAIRS {
        return Err(bad(
            "ring",
            &format!(
                "{combos} tooth combinations in this set; at most {MAX_SET_PAIRS} are searched per set"
            ),
        ));
    }
    Ok(())
}

/// Admissible tooth triples of one simple set, grouped by reduced ring/sun, sorted by k.
fn basics(name: &str, r: &SetRange, c: &Constraints) -> Result<Vec<Basic>, DesignError> {
    let bad = |f: &str, m: &str| DesignError::Invalid {
        field: format!("sets.{name}.{f}"),
        message: m.into(),
    };
    check_ranges(r, &bad)?;
    let mut map: HashMap<Ratio<i64>, Vec<Teeth>> = HashMap::new();
    for sun in r.sun[0]..=r.sun[1] {
        for ring in r.ring[0]..=r.ring[1] {
            let Some(planet) = coaxial_planet(sun, ring, r.planets, c) else {
                continue;
            };
            let k = ring as f64 / sun as f64;
            if let Some([lo, hi]) = c.ring_sun
                && (k < lo || k > hi)
            {
                continue;
            }
            map.entry(Ratio::new(ring, sun)).or_default().push(Teeth {
                sun,
                ring,
                planet,
                sun2: None,
                planet2: None,
            });
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

/// Admissible teeth of one Ravigneaux set: the two searched dimensions
/// (ring/small sun, ring/large sun: distinct values, ascending) and the teeth
/// of every index pair that teeth can make.
///
/// Geometry (in modules): the long pinion meshes the ring and the large sun
/// on one axis (the coaxial condition, with the allowance, assembly and
/// non-interference of a simple set); the short pinion meshes the small sun
/// and the long pinion: its centre distance to the long pinion reaches it
/// when 2 p_short >= s_large - s_small, and its tip clears the ring when
/// s_small + 2 p_short + 4 <= ring. The short pinion is the smallest count
/// meeting both and `min_planet`; the small sun is smaller than the large.
#[allow(clippy::type_complexity)]
fn ravigneaux(
    name: &str,
    r: &SetRange,
    c: &Constraints,
) -> Result<(Vec<f64>, Vec<f64>, HashMap<Vec<usize>, Vec<Teeth>>), DesignError> {
    let bad = |f: &str, m: &str| DesignError::Invalid {
        field: format!("sets.{name}.{f}"),
        message: m.into(),
    };
    check_ranges(r, &bad)?;
    let large = r
        .sun2
        .ok_or_else(|| bad("sun2", "a Ravigneaux set needs the large sun's range"))?;
    let mut found: HashMap<(Ratio<i64>, Ratio<i64>), Vec<Teeth>> = HashMap::new();
    for ring in r.ring[0]..=r.ring[1] {
        for sun2 in large[0]..=large[1] {
            let Some(long) = coaxial_planet(sun2, ring, r.planets, c) else {
                continue;
            };
            for sun in r.sun[0]..=r.sun[1].min(sun2 - 1) {
                let short = c.min_planet.max((sun2 - sun + 1) / 2);
                if sun + 2 * short + 4 > ring {
                    continue;
                }
                let k = ring as f64 / sun as f64;
                if let Some([lo, hi]) = c.ring_sun
                    && (k < lo || k > hi)
                {
                    continue;
                }
                found
                    .entry((Ratio::new(ring, sun), Ratio::new(ring, sun2)))
                    .or_default()
                    .push(Teeth {
                        sun,
                        ring,
                        planet: short,
                        sun2: Some(sun2),
                        planet2: Some(long),
                    });
            }
        }
    }
    if found.is_empty() {
        return Err(bad(
            "sun",
            "no tooth counts in these ranges meet the constraints",
        ));
    }
    let sorted = |pick: fn(&(Ratio<i64>, Ratio<i64>)) -> Ratio<i64>| {
        let mut v: Vec<Ratio<i64>> = found.keys().map(pick).collect();
        v.sort();
        v.dedup();
        v
    };
    let (k1, k2) = (sorted(|k| k.0), sorted(|k| k.1));
    let value = |q: &Ratio<i64>| *q.numer() as f64 / *q.denom() as f64;
    let mut teeth = HashMap::new();
    for ((a, b), mut t) in found {
        t.sort_by_key(|t| (t.sun, t.sun2, t.ring));
        let i = k1.binary_search(&a).unwrap_or_default();
        let j = k2.binary_search(&b).unwrap_or_default();
        teeth.insert(vec![i, j], t);
    }
    Ok((
        k1.iter().map(value).collect(),
        k2.iter().map(value).collect(),
        teeth,
    ))
}

/// The element layouts to search: the base layout alone without
/// `[layout]`; else every combination of the freed elements' placements.
/// `links`: the sets' central links (the columns so far).
fn layouts(spec: &SynthSpec, base: &Spec, links: &[String]) -> Result<Layouts, DesignError> {
    use crate::spec::ElementKind;
    let tx = base.transmission.as_ref();
    let (input, output) = tx.map_or((None, None), |t| (Some(&t.input), Some(&t.output)));
    // Central links: the sets' members and every link an element or the
    // transmission names (the input shaft may reach the sets only through clutches).
    let mut central: Vec<String> = links.to_vec();
    for name in base
        .elements
        .iter()
        .flat_map(|e| e.links.iter())
        .chain(input)
        .chain(output)
    {
        if !central.contains(name) {
            central.push(name.clone());
        }
    }
    let mut out = Layouts::default();
    for (name, placement) in &spec.layout {
        let field = format!("layout.{name}");
        let e = base
            .elements
            .iter()
            .find(|e| &e.name == name)
            .ok_or_else(|| DesignError::Invalid {
                field: field.clone(),
                message: "no shift element of that name in the base train".into(),
            })?;
        let brake = matches!(e.kind, ElementKind::Brake | ElementKind::OneWayBrake);
        let choices: Vec<Vec<String>> = match placement {
            crate::design::Placement::Any(word) if word == "any" => {
                let free: Vec<&String> = central.iter().filter(|l| **l != base.frame).collect();
                if brake {
                    free.into_iter()
                        .filter(|l| Some(*l) != input && Some(*l) != output)
                        .map(|l| vec![l.clone()])
                        .collect()
                } else {
                    let mut pairs = Vec::new();
                    for (i, a) in free.iter().enumerate() {
                        for b in &free[i + 1..] {
                            pairs.push(vec![(*a).clone(), (*b).clone()]);
                        }
                    }
                    pairs
                }
            }
            crate::design::Placement::Any(word) => {
                return Err(DesignError::Invalid {
                    field,
                    message: format!("`{word}`: give \"any\" or a list of link lists"),
                });
            }
            crate::design::Placement::Choices(list) => {
                for (k, c) in list.iter().enumerate() {
                    let want = if brake { 1 } else { 2 };
                    if c.len() != want {
                        return Err(DesignError::Invalid {
                            field: format!("{field}[{k}]"),
                            message: format!(
                                "a {} joins {want} link(s), got {}",
                                if brake { "brake" } else { "clutch" },
                                c.len()
                            ),
                        });
                    }
                    if let Some(l) = c.iter().find(|l| !central.contains(l)) {
                        return Err(DesignError::Invalid {
                            field: format!("{field}[{k}]"),
                            message: format!("`{l}` is not a central link of the base train"),
                        });
                    }
                }
                list.clone()
            }
        };
        if choices.is_empty() {
            return Err(DesignError::Invalid {
                field,
                message: "no placement to try".into(),
            });
        }
        if out.count().saturating_mul(choices.len()) > MAX_LAYOUTS {
            return Err(DesignError::Invalid {
                field: "layout".into(),
                message: format!("more than {MAX_LAYOUTS} element layouts; free fewer elements"),
            });
        }
        out.names.push(name.clone());
        out.choices.push(choices);
    }
    Ok(out)
}

/// The base spec with a layout's elements moved.
fn place(base: &Spec, layout: &[(String, Vec<String>)]) -> Spec {
    let mut spec = base.clone();
    for (name, links) in layout {
        if let Some(e) = spec.elements.iter_mut().find(|e| &e.name == name) {
            e.links.clone_from(links);
        }
    }
    spec
}

/// Two elements on the same links (a layout that wastes one).
fn doubled(elements: &[(&str, &[String])]) -> bool {
    let mut seen: Vec<Vec<&String>> = Vec::new();
    for (_, links) in elements {
        let mut k: Vec<&String> = links.iter().collect();
        k.sort();
        if seen.contains(&k) {
            return true;
        }
        seen.push(k);
    }
    false
}

/// Each gear state's square system for `base`'s element layout: the Willis
/// rows (searched ones marked by `dim_of`), the engaged elements' rows, the
/// frame and w_in = 1.
fn states(
    elements: &[(&str, &[String])],
    frame: &str,
    rows0: &Rows,
    targets: &crate::design::Targets,
) -> Result<Vec<StateSystem>, DesignError> {
    let (tx, willis, dim_of) = (&rows0.tx, &rows0.willis, &rows0.dim_of);
    let mut links = rows0.links.clone();
    for (_, ls) in elements {
        for l in *ls {
            col(l, &mut links);
        }
    }
    let input = col(&tx.input, &mut links);
    let output = col(&tx.output, &mut links);
    let frame = links.iter().position(|l| l == frame);
    let n = links.len();
    let mut states = Vec::new();
    for (name, engaged) in &tx.states {
        let mut rows: Vec<Vec<f64>> = Vec::new();
        let mut marks = Vec::new();
        for (i, &(_, s, r, c, k, sign)) in willis.iter().enumerate() {
            let mut row = vec![0.0; n];
            let [ws, wr, wc] = searched_willis(if k.is_nan() { 0.0 } else { sign * k });
            row[s] += ws;
            row[r] += wr;
            row[c] += wc;
            if let Some(d) = dim_of[i] {
                marks.push((d, rows.len(), s, r, c));
            }
            rows.push(row);
        }
        for el in engaged {
            let (_, e_links) =
                elements
                    .iter()
                    .find(|e| e.0 == el)
                    .ok_or_else(|| DesignError::Invalid {
                        field: format!("transmission.states.{name}"),
                        message: format!("unknown element `{el}`"),
                    })?;
            let mut row = vec![0.0; n];
            let a = col(&e_links[0], &mut links);
            row[a] += 1.0;
            if let Some(b) = e_links.get(1) {
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
            target: targets.ratios.get(name).copied(),
        });
    }
    Ok(states)
}

/// A searched Willis row w_s + k w_r - (1 + k) w_c = 0 (k signed): eq. (2)'s
/// row with tau = -k (the ratio of the sun to the ring with the carrier
/// held), the coefficients of (w_s, w_r, w_c).
fn searched_willis(k: f64) -> [f64; 3] {
    willis_row(-k)
}

/// Write a searched Willis row ([`searched_willis`]) into row `row` of `a`.
fn willis_into(a: &mut DMatrix<f64>, (row, s, r, c): (usize, usize, usize, usize), k: f64) {
    let [ws, wr, wc] = searched_willis(k);
    a.row_mut(row).fill(0.0);
    a[(row, s)] += ws;
    a[(row, r)] += wr;
    a[(row, c)] += wc;
}

/// Whether every gear state's system is regular for generic ratios (two
/// picks of each searched k): a layout whose state is singular for any teeth
/// (an element that locks nothing new) would never be bounded, so it is
/// skipped before the search.
fn generic(states: &[StateSystem], dims: &[Dim]) -> bool {
    states.iter().all(|st| {
        [1usize, 3].iter().any(|&q| {
            let mut a = st.matrix.clone();
            for (d, &(row, s, r, c)) in st.rows.iter().enumerate() {
                let ks = &dims[d].ks;
                let k = dims[d].sign * ks[(ks.len() * q / 4).min(ks.len() - 1)];
                willis_into(&mut a, (row, s, r, c), k);
            }
            // Regular when the smallest LU pivot is not round-off of the largest.
            let u = a.lu().u();
            let pivots = u.diagonal().map(f64::abs);
            pivots.min() > 1e-10 * pivots.max()
        })
    })
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
        let t = &spec.targets;
        for (field, v) in [
            ("tolerance", Some(t.tolerance)),
            ("efficiency", t.efficiency),
            ("max_element_torque", t.max_element_torque),
            ("max_mesh_torque", t.max_mesh_torque),
        ] {
            if v.is_some_and(|v| !(v > 0.0 && v.is_finite())) {
                return Err(DesignError::Invalid {
                    field: format!("targets.{field}"),
                    message: "must be a positive number".into(),
                });
            }
        }
        for (field, v) in [("spread", t.spread), ("steps", t.steps)] {
            if let Some([lo, hi]) = v
                && !(lo.is_finite() && hi.is_finite() && lo <= hi)
            {
                return Err(DesignError::Invalid {
                    field: format!("targets.{field}"),
                    message: "need [min, max] with min <= max".into(),
                });
            }
        }
        for s in spec.targets.ratios.keys() {
            if !tx.states.contains_key(s) {
                return Err(DesignError::UnknownState(s.clone()));
            }
        }
        let mut links: Vec<String> = Vec::new();
        // The Willis rows of every set (name, sun, ring, carrier, k, sign):
        // one for a simple or double-pinion set, two for a Ravigneaux set
        // (small sun, then large sun). Known sets get their k now.
        let mut willis: Vec<WillisRow> = Vec::new();
        for p in &base.planetary {
            let ring = p.ring.clone().ok_or_else(|| DesignError::Invalid {
                field: format!("planetary.{}", p.name),
                message: "synth handles sets with a ring (simple, double-pinion, Ravigneaux)"
                    .into(),
            })?;
            let k = |z: Option<i64>| match (z, p.teeth.ring) {
                (Some(zs), Some(zr)) => zr as f64 / zs as f64,
                _ => f64::NAN,
            };
            let (s, r, c) = (
                col(&p.sun, &mut links),
                col(&ring, &mut links),
                col(&p.carrier, &mut links),
            );
            match p.kind {
                PlanetaryKind::Simple => {
                    willis.push((p.name.clone(), s, r, c, k(p.teeth.sun), 1.0))
                }
                PlanetaryKind::DoublePinion => {
                    willis.push((p.name.clone(), s, r, c, k(p.teeth.sun), -1.0));
                }
                PlanetaryKind::Ravigneaux => {
                    let large = p.sun2.as_deref().ok_or_else(|| DesignError::Invalid {
                        field: format!("planetary.{}.sun2", p.name),
                        message: "a Ravigneaux set needs its large sun".into(),
                    })?;
                    let s2 = col(large, &mut links);
                    willis.push((p.name.clone(), s, r, c, k(p.teeth.sun), -1.0));
                    willis.push((p.name.clone(), s2, r, c, k(p.teeth.sun2), 1.0));
                }
                _ => {
                    return Err(DesignError::Invalid {
                        field: format!("planetary.{}", p.name),
                        message: "synth handles simple, double-pinion and Ravigneaux sets".into(),
                    });
                }
            }
        }
        let set_names: Vec<String> = spec.sets.keys().cloned().collect();
        // Per Willis row, the searched dimension it carries (if any).
        let mut dim_of: Vec<Option<usize>> = vec![None; willis.len()];
        let mut dims = Vec::new();
        let mut unknowns = Vec::new();
        for (name, range) in &spec.sets {
            let rows: Vec<usize> = (0..willis.len())
                .filter(|&i| &willis[i].0 == name)
                .collect();
            let kind = base
                .planetary
                .iter()
                .find(|p| &p.name == name)
                .map(|p| p.kind);
            let field = |f: &str| format!("sets.{name}.{f}");
            let unknown = match (kind, rows.as_slice()) {
                (None, _) => return Err(DesignError::UnknownSet(name.clone())),
                (Some(PlanetaryKind::Simple), &[row]) => {
                    if range.sun2.is_some() {
                        return Err(DesignError::Invalid {
                            field: field("sun2"),
                            message: "a simple set has one sun".into(),
                        });
                    }
                    let b = basics(name, range, &spec.constraints)?;
                    dim_of[row] = Some(dims.len());
                    dims.push(Dim {
                        ks: b.iter().map(|x| x.k).collect(),
                        sign: 1.0,
                    });
                    Unknown {
                        dims: vec![dims.len() - 1],
                        teeth: b
                            .into_iter()
                            .enumerate()
                            .map(|(i, x)| (vec![i], x.teeth))
                            .collect(),
                    }
                }
                (Some(PlanetaryKind::Ravigneaux), &[small, large]) => {
                    let (k1, k2, teeth) = ravigneaux(name, range, &spec.constraints)?;
                    dim_of[small] = Some(dims.len());
                    dims.push(Dim { ks: k1, sign: -1.0 });
                    dim_of[large] = Some(dims.len());
                    dims.push(Dim { ks: k2, sign: 1.0 });
                    Unknown {
                        dims: vec![dims.len() - 2, dims.len() - 1],
                        teeth,
                    }
                }
                _ => {
                    return Err(DesignError::Invalid {
                        field: format!("sets.{name}"),
                        message: "the search finds the teeth of simple and Ravigneaux sets".into(),
                    });
                }
            };
            unknowns.push(unknown);
        }
        for (i, w) in willis.iter().enumerate() {
            if w.4.is_nan() && dim_of[i].is_none() {
                return Err(DesignError::Invalid {
                    field: format!("planetary.{}.teeth", w.0),
                    message: "give sun and ring teeth, or list the set under [sets]".into(),
                });
            }
        }
        let layouts = layouts(&spec, &base, &links)?;
        let rows = Rows {
            tx,
            willis,
            dim_of,
            links,
        };
        let mut search = Search {
            spec,
            base,
            set_names,
            dims,
            unknowns,
            rows,
            layouts,
            variants: Vec::new(),
            skipped_layouts: 0,
        };
        if search.layouts.names.is_empty() {
            // The base layout's errors are the spec's: say them.
            search.states(&[])?;
            search.variants.push(Vec::new());
        } else {
            // Every layout checked in parallel; only the picks that pass are kept.
            use rayon::prelude::*;
            let total = search.layouts.count();
            let kept: Vec<Vec<u32>> = (0..total)
                .into_par_iter()
                .filter_map(|i| {
                    let pick = search.layouts.pick(i);
                    let elements = search.elements(&pick);
                    if doubled(&elements) {
                        return None;
                    }
                    let states = states(
                        &elements,
                        &search.base.frame,
                        &search.rows,
                        &search.spec.targets,
                    );
                    states
                        .ok()
                        .filter(|s| generic(s, &search.dims))
                        .map(|_| pick)
                })
                .collect();
            search.skipped_layouts = (total - kept.len()) as u64;
            search.variants = kept;
        }
        Ok(search)
    }

    /// Every element's name and links in a layout.
    fn elements(&self, pick: &[u32]) -> Vec<(&str, &[String])> {
        self.base
            .elements
            .iter()
            .map(|e| {
                let placed = self
                    .layouts
                    .names
                    .iter()
                    .position(|n| n == &e.name)
                    .and_then(|f| {
                        pick.get(f)
                            .map(|&k| self.layouts.choices[f][k as usize].as_slice())
                    });
                (e.name.as_str(), placed.unwrap_or(e.links.as_slice()))
            })
            .collect()
    }

    /// The gear states' systems of a layout.
    fn states(&self, pick: &[u32]) -> Result<Vec<StateSystem>, DesignError> {
        states(
            &self.elements(pick),
            &self.base.frame,
            &self.rows,
            &self.spec.targets,
        )
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
        self.dims.first().map_or(0, |d| d.ks.len())
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
        let len = self.max_partitions() as u128;
        let slice =
            |p: usize| usize::try_from(len * p as u128 / parts as u128).unwrap_or(usize::MAX);
        let (lo, hi) = (slice(part), slice(part + 1));
        let mut stats = Stats {
            tooth_space: self
                .unknowns
                .iter()
                .map(|u| u.teeth.values().map(|t| t.len() as f64).sum::<f64>())
                .product(),
            ratio_space: self.unknowns.iter().map(|u| u.teeth.len() as f64).product(),
            layouts: self.variants.len() as u64,
            skipped_layouts: self.skipped_layouts,
            ..Stats::default()
        };
        if lo >= hi {
            return Ok((Vec::new(), stats));
        }
        let mut bounds: Vec<(usize, usize)> = self.dims.iter().map(|d| (0, d.ks.len())).collect();
        bounds[0] = (lo, hi);
        let nodes = std::sync::atomic::AtomicU64::new(0);
        let leaves = std::sync::atomic::AtomicU64::new(0);
        // Every layout over the partition's box, in parallel (each bound
        // itself splits its halves with rayon::join).
        use rayon::prelude::*;
        let per_layout: Vec<Result<(Vec<Candidate>, u64), DesignError>> = self
            .variants
            .par_iter()
            .map(|pick| {
                let states = self.states(pick)?;
                let mut out = Vec::new();
                let mut rejected = 0;
                for ks in self.branch(&states, &bounds, &nodes, &leaves) {
                    match self.confirm(pick, &ks)? {
                        Some(c) => out.push(c),
                        None => rejected += 1,
                    }
                }
                rank(&mut out, self.spec.top);
                Ok((out, rejected))
            })
            .collect();
        stats.nodes = nodes.into_inner();
        stats.leaves = leaves.into_inner();
        let mut out = Vec::new();
        for r in per_layout {
            let (c, rejected) = r?;
            out.extend(c);
            stats.rejected += rejected;
        }
        rank(&mut out, self.spec.top);
        Ok((out, stats))
    }

    /// Run the whole space as `parts` partitions one after another (each on
    /// all cores), calling `progress(done, parts, best)` after each with the
    /// best candidates so far (ranked, at most `top`): what a progress bar, an
    /// ETA and a stream of results need. Merged and ranked, the result is
    /// [`Search::run`]'s.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run_in_parts(
        &self,
        parts: usize,
        mut progress: impl FnMut(usize, usize, &[Candidate]),
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        let parts = parts.clamp(1, self.max_partitions().max(1));
        let mut best: Vec<Candidate> = Vec::new();
        let mut done = Vec::with_capacity(parts);
        for part in 0..parts {
            let (found, stats) = self.run_partition(part, parts)?;
            best.extend(found.iter().cloned());
            rank(&mut best, self.spec.top);
            progress(part + 1, parts, &best);
            done.push((found, stats));
        }
        Ok(merge(done, self.spec.top))
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
                let k = self.dims[u].sign * self.dims[u].ks[idx];
                willis_into(&mut a, (row, s, r, c), k);
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
    fn feasible(&self, states: &[StateSystem], bounds: &[(usize, usize)]) -> bool {
        let tol = self.spec.targets.tolerance;
        for st in states {
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
        states: &[StateSystem],
        bounds: &[(usize, usize)],
        nodes: &std::sync::atomic::AtomicU64,
        leaves: &std::sync::atomic::AtomicU64,
    ) -> Vec<Vec<usize>> {
        use std::sync::atomic::Ordering::Relaxed;
        nodes.fetch_add(1, Relaxed);
        if !self.feasible(states, bounds) {
            return Vec::new();
        }
        let widest = (0..bounds.len())
            .max_by_key(|&u| bounds[u].1 - bounds[u].0)
            .unwrap_or(0);
        let (b0, b1) = bounds[widest];
        if b1 - b0 <= 1 {
            // A single point: teeth must make it (a Ravigneaux set's two
            // ratios share the ring), then the box test above was exact up
            // to round-off; check the spread.
            if self.teeth_of(bounds).is_none() {
                return Vec::new();
            }
            leaves.fetch_add(1, Relaxed);
            return if self.leaf_ok(states, bounds) {
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
            || self.branch(states, &left, nodes, leaves),
            || self.branch(states, &right, nodes, leaves),
        );
        l.extend(r);
        l
    }

    fn leaf_ok(&self, states: &[StateSystem], bounds: &[(usize, usize)]) -> bool {
        let tol = self.spec.targets.tolerance;
        let mut fwd = Vec::new();
        for st in states {
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

    /// Per unknown set, the admissible teeth of a point (one index per
    /// dimension); None when some set's ratios cannot be made of teeth.
    fn teeth_of(&self, bounds: &[(usize, usize)]) -> Option<Vec<&Vec<Teeth>>> {
        self.unknowns
            .iter()
            .map(|u| {
                let key: Vec<usize> = u.dims.iter().map(|&d| bounds[d].0).collect();
                u.teeth.get(&key)
            })
            .collect()
    }

    /// The base spec with a candidate's layout and teeth written in.
    pub fn candidate_spec(&self, teeth: &[Teeth], layout: &[(String, Vec<String>)]) -> Spec {
        let mut spec = place(&self.base, layout);
        for (name, t) in self.set_names.iter().zip(teeth) {
            if let Some(p) = spec.planetary.iter_mut().find(|p| &p.name == name) {
                p.teeth.sun = Some(t.sun);
                p.teeth.ring = Some(t.ring);
                p.teeth.planet = Some(t.planet);
                if t.sun2.is_some() {
                    p.teeth.sun2 = t.sun2;
                    p.teeth.planet2 = t.planet2;
                }
            }
        }
        spec
    }

    /// The targets only the exact analysis checks: every step in range, a
    /// progressive set, and per targeted state the efficiency, the element
    /// torques and the mesh torques.
    fn meets_analysis_targets(&self, table: &crate::ShiftTable) -> bool {
        let t = &self.spec.targets;
        if let Some([lo, hi]) = t.steps
            && table
                .steps
                .iter()
                .any(|s| !(s.value >= lo && s.value <= hi))
        {
            return false;
        }
        if t.progressive && table.steps.windows(2).any(|w| w[1].value > w[0].value) {
            return false;
        }
        if t.single_swap
            && table
                .shifts
                .iter()
                .any(|s| s.kind == crate::ShiftKind::Sequential && !s.single_swap)
        {
            return false;
        }
        table
            .gears
            .iter()
            .filter(|g| t.ratios.contains_key(&g.state))
            .all(|g| {
                let efficiency = g.power.as_ref().map(|p| p.efficiency);
                t.efficiency
                    .is_none_or(|min| efficiency.is_some_and(|e| e >= min))
                    && t.max_element_torque
                        .is_none_or(|max| g.elements.iter().all(|e| e.torque.abs() <= max))
                    && t.max_mesh_torque
                        .is_none_or(|max| g.meshes.iter().all(|m| m.multiplier.abs() <= max))
            })
    }

    /// Rebuild the train with the candidate's teeth and solve it exactly;
    /// None when it fails a target only that analysis can check.
    /// In a freed layout, a candidate egt cannot analyse (a state it
    /// refuses) is rejected; in the base layout it is the base train's error.
    fn confirm(&self, pick: &[u32], ks: &[usize]) -> Result<Option<Candidate>, DesignError> {
        let layout = self.layouts.named(pick);
        let point: Vec<(usize, usize)> = ks.iter().map(|&i| (i, i + 1)).collect();
        let sets = self.teeth_of(&point).ok_or_else(|| DesignError::Invalid {
            field: "sets".into(),
            message: "a leaf without teeth reached confirmation".into(),
        })?;
        let teeth: Vec<Teeth> = sets.iter().map(|t| t[0]).collect();
        let analysed =
            Train::from_spec(&self.candidate_spec(&teeth, &layout)).and_then(|t| t.shift_table());
        let table = match analysed {
            Ok(table) => table,
            Err(_) if !layout.is_empty() => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        if !self.meets_analysis_targets(&table) {
            return Ok(None);
        }
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
        let ratio = |ring: i64, sun: i64| {
            crate::numerics::exact::display(&crate::numerics::exact::frac(ring, sun))
        };
        Ok(Some(Candidate {
            basic: teeth.iter().map(|t| ratio(t.ring, t.sun)).collect(),
            basic2: teeth
                .iter()
                .map(|t| t.sun2.map(|s2| ratio(t.ring, s2)))
                .collect(),
            alternatives: sets.iter().map(|t| t.len()).collect(),
            teeth,
            ratios,
            spread: table.spread.as_ref().map(|s| s.value),
            layout,
            score: if nt > 0 {
                (err2 / nt as f64).sqrt()
            } else {
                0.0
            },
        }))
    }
}

/// Partitions' results as one search's: the candidates ranked together
/// ([`rank`]) and the counts summed (the spaces are the whole search's).
pub fn merge(parts: Vec<(Vec<Candidate>, Stats)>, top: usize) -> (Vec<Candidate>, Stats) {
    let mut found = Vec::new();
    let mut total = Stats::default();
    for (c, s) in parts {
        found.extend(c);
        // The spaces and layouts are the whole search's in every partition.
        total.tooth_space = s.tooth_space;
        total.ratio_space = s.ratio_space;
        total.layouts = s.layouts;
        total.skipped_layouts = s.skipped_layouts;
        total.nodes += s.nodes;
        total.leaves += s.leaves;
        total.rejected += s.rejected;
    }
    rank(&mut found, top);
    (found, total)
}

/// Sort by score (then by the teeth, so that the order is canonical) and keep `top`.
pub fn rank(c: &mut Vec<Candidate>, top: usize) {
    c.sort_by(|a, b| {
        a.score.total_cmp(&b.score).then_with(|| {
            let ka: Vec<_> = a.teeth.iter().map(|t| (t.sun, t.sun2, t.ring)).collect();
            let kb: Vec<_> = b.teeth.iter().map(|t| (t.sun, t.sun2, t.ring)).collect();
            ka.cmp(&kb).then_with(|| a.layout.cmp(&b.layout))
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
        zf_search_with(sets, "")
    }

    /// The 8HP search with more lines under `[targets]`.
    fn zf_search_with(sets: &str, targets: &str) -> Search {
        let text = format!(
            "base = \"zf_8hp70.toml\"\ntop = 5\n{sets}\n[targets]\nratios = {{ \"1\" = 4.696, \"2\" = 3.130, \"3\" = 2.104, \"4\" = 1.667, \"5\" = 1.285, \"6\" = 1.000, \"7\" = 0.839, \"8\" = 0.667, \"R\" = -3.297 }}\n{targets}\n"
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

    /// Targets only the exact analysis checks, at the edges of the real
    /// 8HP's figures (`egt shift examples/zf_8hp70.toml`): largest element
    /// torque 2.642 (brake B in R), lowest efficiency 0.9462 (R), steps from
    /// 1.192 to 1.500, not progressive (1.262 then 1.297). Each target passes
    /// the real teeth on one side of its figure and rejects them on the other.
    #[test]
    fn analysis_targets_accept_and_reject_the_real_8hp() {
        let sets = "[sets]\nP3 = { sun = [66, 72], ring = [108, 114] }\nP4 = { sun = [21, 25], ring = [82, 88] }";
        let found = |targets: &str| {
            let (c, stats) = zf_search_with(sets, targets).run().expect("test input");
            (c.len(), stats.rejected)
        };
        assert_eq!(found(""), (1, 0));
        for (pass, fail) in [
            ("max_element_torque = 2.65", "max_element_torque = 2.6"),
            ("efficiency = 0.946", "efficiency = 0.95"),
            ("steps = [1.19, 1.5001]", "steps = [1.2, 1.6]"),
            ("progressive = false", "progressive = true"),
            ("single_swap = true", "steps = [1.0, 1.2]"),
            ("max_mesh_torque = 100.0", "max_mesh_torque = 0.5"),
        ] {
            assert_eq!(found(pass), (1, 0), "{pass}");
            assert_eq!(found(fail), (0, 1), "{fail}");
        }
        let bad = SynthSpec::from_str(
            "base = \"x\"\n[sets]\nP3 = { sun = [66, 72], ring = [108, 114] }\n[targets]\nratios = { \"1\" = 4.7 }\nefficiency = -1\n",
            Format::Toml,
            "s",
        )
        .expect("test input");
        let err = Search::new(bad, parse_spec(ZF, Format::Toml, "zf").expect("test input"))
            .expect_err("must refuse");
        assert!(err.to_string().contains("targets.efficiency"), "{err}");
    }

    /// Free element positions: the three clutches anywhere (21 952 layouts)
    /// with two sets' teeth free. The real layout is found (clutch E on any
    /// two of P3's members: three equivalent placements, each reported), with
    /// the real basic ratios; every candidate's written spec, analysed
    /// exactly, has the reported ratios; bad placements are refused by field.
    #[test]
    fn free_clutch_positions_find_the_real_layout() {
        let sets = "[sets]\nP3 = { sun = [60, 76], ring = [100, 120] }\nP4 = { sun = [20, 28], ring = [76, 92] }\n[layout]\nC = \"any\"\nD = \"any\"\nE = \"any\"";
        let s = zf_search(sets);
        let (found, stats) = s.run().expect("test input");
        assert_eq!(stats.layouts + stats.skipped_layouts, 28 * 28 * 28);
        let real = |c: &Candidate| {
            let links = |e: &str| {
                let mut l = c.layout.iter().find(|x| x.0 == e).expect("freed").1.clone();
                l.sort();
                l
            };
            links("C") == ["input", "ring3_sun4"] && links("D") == ["carrier3", "output"]
        };
        assert_eq!(found.len(), 3, "{found:?}");
        for c in &found {
            assert!(real(c), "{:?}", c.layout);
            assert_eq!(c.basic, ["37/23", "85/23"]);
            let table = Train::from_spec(&s.candidate_spec(&c.teeth, &c.layout))
                .expect("candidate spec")
                .shift_table()
                .expect("analysis");
            for (g, (state, _, exact)) in table.gears.iter().zip(&c.ratios) {
                assert_eq!(&g.state, state);
                assert_eq!(
                    &crate::numerics::exact::display(g.ratio_exact.as_ref().expect("exact")),
                    exact
                );
            }
        }
        for (layout, field) in [
            ("C = [[\"input\"]]", "layout.C[0]"),
            ("C = [[\"input\", \"nowhere\"]]", "layout.C[0]"),
            ("Z = \"any\"", "layout.Z"),
            ("C = \"all\"", "layout.C"),
        ] {
            let text = format!(
                "base = \"x\"\n[sets]\nP4 = {{ sun = [20, 28], ring = [76, 92] }}\n[layout]\n{layout}\n[targets]\nratios = {{ \"1\" = 4.7 }}\n"
            );
            let spec: SynthSpec = toml::from_str(&text).expect("test input");
            let err = Search::new(
                spec,
                parse_spec(ZF, Format::Toml, "zf").expect("test input"),
            )
            .expect_err("must refuse");
            assert!(err.to_string().starts_with(field), "{layout}: {err}");
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
            .run_in_parts(4, |done, of, best| {
                assert!(best.len() <= 5);
                seen.push((done, of));
            })
            .expect("test input");
        assert_eq!(seen, [(1, 4), (2, 4), (3, 4), (4, 4)]);
        let key = |c: &Vec<Candidate>| c.iter().map(|x| x.teeth.clone()).collect::<Vec<_>>();
        assert_eq!(key(&whole), key(&parts));
        assert_eq!(ws.tooth_space, ps.tooth_space);
    }

    const AOD: &str = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/ford_aod_ravigneaux.toml"
    ));

    /// A Ravigneaux set's two searched ratios: the branch and bound keeps
    /// exactly the tooth sets that an exhaustive run of the exact transmission
    /// analysis over every admissible (small sun, large sun, ring) accepts.
    #[test]
    fn ravigneaux_search_equals_exhaustive_exact_analysis() {
        let text = "base = \"aod\"\ntop = 100000\n[sets]\nR = { sun = [24, 36], sun2 = [28, 44], ring = [60, 84] }\n[targets]\ntolerance = 0.03\nratios = { \"1\" = 2.40, \"2\" = 1.47, \"4\" = 0.67, \"R\" = -2.00 }\n";
        let spec: SynthSpec = toml::from_str(text).expect("test input");
        let s = Search::new(
            spec,
            parse_spec(AOD, Format::Toml, "aod").expect("test input"),
        )
        .expect("test input");
        let (found, stats) = s.run().expect("test input");
        let mut got: Vec<(String, String)> = found
            .iter()
            .map(|c| (c.basic[0].clone(), c.basic2[0].clone().expect("Ravigneaux")))
            .collect();
        got.sort();
        // Every admissible tooth set, analysed exactly; its basic ratios kept
        // when every targeted ratio is within the tolerance.
        let mut want = std::collections::BTreeSet::new();
        let teeth: Vec<Teeth> = s.unknowns[0].teeth.values().map(|t| t[0]).collect();
        assert_eq!(teeth.len() as f64, stats.ratio_space);
        for t in teeth {
            let table = Train::from_spec(&s.candidate_spec(&[t], &[]))
                .expect("admissible teeth make a train")
                .shift_table()
                .expect("every state solves");
            let ok = table.gears.iter().all(|g| {
                s.spec
                    .targets
                    .ratios
                    .get(&g.state)
                    .is_none_or(|&r| (g.ratio - r).abs() <= 0.03)
            });
            if ok {
                let q = |z: i64| {
                    crate::numerics::exact::display(&crate::numerics::exact::frac(t.ring, z))
                };
                want.insert((q(t.sun), q(t.sun2.expect("Ravigneaux"))));
            }
        }
        let want: Vec<_> = want.into_iter().collect();
        assert!(
            want.len() > 3,
            "a loose tolerance admits several sets: {want:?}"
        );
        assert_eq!(got, want);
        assert!(got.contains(&("12/5".into(), "2".into())));
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
