//! The branch and bound over boxes of basic ratios: the output speed's
//! range on a box, the pruning, the halving and the leaves' float check.

use nalgebra::DVector;

use super::Search;
use super::space::Teeth;
use super::systems::{StateSystem, willis_into};

impl Search {
    /// Output speeds at the vertices of a box; None if det A changes sign (no bound).
    pub(super) fn state_range(
        &self,
        st: &StateSystem,
        bounds: &[(usize, usize)],
    ) -> Option<(f64, f64)> {
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

    /// The Cramer numerator N and denominator D = det A of w_out = N / D
    /// at every vertex of a box; None when A is singular at a vertex.
    pub(super) fn state_vertices(
        &self,
        st: &StateSystem,
        bounds: &[(usize, usize)],
    ) -> Option<Vec<(f64, f64)>> {
        // Only the dimensions w_out depends on span vertices; the others
        // take their generic value (`StateSystem::fixed`).
        let free: Vec<usize> = (0..bounds.len())
            .filter(|&u| st.fixed.get(u).is_none_or(Option::is_none))
            .collect();
        let mut a = st.matrix.clone();
        let mut out = Vec::with_capacity(1 << free.len());
        for v in 0..(1usize << free.len()) {
            for (u, &(row, s, r, c)) in st.rows.iter().enumerate() {
                let k = match st.fixed.get(u).copied().flatten() {
                    Some(k) => k,
                    None => {
                        let bit = free.iter().position(|&f| f == u).unwrap_or(0);
                        let (b0, b1) = bounds[u];
                        let idx = if v >> bit & 1 == 1 { b1 - 1 } else { b0 };
                        self.dims[u].sign * self.dims[u].ks[idx]
                    }
                };
                willis_into(&mut a, (row, s, r, c), k);
            }
            let lu = a.clone().lu();
            let det = lu.determinant();
            let mut e = DVector::zeros(a.nrows());
            e[st.input_row] = 1.0;
            match lu.solve(&e) {
                Some(w) if det != 0.0 && w[st.output].is_finite() => {
                    out.push((w[st.output] * det, det));
                }
                // Singular here: N is the determinant with w_out's column
                // replaced by the right-hand side (Cramer), D is 0.
                _ => {
                    let mut b = a.clone();
                    b.set_column(st.output, &e);
                    out.push((b.lu().determinant(), 0.0));
                }
            }
        }
        Some(out)
    }

    /// Does the box possibly hold a solution? (false = some state's window
    /// missed.) N and D are affine in each k, so are f_lo = N - w_lo D and
    /// f_hi = N - w_hi D, which take their extremes at the vertices; w_out =
    /// N / D lies in [w_lo, w_hi] only where f_lo and f_hi differ in sign
    /// (or vanish), whatever the sign of D. So a box where both are
    /// positive at every vertex, or both negative, is dropped: this bounds
    /// boxes where det A changes sign too.
    pub(super) fn feasible(&self, states: &[StateSystem], bounds: &[(usize, usize)]) -> bool {
        let tol = self.spec.targets.tolerance;
        let narrow = self.narrowed();
        for st in states {
            let Some(t) = st.target else { continue };
            let tol = tol.min(t.abs() * narrow);
            let (a, b) = (t - tol, t + tol);
            if a <= 0.0 && b >= 0.0 {
                continue;
            }
            // Output speed window 1/ratio.
            let (wlo, whi) = (1.0 / b, 1.0 / a);
            let (wlo, whi) = (wlo.min(whi), wlo.max(whi));
            if let Some(v) = self.state_vertices(st, bounds)
                && misses(&v, wlo, whi)
            {
                return false;
            }
        }
        true
    }

    pub(super) fn branch(
        &self,
        states: &[StateSystem],
        bounds: &[(usize, usize)],
        nodes: &std::sync::atomic::AtomicU64,
        leaves: &std::sync::atomic::AtomicU64,
    ) -> Vec<Vec<usize>> {
        use std::sync::atomic::Ordering::Relaxed;
        nodes.fetch_add(1, Relaxed);
        // Past the leaf budget the run is refused (`run_partition`): stop.
        // Stopped by the caller (`with_cancel`): stop too.
        if leaves.load(Relaxed) > self.spec.max_leaves
            || self.cancelled()
            || self.node_limit.is_some_and(|m| nodes.load(Relaxed) > m)
            || !self.feasible(states, bounds)
        {
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
            // Counted (against the budget) when it passes the float check:
            // each such leaf costs an exact confirmation.
            return if self.leaf_ok(states, bounds) {
                leaves.fetch_add(1, Relaxed);
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

    /// The relative error each targeted state may have for a candidate to
    /// beat the shared incumbent (infinite without one): RMS <= s over n
    /// states bounds each by s sqrt(n).
    fn narrowed(&self) -> f64 {
        self.incumbent.as_ref().map_or(f64::INFINITY, |inc| {
            inc.threshold() * (self.spec.targets.ratios.len() as f64).sqrt()
        })
    }

    pub(super) fn leaf_ok(&self, states: &[StateSystem], bounds: &[(usize, usize)]) -> bool {
        let tol = self.spec.targets.tolerance;
        let mut fwd = Vec::new();
        let (mut err2, mut nt) = (0.0, 0);
        for st in states {
            let Some((w, _)) = self.state_range(st, bounds) else {
                return false;
            };
            let ratio = 1.0 / w;
            if let Some(t) = st.target {
                if (ratio - t).abs() > tol {
                    return false;
                }
                err2 += ((ratio - t) / t).powi(2);
                nt += 1;
            }
            if ratio > 0.0 && ratio.is_finite() {
                fwd.push(ratio);
            }
        }
        if let Some(inc) = &self.incumbent
            && nt > 0
            && (err2 / f64::from(nt)).sqrt() > inc.threshold()
        {
            return false;
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
    pub(super) fn teeth_of(&self, bounds: &[(usize, usize)]) -> Option<Vec<&Vec<Teeth>>> {
        self.unknowns
            .iter()
            .map(|u| {
                let key: Vec<usize> = u.dims.iter().map(|&d| bounds[d].0).collect();
                u.teeth.get(&key)
            })
            .collect()
    }
}

/// Whether N / D misses [w_lo, w_hi] over a box, from (N, D) at its
/// vertices: f_lo = N - w_lo D and f_hi = N - w_hi D both positive at every
/// vertex, or both negative (see [`Search::feasible`]).
pub(crate) fn misses(vertices: &[(f64, f64)], wlo: f64, whi: f64) -> bool {
    let all = |f: &dyn Fn(f64) -> bool| {
        vertices
            .iter()
            .all(|&(n, d)| f(n - wlo * d) && f(n - whi * d))
    };
    !vertices.is_empty() && (all(&|x| x > 0.0) || all(&|x| x < 0.0))
}
