//! The assembler of a compiled program (see `jit.rs`): each operation on
//! vector registers, values held in registers between operations and spilled
//! by Belady's rule (the one read furthest ahead), the checks in mask
//! registers (AVX-512) or mask words (AVX2), through `iced-x86`.

use super::{GOOD, Isa, MASK_BYTES, MASKS, MOVING};
use crate::solve::prepared::tape::{BLOCK, Columns, Op};

/// Where a value is: its register, if any.
#[derive(Clone, Copy)]
struct Held {
    slot: u32,
    /// The operation index of its next read (`usize::MAX`: none).
    next: usize,
    /// Computed here and not yet in its slot.
    dirty: bool,
}

/// The operations' scratch registers (beyond the allocatable ones).
const T0: usize = 100;
const T1: usize = 101;

/// A two-operand vector operation.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
enum Bin {
    Add,
    Sub,
    Mul,
    Div,
    And,
    Xor,
    Max,
}

/// The second operand of a [`Bin`] or a compare: a register, or a constant
/// (its index in the constants).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
enum Src {
    R(usize),
    C(usize),
}

/// An assembler writing one instruction set's forms of the operations
/// `assemble` needs; registers are numbered `0..isa.allocatable()`, and
/// [`T0`] and [`T1`] are the scratch.
#[cfg(target_arch = "x86_64")]
struct Vector {
    a: iced_x86::code_asm::CodeAssembler,
    isa: Isa,
}

#[cfg(target_arch = "x86_64")]
impl Vector {
    fn zmm(r: usize) -> iced_x86::code_asm::AsmRegisterZmm {
        use iced_x86::code_asm::*;
        const ZMM: [AsmRegisterZmm; 30] = [
            zmm0, zmm1, zmm2, zmm3, zmm4, zmm5, zmm6, zmm7, zmm8, zmm9, zmm10, zmm11, zmm12, zmm13,
            zmm14, zmm15, zmm16, zmm17, zmm18, zmm19, zmm20, zmm21, zmm22, zmm23, zmm24, zmm25,
            zmm26, zmm27, zmm28, zmm29,
        ];
        match r {
            T0 => zmm30,
            T1 => zmm31,
            r => ZMM[r],
        }
    }

    fn ymm(r: usize) -> iced_x86::code_asm::AsmRegisterYmm {
        use iced_x86::code_asm::*;
        const YMM: [AsmRegisterYmm; 14] = [
            ymm0, ymm1, ymm2, ymm3, ymm4, ymm5, ymm6, ymm7, ymm8, ymm9, ymm10, ymm11, ymm12, ymm13,
        ];
        match r {
            T0 => ymm15,
            T1 => ymm14,
            r => YMM[r],
        }
    }

    /// A vector of memory at `m`.
    fn wide(
        &self,
        m: iced_x86::code_asm::AsmMemoryOperand,
    ) -> iced_x86::code_asm::AsmMemoryOperand {
        match self.isa {
            Isa::Avx512 => iced_x86::code_asm::zmmword_ptr(m),
            Isa::Avx2 => iced_x86::code_asm::ymmword_ptr(m),
        }
    }

    /// Constant `i` as an operand: broadcast from its one double (AVX-512),
    /// or its four copies (AVX2).
    fn constant(&self, i: usize) -> iced_x86::code_asm::AsmMemoryOperand {
        use iced_x86::code_asm::*;
        match self.isa {
            Isa::Avx512 => qword_bcst(rsi + (i * 8) as i32),
            Isa::Avx2 => ymmword_ptr(rsi + (i * 32) as i32),
        }
    }

    /// `d + x * constant i`, rounded once: for a product that is exact
    /// (`x * 0`: a zero or NaN), the same bits as the product then the sum.
    fn add_product(&mut self, d: usize, x: usize, i: usize) -> Result<(), iced_x86::IcedError> {
        let m = self.constant(i);
        match self.isa {
            Isa::Avx512 => self.a.vfmadd231pd(Self::zmm(d), Self::zmm(x), m),
            Isa::Avx2 => self.a.vfmadd231pd(Self::ymm(d), Self::ymm(x), m),
        }
    }

    fn load(
        &mut self,
        r: usize,
        m: iced_x86::code_asm::AsmMemoryOperand,
    ) -> Result<(), iced_x86::IcedError> {
        let m = self.wide(m);
        match self.isa {
            Isa::Avx512 => self.a.vmovupd(Self::zmm(r), m),
            Isa::Avx2 => self.a.vmovupd(Self::ymm(r), m),
        }
    }

    fn store(
        &mut self,
        m: iced_x86::code_asm::AsmMemoryOperand,
        r: usize,
    ) -> Result<(), iced_x86::IcedError> {
        let m = self.wide(m);
        match self.isa {
            Isa::Avx512 => self.a.vmovupd(m, Self::zmm(r)),
            Isa::Avx2 => self.a.vmovupd(m, Self::ymm(r)),
        }
    }

    fn copy(&mut self, d: usize, x: usize) -> Result<(), iced_x86::IcedError> {
        match self.isa {
            Isa::Avx512 => self.a.vmovapd(Self::zmm(d), Self::zmm(x)),
            Isa::Avx2 => self.a.vmovapd(Self::ymm(d), Self::ymm(x)),
        }
    }

    /// Constant `i` in every lane of `d`.
    fn splat(&mut self, d: usize, i: usize) -> Result<(), iced_x86::IcedError> {
        use iced_x86::code_asm::*;
        match self.isa {
            Isa::Avx512 => self
                .a
                .vbroadcastsd(Self::zmm(d), qword_ptr(rsi + (i * 8) as i32)),
            Isa::Avx2 => self.a.vmovupd(Self::ymm(d), self.constant(i)),
        }
    }

    fn bin(&mut self, op: Bin, d: usize, x: usize, y: Src) -> Result<(), iced_x86::IcedError> {
        macro_rules! emit {
            ($a:expr, $d:expr, $x:expr, $y:expr) => {
                match op {
                    Bin::Add => $a.vaddpd($d, $x, $y),
                    Bin::Sub => $a.vsubpd($d, $x, $y),
                    Bin::Mul => $a.vmulpd($d, $x, $y),
                    Bin::Div => $a.vdivpd($d, $x, $y),
                    Bin::And => $a.vandpd($d, $x, $y),
                    Bin::Xor => $a.vxorpd($d, $x, $y),
                    Bin::Max => $a.vmaxpd($d, $x, $y),
                }
            };
        }
        match (self.isa, y) {
            (Isa::Avx512, Src::R(y)) => emit!(self.a, Self::zmm(d), Self::zmm(x), Self::zmm(y)),
            (Isa::Avx2, Src::R(y)) => emit!(self.a, Self::ymm(d), Self::ymm(x), Self::ymm(y)),
            (Isa::Avx512, Src::C(i)) => {
                let m = self.constant(i);
                emit!(self.a, Self::zmm(d), Self::zmm(x), m)
            }
            (Isa::Avx2, Src::C(i)) => {
                let m = self.constant(i);
                emit!(self.a, Self::ymm(d), Self::ymm(x), m)
            }
        }
    }

    /// Clears every row of check `m` where `x pred y` is false (`pred` an
    /// `_CMP_` predicate): in `k1..k4` (AVX-512), or, as a failure, in the
    /// mask's word (AVX2, which inverts the words at the end). With AVX2 the
    /// compare's result takes [`T0`]: an operand there is read no more.
    fn check(&mut self, m: usize, x: usize, y: Src, pred: i32) -> Result<(), iced_x86::IcedError> {
        use iced_x86::code_asm::*;
        match self.isa {
            Isa::Avx512 => {
                let k = match m {
                    0 => k1.k1(),
                    1 => k2.k2(),
                    2 => k3.k3(),
                    _ => k4.k4(),
                };
                match y {
                    Src::R(y) => self.a.vcmppd(k, Self::zmm(x), Self::zmm(y), pred),
                    Src::C(i) => {
                        let c = self.constant(i);
                        self.a.vcmppd(k, Self::zmm(x), c, pred)
                    }
                }
            }
            Isa::Avx2 => {
                match y {
                    Src::R(y) => self
                        .a
                        .vcmppd(Self::ymm(T0), Self::ymm(x), Self::ymm(y), pred)?,
                    Src::C(i) => {
                        let c = self.constant(i);
                        self.a.vcmppd(Self::ymm(T0), Self::ymm(x), c, pred)?
                    }
                }
                self.a.vmovmskpd(eax, Self::ymm(T0))?;
                self.a.xor(eax, 0xf)?;
                self.gather(m)
            }
        }
    }

    /// Sets the rows of mask `MOVING` where `x != 0` (`_CMP_NEQ_UQ`: true
    /// for NaN); constant `zero` is 0. With AVX2 the compare's result takes
    /// [`T0`], as in [`Vector::check`].
    fn mark(&mut self, x: usize, zero: usize) -> Result<(), iced_x86::IcedError> {
        use iced_x86::code_asm::*;
        let c = self.constant(zero);
        match self.isa {
            Isa::Avx512 => {
                self.a.vcmppd(k6, Self::zmm(x), c, 0x04)?;
                self.a.korb(k5, k5, k6)
            }
            Isa::Avx2 => {
                self.a.vcmppd(Self::ymm(T0), Self::ymm(x), c, 0x04)?;
                self.a.vmovmskpd(eax, Self::ymm(T0))?;
                self.gather(MOVING)
            }
        }
    }

    /// AVX2: ORs the pass's four bits in `eax` into mask `m`'s word, at the
    /// pass's rows (`r10` = the pass's first row).
    fn gather(&mut self, m: usize) -> Result<(), iced_x86::IcedError> {
        use iced_x86::code_asm::*;
        self.a.shlx(rax, rax, r10)?;
        self.a.or(qword_ptr(rdx + (m * MASK_BYTES) as i32), rax)
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) fn assemble(
    isa: Isa,
    ops: &[Op],
    slots: usize,
    cols: Columns,
    outputs: &[u32],
) -> Result<(Vec<u8>, Vec<f64>), iced_x86::IcedError> {
    use iced_x86::code_asm::*;
    const NONE: usize = usize::MAX;
    const LIMIT: usize = 30;
    // The next read of each operand, and of each result, after its operation.
    let mut after_operand: Vec<[usize; 3]> = vec![[NONE; 3]; ops.len()];
    let mut after_dest = vec![NONE; ops.len()];
    let mut next = vec![NONE; slots];
    // The last operation writing each slot: an output's (its slot may hold
    // other values before it, never after).
    let mut last_def = vec![NONE; slots];
    for (i, op) in ops.iter().enumerate().rev() {
        if let Some(d) = op.dest() {
            after_dest[i] = next[d as usize];
            next[d as usize] = NONE;
            if last_def[d as usize] == NONE {
                last_def[d as usize] = i;
            }
        }
        let (reads, k) = operands(op);
        for (j, &a) in reads[..k].iter().enumerate() {
            after_operand[i][j] = next[a as usize];
        }
        for &a in &reads[..k] {
            next[a as usize] = i;
        }
    }

    let mut constants: Vec<f64> = Vec::new();
    let mut constant = |c: f64| -> usize {
        match constants.iter().position(|x| x.to_bits() == c.to_bits()) {
            Some(i) => i,
            None => {
                constants.push(c);
                constants.len() - 1
            }
        }
    };
    let sign = constant(-0.0);
    let magnitude = constant(f64::from_bits(!(1u64 << 63)));
    let one = constant(1.0);
    let zero = constant(0.0);
    let two = constant(2.0);
    let end = cols.end;
    let lanes = isa.lanes();
    let allocatable = isa.allocatable();
    // The slot's memory this pass: its parameter column (through the
    // table, into rax), or its place among the block's slots.
    let home = |v: &mut Vector, s: u32| -> Result<AsmMemoryOperand, IcedError> {
        if (s as usize) < end {
            v.a.mov(rax, qword_ptr(rcx + (s as i32) * 8))?;
            Ok(rax + r9)
        } else {
            Ok(rdi + r9 + (s as usize * BLOCK * 8) as i32)
        }
    };

    let mut v = Vector {
        a: CodeAssembler::new(64)?,
        isa,
    };
    let mut top = v.a.create_label();
    v.a.mov(r8d, (BLOCK / lanes) as u32)?;
    v.a.xor(r9d, r9d)?;
    if isa == Isa::Avx2 {
        // The masks' words gather failures (inverted at the end), and r10 is
        // the pass's first row.
        for m in 0..MASKS {
            v.a.mov(qword_ptr(rdx + (m * MASK_BYTES) as i32), 0)?;
        }
        v.a.xor(r10d, r10d)?;
    }
    v.a.set_label(&mut top)?;
    if isa == Isa::Avx512 {
        for k in [k1, k2, k3, k4] {
            v.a.kxnorb(k, k, k)?;
        }
        v.a.kxorb(k5, k5, k5)?;
    }
    let mut regs: [Option<Held>; LIMIT] = [None; LIMIT];
    let mut where_: Vec<Option<usize>> = vec![None; slots];

    // A free register, spilling the value read furthest ahead if none is
    // (never one of `keep`).
    let take = |v: &mut Vector,
                regs: &mut [Option<Held>; LIMIT],
                where_: &mut Vec<Option<usize>>,
                keep: &[usize]|
     -> Result<usize, IcedError> {
        if let Some(r) = regs[..allocatable].iter().position(Option::is_none) {
            return Ok(r);
        }
        let r = (0..allocatable)
            .filter(|r| !keep.contains(r))
            .max_by_key(|&r| regs[r].map_or(NONE, |h| h.next))
            .unwrap_or_else(|| unreachable!("more registers than operands"));
        if let Some(h) = regs[r].take() {
            if h.dirty && h.next != NONE {
                let m = home(v, h.slot)?;
                v.store(m, r)?;
            }
            where_[h.slot as usize] = None;
        }
        Ok(r)
    };

    // The parameter rules (`Program::check_params`), and the moving rows.
    // Each parameter stays in a register for the operations that read it
    // (as any value, until it is spilled: a parameter is only reloaded).
    for s in 0..end {
        let x = match next[s] {
            NONE => T0,
            first => {
                let r = take(&mut v, &mut regs, &mut where_, &[])?;
                regs[r] = Some(Held {
                    slot: s as u32,
                    next: first,
                    dirty: false,
                });
                where_[s] = Some(r);
                r
            }
        };
        let m = home(&mut v, s as u32)?;
        v.load(x, m)?;
        // Their sum, in column order, in T1 (see `Program::check_params`).
        if s == 0 {
            v.copy(T1, x)?;
        } else {
            v.bin(Bin::Add, T1, T1, Src::R(x))?;
        }
        if s < cols.speed {
            // A ratio is not 0 (_CMP_NEQ_UQ, as `!=`).
            v.check(GOOD, x, Src::C(zero), 0x04)?;
        } else if s >= cols.inertia {
            // _CMP_GE_OQ.
            v.check(GOOD, x, Src::C(zero), 0x1d)?;
        }
        if (cols.accel..cols.torque).contains(&s) {
            v.mark(x, zero)?;
        }
    }
    if end > 0 {
        // Finite: x - x is 0 (_CMP_EQ_OQ with itself), NaN when not.
        v.bin(Bin::Sub, T0, T1, Src::R(T1))?;
        v.check(GOOD, T0, Src::R(T0), 0x00)?;
    }

    for (i, op) in ops.iter().enumerate() {
        // The operands in registers, loaded from their homes if not.
        let (reads, k) = operands(op);
        let mut r = [0usize; 3];
        for j in 0..k {
            let s = reads[j] as usize;
            r[j] = match where_[s] {
                Some(x) => x,
                None => {
                    let x = take(&mut v, &mut regs, &mut where_, &r[..j])?;
                    let m = home(&mut v, s as u32)?;
                    v.load(x, m)?;
                    regs[x] = Some(Held {
                        slot: s as u32,
                        next: NONE,
                        dirty: false,
                    });
                    where_[s] = Some(x);
                    x
                }
            };
        }
        // Their next reads; those read no more free their registers (the
        // result may take one: each sequence reads its operands before it
        // writes the result).
        for j in 0..k {
            if let Some(h) = regs[r[j]].as_mut() {
                h.next = after_operand[i][j];
            }
        }
        for j in 0..k {
            if let Some(h) = regs[r[j]].filter(|h| h.next == NONE) {
                regs[r[j]] = None;
                where_[h.slot as usize] = None;
            }
        }
        let d = match op.dest() {
            Some(s) => {
                // The slot's former value is read no more (a slot is reused
                // only after its last read).
                if let Some(x) = where_[s as usize].take() {
                    regs[x] = None;
                }
                let live: Vec<usize> = r[..k]
                    .iter()
                    .copied()
                    .filter(|&x| regs[x].is_some())
                    .collect();
                take(&mut v, &mut regs, &mut where_, &live)?
            }
            None => 0,
        };
        match *op {
            Op::Neg(..) => v.bin(Bin::Xor, d, r[0], Src::C(sign))?,
            Op::Abs(..) => v.bin(Bin::And, d, r[0], Src::C(magnitude))?,
            Op::AddC(_, _, c) => v.bin(Bin::Add, d, r[0], Src::C(constant(c)))?,
            Op::MulC(_, _, c) => v.bin(Bin::Mul, d, r[0], Src::C(constant(c)))?,
            Op::DivC(_, _, c) => v.bin(Bin::Div, d, r[0], Src::C(constant(c)))?,
            Op::Add(..) => v.bin(Bin::Add, d, r[0], Src::R(r[1]))?,
            Op::Sub(..) => v.bin(Bin::Sub, d, r[0], Src::R(r[1]))?,
            Op::Mul(..) => v.bin(Bin::Mul, d, r[0], Src::R(r[1]))?,
            Op::SubMul(..) => {
                v.bin(Bin::Mul, T0, r[1], Src::R(r[2]))?;
                v.bin(Bin::Sub, d, r[0], Src::R(T0))?;
            }
            Op::AddMul(..) => {
                v.bin(Bin::Mul, T0, r[1], Src::R(r[2]))?;
                v.bin(Bin::Add, d, r[0], Src::R(T0))?;
            }
            Op::Recip(..) => {
                v.splat(T0, one)?;
                v.bin(Bin::Div, d, T0, Src::R(r[0]))?;
            }
            Op::Const(_, c) => v.splat(d, constant(c))?,
            Op::Max(..) => {
                // (a > b ? a : b) + 0 (a - b), as the interpreter; 0 (a - b)
                // is exact, so a fused multiply-add gives the same bits with
                // one instruction less (the max of 12 at 6 links).
                v.bin(Bin::Sub, T0, r[0], Src::R(r[1]))?;
                v.bin(Bin::Max, d, r[0], Src::R(r[1]))?;
                v.add_product(d, T0, zero)?;
            }
            Op::NoLarger(m, ..) => {
                v.bin(Bin::And, T0, r[0], Src::C(magnitude))?;
                v.bin(Bin::And, T1, r[1], Src::C(magnitude))?;
                v.bin(Bin::Mul, T1, T1, Src::C(two))?;
                // _CMP_LE_OQ: false when either is NaN, as `<=`.
                v.check(m as usize, T0, Src::R(T1), 0x12)?;
            }
            Op::AtMost(m, _, limit) => {
                v.check(m as usize, r[0], Src::C(constant(limit)), 0x12)?;
            }
            Op::Finite(m, _) => {
                v.bin(Bin::Sub, T0, r[0], Src::R(r[0]))?;
                v.check(m as usize, T0, Src::R(T0), 0x00)?;
            }
        }
        if let Some(s) = op.dest() {
            let output = |(_, o): &(usize, &u32)| **o == s && last_def[s as usize] == i;
            for (o, _) in outputs.iter().enumerate().filter(output) {
                v.a.mov(rax, qword_ptr(rcx + ((end + o) * 8) as i32))?;
                v.store(rax + r9, d)?;
            }
            if after_dest[i] != NONE {
                regs[d] = Some(Held {
                    slot: s,
                    next: after_dest[i],
                    dirty: true,
                });
                where_[s as usize] = Some(d);
            }
        }
    }
    // Outputs no operation computes (a parameter's slot): copied.
    for (o, &s) in outputs.iter().enumerate() {
        if last_def[s as usize] == NONE {
            let m = home(&mut v, s)?;
            v.load(T0, m)?;
            v.a.mov(rax, qword_ptr(rcx + ((end + o) * 8) as i32))?;
            v.store(rax + r9, T0)?;
        }
    }
    match isa {
        Isa::Avx512 => {
            for (m, k) in [k1, k2, k3, k4, k5].into_iter().enumerate() {
                v.a.kmovb(byte_ptr(rdx + (m * MASK_BYTES) as i32), k)?;
            }
            v.a.add(rdx, 1)?;
        }
        Isa::Avx2 => v.a.add(r10, lanes as i32)?,
    }
    v.a.add(r9, (lanes * 8) as i32)?;
    v.a.dec(r8d)?;
    v.a.jnz(top)?;
    if isa == Isa::Avx2 {
        // The checks' words held failures.
        for m in 0..MASKS {
            if m != MOVING {
                v.a.not(qword_ptr(rdx + (m * MASK_BYTES) as i32))?;
            }
        }
    }
    v.a.vzeroupper()?;
    v.a.ret()?;
    let bytes = v.a.assemble(0)?;
    let constants = match isa {
        Isa::Avx512 => constants,
        Isa::Avx2 => constants.iter().flat_map(|&c| [c; 4]).collect(),
    };
    Ok((bytes, constants))
}

/// An operation's operands, in order, and how many.
fn operands(op: &Op) -> ([u32; 3], usize) {
    let mut op = *op;
    let mut reads = [u32::MAX; 3];
    let mut k = 0;
    op.operands(|a| {
        reads[k] = *a;
        k += 1;
    });
    (reads, k)
}

#[cfg(not(target_arch = "x86_64"))]
pub(super) fn assemble(
    _: Isa,
    _: &[Op],
    _: usize,
    _: Columns,
    _: &[u32],
) -> Result<(Vec<u8>, Vec<f64>), ()> {
    Err(())
}
