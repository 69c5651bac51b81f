//! The linear path: a block of rows whose outputs are linear in the varying
//! speeds, accelerations and torques, solved as a base row plus one
//! response per varying column.

use crate::solve::prepared::Compute;

use super::outputs::bad_parameter;
use super::plan::BatchPlan;
use super::run::RowError;
use super::worker::Worker;

/// Fewest rows in a block for the linear path (below it, row by row is as fast).
pub(super) const LINEAR_MIN_ROWS: usize = 8;

/// Buffers of the linear path: the varying columns, the base row, the
/// response columns and the conditions.
#[derive(Debug, Default)]
pub(super) struct Linear {
    /// Per column: differs within the block.
    pub(super) diff: Vec<bool>,
    /// The varying columns (input speeds, accelerations, torques).
    pub(super) varying: Vec<usize>,
    /// The varying accelerations.
    pub(super) accel_varying: Vec<usize>,
    /// The base row of the response held (varying columns at zero).
    pub(super) row: Vec<f64>,
    pub(super) y0: Vec<f64>,
    /// Row-major, one row of outputs per varying column: R_j = f(base + e_j) - f(base).
    pub(super) response: Vec<f64>,
    /// Per varying column, the outputs it moves: R_j is zero outside
    /// `spans[j]` (an input speed moves no torque, a torque no speed).
    pub(super) spans: Vec<(usize, usize)>,
    /// The condition outputs of a moving row (some acceleration not zero).
    pub(super) cond_moving: Vec<f64>,
    /// The base row prescribes no acceleration.
    pub(super) static_base: bool,
    /// A response is held.
    pub(super) valid: bool,
    /// A column-major block's first row.
    pub(super) first_row: Vec<f64>,
}

impl Linear {
    /// Whether the response held is that of the block whose first row is
    /// `row0` and whose varying columns (among `linear`) are marked in
    /// `diff`: the same base row (the varying columns at zero) and the same
    /// varying columns.
    fn same_base(&self, row0: &[f64], linear: std::ops::Range<usize>) -> bool {
        self.valid
            && self.row.len() == row0.len()
            && (0..row0.len()).all(|c| {
                let v = if self.diff[c] { 0.0 } else { row0[c] };
                v.to_bits() == self.row[c].to_bits()
            })
            && self
                .varying
                .iter()
                .copied()
                .eq(linear.filter(|&c| self.diff[c]))
    }
}

impl BatchPlan {
    /// Whether the linear path may take a block held column by column: its
    /// ratios, inertias, masses and efficiencies are the same in every row
    /// (as `Worker::eval_linear` asks, before its other conditions).
    pub(super) fn linear_may<'c>(&self, column: impl Fn(usize) -> &'c [f64], n: usize) -> bool {
        let g = self.groups;
        self.compute != Compute::Power
            && n >= LINEAR_MIN_ROWS
            && (0..g.speed).chain(g.inertia..g.end).all(|k| {
                let c = column(k);
                c.iter().all(|x| x.to_bits() == c[0].to_bits())
            })
    }
}

impl Worker<'_> {
    /// A block of rows by the linear path when it applies (see the module
    /// docs): true when every row of `rows` was written (failed rows to
    /// `errors`); false when the block must be solved row by row.
    pub(super) fn eval_linear(
        &mut self,
        lin: &mut Linear,
        rows: &[f64],
        out: &mut [f64],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> bool {
        let plan = self.plan;
        let g = plan.groups;
        let (p, q) = (plan.parameters.len(), plan.all.len());
        let n = rows.len().checked_div(p).unwrap_or(0);
        if plan.compute == Compute::Power || n < LINEAR_MIN_ROWS {
            return false;
        }
        let row0 = &rows[..p];
        let fixed = |c: usize| c < g.speed || c >= g.inertia;
        // A ratio sweep leaves at its second row, before the whole pass.
        if (0..p).any(|c| fixed(c) && rows[p + c].to_bits() != row0[c].to_bits()) {
            return false;
        }
        // One pass: which columns differ from the first row's.
        lin.diff.clear();
        lin.diff.resize(p, false);
        for r in rows.chunks(p) {
            for ((d, a), b) in lin.diff.iter_mut().zip(r).zip(row0) {
                *d |= a.to_bits() != b.to_bits();
            }
        }
        if (0..p).any(|c| fixed(c) && lin.diff[c]) {
            return false;
        }
        let same = lin.same_base(row0, g.speed..g.inertia);
        if !same && !self.linear_response(lin, row0) {
            return false;
        }
        let conds = plan.all_conditions().start;
        let m = lin.varying.len();
        for (r, (row, o)) in rows.chunks(p).zip(out.chunks_mut(q)).enumerate() {
            // Every other column equals the base row's, which solved: only
            // the varying columns can be bad (the first in column order, as
            // `check` would name it).
            if let Some(&c) = lin.varying.iter().find(|&&c| !row[c].is_finite()) {
                o.fill(f64::NAN);
                errors.push(RowError {
                    row: first + r,
                    error: bad_parameter(plan, c, row[c]),
                });
                continue;
            }
            o.copy_from_slice(&lin.y0);
            for j in 0..m {
                let pj = row[lin.varying[j]];
                let (lo, hi) = lin.spans[j];
                for (y, rj) in o[lo..hi]
                    .iter_mut()
                    .zip(&lin.response[j * q + lo..j * q + hi])
                {
                    *y += pj * rj;
                }
            }
            if lin.static_base && lin.accel_varying.iter().any(|&c| row[c] != 0.0) {
                o[conds..].copy_from_slice(&lin.cond_moving);
            }
        }
        true
    }

    /// [`Worker::eval_linear`] on a block held column by column (`column(k)`
    /// is the block's part of parameter column `k`, `out[o]` of chosen output
    /// column `o`), for a block whose fixed columns are equal in every row
    /// (`BatchPlan::linear_may`). Each output element takes the operations
    /// `eval_linear` gives it, in the same order (y0, then `+= p_j R_j` for
    /// each varying column in order), so the numbers are its numbers bit for
    /// bit; only the chosen outputs are computed. False when the block must
    /// be solved otherwise (a base or unit row that fails to solve).
    pub(super) fn eval_linear_columns<'c>(
        &mut self,
        lin: &mut Linear,
        column: impl Fn(usize) -> &'c [f64],
        out: &mut [&mut [f64]],
        first: usize,
        errors: &mut Vec<RowError>,
    ) -> bool {
        let plan = self.plan;
        let g = plan.groups;
        let p = plan.parameters.len();
        let n = out.first().map_or(0, |c| c.len());
        if plan.compute == Compute::Power || n < LINEAR_MIN_ROWS {
            return false;
        }
        let mut row0 = std::mem::take(&mut lin.first_row);
        row0.clear();
        row0.extend((0..p).map(|k| column(k)[0]));
        lin.diff.clear();
        lin.diff.resize(p, false);
        for (k, d) in lin
            .diff
            .iter_mut()
            .enumerate()
            .take(g.inertia)
            .skip(g.speed)
        {
            let (c, b) = (column(k), row0[k].to_bits());
            *d = c.iter().any(|x| x.to_bits() != b);
        }
        let same = lin.same_base(&row0, g.speed..g.inertia);
        let solved = same || self.linear_response(lin, &row0);
        lin.first_row = row0;
        if !solved {
            return false;
        }
        let conds = plan.all_conditions().start;
        let q = plan.all.len();
        for (o, &k) in out.iter_mut().zip(&plan.chosen) {
            o.fill(lin.y0[k]);
            for (j, &c) in lin.varying.iter().enumerate() {
                let (lo, hi) = lin.spans[j];
                if (lo..hi).contains(&k) {
                    let rj = lin.response[j * q + k];
                    for (y, &pj) in o.iter_mut().zip(column(c)) {
                        *y += pj * rj;
                    }
                }
            }
            if lin.static_base && k >= conds {
                let v = lin.cond_moving[k - conds];
                for &c in &lin.accel_varying {
                    for (y, &a) in o.iter_mut().zip(column(c)) {
                        if a != 0.0 {
                            *y = v;
                        }
                    }
                }
            }
        }
        // Only the varying columns can be bad (the first in column order,
        // as `check` would name it); such a row's outputs are NaN.
        for r in 0..n {
            if let Some(&c) = lin.varying.iter().find(|&&c| !column(c)[r].is_finite()) {
                out.iter_mut().for_each(|o| o[r] = f64::NAN);
                errors.push(RowError {
                    row: first + r,
                    error: bad_parameter(plan, c, column(c)[r]),
                });
            }
        }
        true
    }

    /// The linear path's response for a block whose first row is `row0` and
    /// whose varying columns are marked in `lin.diff`: y0 at the base row
    /// (varying columns at zero) and R_j = f(base + e_j) - y0; false when a
    /// solve fails (the block is then solved row by row, with its errors).
    fn linear_response(&mut self, lin: &mut Linear, row0: &[f64]) -> bool {
        let plan = self.plan;
        let g = plan.groups;
        let q = plan.all.len();
        lin.valid = false;
        lin.varying.clear();
        lin.varying
            .extend((g.speed..g.inertia).filter(|&c| lin.diff[c]));
        lin.row.clear();
        lin.row.extend_from_slice(row0);
        for &c in &lin.varying {
            lin.row[c] = 0.0;
        }
        lin.y0.resize(q, 0.0);
        if self.eval_all(&lin.row, &mut lin.y0).is_err() {
            return false;
        }
        let m = lin.varying.len();
        lin.response.resize(m * q, 0.0);
        for j in 0..m {
            let c = lin.varying[j];
            lin.row[c] = 1.0;
            let rj = &mut lin.response[j * q..(j + 1) * q];
            let solved = self.eval_all(&lin.row, rj);
            lin.row[c] = 0.0;
            if solved.is_err() {
                return false;
            }
            for (r, y) in rj.iter_mut().zip(&lin.y0) {
                *r -= y;
            }
        }
        // The conditions are not linear: eq. (8) is factored only when some
        // acceleration is prescribed. Keep those of a moving row apart.
        let conds = plan.all_conditions().start;
        let accel = g.accel..g.torque;
        lin.static_base = accel.clone().all(|c| lin.row[c] == 0.0);
        lin.accel_varying.clear();
        lin.accel_varying
            .extend(lin.varying.iter().copied().filter(|c| accel.contains(c)));
        lin.cond_moving.clear();
        lin.cond_moving.extend_from_slice(&lin.y0[conds..]);
        if let Some(j) = lin.varying.iter().position(|c| accel.contains(c)) {
            // R_j's conditions are y_j - y0: add y0 back.
            for (k, v) in lin.cond_moving.iter_mut().enumerate() {
                *v += lin.response[j * q + conds + k];
            }
        }
        lin.spans.clear();
        for j in 0..m {
            let rj = &mut lin.response[j * q..(j + 1) * q];
            rj[conds..].fill(0.0);
            let lo = rj.iter().position(|&v| v != 0.0).unwrap_or(0);
            let hi = rj.iter().rposition(|&v| v != 0.0).map_or(0, |k| k + 1);
            lin.spans.push((lo, hi.max(lo)));
        }
        lin.valid = true;
        true
    }
}
