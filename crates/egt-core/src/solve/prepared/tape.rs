//! [`PreparedTrain::solve`] as a straight-line program: the train's
//! equations eliminated once, symbolically, in one fixed pivot order, and the
//! resulting list of operations then run over blocks of [`BLOCK`] rows.
//!
//! The elimination knows which entries are structurally zero (a Willis row
//! has three non-zeros, the input rows one, \[M\] is sparse), so the program
//! holds only the operations on non-zeros: about a third of the dense LU's
//! at 6 links. Each operation is emitted once however often the elimination
//! asks for it (the three systems share their Willis rows and often their
//! pivots; |-x| is |x|): 155 operations at 6 links, 199 before for the Fig. 3
//! train's dynamics and 147 after. Each operation runs over a whole block, so a dependent chain
//! (a substitution) no longer waits on its own latency, and the cost of
//! reading the program is shared by the block's rows.
//!
//! The fixed order is the base row's partial-pivoting order. The program
//! checks, in every row, that this order is still a partial-pivoting order
//! (every pivot at least as large as the candidates below it), and bounds
//! each system's condition number from above as
//! [`LaneLu::condition_bound`](crate::numerics::lanes::LaneLu::condition_bound)
//! does. A row whose pivots would differ, whose bound is past
//! [`COND_WARN`] / 2, or any of whose results is not finite is left to the
//! lanes and the row-by-row solve, which give its estimate, warning or error:
//! so a row evaluated here is one where the condition columns hold bounds
//! (the batch's `with_condition_bounds`), and every warning and refusal is
//! what the row-by-row solve gives. The program's numbers differ from the
//! row-by-row solve's only by rounding (another order of the same
//! operations; tested within 1e-12 of the largest output, and against exact
//! rationals in the accuracy harness).
//!
//! With the `jit` feature, where the machine has AVX-512 or AVX2, the
//! program also runs as machine code compiled for the train (see
//! `super::jit`): the same operations in the same order, with the values
//! kept in registers, giving the same numbers and the same checks bit for
//! bit. The finiteness checks are sums (one for
//! the parameters, one for the results): a sum is finite when every term is,
//! unless it overflows, and such a row is left to the lanes.

#[cfg(feature = "jit")]
use super::jit::{GOOD, MASK_BYTES, MASKS, MOVING};
use super::{Compute, PreparedTrain};
use crate::model::equations::willis_row;
use crate::numerics::linalg::COND_WARN;

/// How much larger than a pivot a candidate below it may be: the
/// multipliers of `L` are at most this in magnitude (threshold pivoting;
/// partial pivoting is 1).
const PIVOT_RATIO: f64 = 2.0;

/// Rows a program runs over at once.
pub(crate) const BLOCK: usize = 64;
type Block = [f64; BLOCK];

/// A value while the program is built: a constant, or the slot of an operation's result.
#[derive(Debug, Clone, Copy, PartialEq)]
enum S {
    C(f64),
    V(u32),
}

/// One operation: its result's slot first. Every operation reads slots
/// written before it; no result overwrites one of its own operands.
#[derive(Debug, Clone, Copy)]
pub(super) enum Op {
    Neg(u32, u32),
    AddC(u32, u32, f64),
    MulC(u32, u32, f64),
    DivC(u32, u32, f64),
    Add(u32, u32, u32),
    Sub(u32, u32, u32),
    Mul(u32, u32, u32),
    /// `a - b c`.
    SubMul(u32, u32, u32, u32),
    /// `a + b c` (the bound's non-negative substitutions).
    AddMul(u32, u32, u32, u32),
    Recip(u32, u32),
    Abs(u32, u32),
    Const(u32, f64),
    /// The larger, NaN when either is not finite (only on non-negative values).
    Max(u32, u32, u32),
    /// Row check `m`: `|a| <= |b|` (a pivot at least as large as a candidate).
    NoLarger(u8, u32, u32),
    /// Row check `m`: `a <= limit` (false for NaN).
    AtMost(u8, u32, f64),
    /// Row check `m`: `a` finite.
    Finite(u8, u32),
}

impl Op {
    /// The result's slot (none for a check).
    pub(super) fn dest(&self) -> Option<u32> {
        let mut op = *self;
        op.dest_mut().map(|d| *d)
    }

    /// The result's slot, to rename it.
    fn dest_mut(&mut self) -> Option<&mut u32> {
        match self {
            Op::Neg(d, _)
            | Op::AddC(d, _, _)
            | Op::MulC(d, _, _)
            | Op::DivC(d, _, _)
            | Op::Add(d, _, _)
            | Op::Sub(d, _, _)
            | Op::Mul(d, _, _)
            | Op::SubMul(d, _, _, _)
            | Op::AddMul(d, _, _, _)
            | Op::Recip(d, _)
            | Op::Abs(d, _)
            | Op::Const(d, _)
            | Op::Max(d, _, _) => Some(d),
            Op::NoLarger(..) | Op::AtMost(..) | Op::Finite(..) => None,
        }
    }

    /// The slots read, each passed to `f` (by reference, to rename them).
    pub(super) fn operands(&mut self, mut f: impl FnMut(&mut u32)) {
        match self {
            Op::Neg(_, a)
            | Op::AddC(_, a, _)
            | Op::MulC(_, a, _)
            | Op::DivC(_, a, _)
            | Op::Recip(_, a)
            | Op::Abs(_, a)
            | Op::AtMost(_, a, _)
            | Op::Finite(_, a) => f(a),
            Op::Add(_, a, b)
            | Op::Sub(_, a, b)
            | Op::Mul(_, a, b)
            | Op::Max(_, a, b)
            | Op::NoLarger(_, a, b) => {
                f(a);
                f(b);
            }
            Op::SubMul(_, a, b, c) | Op::AddMul(_, a, b, c) => {
                f(a);
                f(b);
                f(c);
            }
            Op::Const(..) => {}
        }
    }
}

/// The systems whose checks a row's validity combines.
const KIN: u8 = 0;
const PSI: u8 = 1;
const FORCE: u8 = 2;

/// A program for one [`PreparedTrain`] and one [`Compute`].
#[derive(Debug, Clone)]
pub(crate) struct Program {
    ops: Vec<Op>,
    slots: usize,
    /// The batch's output columns, in its order: the slot of each.
    outputs: Vec<u32>,
    /// What a static row holds instead, with \[Psi_w\] apart (zero
    /// accelerations, condition 1): (output column, value).
    statics: Vec<(usize, f64)>,
    /// The systems each row must pass: speeds, \[Psi_w\] apart, force apart.
    needs: [bool; 3],
    /// The parameter columns; those before `cols.end` are loaded into slots
    /// `0..cols.end`.
    cols: Columns,
    /// The operations as machine code, where this machine runs it.
    #[cfg(feature = "jit")]
    code: Option<super::jit::Code>,
}

/// A block's slots and checks, one per thread.
#[derive(Debug, Clone)]
pub(crate) struct ProgramWorkspace {
    vals: Vec<Block>,
    ok: [[bool; BLOCK]; 3],
    /// Rows of the block that passed every check (and their own parameter check).
    pub valid: [bool; BLOCK],
    /// Every row of a whole block is valid (set by the compiled code only;
    /// false says nothing).
    pub all_valid: bool,
    moving: [bool; BLOCK],
    arch: pulp::Arch,
    /// The compiled code's pointer table.
    #[cfg(feature = "jit")]
    io: Vec<usize>,
}

/// The columns of one row's parameters, as the batch lays them out.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Columns {
    pub ratio: usize,
    pub speed: usize,
    pub accel: usize,
    pub torque: usize,
    pub inertia: usize,
    pub mass: usize,
    pub end: usize,
}

/// An operation with its result's slot left out, operands of commutative
/// operations in order, constants by their bits: equal keys, equal results.
type Key = (u8, [u32; 3], u64);

impl Op {
    /// The key of the value (or check) this operation computes.
    fn key(&self) -> Key {
        let ord = |a: u32, b: u32| if a <= b { [a, b] } else { [b, a] };
        match *self {
            Op::Neg(_, a) => (0, [a, 0, 0], 0),
            Op::AddC(_, a, c) => (1, [a, 0, 0], c.to_bits()),
            Op::MulC(_, a, c) => (2, [a, 0, 0], c.to_bits()),
            Op::DivC(_, a, c) => (3, [a, 0, 0], c.to_bits()),
            Op::Add(_, a, b) => (4, [ord(a, b)[0], ord(a, b)[1], 0], 0),
            Op::Sub(_, a, b) => (5, [a, b, 0], 0),
            Op::Mul(_, a, b) => (6, [ord(a, b)[0], ord(a, b)[1], 0], 0),
            Op::SubMul(_, a, b, c) => (7, [a, ord(b, c)[0], ord(b, c)[1]], 0),
            Op::AddMul(_, a, b, c) => (8, [a, ord(b, c)[0], ord(b, c)[1]], 0),
            Op::Recip(_, a) => (9, [a, 0, 0], 0),
            Op::Abs(_, a) => (10, [a, 0, 0], 0),
            Op::Const(_, c) => (11, [0, 0, 0], c.to_bits()),
            Op::Max(_, a, b) => (12, [ord(a, b)[0], ord(a, b)[1], 0], 0),
            Op::NoLarger(m, a, b) => (13, [a, b, u32::from(m)], 0),
            Op::AtMost(m, a, c) => (14, [a, u32::from(m), 0], c.to_bits()),
            Op::Finite(m, a) => (15, [a, u32::from(m), 0], 0),
        }
    }
}

struct Builder {
    ops: Vec<Op>,
    next: u32,
    /// The value each key was computed into, or the check already made:
    /// an operation is emitted once however often the elimination asks for
    /// it (the systems share their Willis rows, and often their pivots).
    seen: std::collections::HashMap<Key, S>,
    /// The operation that computed each value, from the first result on.
    first: u32,
    defs: Vec<Op>,
}

impl Builder {
    fn new(first: u32) -> Self {
        Builder {
            ops: Vec::new(),
            next: first,
            seen: std::collections::HashMap::new(),
            first,
            defs: Vec::new(),
        }
    }

    fn push(&mut self, f: impl FnOnce(u32) -> Op) -> S {
        let d = self.next;
        let op = f(d);
        let key = op.key();
        if let Some(&v) = self.seen.get(&key) {
            return v;
        }
        self.next += 1;
        self.ops.push(op);
        self.defs.push(op);
        self.seen.insert(key, S::V(d));
        S::V(d)
    }

    /// A check, once.
    fn check(&mut self, op: Op) {
        if self.seen.insert(op.key(), S::C(0.0)).is_none() {
            self.ops.push(op);
        }
    }

    /// The operation that computed `v` (none for a parameter).
    fn def(&self, v: u32) -> Option<Op> {
        v.checked_sub(self.first)
            .and_then(|i| self.defs.get(i as usize))
            .copied()
    }

    fn neg(&mut self, a: S) -> S {
        match a {
            S::C(c) => S::C(-c),
            S::V(a) => match self.def(a) {
                Some(Op::Neg(_, x)) => S::V(x),
                _ => self.push(|d| Op::Neg(d, a)),
            },
        }
    }

    fn add(&mut self, a: S, b: S) -> S {
        match (a, b) {
            (S::C(x), S::C(y)) => S::C(x + y),
            (S::C(c), S::V(v)) | (S::V(v), S::C(c)) if c == 0.0 => S::V(v),
            (S::C(c), S::V(v)) | (S::V(v), S::C(c)) => self.push(|d| Op::AddC(d, v, c)),
            (S::V(x), S::V(y)) => self.push(|d| Op::Add(d, x, y)),
        }
    }

    fn sub(&mut self, a: S, b: S) -> S {
        match (a, b) {
            (_, S::C(c)) => self.add(a, S::C(-c)),
            (S::C(c), S::V(_)) => {
                let n = self.neg(b);
                self.add(n, S::C(c))
            }
            (S::V(x), S::V(y)) => self.push(|d| Op::Sub(d, x, y)),
        }
    }

    fn mul(&mut self, a: S, b: S) -> S {
        match (a, b) {
            (S::C(x), S::C(y)) => S::C(x * y),
            (S::C(c), S::V(_)) | (S::V(_), S::C(c)) if c == 0.0 => S::C(0.0),
            (S::C(c), S::V(v)) | (S::V(v), S::C(c)) if c == 1.0 => S::V(v),
            (S::C(c), S::V(v)) | (S::V(v), S::C(c)) if c == -1.0 => self.neg(S::V(v)),
            (S::C(c), S::V(v)) | (S::V(v), S::C(c)) => self.push(|d| Op::MulC(d, v, c)),
            (S::V(x), S::V(y)) => self.push(|d| Op::Mul(d, x, y)),
        }
    }

    /// `a - b c`.
    fn sub_mul(&mut self, a: S, b: S, c: S) -> S {
        match (a, b, c) {
            (S::V(a), S::V(b), S::V(c)) => self.push(|d| Op::SubMul(d, a, b, c)),
            _ => {
                let p = self.mul(b, c);
                self.sub(a, p)
            }
        }
    }

    /// `a + b c`.
    fn add_mul(&mut self, a: S, b: S, c: S) -> S {
        match (a, b, c) {
            (S::V(a), S::V(b), S::V(c)) => self.push(|d| Op::AddMul(d, a, b, c)),
            _ => {
                let p = self.mul(b, c);
                self.add(a, p)
            }
        }
    }

    fn recip(&mut self, a: S) -> S {
        match a {
            S::C(c) => S::C(1.0 / c),
            S::V(a) => self.push(|d| Op::Recip(d, a)),
        }
    }

    fn div(&mut self, a: S, c: f64) -> S {
        match a {
            S::C(x) => S::C(x / c),
            S::V(a) => self.push(|d| Op::DivC(d, a, c)),
        }
    }

    fn abs(&mut self, a: S) -> S {
        match a {
            S::C(c) => S::C(c.abs()),
            S::V(a) => match self.def(a) {
                Some(Op::Neg(_, x)) => self.abs(S::V(x)),
                Some(Op::Abs(..)) => S::V(a),
                _ => self.push(|d| Op::Abs(d, a)),
            },
        }
    }

    /// Of two non-negative values.
    fn max(&mut self, a: S, b: S) -> S {
        match (a, b) {
            (S::C(x), S::C(y)) => S::C(x.max(y)),
            (S::C(c), v) | (v, S::C(c)) if c == 0.0 => v,
            _ => {
                let (x, y) = (self.slot(a), self.slot(b));
                self.push(|d| Op::Max(d, x, y))
            }
        }
    }

    /// The slot of `a`, a constant written into one if need be.
    fn slot(&mut self, a: S) -> u32 {
        match a {
            S::V(v) => v,
            S::C(c) => match self.push(|d| Op::Const(d, c)) {
                S::V(v) => v,
                S::C(_) => unreachable!("push returns a slot"),
            },
        }
    }

    /// Row check `m`: `a <= limit`.
    fn at_most(&mut self, m: u8, a: S, limit: f64) -> Result<(), ()> {
        match a {
            S::C(c) if c <= limit => Ok(()),
            S::C(_) => Err(()),
            S::V(a) => {
                self.check(Op::AtMost(m, a, limit));
                Ok(())
            }
        }
    }

    /// Row check `m`: `|a| <= |pivot|`.
    fn no_larger(&mut self, m: u8, a: S, pivot: S) -> Result<(), ()> {
        match (a, pivot) {
            (S::C(x), S::C(y)) if x.abs() <= PIVOT_RATIO * y.abs() => Ok(()),
            (S::C(_), S::C(_)) => Err(()),
            (S::C(0.0), _) => Ok(()),
            _ => {
                let (a, p) = (self.slot(a), self.slot(pivot));
                self.check(Op::NoLarger(m, a, p));
                Ok(())
            }
        }
    }
}

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
        // As `LaneLu::condition_bound`: ||U^-1||_1 <= max(M(U)^-T e) and
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
    /// the program needs (the lanes then solve every row).
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
        // terms is, unless it overflows, and that row is left to the lanes,
        // which solve it.
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

impl Program {
    /// Operations and checks.
    pub(crate) fn len(&self) -> usize {
        self.ops.len()
    }

    /// Whether the operations run as machine code (see `super::jit`).
    #[cfg(feature = "jit")]
    pub(crate) fn compiled(&self) -> bool {
        self.code.is_some()
    }

    /// Whether the operations run as machine code: never without the `jit`
    /// feature.
    #[cfg(not(feature = "jit"))]
    pub(crate) fn compiled(&self) -> bool {
        false
    }

    /// The same program with its operations as machine code, where this
    /// machine runs it: the parameters' and the outputs' slots are the ones
    /// read back.
    #[cfg(feature = "jit")]
    pub(crate) fn compile(mut self) -> Self {
        self.code = super::jit::Code::compile(&self.ops, self.slots, self.cols, &self.outputs);
        self
    }

    /// The same program, interpreted: no machine code without the `jit`
    /// feature.
    #[cfg(not(feature = "jit"))]
    pub(crate) fn compile(self) -> Self {
        self
    }

    /// The same program compiled with `isa` (interpreted where this machine
    /// does not run it, or with None).
    #[cfg(all(test, feature = "jit"))]
    pub(crate) fn with_code(mut self, isa: Option<super::jit::Isa>) -> Self {
        self.code = isa.and_then(|isa| {
            super::jit::Code::compile_for(isa, &self.ops, self.slots, self.cols, &self.outputs)
        });
        self
    }

    /// The instructions the program's code uses, if compiled.
    #[cfg(all(test, feature = "jit"))]
    pub(crate) fn isa(&self) -> Option<super::jit::Isa> {
        self.code.as_ref().map(super::jit::Code::isa)
    }

    /// Drop the operations nothing reads, then give each result a slot that
    /// is reused once its last reader has run (the parameters' and the
    /// results' slots are never reused).
    fn allocate(&mut self, count: usize) {
        let mut pinned = vec![false; count];
        pinned[..self.cols.end].iter_mut().for_each(|p| *p = true);
        for &v in &self.outputs {
            pinned[v as usize] = true;
        }
        // Live: read by a kept operation, or a result.
        let mut live = pinned.clone();
        let mut keep = vec![false; self.ops.len()];
        for (i, op) in self.ops.iter_mut().enumerate().rev() {
            if op.dest().is_none_or(|d| live[d as usize]) {
                keep[i] = true;
                op.operands(|a| live[*a as usize] = true);
            }
        }
        let mut ops: Vec<Op> = self
            .ops
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(op, _)| *op)
            .collect();
        let mut last = vec![usize::MAX; count];
        for (i, op) in ops.iter_mut().enumerate() {
            op.operands(|a| last[*a as usize] = i);
        }
        let mut slot = vec![u32::MAX; count];
        for (v, s) in slot.iter_mut().enumerate().take(self.cols.end) {
            *s = v as u32;
        }
        let mut free: Vec<u32> = Vec::new();
        let mut slots = self.cols.end as u32;
        let mut read: Vec<u32> = Vec::with_capacity(3);
        for (i, op) in ops.iter_mut().enumerate() {
            read.clear();
            op.operands(|a| {
                read.push(*a);
                *a = slot[*a as usize];
            });
            if let Some(d) = op.dest_mut() {
                let s = free.pop().unwrap_or_else(|| {
                    slots += 1;
                    slots - 1
                });
                slot[*d as usize] = s;
                *d = s;
            }
            // Freed after the result has its slot, so no result overwrites an operand.
            read.sort_unstable();
            read.dedup();
            for &v in &read {
                if last[v as usize] == i && !pinned[v as usize] {
                    free.push(slot[v as usize]);
                }
            }
        }
        for v in &mut self.outputs {
            *v = slot[*v as usize];
        }
        self.ops = ops;
        self.slots = slots as usize;
    }
}

/// The result's block and the blocks before and after it, so that operands
/// (any number, repeated or not) are read while the result is written.
struct Split<'a> {
    lo: &'a [Block],
    hi: &'a [Block],
    d: usize,
}

impl<'a> Split<'a> {
    #[inline(always)]
    fn get(&self, a: u32) -> &'a Block {
        let a = a as usize;
        if a < self.d {
            &self.lo[a]
        } else {
            &self.hi[a - self.d - 1]
        }
    }
}

#[inline(always)]
fn split(vals: &mut [Block], d: u32) -> (&mut Block, Split<'_>) {
    let (lo, rest) = vals.split_at_mut(d as usize);
    let (out, hi) = rest
        .split_first_mut()
        .unwrap_or_else(|| unreachable!("a result's slot is allocated"));
    (
        out,
        Split {
            lo,
            hi,
            d: d as usize,
        },
    )
}

impl Program {
    /// Buffers for one thread.
    pub(crate) fn workspace(&self) -> ProgramWorkspace {
        ProgramWorkspace {
            vals: vec![[0.0; BLOCK]; self.slots],
            ok: [[true; BLOCK]; 3],
            valid: [false; BLOCK],
            all_valid: false,
            moving: [false; BLOCK],
            arch: pulp::Arch::new(),
            #[cfg(feature = "jit")]
            io: Vec::new(),
        }
    }

    /// Run the program on up to [`BLOCK`] rows (row-major, `p` columns).
    /// Afterwards `w.valid[r]` says whether row `r` passed the parameter
    /// rules (as the batch's check) and every check of the program, so that
    /// its results are those [`Program::write`] wrote.
    pub(crate) fn run(&self, w: &mut ProgramWorkspace, rows: &[f64], p: usize) {
        let count = rows.len() / p;
        debug_assert!(count <= BLOCK);
        // Column by column; each row's numbers touch only its own lane, so a
        // bad row's NaN (or a stale row past the last) harms no other.
        for (k, v) in w.vals[..self.cols.end].iter_mut().enumerate() {
            for (x, &y) in v.iter_mut().zip(rows[k..].iter().step_by(p)) {
                *x = y;
            }
        }
        self.check_and_run(w, count);
    }

    /// [`Program::run`] on up to [`BLOCK`] rows held column by column:
    /// `column(k)` is the block's part of parameter column `k`, all of one
    /// length.
    pub(crate) fn run_columns<'c>(
        &self,
        w: &mut ProgramWorkspace,
        column: impl Fn(usize) -> &'c [f64],
    ) {
        let mut count = BLOCK;
        for (k, v) in w.vals[..self.cols.end].iter_mut().enumerate() {
            let c = column(k);
            count = c.len();
            v[..count].copy_from_slice(c);
        }
        self.check_and_run(w, count);
    }

    /// [`Program::run_columns`] then [`Program::write_columns`] on rows
    /// `at..to` of the columns (`column(k)` all of parameter column `k`,
    /// `out[o]` of output column `o`), at most [`BLOCK`] rows: a whole block
    /// is read in place by the compiled code, and its outputs written in
    /// place unless `crowded` (the output columns crowd the cache's sets,
    /// [`crowded`]: then into the block's slots and copied).
    pub(crate) fn solve_columns<'c>(
        &self,
        w: &mut ProgramWorkspace,
        column: impl Fn(usize) -> &'c [f64],
        out: &mut [&mut [f64]],
        (at, to): (usize, usize),
        crowded: bool,
    ) {
        #[cfg(feature = "jit")]
        if let Some(code) = &self.code
            && to - at == BLOCK
        {
            let mut masks = [0u8; MASKS * MASK_BYTES];
            let in_place = super::jit::InPlace {
                column: &column,
                out: (!crowded).then_some(&mut *out),
                at,
            };
            code.run(&mut w.vals, &mut masks, &mut w.io, Some(in_place));
            self.finish(w, &masks, BLOCK);
            if crowded {
                self.write_columns(w, out, at, to);
            } else {
                self.write_statics(w, out, at, to);
            }
            return;
        }
        #[cfg(not(feature = "jit"))]
        let _ = crowded;
        self.run_columns(w, |k| &column(k)[at..to]);
        self.write_columns(w, out, at, to);
    }

    /// Each row's validity and motion from the compiled code's masks.
    #[cfg(feature = "jit")]
    fn finish(&self, w: &mut ProgramWorkspace, masks: &[u8; MASKS * MASK_BYTES], count: usize) {
        const { assert!(BLOCK == 64, "a block's rows are the bits of a u64") };
        let word = |m: usize| {
            let bytes: [u8; 8] = std::array::from_fn(|p| masks[m * MASK_BYTES + p]);
            u64::from_le_bytes(bytes)
        };
        let mut valid = word(GOOD) & u64::MAX.checked_shr(64 - count as u32).unwrap_or(0);
        for m in [KIN, PSI, FORCE] {
            if self.needs[m as usize] {
                valid &= word(m as usize);
            }
        }
        // The usual block: every row valid, and moving (or none). Filled
        // whole; bit by bit only otherwise (a bit test and a store a row,
        // kept scalar by the compiler: a one-thread `egt batch` of 10^7 rows
        // ran 7 % faster without them; docs/performance.md (history: git log -p -- docs/benchmarks.md)).
        let bits = |mask: u64| match mask {
            u64::MAX => [true; BLOCK],
            0 => [false; BLOCK],
            _ => std::array::from_fn(|r| mask >> r & 1 == 1),
        };
        w.valid = bits(valid);
        w.moving = bits(word(MOVING));
        w.all_valid = valid == u64::MAX;
    }

    /// The parameter rules on the loaded columns, the operations, and each
    /// row's validity.
    fn check_and_run(&self, w: &mut ProgramWorkspace, count: usize) {
        #[cfg(feature = "jit")]
        if let Some(code) = &self.code {
            let mut masks = [0u8; MASKS * MASK_BYTES];
            code.run(&mut w.vals, &mut masks, &mut w.io, None);
            self.finish(w, &masks, count);
            return;
        }
        let arch = w.arch;
        arch.dispatch(Run {
            program: self,
            w,
            count,
        });
    }

    /// The parameter rules on the loaded columns (`good`), and the rows
    /// that prescribe an acceleration (`w.moving`).
    #[inline(always)]
    fn check_params(&self, w: &mut ProgramWorkspace, good: &mut [bool; BLOCK]) {
        let c = self.cols;
        w.moving = [false; BLOCK];
        // Finite when their sum is (in column order, as the compiled code
        // adds them): a row whose sum overflows is left to the lanes.
        let mut sum = [0.0; BLOCK];
        for (k, v) in w.vals[..self.cols.end].iter().enumerate() {
            if k == 0 {
                sum = *v;
            } else {
                sum.iter_mut().zip(v.iter()).for_each(|(s, &x)| *s += x);
            }
            let column = good.iter_mut().zip(v.iter());
            if k < c.speed {
                column.for_each(|(g, &x)| *g &= x != 0.0);
            } else if k >= c.inertia {
                column.for_each(|(g, &x)| *g &= x >= 0.0);
            }
            if (c.accel..c.torque).contains(&k) {
                for (m, &x) in w.moving.iter_mut().zip(v.iter()) {
                    *m |= x != 0.0;
                }
            }
        }
        if self.cols.end > 0 {
            good.iter_mut()
                .zip(sum)
                .for_each(|(g, s)| *g &= s.is_finite());
        }
    }

    #[inline(always)]
    fn run_ops(&self, w: &mut ProgramWorkspace) {
        let ProgramWorkspace { vals, ok, .. } = w;
        for op in &self.ops {
            match *op {
                Op::Neg(d, a) => {
                    let (o, s) = split(vals, d);
                    let a = s.get(a);
                    for r in 0..BLOCK {
                        o[r] = -a[r];
                    }
                }
                Op::AddC(d, a, c) => {
                    let (o, s) = split(vals, d);
                    let a = s.get(a);
                    for r in 0..BLOCK {
                        o[r] = a[r] + c;
                    }
                }
                Op::MulC(d, a, c) => {
                    let (o, s) = split(vals, d);
                    let a = s.get(a);
                    for r in 0..BLOCK {
                        o[r] = a[r] * c;
                    }
                }
                Op::DivC(d, a, c) => {
                    let (o, s) = split(vals, d);
                    let a = s.get(a);
                    for r in 0..BLOCK {
                        o[r] = a[r] / c;
                    }
                }
                Op::Add(d, a, b) => {
                    let (o, s) = split(vals, d);
                    let (a, b) = (s.get(a), s.get(b));
                    for r in 0..BLOCK {
                        o[r] = a[r] + b[r];
                    }
                }
                Op::Sub(d, a, b) => {
                    let (o, s) = split(vals, d);
                    let (a, b) = (s.get(a), s.get(b));
                    for r in 0..BLOCK {
                        o[r] = a[r] - b[r];
                    }
                }
                Op::Mul(d, a, b) => {
                    let (o, s) = split(vals, d);
                    let (a, b) = (s.get(a), s.get(b));
                    for r in 0..BLOCK {
                        o[r] = a[r] * b[r];
                    }
                }
                Op::SubMul(d, a, b, c) => {
                    let (o, s) = split(vals, d);
                    let (a, b, c) = (s.get(a), s.get(b), s.get(c));
                    for r in 0..BLOCK {
                        o[r] = a[r] - b[r] * c[r];
                    }
                }
                Op::AddMul(d, a, b, c) => {
                    let (o, s) = split(vals, d);
                    let (a, b, c) = (s.get(a), s.get(b), s.get(c));
                    for r in 0..BLOCK {
                        o[r] = a[r] + b[r] * c[r];
                    }
                }
                Op::Recip(d, a) => {
                    let (o, s) = split(vals, d);
                    let a = s.get(a);
                    for r in 0..BLOCK {
                        o[r] = 1.0 / a[r];
                    }
                }
                Op::Abs(d, a) => {
                    let (o, s) = split(vals, d);
                    let a = s.get(a);
                    for r in 0..BLOCK {
                        o[r] = a[r].abs();
                    }
                }
                Op::Const(d, c) => {
                    vals[d as usize] = [c; BLOCK];
                }
                Op::Max(d, a, b) => {
                    let (o, s) = split(vals, d);
                    let (a, b) = (s.get(a), s.get(b));
                    for r in 0..BLOCK {
                        // 0 (a - b) is NaN when either is not finite (both are >= 0).
                        // The select is x86's `maxpd` (the compiled code's).
                        let m = if a[r] > b[r] { a[r] } else { b[r] };
                        o[r] = m + 0.0 * (a[r] - b[r]);
                    }
                }
                Op::NoLarger(m, a, b) => {
                    let (a, b) = (&vals[a as usize], &vals[b as usize]);
                    let ok = &mut ok[m as usize];
                    for r in 0..BLOCK {
                        ok[r] &= a[r].abs() <= PIVOT_RATIO * b[r].abs();
                    }
                }
                Op::AtMost(m, a, limit) => {
                    let a = &vals[a as usize];
                    let ok = &mut ok[m as usize];
                    for r in 0..BLOCK {
                        ok[r] &= a[r] <= limit;
                    }
                }
                Op::Finite(m, a) => {
                    let a = &vals[a as usize];
                    let ok = &mut ok[m as usize];
                    for r in 0..BLOCK {
                        ok[r] &= a[r].is_finite();
                    }
                }
            }
        }
    }

    /// Write the outputs into `out` (row-major, the batch's columns, one
    /// row per row of the last [`Program::run`]); the rows not valid get
    /// numbers that mean nothing, to be overwritten.
    pub(crate) fn write(&self, w: &ProgramWorkspace, out: &mut [f64]) {
        let q = self.outputs.len();
        for (o, &k) in self.outputs.iter().enumerate() {
            for (d, &v) in out[o..].iter_mut().step_by(q).zip(&w.vals[k as usize]) {
                *d = v;
            }
        }
        if !self.statics.is_empty() {
            for (r, row) in out.chunks_exact_mut(q).take(BLOCK).enumerate() {
                if !w.moving[r] {
                    for &(o, v) in &self.statics {
                        row[o] = v;
                    }
                }
            }
        }
    }

    /// [`Program::write`] column by column: rows `at..to` of each output
    /// column `out[o]` (the rows of the last [`Program::run_columns`]).
    pub(crate) fn write_columns(
        &self,
        w: &ProgramWorkspace,
        out: &mut [&mut [f64]],
        at: usize,
        to: usize,
    ) {
        for (d, &k) in out.iter_mut().zip(&self.outputs) {
            d[at..to].copy_from_slice(&w.vals[k as usize][..to - at]);
        }
        self.write_statics(w, out, at, to);
    }

    /// What the static rows among `at..to` hold instead (see `statics`).
    fn write_statics(&self, w: &ProgramWorkspace, out: &mut [&mut [f64]], at: usize, to: usize) {
        for &(o, v) in &self.statics {
            for (d, &m) in out[o][at..to].iter_mut().zip(&w.moving) {
                if !m {
                    *d = v;
                }
            }
        }
    }
}

/// Whether columns starting at `starts` (byte addresses) crowd the L1
/// cache's sets: some set is under the first [`BLOCK`] rows of more than
/// 12 of them (a block of a column is 8 lines; the set is the address
/// modulo 4 KiB, the way x86 cores with 48 KiB, 12-way L1 caches index it).
/// The columns of a column-major matrix of 512 x 2^k rows all start at one
/// offset modulo 4 KiB. Writing its output columns in place a block at a
/// time, the program ran 3 times slower than with 4 000 rows (19.4 against
/// 6.5 ns a row at 6 links, 4 096 rows); through the block's slots and
/// copied, 9.8 ns (reading the parameters through the slots as well did
/// not help: 10.6; docs/performance.md (history: git log -p -- docs/benchmarks.md)).
pub(crate) fn crowded(starts: impl IntoIterator<Item = usize>) -> bool {
    const LINE: usize = 64;
    const SETS: usize = 4096 / LINE;
    const LINES: usize = BLOCK * 8 / LINE;
    let mut under = [0usize; SETS];
    for a in starts {
        let s = (a % 4096) / LINE;
        for d in 0..LINES {
            under[(s + d) % SETS] += 1;
        }
    }
    under.iter().any(|&n| n > 12)
}

/// One block's run as a [`pulp::WithSimd`], compiled for the detected
/// instruction set (as the lanes' `Group`): the parameter rules, the
/// operations, and each row's validity.
struct Run<'a> {
    program: &'a Program,
    w: &'a mut ProgramWorkspace,
    /// Rows loaded; those past it are stale and never valid.
    count: usize,
}

impl pulp::WithSimd for Run<'_> {
    type Output = ();
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Run { program, w, count } = self;
        w.all_valid = false;
        let mut good = [true; BLOCK];
        program.check_params(w, &mut good);
        w.ok = [[true; BLOCK]; 3];
        program.run_ops(w);
        let needs = program.needs;
        for r in 0..BLOCK {
            let ok = |m: u8| !needs[m as usize] || w.ok[m as usize][r];
            w.valid[r] = r < count && good[r] && ok(KIN) && ok(PSI) && ok(FORCE);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::crowded;

    /// The columns of a column-major matrix of 512 x 2^k rows start at one
    /// offset modulo 4 KiB: more than 12 of them crowd the cache's sets;
    /// other row counts spread them.
    #[test]
    fn columns_of_512_times_2k_rows_crowd_the_cache() {
        let starts = |rows: usize, cols: usize| (0..cols).map(move |c| 0x1_0000 + c * rows * 8);
        assert!(crowded(starts(4096, 22)));
        assert!(crowded(starts(512, 13)));
        assert!(crowded(starts(1 << 20, 13)));
        assert!(!crowded(starts(512, 12)));
        assert!(!crowded(starts(4000, 22)));
        assert!(!crowded(starts(10_000, 60)));
        assert!(!crowded(starts(1000, 60)));
        // More columns than a u16 counts (a train of 10^5 links' outputs).
        assert!(crowded(starts(4096, 70_000)));
    }
}
