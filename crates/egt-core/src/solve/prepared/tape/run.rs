//! Running the program (interpreted) over blocks of [`BLOCK`] rows: the
//! parameter rules, the operations, each row's validity, and the results
//! written out.

use super::*;

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
            let in_place = super::super::jit::InPlace {
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
        // adds them): a row whose sum overflows is left to the row-by-row solve.
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
/// instruction set: the parameter rules, the
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
