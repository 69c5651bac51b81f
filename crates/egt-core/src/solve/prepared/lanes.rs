//! [`PreparedTrain::solve`] for [`LANES`] scenarios at once: the same
//! equations, filled and solved lane by lane with [`LaneLu`]. A lane that
//! would pivot differently from the group, or whose system is singular or
//! past [`COND_REFUSE`](crate::numerics::linalg::COND_REFUSE), is marked dead
//! and left to [`PreparedTrain::solve`], which gives its result or its error.
//! A live lane's numbers are those a fresh [`Workspace`](super::Workspace)
//! gives (tested bit for bit in `batch`).

use super::{Compute, MassModel, PreparedTrain};
use crate::model::equations::willis_row;
use crate::numerics::lanes::{LANES, Lane, LaneLu, Live};
use crate::numerics::linalg::{COND_WARN, Dim, Dynamic, Fixed};

/// The scenarios of one group, structure of arrays, and the buffers of their
/// solve; results are read from here.
#[derive(Debug, Clone)]
pub(crate) struct LaneWorkspace {
    kin: LaneLu,
    acc: LaneLu,
    force: LaneLu,
    /// Parameters, one entry per column of a [`Scenario`](super::Scenario) group.
    pub ratios: Vec<Lane>,
    pub speeds: Vec<Lane>,
    pub accelerations: Vec<Lane>,
    pub torques: Vec<Lane>,
    pub inertia: Vec<Lane>,
    pub mass: Vec<Lane>,
    /// Results: speeds, accelerations, multipliers then driving torques, conditions.
    pub speed: Vec<Lane>,
    pub accel: Vec<Lane>,
    pub x: Vec<Lane>,
    pub cond: [Lane; 3],
    m: Vec<Lane>,
    x2: Vec<Lane>,
    arch: pulp::Arch,
}

impl PreparedTrain {
    /// Buffers for groups of [`LANES`] scenarios on one thread (none for a
    /// sparse train, which the lanes do not solve).
    pub(crate) fn lane_workspace(&self) -> LaneWorkspace {
        let dense = !self.is_sparse();
        let n = if dense { self.n } else { 0 };
        let f = self.inputs.len();
        let z = |k: usize| vec![[0.0; LANES]; if dense { k } else { 0 }];
        LaneWorkspace {
            kin: LaneLu::new(n),
            acc: LaneLu::new(n),
            force: LaneLu::new(n),
            ratios: z(self.circuits.len()),
            speeds: z(f),
            accelerations: z(self.accelerated.len()),
            torques: z(n),
            inertia: z(self.mass.inertia_links.len()),
            mass: z(self.mass.mass_links.len()),
            speed: z(n),
            accel: z(n),
            x: z(n),
            cond: [[1.0; LANES]; 3],
            m: z(n * n),
            x2: z(n),
            arch: pulp::Arch::new(),
        }
    }

    /// Constraint rows (eq. 2 with the lanes' ratios, then the extras) and
    /// `value` in each of `links`' columns below them, into zeroed `out`.
    #[inline(always)]
    fn lane_rows(&self, ratios: &[Lane], links: &[usize], value: f64, out: &mut [Lane]) {
        let n = self.n;
        out.iter_mut().for_each(|v| *v = [0.0; LANES]);
        for (m, (cols, t)) in self.circuits.iter().zip(ratios).enumerate() {
            for (i, k) in cols.iter().enumerate() {
                if let Some(k) = k {
                    let e = &mut out[m * n + k];
                    for l in 0..LANES {
                        e[l] += willis_row(t[l])[i];
                    }
                }
            }
        }
        let base = self.circuits.len();
        for (e, row) in self.extras.iter().enumerate() {
            for &(k, v) in row {
                if let Some(k) = k {
                    out[(base + e) * n + k].iter_mut().for_each(|x| *x += v);
                }
            }
        }
        let c = self.constraints();
        for (r, &k) in links.iter().enumerate() {
            out[(c + r) * n + k] = [value; LANES];
        }
    }

    /// Solve the group in `w` (kinematics or ideal dynamics), as
    /// [`PreparedTrain::solve`] on a fresh workspace solves each lane. Lanes
    /// dead on entry are not looked at; lanes that die are left for
    /// [`PreparedTrain::solve`].
    ///
    /// With `bounds`, a condition estimate is made only where
    /// [`LaneLu::condition_or_bound`] cannot show it below [`COND_WARN`] / 2: the
    /// same lanes die, every condition past `COND_WARN / 2` is the estimate,
    /// the others are upper bounds.
    ///
    /// # Panics
    /// For [`Compute::Forces`] or [`Compute::Power`] (solved one at a time).
    pub(crate) fn solve_lanes(
        &self,
        w: &mut LaneWorkspace,
        live: &mut Live,
        what: Compute,
        bounds: bool,
    ) {
        assert!(!self.is_sparse(), "lanes solve dense trains");
        assert!(
            matches!(what, Compute::Kinematics | Compute::Dynamics),
            "lanes solve kinematics and ideal dynamics"
        );
        // The build targets baseline x86-64; run the group with the widest
        // vector instructions this machine has (pulp detects them once).
        let arch = w.arch;
        arch.dispatch(Group {
            plan: self,
            w,
            live,
            what,
            bounds,
        });
    }

    #[inline(always)]
    fn solve_lanes_in<D: Dim>(
        &self,
        d: D,
        w: &mut LaneWorkspace,
        live: &mut Live,
        what: Compute,
        bounds: bool,
    ) {
        let c = self.constraints();
        let LaneWorkspace {
            kin,
            acc,
            force,
            ratios,
            speeds,
            accelerations,
            torques,
            inertia,
            mass,
            speed,
            accel,
            x,
            cond,
            m,
            x2,
            arch: _,
        } = w;
        self.lane_rows(ratios, &self.inputs, 1.0, kin.matrix_mut());
        kin.factor(d, live);
        cond[0] = condition(kin, d, live, bounds);
        rhs(c, speeds, speed);
        if what == Compute::Kinematics {
            kin.solve(d, speed);
            keep(&self.inputs, speeds, speed);
            return;
        }
        let mut moving = [false; LANES];
        for a in accelerations.iter() {
            for l in 0..LANES {
                moving[l] |= a[l] != 0.0;
            }
        }
        rhs(c, accelerations, accel);
        kin.solve(d, speed);
        // Which lanes solve eq. (10) through [Psi_w] (eq. 8): all of them when
        // it is the speed system, the moving ones when it is factored apart.
        let psi: Live;
        let psi_cond: Lane;
        let psi_lu: &LaneLu;
        if self.accel_shared {
            cond[1] = cond[0];
            psi = [true; LANES];
            psi_cond = cond[0];
            kin.solve(d, accel);
            psi_lu = kin;
        } else {
            psi = moving;
            psi_cond = if moving.iter().zip(live.iter()).any(|(&a, &b)| a && b) {
                self.lane_rows(ratios, &self.accelerated, 1.0, acc.matrix_mut());
                // A static lane does not need eq. (8): its failure is not the lane's.
                let mut ok = *live;
                acc.factor(d, &mut ok);
                let k = condition(acc, d, &mut ok, bounds);
                for l in 0..LANES {
                    live[l] &= ok[l] || !moving[l];
                }
                acc.solve(d, accel);
                k
            } else {
                [1.0; LANES]
            };
            for l in 0..LANES {
                cond[1][l] = if moving[l] { psi_cond[l] } else { 1.0 };
            }
            psi_lu = acc;
        }
        for l in (0..LANES).filter(|&l| !moving[l]) {
            accel.iter_mut().for_each(|v| v[l] = 0.0);
        }
        for (&k, a) in self.accelerated.iter().zip(accelerations.iter()) {
            accel[k] = *a;
        }
        keep(&self.inputs, speeds, speed);
        self.mass.fill_lanes(inertia, mass, m);
        // {Q} - [M]{w'}.
        let n = self.n;
        for (i, o) in x.iter_mut().enumerate() {
            let mut s = [-0.0; LANES];
            for (mij, aj) in m[i * n..(i + 1) * n].iter().zip(accel.iter()) {
                for l in 0..LANES {
                    s[l] += mij[l] * aj[l];
                }
            }
            for l in 0..LANES {
                o[l] = torques[i][l] - s[l];
            }
        }
        let through_psi = self.force_shared && psi.iter().zip(live.iter()).any(|(&p, &b)| p && b);
        let apart = !self.force_shared || psi.iter().zip(live.iter()).any(|(&p, &b)| !p && b);
        if apart {
            // The force matrix, factored for the lanes that do not go through [Psi_w].
            x2.copy_from_slice(x);
            self.lane_rows(ratios, &self.driving, -1.0, force.matrix_mut());
            let mut ok = *live;
            force.factor(d, &mut ok);
            let k = condition(force, d, &mut ok, bounds);
            force.solve_transpose(d, x2);
            for l in 0..LANES {
                if !(self.force_shared && psi[l]) {
                    live[l] &= ok[l];
                    cond[2][l] = k[l];
                }
            }
        }
        if through_psi {
            // F = D [Psi_w] with D = diag(1, .., 1, -1, .., -1): x = D [Psi_w]^-T r.
            psi_lu.solve_transpose(d, x);
            x[c..]
                .iter_mut()
                .for_each(|v| v.iter_mut().for_each(|y| *y = -*y));
        }
        for l in 0..LANES {
            if self.force_shared && psi[l] {
                cond[2][l] = psi_cond[l];
            } else {
                for (a, b) in x.iter_mut().zip(x2.iter()) {
                    a[l] = b[l];
                }
            }
        }
    }
}

/// One group's solve as a [`pulp::WithSimd`]: `with_simd` is inlined into
/// pulp's function compiled for the detected instruction set, and everything
/// it calls is `inline(always)`, so the whole group is compiled for it.
struct Group<'a> {
    plan: &'a PreparedTrain,
    w: &'a mut LaneWorkspace,
    live: &'a mut Live,
    what: Compute,
    bounds: bool,
}

impl pulp::WithSimd for Group<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Group {
            plan,
            w,
            live,
            what,
            bounds,
        } = self;
        // Unrolled for the smallest orders only: each order is one more
        // copy of the whole group inlined per instruction set, and those
        // copies were most of the crate's optimised build time
        // (docs/performance.md, "Build time").
        macro_rules! unrolled {
            ($($k:literal)*) => {
                match plan.n {
                    $($k => plan.solve_lanes_in(Fixed::<$k>, w, live, what, bounds),)*
                    n => plan.solve_lanes_in(Dynamic(n), w, live, what, bounds),
                }
            };
        }
        unrolled!(1 2 3 4 5 6);
    }
}

impl MassModel {
    /// [`MassModel::fill`] for every lane.
    #[inline(always)]
    fn fill_lanes(&self, inertia: &[Lane], mass: &[Lane], m: &mut [Lane]) {
        let n = self.n;
        m.iter_mut().for_each(|v| *v = [0.0; LANES]);
        for e in &self.entries {
            if let Some((c, s)) = e.spin {
                let d = &mut m[c * n + c];
                for l in 0..LANES {
                    d[l] += e.copies * inertia[s][l];
                }
            }
            if let Some((s, range)) = &e.float {
                let mut w = mass[*s];
                w.iter_mut().for_each(|v| *v *= e.copies);
                // `fill` multiplies w * da * db left to right: (w * da) * db.
                let terms = &self.terms[range.clone()];
                for &(a, da) in terms {
                    let mut wa = w;
                    wa.iter_mut().for_each(|v| *v *= da);
                    for &(b, db) in terms {
                        let e = &mut m[a * n + b];
                        for l in 0..LANES {
                            e[l] += wa[l] * db;
                        }
                    }
                }
            }
        }
    }
}

/// The condition estimate, or with `bounds` the bound where it shows the
/// condition small (see [`PreparedTrain::solve_lanes`]).
#[inline(always)]
fn condition<D: Dim>(lu: &mut LaneLu, d: D, live: &mut Live, bounds: bool) -> Lane {
    if bounds {
        lu.condition_or_bound(d, live, COND_WARN)
    } else {
        lu.condition(d, live)
    }
}

/// Zeros, then the prescribed values below the constraint rows.
#[inline(always)]
fn rhs(c: usize, values: &[Lane], out: &mut [Lane]) {
    out.iter_mut().for_each(|v| *v = [0.0; LANES]);
    out[c..c + values.len()].copy_from_slice(values);
}

/// The prescribed speeds are data (as `PreparedTrain::keep_inputs`).
#[inline(always)]
fn keep(inputs: &[usize], values: &[Lane], speed: &mut [Lane]) {
    for (&k, v) in inputs.iter().zip(values) {
        speed[k] = *v;
    }
    speed
        .iter_mut()
        .for_each(|v| v.iter_mut().for_each(|x| *x += 0.0));
}
