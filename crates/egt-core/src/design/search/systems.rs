//! The gear states' square systems A(k) w = e: the Willis rows (searched
//! ones marked), the engaged elements' rows, the frame and w_in = 1.

use std::collections::HashMap;

use nalgebra::DMatrix;

use crate::error::DesignError;
use crate::model::equations::willis_row;

use super::Search;
use super::layouts::Placed;
use super::space::{Dim, Teeth};

/// An unknown set: its dimensions (one, or two for a Ravigneaux set) and the
/// admissible teeth of every combination of their indices that teeth can make.
#[derive(Debug, Clone)]
pub(super) struct Unknown {
    pub(super) dims: Vec<usize>,
    pub(super) teeth: HashMap<Vec<usize>, Vec<Teeth>>,
}

/// A gear state's square system with the searched rows marked.
#[derive(Debug, Clone)]
pub(super) struct StateSystem {
    pub(super) matrix: DMatrix<f64>,
    /// Per dimension: (row, sun col, ring col, carrier col).
    pub(super) rows: Vec<(usize, usize, usize, usize)>,
    pub(super) output: usize,
    pub(super) input_row: usize,
    pub(super) target: Option<f64>,
    /// Per dimension: Some(signed k) where w_out does not depend on it
    /// ([`Search::states`]); the bound then takes that one generic value
    /// for it at every vertex. N and D may still both depend on it through
    /// a common factor, which changes sign inside boxes and would keep the
    /// vertex test from ever dropping them.
    pub(super) fixed: Vec<Option<f64>>,
}

/// What the gear states' systems are built from (kept so that each layout's
/// systems are rebuilt when it is searched instead of stored for all).
#[derive(Debug, Clone)]
pub(super) struct Rows {
    pub(super) tx: crate::spec::TransmissionSpec,
    pub(super) willis: Vec<WillisRow>,
    pub(super) dim_of: Vec<Option<usize>>,
    pub(super) links: Vec<String>,
}

/// The Willis rows of the sets: (set, sun col, ring col, carrier col, k, sign).
pub(super) type WillisRow = (String, usize, usize, usize, f64, f64);

/// A column of `links`, added when new.
pub(super) fn col(name: &str, links: &mut Vec<String>) -> usize {
    if let Some(i) = links.iter().position(|l| l == name) {
        i
    } else {
        links.push(name.to_string());
        links.len() - 1
    }
}

/// Each gear state's square system for `base`'s element layout: the Willis
/// rows (searched ones marked by `dim_of`), the engaged elements' rows, the
/// frame and w_in = 1.
pub(super) fn states(
    elements: &[Placed<'_>],
    frame: &str,
    rows0: &Rows,
    targets: &crate::design::Targets,
) -> Result<Vec<StateSystem>, DesignError> {
    let (tx, willis, dim_of) = (&rows0.tx, &rows0.willis, &rows0.dim_of);
    let mut links = rows0.links.clone();
    for e in elements {
        for l in e.links {
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
            let e_links = elements
                .iter()
                .find(|e| e.name == el)
                .ok_or_else(|| DesignError::Invalid {
                    field: format!("transmission.states.{name}"),
                    message: format!("unknown element `{el}`"),
                })?
                .links;
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
            fixed: Vec::new(),
        });
    }
    Ok(states)
}

/// A searched Willis row w_s + k w_r - (1 + k) w_c = 0 (k signed): eq. (2)'s
/// row with tau = -k (the ratio of the sun to the ring with the carrier
/// held), the coefficients of (w_s, w_r, w_c).
pub(crate) fn searched_willis(k: f64) -> [f64; 3] {
    willis_row(-k)
}

/// Write a searched Willis row ([`searched_willis`]) into row `row` of `a`.
pub(super) fn willis_into(
    a: &mut DMatrix<f64>,
    (row, s, r, c): (usize, usize, usize, usize),
    k: f64,
) {
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
pub(super) fn generic(states: &[StateSystem], dims: &[Dim]) -> bool {
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
    /// The gear states' systems of a layout, each targeted state with the
    /// dimensions its w_out does not depend on marked (`fixed`).
    pub(super) fn states(&self, pick: &[u32]) -> Result<Vec<StateSystem>, DesignError> {
        let mut states = states(
            &self.elements(pick),
            &self.base.frame,
            &self.rows,
            &self.spec.targets,
        )?;
        for st in &mut states {
            if st.target.is_some() {
                st.fixed = independent(st, &self.dims);
            }
        }
        Ok(states)
    }
}

/// Per dimension, Some(signed generic k) where the state's w_out does not
/// depend on it: w_out is a Moebius function of each k (N and D affine in
/// it), so equal at two values with the others generic means constant in it.
fn independent(st: &StateSystem, dims: &[Dim]) -> Vec<Option<f64>> {
    // Two generic values of each dimension's range, no tooth ratio, and
    // different for every dimension: sets of one range must not get equal
    // ratios, where a factor such as k_a - k_b vanishes and w_out could
    // look independent of a ratio it depends on.
    let at = |i: usize, f: f64| {
        let d = &dims[i];
        let (lo, hi) = (d.ks[0], d.ks[d.ks.len() - 1]);
        d.sign * (lo + (0.2 + 0.6 * f.fract()) * (hi - lo))
    };
    let pick = |i: usize, q: usize| {
        let i_f = i as f64;
        if q == 0 {
            at(i, 0.381_966 + 0.618_034 * i_f)
        } else {
            at(i, 0.723_607 + 0.414_214 * i_f)
        }
    };
    let g: Vec<f64> = (0..dims.len()).map(|i| pick(i, 0)).collect();
    let w = |ks: &[f64]| -> Option<f64> {
        let mut a = st.matrix.clone();
        for (d, &(row, s, r, c)) in st.rows.iter().enumerate() {
            willis_into(&mut a, (row, s, r, c), ks[d]);
        }
        let mut e = nalgebra::DVector::zeros(a.nrows());
        e[st.input_row] = 1.0;
        let w = a.lu().solve(&e)?[st.output];
        w.is_finite().then_some(w)
    };
    let none = vec![None; dims.len()];
    let Some(w0) = w(&g) else {
        return none;
    };
    (0..dims.len())
        .map(|d| {
            if dims[d].ks.len() < 2 {
                return None;
            }
            let mut h = g.clone();
            h[d] = pick(d, 1);
            let w1 = w(&h)?;
            same_speed(w1, w0).then_some(g[d])
        })
        .collect()
}

/// Two output speeds (per unit input speed) equal up to round-off: relative
/// 1e-9, and absolute 1e-12 near zero, where a held output's speed is
/// round-off of either sign.
pub(crate) fn same_speed(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()) + 1e-12
}
