//! Writing a solved row's outputs and checking a row's parameters: the
//! [`Solution`] of a row wherever it was solved, and the errors of bad values.

use crate::error::{Error, Result};
use crate::solve::prepared::{Compute, Workspace};
use crate::solve::prepared::{efficiency_ok, non_negative, ratio_ok};

use super::plan::BatchPlan;

/// One row's results, wherever they were solved: a worker's slices, or one
/// lane of a group (read in place, no copy).
pub(super) trait Solution {
    fn speed(&self, k: usize) -> f64;
    fn accel(&self, k: usize) -> f64;
    /// Multipliers, then driving torques.
    fn x(&self, k: usize) -> f64;
    fn cond(&self) -> [f64; 3];
    fn power(&self) -> Option<crate::solve::prepared::PowerSummary>;
}

impl Solution for (&Workspace, &BatchPlan) {
    fn speed(&self, k: usize) -> f64 {
        self.0.speeds()[k]
    }
    fn accel(&self, k: usize) -> f64 {
        self.0.accelerations()[k]
    }
    fn x(&self, k: usize) -> f64 {
        let pt = &self.1.prepared;
        let m = self.0.multipliers(pt);
        m.get(k)
            .copied()
            .unwrap_or_else(|| self.0.driving_torques(pt)[k - m.len()])
    }
    fn cond(&self) -> [f64; 3] {
        self.0.conditions()
    }
    fn power(&self) -> Option<crate::solve::prepared::PowerSummary> {
        (self.1.compute == Compute::Power).then(|| self.0.power())
    }
}

/// Write a row's output columns, in the order of [`BatchPlan::outputs`].
#[inline]
pub(super) fn write_outputs(plan: &BatchPlan, s: &impl Solution, out: &mut [f64]) {
    let mut o = 0;
    let mut put = |v: f64| {
        out[o] = v;
        o += 1;
    };
    for &k in &plan.known {
        put(s.speed(k));
    }
    if plan.compute != Compute::Kinematics {
        for &k in &plan.known {
            put(s.accel(k));
        }
        let pt = &plan.prepared;
        for k in 0..pt.constraints() + pt.dof() {
            put(s.x(k));
        }
        for &(m, r) in &plan.forces {
            put(s.x(m) / r);
        }
    }
    if let Some(p) = s.power() {
        put(p.input);
        put(p.output);
        put(p.loss);
        put(p.kinetic_rate);
        put(if p.input > 0.0 {
            crate::analysis::power::efficiency(p.input, p.loss, p.kinetic_rate)
        } else {
            f64::NAN
        });
    }
    let cond = s.cond();
    put(cond[0]);
    if plan.compute != Compute::Kinematics {
        put(cond[1]);
        put(cond[2]);
    }
}

/// Every parameter finite; inertias and masses non-negative; efficiencies in (0, 1].
pub(super) fn check(plan: &BatchPlan, row: &[f64]) -> Result<()> {
    let g = plan.groups;
    // One pass per group of columns; the column-by-column search below only
    // runs to name the bad one.
    let good = row[..g.speed].iter().all(|&v| ratio_ok(v))
        && row[g.speed..g.inertia].iter().all(|v| v.is_finite())
        && row[g.inertia..g.efficiency]
            .iter()
            .all(|&v| non_negative(v))
        && row[g.efficiency..].iter().all(|&v| efficiency_ok(v));
    if good {
        return Ok(());
    }
    for (c, &v) in row.iter().enumerate() {
        let ok = if c < g.speed {
            ratio_ok(v)
        } else if c < g.inertia {
            v.is_finite()
        } else if c < g.efficiency {
            non_negative(v)
        } else {
            efficiency_ok(v)
        };
        if !ok {
            return Err(bad_parameter(plan, c, v));
        }
    }
    Ok(())
}

#[cold]
pub(super) fn bad_parameter(plan: &BatchPlan, c: usize, v: f64) -> Error {
    let g = plan.groups;
    let expected = if v.is_nan() {
        "a number (the spec gives no value; set it)"
    } else if !v.is_finite() {
        "a finite number"
    } else if c < g.speed {
        "a non-zero Willis ratio"
    } else if c >= g.efficiency {
        "an efficiency in (0, 1]"
    } else {
        "a value >= 0"
    };
    Error::spec(
        plan.parameters[c].clone(),
        crate::SpecErrorKind::OutOfRange {
            value: v,
            expected: expected.into(),
        },
    )
}

/// Every value finite: the quick test of a task's outputs (v * 0 is 0 for a
/// finite v and NaN for an infinite or NaN one; eight sums, so it vectorises).
#[inline]
pub(super) fn all_finite(v: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let mut chunks = v.chunks_exact(8);
    for c in &mut chunks {
        for (a, x) in acc.iter_mut().zip(c) {
            *a += x * 0.0;
        }
    }
    let tail: f64 = chunks.remainder().iter().map(|x| x * 0.0).sum();
    acc.iter().sum::<f64>() + tail == 0.0
}

/// The rows of a task (`n` rows from row `first`; `at(r, o)` reads output
/// `o` of its row `r`) whose results overflowed, with the first output that
/// did: an inf or NaN where the analysis gives a number (`power.efficiency`
/// is NaN by design when no power goes in). Rows already failed are skipped.
#[cold]
pub(super) fn overflowed(
    plan: &BatchPlan,
    n: usize,
    first: usize,
    at: impl Fn(usize, usize) -> f64,
    errors: &[super::RowError],
) -> Vec<(usize, usize)> {
    let skip = plan.names.iter().position(|s| s == "power.efficiency");
    (0..n)
        .filter(|&r| !errors.iter().any(|e| e.row == first + r))
        .filter_map(|r| {
            (0..plan.names.len())
                .find(|&o| Some(o) != skip && !at(r, o).is_finite())
                .map(|o| (r, o))
        })
        .collect()
}

/// The rows [`overflowed`] found, as failed rows (`non_finite_result`, as the
/// single-scenario analyses refuse the same inputs), merged in row order.
#[cold]
pub(super) fn refuse(
    plan: &BatchPlan,
    bad: Vec<(usize, usize)>,
    first: usize,
    errors: &mut Vec<super::RowError>,
) {
    if bad.is_empty() {
        return;
    }
    errors.extend(bad.into_iter().map(|(r, o)| {
        super::RowError {
            row: first + r,
            error: crate::AnalysisError::NonFinite {
                what: plan.names[o].clone(),
                detail: "a result overflowed: the inputs exceed the range of double precision"
                    .into(),
            }
            .into(),
        }
    }));
    errors.sort_by_key(|e| e.row);
}
