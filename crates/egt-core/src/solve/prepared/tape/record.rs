//! Recording the program: each operation and check emitted once (equal
//! operands and constants, equal result), with the constants folded.

use super::*;

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

pub(super) struct Builder {
    pub(super) ops: Vec<Op>,
    pub(super) next: u32,
    /// The value each key was computed into, or the check already made:
    /// an operation is emitted once however often the elimination asks for
    /// it (the systems share their Willis rows, and often their pivots).
    pub(super) seen: std::collections::HashMap<Key, S>,
    /// The operation that computed each value, from the first result on.
    pub(super) first: u32,
    pub(super) defs: Vec<Op>,
}

impl Builder {
    pub(super) fn new(first: u32) -> Self {
        Builder {
            ops: Vec::new(),
            next: first,
            seen: std::collections::HashMap::new(),
            first,
            defs: Vec::new(),
        }
    }

    pub(super) fn push(&mut self, f: impl FnOnce(u32) -> Op) -> S {
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
    pub(super) fn check(&mut self, op: Op) {
        if self.seen.insert(op.key(), S::C(0.0)).is_none() {
            self.ops.push(op);
        }
    }

    /// The operation that computed `v` (none for a parameter).
    pub(super) fn def(&self, v: u32) -> Option<Op> {
        v.checked_sub(self.first)
            .and_then(|i| self.defs.get(i as usize))
            .copied()
    }

    pub(super) fn neg(&mut self, a: S) -> S {
        match a {
            S::C(c) => S::C(-c),
            S::V(a) => match self.def(a) {
                Some(Op::Neg(_, x)) => S::V(x),
                _ => self.push(|d| Op::Neg(d, a)),
            },
        }
    }

    pub(super) fn add(&mut self, a: S, b: S) -> S {
        match (a, b) {
            (S::C(x), S::C(y)) => S::C(x + y),
            (S::C(c), S::V(v)) | (S::V(v), S::C(c)) if c == 0.0 => S::V(v),
            (S::C(c), S::V(v)) | (S::V(v), S::C(c)) => self.push(|d| Op::AddC(d, v, c)),
            (S::V(x), S::V(y)) => self.push(|d| Op::Add(d, x, y)),
        }
    }

    pub(super) fn sub(&mut self, a: S, b: S) -> S {
        match (a, b) {
            (_, S::C(c)) => self.add(a, S::C(-c)),
            (S::C(c), S::V(_)) => {
                let n = self.neg(b);
                self.add(n, S::C(c))
            }
            (S::V(x), S::V(y)) => self.push(|d| Op::Sub(d, x, y)),
        }
    }

    pub(super) fn mul(&mut self, a: S, b: S) -> S {
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
    pub(super) fn sub_mul(&mut self, a: S, b: S, c: S) -> S {
        match (a, b, c) {
            (S::V(a), S::V(b), S::V(c)) => self.push(|d| Op::SubMul(d, a, b, c)),
            _ => {
                let p = self.mul(b, c);
                self.sub(a, p)
            }
        }
    }

    /// `a + b c`.
    pub(super) fn add_mul(&mut self, a: S, b: S, c: S) -> S {
        match (a, b, c) {
            (S::V(a), S::V(b), S::V(c)) => self.push(|d| Op::AddMul(d, a, b, c)),
            _ => {
                let p = self.mul(b, c);
                self.add(a, p)
            }
        }
    }

    pub(super) fn recip(&mut self, a: S) -> S {
        match a {
            S::C(c) => S::C(1.0 / c),
            S::V(a) => self.push(|d| Op::Recip(d, a)),
        }
    }

    pub(super) fn div(&mut self, a: S, c: f64) -> S {
        match a {
            S::C(x) => S::C(x / c),
            S::V(a) => self.push(|d| Op::DivC(d, a, c)),
        }
    }

    pub(super) fn abs(&mut self, a: S) -> S {
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
    pub(super) fn max(&mut self, a: S, b: S) -> S {
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
    pub(super) fn slot(&mut self, a: S) -> u32 {
        match a {
            S::V(v) => v,
            S::C(c) => match self.push(|d| Op::Const(d, c)) {
                S::V(v) => v,
                S::C(_) => unreachable!("push returns a slot"),
            },
        }
    }

    /// Row check `m`: `a <= limit`.
    pub(super) fn at_most(&mut self, m: u8, a: S, limit: f64) -> Result<(), ()> {
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
    pub(super) fn no_larger(&mut self, m: u8, a: S, pivot: S) -> Result<(), ()> {
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
