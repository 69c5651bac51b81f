//! A [`Program`](super::tape::Program) compiled to x86-64 vector machine
//! code for one train: its operations in order, eight rows to a register
//! (AVX-512) or four (AVX2), with the values kept in the vector registers
//! between operations instead of being stored to and reloaded from the
//! block's slots after each one.
//!
//! The interpreter (`Program::run_ops`) reads and writes a slot of
//! [`BLOCK`] rows for every operation, and picks each operation by an
//! indirect jump. Here each operation is one to four instructions on
//! registers; a value goes to its slot only when it is an output (written
//! once, where it is computed) or when the registers run out (the one read
//! furthest ahead is spilled, as Belady's rule). The code runs the block
//! as `BLOCK / lanes` passes of one loop body. It reads the parameters from
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
//! the checks refuse holds (tested for both instruction sets:
//! `compiled_and_interpreted_programs_agree_bit_for_bit`). With AVX-512
//! the checks accumulate in the mask registers `k1` to `k5`, one bit a row,
//! written out as one byte a pass; with AVX2 each check's four bits are
//! moved to a general register (`vmovmskpd`) and gathered, as failures, in
//! the masks' words in memory.
//!
//! x86-64 with AVX-512F and DQ gets AVX-512 code; with AVX2, BMI2 and FMA but
//! not AVX-512, AVX2 code (both detected at run time). Any other machine,
//! or a program past [`MAX_OPS`] operations, keeps the interpreter.
//! `EGT_JIT=0` in the environment turns the compilation off; `EGT_JIT=avx2`
//! asks for AVX2 code where AVX-512 would be used.
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

/// Bytes a mask takes: one bit a row of the block (mask `m`'s row `r` is
/// bit `r % 8` of byte `m * MASK_BYTES + r / 8`).
pub(crate) const MASK_BYTES: usize = BLOCK / 8;

/// The vector instructions code is assembled with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Isa {
    /// AVX-512F and DQ: 8 rows a zmm register, 30 registers for values.
    Avx512,
    /// AVX2, BMI2 and FMA: 4 rows a ymm register, 14 registers for values.
    Avx2,
}

impl Isa {
    /// Rows a register holds.
    fn lanes(self) -> usize {
        match self {
            Isa::Avx512 => 8,
            Isa::Avx2 => 4,
        }
    }

    /// Registers for values (the rest are the operations' scratch).
    fn allocatable(self) -> usize {
        match self {
            Isa::Avx512 => 30,
            Isa::Avx2 => 14,
        }
    }

    /// Whether this machine runs the code.
    pub(crate) fn detected(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            match self {
                Isa::Avx512 => {
                    std::arch::is_x86_feature_detected!("avx512f")
                        && std::arch::is_x86_feature_detected!("avx512dq")
                }
                Isa::Avx2 => {
                    std::arch::is_x86_feature_detected!("avx2")
                        && std::arch::is_x86_feature_detected!("bmi2")
                        && std::arch::is_x86_feature_detected!("fma")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }
}

/// The masks a pass writes: the program's three checks, the parameter
/// rules, and the rows with an acceleration.
pub(crate) const MASKS: usize = 5;
/// The parameter rules' mask, and the moving rows'.
pub(crate) const GOOD: usize = 3;
pub(crate) const MOVING: usize = 4;

/// `fn(vals, constants, masks, io)`: the block's slots (slot `s` at `vals +
/// s * BLOCK`), the constants the code reads, the masks (`MASK_BYTES` a
/// mask, see [`MASK_BYTES`]), and the table of the parameter
/// columns' then the output columns' first elements, each `BLOCK` long.
type Entry = unsafe extern "sysv64" fn(*mut f64, *const f64, *mut u8, *const usize);

/// A program's machine code, shared by the clones of its program.
#[derive(Clone)]
pub(crate) struct Code {
    inner: Arc<Inner>,
}

struct Inner {
    map: memmap2::Mmap,
    isa: Isa,
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
        write!(
            f,
            "Code({:?}, {} bytes)",
            self.inner.isa,
            self.inner.map.len()
        )
    }
}

/// The instructions this machine's code is assembled with, if any: AVX-512
/// where it runs, else AVX2; `EGT_JIT=0` none, `EGT_JIT=avx2` AVX2.
pub(crate) fn chosen() -> Option<Isa> {
    static ISA: std::sync::OnceLock<Option<Isa>> = std::sync::OnceLock::new();
    *ISA.get_or_init(|| {
        let wanted = std::env::var("EGT_JIT").unwrap_or_default();
        let order: &[Isa] = match wanted.as_str() {
            "0" => &[],
            "avx2" => &[Isa::Avx2],
            _ => &[Isa::Avx512, Isa::Avx2],
        };
        order.iter().copied().find(|isa| isa.detected())
    })
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
        Code::compile_for(chosen()?, ops, slots, cols, outputs)
    }

    /// The instructions the code uses.
    #[cfg(test)]
    pub(crate) fn isa(&self) -> Isa {
        self.inner.isa
    }

    /// [`Code::compile`] with `isa`, if this machine runs it.
    pub(crate) fn compile_for(
        isa: Isa,
        ops: &[Op],
        slots: usize,
        cols: Columns,
        outputs: &[u32],
    ) -> Option<Code> {
        if !isa.detected() || ops.len() > MAX_OPS || cols.end > slots {
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
        let (bytes, constants) = assemble(isa, ops, slots, cols, outputs).ok()?;
        let mut map = memmap2::MmapMut::map_anon(bytes.len()).ok()?;
        map.copy_from_slice(&bytes);
        let map = map.make_exec().ok()?;
        Some(Code {
            inner: Arc::new(Inner {
                map,
                isa,
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
    /// `out[o][at..at + BLOCK]` (to their slots when `out` is None);
    /// without, both are the block's slots (the parameters loaded there,
    /// the outputs read from there).
    pub(crate) fn run<'c>(
        &self,
        vals: &mut [[f64; BLOCK]],
        masks: &mut [u8; MASKS * MASK_BYTES],
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
                match out {
                    Some(out) => {
                        assert_eq!(out.len(), inner.outputs.len(), "an output column each");
                        for c in out.iter_mut() {
                            let c = &mut c[at..];
                            assert!(c.len() >= BLOCK, "a whole block of each output column");
                            io.push(c.as_mut_ptr() as usize);
                        }
                    }
                    // Into their slots.
                    None => io.extend(
                        (inner.outputs.iter()).map(|&s| base.wrapping_add(s as usize) as usize),
                    ),
                }
            }
        }
        #[allow(unsafe_code)]
        // SAFETY: the map holds code assembled by `assemble` for the
        // System V ABI, touching only caller-saved registers. It reads and
        // writes slots below `inner.slots` (checked in `compile`), each
        // `BLOCK` f64 long, within `vals` (asserted above); it reads
        // `constants` at the indices it was assembled with (this vector,
        // kept with it); it writes `MASKS * MASK_BYTES` bytes of `masks`; it
        // reads the `end + outputs` entries of `io` (built above) and,
        // through each, `BLOCK` f64: slots within `vals`, or columns
        // asserted above to hold a whole block from `at`. The parameters
        // are only read and the outputs only written. It holds no pointer
        // past its return. Its instruction set was detected (`compile_for`).
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
/// (output column `o`; None: the outputs go to their slots).
pub(crate) struct InPlace<'a, 'b, 'c> {
    pub column: &'a dyn Fn(usize) -> &'c [f64],
    pub out: Option<&'a mut [&'b mut [f64]]>,
    pub at: usize,
}

mod assemble;
use assemble::assemble;
