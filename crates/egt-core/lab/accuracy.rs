//! The accuracy study: one scenario (speeds, eq. 2; accelerations, eq. 8;
//! multipliers and driving torques, eq. 10) solved by every method egt
//! offers, each against the exact rational solution of the same data.
//!
//! The data of a [`Problem`] are f64 numbers (ratios, speeds, accelerations,
//! loads, inertias, masses, offsets); every finite f64 is a dyadic rational,
//! so the reference is the exact solution of exactly those numbers. A
//! method's error is then its own: forming the matrices in floating point,
//! factoring, substituting. Errors are normwise and relative, per quantity:
//! ||x - x*||_inf / ||x*||_inf.
//!
//! Methods: egt's prepared path ([`egt_core::solve::prepared::PreparedTrain::solve`],
//! its in-place LU with the condition estimate and refusal past
//! [`egt_core::numerics::linalg::COND_REFUSE`]); the same LU plus one step of iterative
//! refinement with the residual in doubled precision (Dot2, Ogita-Rump-Oishi);
//! nalgebra's LU with partial pivoting; faer's LU with partial pivoting;
//! nalgebra's Householder QR; nalgebra's SVD; and exact rationals.
//! `docs/accuracy.md` reports the study, and `crates/egt-core/tests/core/accuracy.rs`
//! holds its claims as tests.

use faer::linalg::solvers::Solve;
use nalgebra::DMatrix;
use num_traits::Zero;

use egt_core::batch::{BatchPlan, BatchSpec};
use egt_core::error::{AnalysisError, Error, Result, SpecErrorKind};
use egt_core::model::train::Train;
use egt_core::numerics::exact::{self, Q, QMatrix};
use egt_core::numerics::linalg::Lu;
use egt_core::solve::prepared::{Compute, PreparedTrain, Scenario};

/// A way of solving the three linear systems of a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// egt's prepared path: in-place LU, condition estimate, refusal.
    Egt,
    /// egt's LU plus one step of iterative refinement (residual in doubled precision).
    EgtRefined,
    /// nalgebra's LU with partial pivoting.
    NalgebraLu,
    /// faer's LU with partial pivoting.
    FaerLu,
    /// nalgebra's Householder QR.
    NalgebraQr,
    /// nalgebra's singular value decomposition.
    NalgebraSvd,
    /// Exact rational arithmetic (Gauss-Jordan over `BigRational`), rounded at the end.
    Exact,
}

impl Method {
    /// Every method, egt's first.
    pub const ALL: [Method; 7] = [
        Method::Egt,
        Method::EgtRefined,
        Method::NalgebraLu,
        Method::FaerLu,
        Method::NalgebraQr,
        Method::NalgebraSvd,
        Method::Exact,
    ];

    /// A short name for tables and charts.
    pub fn name(self) -> &'static str {
        match self {
            Method::Egt => "egt LU",
            Method::EgtRefined => "egt LU + refinement",
            Method::NalgebraLu => "nalgebra LU",
            Method::FaerLu => "faer LU",
            Method::NalgebraQr => "nalgebra QR",
            Method::NalgebraSvd => "nalgebra SVD",
            Method::Exact => "exact rationals",
        }
    }
}

/// The results compared: speeds and accelerations of the coordinates, the
/// multipliers, the driving torques.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Speeds of the coordinates.
    pub speeds: Vec<f64>,
    /// Accelerations of the coordinates.
    pub accelerations: Vec<f64>,
    /// Multipliers (Willis rows, then extra rows).
    pub multipliers: Vec<f64>,
    /// Driving torques.
    pub torques: Vec<f64>,
    /// egt's condition estimates (speed system, eq. 8, eq. 10), for egt's methods.
    pub conditions: Option<[f64; 3]>,
}

/// Normwise relative errors of a solution against the exact one.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Errors {
    /// Speeds.
    pub speeds: f64,
    /// Accelerations.
    pub accelerations: f64,
    /// Multipliers.
    pub multipliers: f64,
    /// Driving (input) torques.
    pub torques: f64,
}

impl Errors {
    /// The largest of the four.
    pub fn max(&self) -> f64 {
        self.speeds
            .max(self.accelerations)
            .max(self.multipliers)
            .max(self.torques)
    }
}

/// The errors of one row of a dynamics batch's outputs (the speeds and
/// accelerations of its known coordinates, the multipliers, the driving
/// torques) against `exact`, the columns matched by name.
///
/// # Panics
/// When an output names a coordinate `train` does not have, or a group of
/// columns is missing.
pub fn row_errors(plan: &BatchPlan, train: &Train, row: &[f64], exact: &Solution) -> Errors {
    let coordinate = |link: &str| {
        train
            .coordinates()
            .iter()
            .position(|&l| train.link_name(l) == link)
            .unwrap_or_else(|| panic!("no coordinate {link}"))
    };
    // (computed, exact) per group of columns, in the outputs' order.
    let mut groups: [(Vec<f64>, Vec<f64>); 4] = Default::default();
    let (mut lambdas, mut drivers) = (0, 0);
    for (c, o) in plan.outputs().iter().enumerate() {
        let (g, x) = if let Some(l) = o.strip_prefix("speed.") {
            (0, exact.speeds[coordinate(l)])
        } else if let Some(l) = o.strip_prefix("accel.") {
            (1, exact.accelerations[coordinate(l)])
        } else if o.starts_with("lambda.") {
            lambdas += 1;
            (2, exact.multipliers[lambdas - 1])
        } else if o.starts_with("driving_torque.") {
            drivers += 1;
            (3, exact.torques[drivers - 1])
        } else {
            continue;
        };
        groups[g].0.push(row[c]);
        groups[g].1.push(x);
    }
    assert!(
        groups.iter().all(|g| !g.0.is_empty()),
        "a group of columns is missing"
    );
    let e = |g: usize| relative_error(&groups[g].0, &groups[g].1);
    Errors {
        speeds: e(0),
        accelerations: e(1),
        multipliers: e(2),
        torques: e(3),
    }
}

/// ||x - x*||_inf / ||x*||_inf (0 when both are zero; infinite for a non-finite x).
pub fn relative_error(x: &[f64], exact: &[f64]) -> f64 {
    let scale = exact.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let diff = x
        .iter()
        .zip(exact)
        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    if x.iter().any(|v| !v.is_finite()) {
        f64::INFINITY
    } else if scale == 0.0 {
        diff
    } else {
        diff / scale
    }
}

impl Solution {
    /// Errors against the exact solution.
    pub fn errors(&self, exact: &Solution) -> Errors {
        Errors {
            speeds: relative_error(&self.speeds, &exact.speeds),
            accelerations: relative_error(&self.accelerations, &exact.accelerations),
            multipliers: relative_error(&self.multipliers, &exact.multipliers),
            torques: relative_error(&self.torques, &exact.torques),
        }
    }
}

/// One scenario of one train, with everything needed to solve it every way.
#[derive(Debug, Clone)]
pub struct Problem {
    plan: BatchPlan,
    row: Vec<f64>,
}

/// Dense row-major square matrix helpers for the float methods.
type Dense = Vec<f64>;

impl Problem {
    /// The scenario the spec's `[analysis]` section describes (inverse dynamics, ideal meshes).
    ///
    /// # Errors
    /// As [`BatchSpec::from_analysis`] and [`BatchPlan::new`]; a parameter
    /// the spec leaves without a value.
    pub fn from_train(train: &Train) -> Result<Self> {
        let plan = BatchPlan::new(train, &BatchSpec::from_analysis(train, Compute::Dynamics)?)?;
        let row = plan.base().to_vec();
        Problem::new(plan, row)
    }

    /// A given row of a dynamics batch plan.
    ///
    /// # Errors
    /// A plan that does not compute dynamics, or a row of the wrong length or with NaN.
    pub fn new(plan: BatchPlan, row: Vec<f64>) -> Result<Self> {
        if plan.compute() != Compute::Dynamics || row.len() != plan.parameters().len() {
            return Err(Error::invalid(
                "problem",
                "an accuracy problem needs a full row of a dynamics batch plan",
            ));
        }
        if let Some(c) = row.iter().position(|v| !v.is_finite()) {
            return Err(Error::spec(
                plan.parameters()[c].clone(),
                SpecErrorKind::NonFinite { value: row[c] },
            ));
        }
        Ok(Problem { plan, row })
    }

    /// Order of the systems (the number of coordinates).
    pub fn n(&self) -> usize {
        self.plan.prepared().n()
    }

    /// The batch plan underneath (parameter names, prepared train).
    pub fn plan(&self) -> &BatchPlan {
        &self.plan
    }

    fn pt(&self) -> &PreparedTrain {
        self.plan.prepared()
    }

    /// The parameter slices of the row (see `batch.rs` for the layout).
    fn scenario(&self) -> Scenario<'_> {
        let pt = self.pt();
        let (g, f, n) = (pt.gears(), pt.dof(), pt.n());
        let (ni, nm) = (
            pt.mass_model().inertia_links().len(),
            pt.mass_model().mass_links().len(),
        );
        let r = &self.row;
        let mut at = 0;
        let mut take = |k: usize| {
            let s = &r[at..at + k];
            at += k;
            s
        };
        Scenario {
            ratios: take(g),
            speeds: take(f),
            accelerations: take(f),
            torques: take(n),
            inertia: take(ni),
            mass: take(nm),
            efficiency: &[],
            mass_matrix: None,
        }
    }

    /// Solve with one method.
    ///
    /// # Errors
    /// egt's refusal of an ill-conditioned or singular system; a singular
    /// system for the other methods (they return whatever they compute otherwise).
    pub fn solve(&self, method: Method) -> Result<Solution> {
        match method {
            Method::Egt => self.solve_egt(),
            Method::Exact => self.exact(),
            Method::EgtRefined => self.solve_refined(),
            Method::NalgebraLu => self.solve_dense(|a, b, n| {
                let m = DMatrix::from_row_slice(n, n, a);
                let x = m.lu().solve(&nalgebra::DVector::from_column_slice(b))?;
                b.copy_from_slice(x.as_slice());
                Some(())
            }),
            Method::FaerLu => self.solve_dense(|a, b, n| {
                let m = faer::Mat::<f64>::from_fn(n, n, |i, j| a[i * n + j]);
                let rhs = faer::Col::<f64>::from_fn(n, |i| b[i]);
                let x = m.partial_piv_lu().solve(&rhs);
                for (i, v) in b.iter_mut().enumerate() {
                    *v = x[i];
                }
                Some(())
            }),
            Method::NalgebraQr => self.solve_dense(|a, b, n| {
                let m = DMatrix::from_row_slice(n, n, a);
                let x = m.qr().solve(&nalgebra::DVector::from_column_slice(b))?;
                b.copy_from_slice(x.as_slice());
                Some(())
            }),
            Method::NalgebraSvd => self.solve_dense(|a, b, n| {
                let m = DMatrix::from_row_slice(n, n, a);
                let x = m
                    .svd(true, true)
                    .solve(&nalgebra::DVector::from_column_slice(b), 0.0)
                    .ok()?;
                b.copy_from_slice(x.as_slice());
                Some(())
            }),
        }
    }

    fn solve_egt(&self) -> Result<Solution> {
        let pt = self.pt();
        let mut ws = pt.workspace();
        pt.solve(&mut ws, &self.scenario(), Compute::Dynamics)?;
        Ok(Solution {
            speeds: ws.speeds().to_vec(),
            accelerations: ws.accelerations().to_vec(),
            multipliers: ws.multipliers(pt).to_vec(),
            torques: ws.driving_torques(pt).to_vec(),
            conditions: Some(ws.conditions()),
        })
    }

    /// The three solves with a dense solver `solve(a, b, n)` that overwrites
    /// `b` with the solution of the row-major `a x = b`, as a user of that
    /// library would write them: form each matrix, solve, form the next
    /// right-hand side.
    fn solve_dense(
        &self,
        solve: impl Fn(&[f64], &mut [f64], usize) -> Option<()>,
    ) -> Result<Solution> {
        let pt = self.pt();
        let s = self.scenario();
        let n = pt.n();
        let c = pt.constraints();
        let singular = || -> egt_core::Error {
            AnalysisError::Singular {
                what: "a system of the scenario".into(),
                detail: "the solver found it singular".into(),
            }
            .into()
        };
        let mut a: Dense = vec![0.0; n * n];
        pt.kinematic_matrix(s.ratios, &mut a);
        let mut w = vec![0.0; n];
        pt.input_rhs(s.speeds, &mut w);
        solve(&a, &mut w, n).ok_or_else(singular)?;
        pt.acceleration_matrix(s.ratios, &mut a);
        let mut acc = vec![0.0; n];
        pt.input_rhs(s.accelerations, &mut acc);
        solve(&a, &mut acc, n).ok_or_else(singular)?;
        let mut m = vec![0.0; n * n];
        pt.mass_model().fill(s.inertia, s.mass, &mut m);
        let mut x = vec![0.0; n];
        pt.force_rhs(&m, s.torques, &acc, &mut x);
        pt.force_matrix(s.ratios, &mut a);
        let at = transpose(&a, n);
        solve(&at, &mut x, n).ok_or_else(singular)?;
        Ok(Solution {
            speeds: w,
            accelerations: acc,
            multipliers: x[..c].to_vec(),
            torques: x[c..].to_vec(),
            conditions: None,
        })
    }

    /// egt's LU and one step of iterative refinement per system. The residual
    /// b - A x is accumulated in doubled precision (Dot2) from the data
    /// themselves (the terms 1, -tau, tau, -1 of each Willis row), so neither
    /// the solve nor the rounding of tau - 1 in forming A survives the step;
    /// the right-hand side of eq. (10) is formed in doubled precision too.
    fn solve_refined(&self) -> Result<Solution> {
        let pt = self.pt();
        let s = self.scenario();
        let (n, c) = (pt.n(), pt.constraints());
        let singular = || -> egt_core::Error {
            AnalysisError::Singular {
                what: "a system of the scenario".into(),
                detail: "a pivot column is zero".into(),
            }
            .into()
        };
        let mut a: Dense = vec![0.0; n * n];
        let mut solve = |system: usize, b: &mut [f64]| -> Result<()> {
            let transpose = system == 2;
            match system {
                0 => pt.kinematic_matrix(s.ratios, &mut a),
                1 => pt.acceleration_matrix(s.ratios, &mut a),
                _ => pt.force_matrix(s.ratios, &mut a),
            }
            let mut lu = Lu::new(n);
            lu.matrix_mut().copy_from_slice(&a);
            lu.factor().map_err(|_| singular())?;
            let rhs = b.to_vec();
            if transpose {
                lu.solve_transpose(b);
            } else {
                lu.solve(b);
            }
            // r = rhs - A x (or rhs - A^T x) as (sum, compensation) pairs.
            let mut acc: Vec<(f64, f64)> = rhs.iter().map(|&v| (v, 0.0)).collect();
            pt.for_each_term(s.ratios, system, |row, col, coef| {
                let (i, x) = if transpose {
                    (col, b[row])
                } else {
                    (row, b[col])
                };
                let p = -coef * x;
                let e = (-coef).mul_add(x, -p);
                let (t, q) = two_sum(acc[i].0, p);
                acc[i] = (t, acc[i].1 + q + e);
            });
            let mut r: Vec<f64> = acc.iter().map(|(s, c)| s + c).collect();
            if transpose {
                lu.solve_transpose(&mut r);
            } else {
                lu.solve(&mut r);
            }
            for (x, d) in b.iter_mut().zip(&r) {
                *x += d;
            }
            Ok(())
        };
        let mut w = vec![0.0; n];
        pt.input_rhs(s.speeds, &mut w);
        solve(0, &mut w)?;
        let mut acc = vec![0.0; n];
        pt.input_rhs(s.accelerations, &mut acc);
        solve(1, &mut acc)?;
        let mut m = vec![0.0; n * n];
        pt.mass_model().fill(s.inertia, s.mass, &mut m);
        let mut x: Vec<f64> = (0..n)
            .map(|i| residual(&m[i * n..(i + 1) * n], &acc, s.torques[i]))
            .collect();
        solve(2, &mut x)?;
        Ok(Solution {
            speeds: w,
            accelerations: acc,
            multipliers: x[..c].to_vec(),
            torques: x[c..].to_vec(),
            conditions: None,
        })
    }

    fn exact_data(&self) -> (Scenario<'_>, Vec<Q>, [QMatrix; 3]) {
        let s = self.scenario();
        let ratios: Vec<Q> = s.ratios.iter().map(|&v| exact_of(v)).collect();
        let mats = self.pt().exact_matrices(&ratios);
        (s, ratios, mats)
    }

    /// The exact solution of the same f64 data, rounded to f64 at the end.
    ///
    /// # Errors
    /// [`AnalysisError::Singular`] when a system is exactly singular.
    pub fn exact(&self) -> Result<Solution> {
        let (s, _, [k, psi, f]) = self.exact_data();
        let pt = self.pt();
        let (n, c) = (pt.n(), pt.constraints());
        let q = |v: &[f64]| -> Vec<Q> { v.iter().map(|&x| exact_of(x)).collect() };
        let rhs = |vals: &[f64]| -> Vec<Q> {
            let mut b = vec![Q::zero(); n];
            for (r, v) in vals.iter().enumerate() {
                b[c + r] = exact_of(*v);
            }
            b
        };
        let singular = |_| -> egt_core::Error {
            AnalysisError::Singular {
                what: "a system of the scenario".into(),
                detail: "exactly singular".into(),
            }
            .into()
        };
        let w = exact::solve(&k, &rhs(s.speeds)).map_err(singular)?;
        let acc = exact::solve(&psi, &rhs(s.accelerations)).map_err(singular)?;
        let m = pt.mass_model().fill_exact(&q(s.inertia), &q(s.mass));
        let torques = q(s.torques);
        let r: Vec<Q> = (0..n)
            .map(|i| {
                let mw: Q = (0..n).map(|j| &m[i][j] * &acc[j]).sum();
                &torques[i] - mw
            })
            .collect();
        let ft: QMatrix = (0..n)
            .map(|i| (0..n).map(|j| f[j][i].clone()).collect())
            .collect();
        let x = exact::solve(&ft, &r).map_err(singular)?;
        let f64s = |v: &[Q]| -> Vec<f64> { v.iter().map(exact::to_f64).collect() };
        Ok(Solution {
            speeds: f64s(&w),
            accelerations: f64s(&acc),
            multipliers: f64s(&x[..c]),
            torques: f64s(&x[c..]),
            conditions: None,
        })
    }

    /// The problem for tools outside Rust: the prepared structure (see
    /// [`PreparedTrain::structure`]), the parameter values by group, and the
    /// exact solution rounded to f64.
    ///
    /// # Errors
    /// As [`Problem::exact`].
    pub fn to_json(&self) -> Result<serde_json::Value> {
        let s = self.scenario();
        let exact = self.exact()?;
        Ok(serde_json::json!({
            "structure": self.pt().structure(),
            "constraints": self.pt().constraints(),
            "values": {
                "ratios": s.ratios, "speeds": s.speeds, "accelerations": s.accelerations,
                "torques": s.torques, "inertia": s.inertia, "mass": s.mass,
            },
            "exact": {
                "speeds": exact.speeds, "accelerations": exact.accelerations,
                "multipliers": exact.multipliers, "torques": exact.torques,
            },
        }))
    }

    /// The true 1-norm condition numbers ||A||_1 ||A^-1||_1 of the speed
    /// system, \[Psi_w\] (eq. 8) and the force system (eq. 10), from exact
    /// inverses (infinite when singular).
    pub fn true_conditions(&self) -> [f64; 3] {
        let (_, _, mats) = self.exact_data();
        mats.map(|a| exact_condition(&a))
    }
}

/// ||A||_1 ||A^-1||_1 with A^-1 computed exactly (Gauss-Jordan on [A | I]).
pub fn exact_condition(a: &QMatrix) -> f64 {
    let n = a.len();
    let mut aug: QMatrix = a
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut r = row.clone();
            r.extend((0..n).map(|j| if i == j { exact::q(1) } else { Q::zero() }));
            r
        })
        .collect();
    let pivots = exact::rref(&mut aug);
    if pivots.iter().filter(|&&p| p < n).count() < n {
        return f64::INFINITY;
    }
    let norm1 = |col: &dyn Fn(usize, usize) -> f64| -> f64 {
        (0..n)
            .map(|j| (0..n).map(|i| col(i, j).abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let an = norm1(&|i, j| exact::to_f64(&a[i][j]));
    let inv = norm1(&|i, j| exact::to_f64(&aug[i][n + j]));
    an * inv
}

fn transpose(a: &[f64], n: usize) -> Dense {
    let mut t = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            t[j * n + i] = a[i * n + j];
        }
    }
    t
}

/// a + b as an unevaluated sum (s, e) with s + e exact (Knuth's TwoSum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let z = s - a;
    (s, (a - (s - z)) + (b - z))
}

/// b - a.x in doubled working precision (Dot2 of Ogita, Rump and Oishi).
pub fn residual(a: &[f64], x: &[f64], b: f64) -> f64 {
    let (mut s, mut c) = (b, 0.0);
    for (&ai, &xi) in a.iter().zip(x) {
        let p = -ai * xi;
        let e = (-ai).mul_add(xi, -p);
        let (t, q) = two_sum(s, p);
        s = t;
        c += q + e;
    }
    s + c
}

/// The exact rational value of a finite float (0 for a non-finite one).
fn exact_of(v: f64) -> Q {
    exact::from_f64(v).unwrap_or_else(Q::zero)
}
