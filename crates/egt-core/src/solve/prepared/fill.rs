//! The equation fills of a [`PreparedTrain`]: the Willis rows and extra
//! constraints, the matrices of eq. (2), (8) and (10), their exact forms, and
//! the right-hand sides.

use super::*;

impl PreparedTrain {
    /// \[V\] of eq. (23) for `ratios`: the speed of every coordinate per unit
    /// speed of each input (one dense column per input), by the speed
    /// system's factorisation (sparse for a large train), with its condition.
    ///
    /// # Errors
    /// The checked factorisation's, naming the system `what` and what a
    /// zero pivot means (`detail`).
    pub(crate) fn velocity_columns(
        &self,
        ratios: &[f64],
        what: &str,
        detail: &str,
    ) -> Result<(nalgebra::DMatrix<f64>, f64)> {
        let (n, f) = (self.n, self.inputs.len());
        let mut lu = match &self.sparse {
            Some(factors) => factors[0].clone(),
            None => Factor::Dense(Lu::new(n)),
        };
        let cond = lu.fill_factor(self, ratios, 0, what, detail)?;
        let c = self.constraints();
        let mut v = nalgebra::DMatrix::zeros(n, f);
        let mut b = vec![0.0; n];
        for col in 0..f {
            b.iter_mut().for_each(|x| *x = 0.0);
            b[c + col] = 1.0;
            lu.solve(&mut b);
            for (r, &x) in b.iter().enumerate() {
                v[(r, col)] = x;
            }
        }
        Ok((v, cond))
    }

    /// Every term of system `system` (0: speeds, 1: \[Psi_w\], 2: the force
    /// matrix) for `ratios` as (row, column, value), in the order and with
    /// the values the dense fill adds them: the Willis rows (1, -tau, tau - 1),
    /// the extra rows, then the unit (or, for the force matrix, -1) rows.
    pub(super) fn for_each_entry(
        &self,
        ratios: &[f64],
        system: usize,
        f: impl FnMut(usize, usize, f64),
    ) {
        self.visit_terms(ratios, system, false, f);
    }

    /// Write the constraint rows (eq. 2 with `taus`, then the extras) into the
    /// zeroed row-major `out` with `n` columns.
    fn fill_constraints(&self, taus: &[f64], out: &mut [f64]) {
        let n = self.n;
        for (m, (cols, &t)) in self.circuits.iter().zip(taus).enumerate() {
            for (k, v) in cols.iter().zip(willis_row(t)) {
                if let Some(k) = k {
                    out[m * n + k] += v;
                }
            }
        }
        let base = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    out[(base + e) * n + k] += v;
                }
            }
        }
    }

    /// The speed system: constraint rows, then a unit row per input link.
    /// Row-major n x n into `out`.
    pub fn kinematic_matrix(&self, ratios: &[f64], out: &mut [f64]) {
        self.unit_rows(ratios, &self.inputs, out);
    }

    /// \[Psi_w\] of eq. (8): constraint rows, then a unit row per accelerated link.
    pub fn acceleration_matrix(&self, ratios: &[f64], out: &mut [f64]) {
        self.unit_rows(ratios, &self.accelerated, out);
    }

    fn unit_rows(&self, ratios: &[f64], links: &[usize], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        self.fill_constraints(ratios, out);
        let c = self.constraints();
        for (r, &k) in links.iter().enumerate() {
            out[(c + r) * self.n + k] = 1.0;
        }
    }

    /// The matrix whose transpose eq. (10) solves: constraint rows with the
    /// force ratios, then -1 in each driving link's column. Row-major into `out`.
    pub fn force_matrix(&self, force_ratios: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        self.fill_constraints(force_ratios, out);
        let c = self.constraints();
        for (r, &k) in self.driving.iter().enumerate() {
            out[(c + r) * self.n + k] = -1.0;
        }
    }

    /// The prepared structure as JSON, for tools outside Rust (the benchmark's
    /// SymPy and NumPy routes build the same equations from it): coordinates
    /// `n`; per circuit the columns of gear i, gear j and the carrier (null
    /// for the frame); extra rows as (column, coefficient) pairs; the input,
    /// accelerated and driving columns; the mass model (per link: its copies,
    /// its inertia slot and column, its mass slot and eq. 4 terms (column, offset)).
    pub fn structure(&self) -> serde_json::Value {
        let entries: Vec<serde_json::Value> = self
            .mass
            .entries
            .iter()
            .map(|e| {
                serde_json::json!({
                    "copies": e.copies,
                    "spin": e.spin.map(|(c, s)| serde_json::json!({"column": c, "slot": s})),
                    "float": e.float.as_ref().map(|(s, r)| serde_json::json!({
                        "slot": s,
                        "terms": self.mass.terms[r.clone()].iter().map(|&(c, d)| serde_json::json!([c, d])).collect::<Vec<_>>(),
                    })),
                })
            })
            .collect();
        serde_json::json!({
            "n": self.n,
            "circuits": self.circuits,
            "extras": self.extras,
            "inputs": self.inputs,
            "accelerated": self.accelerated,
            "driving": self.driving,
            "mass": entries,
        })
    }

    /// Every entry of the speed system (`system` 0), \[Psi_w\] (1) or the force
    /// matrix (2) as a sum of terms `f(row, column, coefficient)` whose
    /// coefficients are the data themselves (1, -tau, tau, -1), so that a
    /// residual built from them carries no rounding of tau - 1.
    pub fn for_each_term(&self, ratios: &[f64], system: usize, f: impl FnMut(usize, usize, f64)) {
        self.visit_terms(ratios, system, true, f);
    }

    /// The terms of system `system`: each Willis row as (1, -tau, tau, -1)
    /// when `split` ([`PreparedTrain::for_each_term`]), else as the dense
    /// fill adds it, (1, -tau, tau - 1) ([`PreparedTrain::for_each_entry`]);
    /// then the extra rows and the input, accelerated or driving rows.
    fn visit_terms(
        &self,
        ratios: &[f64],
        system: usize,
        split: bool,
        mut f: impl FnMut(usize, usize, f64),
    ) {
        for (m, (cols, &t)) in self.circuits.iter().zip(ratios).enumerate() {
            let row = if split { [1.0, -t, t] } else { willis_row(t) };
            for (k, v) in cols.iter().zip(row) {
                if let Some(k) = k {
                    f(m, *k, v);
                }
            }
            if let (true, Some(k)) = (split, cols[2]) {
                f(m, k, -1.0);
            }
        }
        let c0 = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    f(c0 + e, k, v);
                }
            }
        }
        let c = self.constraints();
        let (links, v) = match system {
            0 => (&self.inputs, 1.0),
            1 => (&self.accelerated, 1.0),
            _ => (&self.driving, -1.0),
        };
        for (r, &k) in links.iter().enumerate() {
            f(c + r, k, v);
        }
    }

    /// The speed system, \[Psi_w\] and the force matrix (not transposed) in
    /// exact rationals, for exact ratios: a reference to verify float solves
    /// against (the accuracy study in `lab/` does).
    pub fn exact_matrices(&self, ratios: &[Q]) -> [QMatrix; 3] {
        let n = self.n;
        let mut base = vec![vec![Q::zero(); n]; n];
        for (m, (cols, t)) in self.circuits.iter().zip(ratios).enumerate() {
            let one = exact::q(1);
            for (k, v) in cols.iter().zip([one.clone(), -t.clone(), t - &one]) {
                if let Some(k) = k {
                    base[m][*k] += v;
                }
            }
        }
        let c0 = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    base[c0 + e][k] += exact_of(v);
                }
            }
        }
        let c = self.constraints();
        let with = |links: &[usize], v: i64| {
            let mut a = base.clone();
            for (r, &k) in links.iter().enumerate() {
                a[c + r][k] = exact::q(v);
            }
            a
        };
        [
            with(&self.inputs, 1),
            with(&self.accelerated, 1),
            with(&self.driving, -1),
        ]
    }

    /// The right-hand side of the speed (or acceleration) solve: zeros, then the prescribed values.
    pub fn input_rhs(&self, values: &[f64], out: &mut [f64]) {
        let c = self.constraints();
        out.iter_mut().for_each(|v| *v = 0.0);
        out[c..].copy_from_slice(values);
    }

    /// The right-hand side of eq. (10), {Q} - \[M\]{w'}, into `out`.
    pub fn force_rhs(&self, mass: &[f64], torques: &[f64], accel: &[f64], out: &mut [f64]) {
        let n = self.n;
        for (i, o) in out.iter_mut().enumerate() {
            let row = &mass[i * n..(i + 1) * n];
            *o = torques[i] - row.iter().zip(accel).map(|(a, b)| a * b).sum::<f64>();
        }
    }
}
