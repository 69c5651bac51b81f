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
//! each system's condition number from above, `||A||_1 ||U^-1||_1 ||L^-1||_1`
//! with the inverse norms bounded through the comparison matrices of the
//! factors (one non-negative substitution each). A row whose pivots would
//! differ, whose bound is past [`COND_WARN`] / 2, or any of whose results
//! is not finite is left to the row-by-row solve, which gives its
//! estimate, warning or error:
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
//! unless it overflows, and such a row is left to the row-by-row solve.

#[cfg(feature = "jit")]
use super::jit::{GOOD, MASK_BYTES, MASKS, MOVING};
use super::{Compute, PreparedTrain};
use crate::model::equations::willis_row;
use crate::numerics::linalg::COND_WARN;

mod eliminate;
mod record;
mod run;

pub(crate) use run::crowded;

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
