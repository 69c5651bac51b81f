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

    /// Does the box possibly hold a solution? (false = every state's window missed by some state.)
    pub(super) fn feasible(&self, states: &[StateSystem], bounds: &[(usize, usize)]) -> bool {
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

    pub(super) fn leaf_ok(&self, states: &[StateSystem], bounds: &[(usize, usize)]) -> bool {
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
