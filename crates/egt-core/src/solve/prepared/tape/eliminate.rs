//! The symbolic elimination: the three systems of a [`PreparedTrain`] factored
//! once in the base row's pivot order, with the checks each row must pass,
//! into a [`Program`].

use super::record::Builder;
use super::*;

/// One system factored in the base row's pivot order: `L` below the
/// diagonal (unit), `U` on and above it, the inverse pivots, the row swaps
/// (LAPACK order) and the system's condition bound.
struct SymLu {
    n: usize,
    a: Vec<S>,
    piv: Vec<usize>,
    dinv: Vec<S>,
    cond: S,
}

/// A system's matrix: symbolic entries and the base row's values.
struct System {
    a: Vec<S>,
    base: Vec<f64>,
}

impl Builder {
    /// Factor `sys` (n x n) with the base row's partial pivoting; the row
    /// checks `m` that every row's pivots are partial-pivoting pivots, are
    /// finite, and that the condition bound is at most [`COND_WARN`] / 2.
    /// None when the base row is singular there.
    fn factor(&mut self, sys: System, n: usize, m: u8) -> Option<SymLu> {
        let System { mut a, mut base } = sys;
        // ||A||_1: the largest column sum of magnitudes.
        let mut anorm = S::C(0.0);
        for j in 0..n {
            let mut s = S::C(0.0);
            for i in 0..n {
                let v = self.abs(a[i * n + j]);
                s = self.add(s, v);
            }
            anorm = self.max(anorm, s);
        }
        let mut piv = vec![0; n];
        let mut dinv = vec![S::C(0.0); n];
        for k in 0..n {
            let mut p = k;
            for i in k + 1..n {
                if base[i * n + k].abs() > base[p * n + k].abs() {
                    p = i;
                }
            }
            let best = base[p * n + k].abs();
            if best == 0.0 || !best.is_finite() {
                return None;
            }
            for i in (k..n).filter(|&i| i != p) {
                self.no_larger(m, a[i * n + k], a[p * n + k]).ok()?;
            }
            piv[k] = p;
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                    base.swap(k * n + j, p * n + j);
                }
            }
            let pivot = a[k * n + k];
            let size = self.abs(pivot);
            self.at_most(m, size, f64::MAX).ok()?;
            let inv = self.recip(pivot);
            let binv = 1.0 / base[k * n + k];
            dinv[k] = inv;
            for i in k + 1..n {
                if a[i * n + k] == S::C(0.0) {
                    continue;
                }
                let f = self.mul(a[i * n + k], inv);
                a[i * n + k] = f;
                let bf = base[i * n + k] * binv;
                base[i * n + k] = bf;
                for j in k + 1..n {
                    if a[k * n + j] != S::C(0.0) {
                        a[i * n + j] = self.sub_mul(a[i * n + j], f, a[k * n + j]);
                        base[i * n + j] -= bf * base[k * n + j];
                    }
                }
            }
        }
        // ||U^-1||_1 <= max(M(U)^-T e) and
        // ||L^-1||_1 <= max(M(L)^-T e), non-negative substitutions.
        let mut y = vec![S::C(1.0); n];
        let mut umax = S::C(0.0);
        for j in 0..n {
            let d = self.abs(dinv[j]);
            let yj = self.mul(y[j], d);
            umax = self.max(umax, yj);
            for i in j + 1..n {
                if a[j * n + i] != S::C(0.0) {
                    let u = self.abs(a[j * n + i]);
                    y[i] = self.add_mul(y[i], u, yj);
                }
            }
        }
        let mut z = vec![S::C(1.0); n];
        let mut lmax = S::C(0.0);
        for k in (0..n).rev() {
            let zk = z[k];
            lmax = self.max(lmax, zk);
            for j in 0..k {
                if a[k * n + j] != S::C(0.0) {
                    let l = self.abs(a[k * n + j]);
                    z[j] = self.add_mul(z[j], l, zk);
                }
            }
        }
        let au = self.mul(anorm, umax);
        let cond = self.mul(au, lmax);
        self.at_most(m, cond, 0.5 * COND_WARN).ok()?;
        Some(SymLu {
            n,
            a,
            piv,
            dinv,
            cond,
        })
    }

    /// `A x = b` in place.
    #[allow(clippy::needless_range_loop)]
    fn solve(&mut self, lu: &SymLu, b: &mut [S]) {
        let n = lu.n;
        for k in 0..n {
            b.swap(k, lu.piv[k]);
        }
        for i in 1..n {
            let mut s = b[i];
            for j in 0..i {
                s = self.sub_mul(s, lu.a[i * n + j], b[j]);
            }
            b[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for j in i + 1..n {
                s = self.sub_mul(s, lu.a[i * n + j], b[j]);
            }
            b[i] = self.mul(s, lu.dinv[i]);
        }
    }

    /// `A^T x = b` in place.
    #[allow(clippy::needless_range_loop)]
    fn solve_transpose(&mut self, lu: &SymLu, b: &mut [S]) {
        let n = lu.n;
        for i in 0..n {
            let y = self.mul(b[i], lu.dinv[i]);
            b[i] = y;
            for j in i + 1..n {
                b[j] = self.sub_mul(b[j], lu.a[i * n + j], y);
            }
        }
        for i in (1..n).rev() {
            let z = b[i];
            for j in 0..i {
                b[j] = self.sub_mul(b[j], lu.a[i * n + j], z);
            }
        }
        for k in (0..n).rev() {
            b.swap(k, lu.piv[k]);
        }
    }
}

/// The Willis entries of one circuit's ratio slot: 1, -t, t - 1.
type Willis = [S; 3];

impl PreparedTrain {
    /// A system's matrix as [`PreparedTrain::lane_rows`] fills it: constraint
    /// rows, then `value` in each of `links`' columns.
    fn symbolic_rows(
        &self,
        willis: &[Willis],
        base_ratios: &[f64],
        links: &[usize],
        value: f64,
        b: &mut Builder,
    ) -> System {
        let n = self.n;
        let mut a = vec![S::C(0.0); n * n];
        let mut base = vec![0.0; n * n];
        for (m, (cols, (w, &t))) in self
            .circuits
            .iter()
            .zip(willis.iter().zip(base_ratios))
            .enumerate()
        {
            for (i, k) in cols.iter().enumerate() {
                if let Some(k) = k {
                    a[m * n + k] = b.add(a[m * n + k], w[i]);
                    base[m * n + k] += willis_row(t)[i];
                }
            }
        }
        let c0 = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    a[(c0 + e) * n + k] = b.add(a[(c0 + e) * n + k], S::C(v));
                    base[(c0 + e) * n + k] += v;
                }
            }
        }
        let c = self.constraints();
        for (r, &k) in links.iter().enumerate() {
            a[(c + r) * n + k] = S::C(value);
            base[(c + r) * n + k] = value;
        }
        System { a, base }
    }

    /// The program of `compute` (kinematics or ideal dynamics) for rows laid
    /// out as `cols`, eliminated in the pivot order of the row `base`. Its
    /// outputs are the batch's columns: the speeds of `known`; then for
    /// dynamics their accelerations, the multipliers and driving torques,
    /// and the meshing force `x_m / r` of each of `forces`; the conditions.
    /// Only the columns `chosen` of these are written, in that order, and
    /// only what they need is computed (the checks of pivots and condition
    /// bounds always are; only the chosen results are checked finite).
    /// None when the base row is singular or ill-conditioned in a system
    /// the program needs (every row is then solved on its own).
    pub(crate) fn program(
        &self,
        compute: Compute,
        cols: Columns,
        base: &[f64],
        (known, forces): (&[usize], &[(usize, f64)]),
        chosen: &[usize],
    ) -> Option<Program> {
        if self.is_sparse() || !matches!(compute, Compute::Kinematics | Compute::Dynamics) {
            return None;
        }
        let n = self.n;
        let c = self.constraints();
        let mut b = Builder::new(u32::try_from(cols.end).ok()?);
        let slot = |k: usize| S::V(k as u32);
        let base_ratios = &base[cols.ratio..cols.speed];
        let willis: Vec<Willis> = (cols.ratio..cols.speed)
            .map(|r| {
                let t = slot(r);
                let minus = b.neg(t);
                let less = b.add(t, S::C(-1.0));
                [S::C(1.0), minus, less]
            })
            .collect();
        let kin = self.symbolic_rows(&willis, base_ratios, &self.inputs, 1.0, &mut b);
        let kin = b.factor(kin, n, KIN)?;
        let mut speed = vec![S::C(0.0); n];
        for (r, col) in (cols.speed..cols.accel).enumerate() {
            speed[c + r] = slot(col);
        }
        b.solve(&kin, &mut speed);
        for (&k, col) in self.inputs.iter().zip(cols.speed..cols.accel) {
            speed[k] = slot(col);
        }
        let mut needs = [true, false, false];
        let (accel, x, cond) = if compute == Compute::Kinematics {
            (Vec::new(), Vec::new(), [kin.cond, S::C(1.0), S::C(1.0)])
        } else {
            let mut accel = vec![S::C(0.0); n];
            for (r, col) in (cols.accel..cols.torque).enumerate() {
                accel[c + r] = slot(col);
            }
            let apart;
            let psi = if self.accel_shared {
                &kin
            } else {
                let sys = self.symbolic_rows(&willis, base_ratios, &self.accelerated, 1.0, &mut b);
                apart = b.factor(sys, n, PSI)?;
                needs[PSI as usize] = true;
                &apart
            };
            b.solve(psi, &mut accel);
            for (&k, col) in self.accelerated.iter().zip(cols.accel..cols.torque) {
                accel[k] = slot(col);
            }
            // {Q} - [M]{w'}, [M] from its terms.
            let mut m = vec![S::C(0.0); n * n];
            for e in &self.mass.entries {
                if let Some((k, s)) = e.spin {
                    let v = b.mul(S::C(e.copies), slot(cols.inertia + s));
                    m[k * n + k] = b.add(m[k * n + k], v);
                }
                if let Some((s, range)) = &e.float {
                    let w = b.mul(S::C(e.copies), slot(cols.mass + s));
                    let terms = &self.mass.terms[range.clone()];
                    for &(i, di) in terms {
                        let wi = b.mul(w, S::C(di));
                        for &(j, dj) in terms {
                            let v = b.mul(wi, S::C(dj));
                            m[i * n + j] = b.add(m[i * n + j], v);
                        }
                    }
                }
            }
            let mut x: Vec<S> = (0..n).map(|i| slot(cols.torque + i)).collect();
            for (i, xi) in x.iter_mut().enumerate() {
                for (j, &aj) in accel.iter().enumerate() {
                    *xi = b.sub_mul(*xi, m[i * n + j], aj);
                }
            }
            let force_cond = if self.force_shared {
                // F = D [Psi_w] with D = diag(1, .., 1, -1, .., -1).
                b.solve_transpose(psi, &mut x);
                for v in &mut x[c..] {
                    *v = b.neg(*v);
                }
                psi.cond
            } else {
                let sys = self.symbolic_rows(&willis, base_ratios, &self.driving, -1.0, &mut b);
                let force = b.factor(sys, n, FORCE)?;
                needs[FORCE as usize] = true;
                b.solve_transpose(&force, &mut x);
                force.cond
            };
            (accel, x, [kin.cond, psi.cond, force_cond])
        };
        let apart = compute == Compute::Dynamics && !self.accel_shared;
        // The speeds with -0 as 0, as the row-by-row solve gives them.
        let mut outputs: Vec<(S, Option<f64>)> = known
            .iter()
            .map(|&k| match speed[k] {
                S::V(v) => (b.push(|d| Op::AddC(d, v, 0.0)), None),
                c => (c, None),
            })
            .collect();
        if compute == Compute::Dynamics {
            outputs.extend(known.iter().map(|&k| (accel[k], apart.then_some(0.0))));
            outputs.extend(x.iter().map(|&v| (v, None)));
            for &(m, r) in forces {
                let f = b.div(x[m], r);
                outputs.push((f, None));
            }
        }
        let results = outputs.len();
        outputs.push((cond[0], None));
        if compute == Compute::Dynamics {
            outputs.push((cond[1], apart.then_some(1.0)));
            outputs.push((cond[2], None));
        }
        let outputs: Vec<(S, Option<f64>)> = (chosen.iter())
            .map(|&o| outputs.get(o).copied())
            .collect::<Option<_>>()?;
        // The results are finite when their sum is: one check for all. A
        // sum with an infinite or NaN term is not finite; one of finite
        // terms is, unless it overflows, and that row is left to the
        // row-by-row solve.
        let mut terms: Vec<S> = (chosen.iter().zip(&outputs))
            .filter(|(o, v)| **o < results && matches!(v.0, S::V(_)))
            .map(|(_, v)| v.0)
            .collect();
        while terms.len() > 1 {
            terms = (terms.chunks(2))
                .map(|t| if let [x, y] = t { b.add(*x, *y) } else { t[0] })
                .collect();
        }
        if let Some(S::V(v)) = terms.first() {
            b.check(Op::Finite(KIN, *v));
        }
        let statics = outputs
            .iter()
            .enumerate()
            .filter_map(|(o, v)| v.1.map(|x| (o, x)))
            .collect();
        let outputs = outputs.into_iter().map(|v| b.slot(v.0)).collect();
        let mut program = Program {
            ops: b.ops,
            slots: 0,
            outputs,
            statics,
            needs,
            cols,
            #[cfg(feature = "jit")]
            code: None,
        };
        program.allocate(b.next as usize);
        Some(program)
    }
}
