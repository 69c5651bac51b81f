//! A [`Program`](super::tape::Program) compiled to AVX-512 machine code
//! for one train: its operations in order, eight rows to a register, with
//! the values kept in the 32 vector registers between operations instead of
//! being stored to and reloaded from the block's slots after each one.
//!
//! The interpreter (`Program::run_ops`) reads and writes a slot of
//! [`BLOCK`] rows for every operation, and picks each operation by an
//! indirect jump. Here each operation is one to four instructions on
//! registers; a value goes to its slot only when it is an output (written
//! once, where it is computed) or when the registers run out (the one read
//! furthest ahead is spilled, as Belady's rule). The code runs the block
//! as `BLOCK / 8` passes of one loop body. It reads the parameters from
//! their columns and writes the outputs into theirs through a table of
//! pointers, so a whole block of a column-major batch is not copied in and
//! out (a part block, or a row-major one, points it at the block's slots).
//! It also checks the parameters (the batch's rules) and marks the rows
//! that prescribe an acceleration, as `Program::check_params` does.
//!
//! Every operation is the interpreter's, in its order, with its rounding:
//! no fused multiply-add, divisions as divisions (`1 / a`, `a / c`),
//! negation and absolute value on the sign bit. So every result is the
//! interpreter's bit for bit, except the payload of a NaN, which only a row
//! the checks refuse holds (tested: `jit_and_interpreter_agree_bit_for_bit`).
//! The checks accumulate in the mask registers `k1` to `k5`, one bit a row,
//! and are written out as one byte a pass.
//!
//! Only x86-64 with AVX-512F and DQ (detected at run time) gets code; any
//! other machine, or a program past [`MAX_OPS`] operations, keeps the
//! interpreter. `EGT_JIT=0` in the environment turns the compilation off.
//!
//! This is the crate's one `unsafe`: making the code executable is done by
//! `memmap2`, and calling it is a call through a function pointer to bytes
//! this module assembled (with `iced-x86`) from a program whose every slot
//! index is below the block's slot count (checked before assembling).

use super::tape::{BLOCK, Columns, Op};
use std::sync::Arc;

/// Programs past this many operations stay interpreted (their code would
/// outgrow the instruction cache: about 20 bytes an operation).
pub(crate) const MAX_OPS: usize = 4_000;

/// Rows a register holds.
const LANES: usize = 8;
/// Passes of the loop body over a block.
pub(crate) const PASSES: usize = BLOCK / LANES;

/// Registers for values; zmm29 to zmm31 are the operations' scratch.
const ALLOCATABLE: usize = 29;

/// The masks a pass writes: the program's three checks, the parameter
/// rules, and the rows with an acceleration.
pub(crate) const MASKS: usize = 5;
/// The parameter rules' mask, and the moving rows'.
pub(crate) const GOOD: usize = 3;
pub(crate) const MOVING: usize = 4;

/// `fn(vals, constants, masks, io)`: the block's slots (slot `s` at `vals +
/// s * BLOCK`), the constants the code reads, the masks (byte `m * PASSES +
/// p`: the rows of pass `p` in mask `m`), and the table of the parameter
/// columns' then the output columns' first elements, each `BLOCK` long.
type Entry = unsafe extern "sysv64" fn(*mut f64, *const f64, *mut u8, *const usize);

/// A program's machine code, shared by the clones of its program.
#[derive(Clone)]
pub(crate) struct Code {
    inner: Arc<Inner>,
}

struct Inner {
    map: memmap2::Mmap,
    constants: Vec<f64>,
    /// The slot count the code was assembled for.
    slots: usize,
    /// The parameter columns it reads (`Columns::end`).
    end: usize,
    /// The output columns' slots.
    outputs: Vec<u32>,
}

impl std::fmt::Debug for Code {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Code({} bytes)", self.inner.map.len())
    }
}

/// Whether this machine runs the code, and whether it is wanted.
fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        static OK: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *OK.get_or_init(|| {
            std::env::var("EGT_JIT").map_or(true, |v| v != "0")
                && std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512dq")
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

impl Code {
    /// Code for `ops` over `slots` slots, or none (not available here, too
    /// long, or a slot out of range).
    pub(crate) fn compile(
        ops: &[Op],
        slots: usize,
        cols: Columns,
        outputs: &[u32],
    ) -> Option<Code> {
        if !available() || ops.len() > MAX_OPS || cols.end > slots {
            return None;
        }
        let mut in_range = outputs.iter().all(|&s| (s as usize) < slots);
        for op in ops {
            let mut op = *op;
            op.operands(|a| in_range &= (*a as usize) < slots);
            in_range &= op.dest().is_none_or(|d| (d as usize) < slots);
        }
        // A slot's offset must fit an i32 displacement.
        if !in_range || slots.checked_mul(BLOCK * 8)? > i32::MAX as usize / 2 {
            return None;
        }
        let (bytes, constants) = assemble(ops, slots, cols, outputs).ok()?;
        let mut map = memmap2::MmapMut::map_anon(bytes.len()).ok()?;
        map.copy_from_slice(&bytes);
        let map = map.make_exec().ok()?;
        Some(Code {
            inner: Arc::new(Inner {
                map,
                constants,
                slots,
                end: cols.end,
                outputs: outputs.to_vec(),
            }),
        })
    }

    /// Run the code over one block: `vals` the block's slots, `masks` the
    /// masks' bytes (see [`Entry`]), `io` a buffer for the pointer table.
    /// With `columns` ([`InPlace`]), the parameters are read from
    /// `column(k)[at..at + BLOCK]` and the outputs written to
    /// `out[o][at..at + BLOCK]`; without, both are the block's slots (the
    /// parameters loaded there, the outputs read from there).
    pub(crate) fn run<'c>(
        &self,
        vals: &mut [[f64; BLOCK]],
        masks: &mut [u8; MASKS * PASSES],
        io: &mut Vec<usize>,
        columns: Option<InPlace<'_, '_, 'c>>,
    ) {
        let inner = &*self.inner;
        assert!(vals.len() >= inner.slots, "a block's slots for its program");
        let base = vals.as_mut_ptr();
        io.clear();
        match columns {
            None => {
                // Slot `s` starts at `base + s` (a slot is one `[f64; BLOCK]`).
                io.extend((0..inner.end).map(|k| base.wrapping_add(k) as usize));
                io.extend((inner.outputs.iter()).map(|&s| base.wrapping_add(s as usize) as usize));
            }
            Some(InPlace { column, out, at }) => {
                for k in 0..inner.end {
                    let c = &column(k)[at..];
                    assert!(c.len() >= BLOCK, "a whole block of parameter column {k}");
                    io.push(c.as_ptr() as usize);
                }
                assert_eq!(out.len(), inner.outputs.len(), "an output column each");
                for c in out.iter_mut() {
                    let c = &mut c[at..];
                    assert!(c.len() >= BLOCK, "a whole block of each output column");
                    io.push(c.as_mut_ptr() as usize);
                }
            }
        }
        #[allow(unsafe_code)]
        // SAFETY: the map holds code assembled by `assemble` for the
        // System V ABI, touching only caller-saved registers. It reads and
        // writes slots below `inner.slots` (checked in `compile`), each
        // `BLOCK` f64 long, within `vals` (asserted above); it reads
        // `constants` at the indices it was assembled with (this vector,
        // kept with it); it writes `MASKS * PASSES` bytes of `masks`; it
        // reads the `end + outputs` entries of `io` (built above) and,
        // through each, `BLOCK` f64: slots within `vals`, or columns
        // asserted above to hold a whole block from `at`. The parameters
        // are only read and the outputs only written. It holds no pointer
        // past its return. AVX-512F and DQ were detected.
        unsafe {
            let entry: Entry = std::mem::transmute::<*const u8, Entry>(inner.map.as_ptr());
            entry(
                base.cast::<f64>(),
                inner.constants.as_ptr(),
                masks.as_mut_ptr(),
                io.as_ptr(),
            );
        }
    }
}

/// A whole block of a column-major batch, read and written in place: rows
/// `at..at + BLOCK` of `column(k)` (parameter column `k`) and of `out[o]`
/// (output column `o`).
pub(crate) struct InPlace<'a, 'b, 'c> {
    pub column: &'a dyn Fn(usize) -> &'c [f64],
    pub out: &'a mut [&'b mut [f64]],
    pub at: usize,
}

/// Where a value is: its register, if any.
#[derive(Clone, Copy)]
struct Held {
    slot: u32,
    /// The operation index of its next read (`usize::MAX`: none).
    next: usize,
    /// Computed here and not yet in its slot.
    dirty: bool,
}

#[cfg(target_arch = "x86_64")]
fn assemble(
    ops: &[Op],
    slots: usize,
    cols: Columns,
    outputs: &[u32],
) -> Result<(Vec<u8>, Vec<f64>), iced_x86::IcedError> {
    use iced_x86::code_asm::*;
    const NONE: usize = usize::MAX;
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

    let zmm = [
        zmm0, zmm1, zmm2, zmm3, zmm4, zmm5, zmm6, zmm7, zmm8, zmm9, zmm10, zmm11, zmm12, zmm13,
        zmm14, zmm15, zmm16, zmm17, zmm18, zmm19, zmm20, zmm21, zmm22, zmm23, zmm24, zmm25, zmm26,
        zmm27, zmm28,
    ];
    let (t0, t1) = (zmm30, zmm31);
    // Check `m`'s mask, as the destination of a compare and its write mask.
    let accumulate = |m: usize| match m {
        0 => k1.k1(),
        1 => k2.k2(),
        2 => k3.k3(),
        _ => k4.k4(),
    };
    let mut constants: Vec<f64> = Vec::new();
    let mut constant = |c: f64| -> i32 {
        let i = match constants.iter().position(|x| x.to_bits() == c.to_bits()) {
            Some(i) => i,
            None => {
                constants.push(c);
                constants.len() - 1
            }
        };
        (i * 8) as i32
    };
    let sign = constant(-0.0);
    let magnitude = constant(f64::from_bits(!(1u64 << 63)));
    let one = constant(1.0);
    let zero = constant(0.0);
    let two = constant(2.0);
    let end = cols.end;
    // The slot's memory this pass: its parameter column (through the
    // table, into rax), or its place among the block's slots.
    let home = |a: &mut CodeAssembler, s: u32| -> Result<AsmMemoryOperand, IcedError> {
        if (s as usize) < end {
            a.mov(rax, qword_ptr(rcx + (s as i32) * 8))?;
            Ok(zmmword_ptr(rax + r9))
        } else {
            Ok(zmmword_ptr(rdi + r9 + (s as usize * BLOCK * 8) as i32))
        }
    };

    let mut a = CodeAssembler::new(64)?;
    let mut top = a.create_label();
    a.mov(r8d, PASSES as u32)?;
    a.xor(r9d, r9d)?;
    a.set_label(&mut top)?;
    for k in [k1, k2, k3, k4] {
        a.kxnorb(k, k, k)?;
    }
    a.kxorb(k5, k5, k5)?;
    let mut regs: [Option<Held>; ALLOCATABLE] = [None; ALLOCATABLE];
    let mut where_: Vec<Option<usize>> = vec![None; slots];

    // A free register, spilling the value read furthest ahead if none is
    // (never one of `keep`).
    let take = |a: &mut CodeAssembler,
                regs: &mut [Option<Held>; ALLOCATABLE],
                where_: &mut Vec<Option<usize>>,
                keep: &[usize]|
     -> Result<usize, IcedError> {
        if let Some(r) = regs.iter().position(Option::is_none) {
            return Ok(r);
        }
        let r = (0..ALLOCATABLE)
            .filter(|r| !keep.contains(r))
            .max_by_key(|&r| regs[r].map_or(NONE, |h| h.next))
            .unwrap_or_else(|| unreachable!("more registers than operands"));
        if let Some(h) = regs[r].take() {
            if h.dirty && h.next != NONE {
                let m = home(a, h.slot)?;
                a.vmovupd(m, zmm[r])?;
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
            NONE => t0,
            first => {
                let r = take(&mut a, &mut regs, &mut where_, &[])?;
                regs[r] = Some(Held {
                    slot: s as u32,
                    next: first,
                    dirty: false,
                });
                where_[s] = Some(r);
                zmm[r]
            }
        };
        let m = home(&mut a, s as u32)?;
        a.vmovupd(x, m)?;
        // Their sum, in column order, in t1 (see `Program::check_params`).
        if s == 0 {
            a.vmovapd(t1, x)?;
        } else {
            a.vaddpd(t1, t1, x)?;
        }
        if s < cols.speed {
            // A ratio is not 0 (_CMP_NEQ_UQ, as `!=`).
            a.vcmppd(accumulate(GOOD), x, qword_bcst(rsi + zero), 0x04)?;
        } else if s >= cols.inertia {
            // _CMP_GE_OQ.
            a.vcmppd(accumulate(GOOD), x, qword_bcst(rsi + zero), 0x1d)?;
        }
        if (cols.accel..cols.torque).contains(&s) {
            // `x != 0` (_CMP_NEQ_UQ: true for NaN).
            a.vcmppd(k6, x, qword_bcst(rsi + zero), 0x04)?;
            a.korb(k5, k5, k6)?;
        }
    }
    if end > 0 {
        // Finite: x - x is 0 (_CMP_EQ_OQ with itself), NaN when not.
        a.vsubpd(t0, t1, t1)?;
        a.vcmppd(accumulate(GOOD), t0, t0, 0x00)?;
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
                    let x = take(&mut a, &mut regs, &mut where_, &r[..j])?;
                    let m = home(&mut a, s as u32)?;
                    a.vmovupd(zmm[x], m)?;
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
                take(&mut a, &mut regs, &mut where_, &live)?
            }
            None => 0,
        };
        let z = |j: usize| zmm[r[j]];
        let out = zmm[d];
        let bc = |off: i32| qword_bcst(rsi + off);
        match *op {
            Op::Neg(..) => a.vxorpd(out, z(0), bc(sign))?,
            Op::Abs(..) => a.vandpd(out, z(0), bc(magnitude))?,
            Op::AddC(_, _, c) => a.vaddpd(out, z(0), bc(constant(c)))?,
            Op::MulC(_, _, c) => a.vmulpd(out, z(0), bc(constant(c)))?,
            Op::DivC(_, _, c) => a.vdivpd(out, z(0), bc(constant(c)))?,
            Op::Add(..) => a.vaddpd(out, z(0), z(1))?,
            Op::Sub(..) => a.vsubpd(out, z(0), z(1))?,
            Op::Mul(..) => a.vmulpd(out, z(0), z(1))?,
            Op::SubMul(..) => {
                a.vmulpd(t0, z(1), z(2))?;
                a.vsubpd(out, z(0), t0)?;
            }
            Op::AddMul(..) => {
                a.vmulpd(t0, z(1), z(2))?;
                a.vaddpd(out, z(0), t0)?;
            }
            Op::Recip(..) => {
                a.vbroadcastsd(t0, qword_ptr(rsi + one))?;
                a.vdivpd(out, t0, z(0))?;
            }
            Op::Const(_, c) => a.vbroadcastsd(out, qword_ptr(rsi + constant(c)))?,
            Op::Max(..) => {
                // (a > b ? a : b) + 0 (a - b), as the interpreter.
                a.vsubpd(t0, z(0), z(1))?;
                a.vmulpd(t0, t0, bc(zero))?;
                a.vmaxpd(out, z(0), z(1))?;
                a.vaddpd(out, out, t0)?;
            }
            Op::NoLarger(m, ..) => {
                a.vandpd(t0, z(0), bc(magnitude))?;
                a.vandpd(t1, z(1), bc(magnitude))?;
                a.vmulpd(t1, t1, bc(two))?;
                // _CMP_LE_OQ: false when either is NaN, as `<=`.
                a.vcmppd(accumulate(m as usize), t0, t1, 0x12)?;
            }
            Op::AtMost(m, _, limit) => {
                a.vcmppd(accumulate(m as usize), z(0), bc(constant(limit)), 0x12)?;
            }
            Op::Finite(m, _) => {
                a.vsubpd(t0, z(0), z(0))?;
                a.vcmppd(accumulate(m as usize), t0, t0, 0x00)?;
            }
        }
        if let Some(s) = op.dest() {
            let output = |(_, v): &(usize, &u32)| **v == s && last_def[s as usize] == i;
            for (o, _) in outputs.iter().enumerate().filter(output) {
                a.mov(rax, qword_ptr(rcx + ((end + o) * 8) as i32))?;
                a.vmovupd(zmmword_ptr(rax + r9), out)?;
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
            let m = home(&mut a, s)?;
            a.vmovupd(t0, m)?;
            a.mov(rax, qword_ptr(rcx + ((end + o) * 8) as i32))?;
            a.vmovupd(zmmword_ptr(rax + r9), t0)?;
        }
    }
    for (m, k) in [k1, k2, k3, k4, k5].into_iter().enumerate() {
        a.kmovb(byte_ptr(rdx + (m * PASSES) as i32), k)?;
    }
    a.add(r9, (LANES * 8) as i32)?;
    a.add(rdx, 1)?;
    a.dec(r8d)?;
    a.jnz(top)?;
    a.vzeroupper()?;
    a.ret()?;
    let bytes = a.assemble(0)?;
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
fn assemble(_: &[Op], _: usize, _: Columns, _: &[u32]) -> Result<(Vec<u8>, Vec<f64>), ()> {
    Err(())
}
