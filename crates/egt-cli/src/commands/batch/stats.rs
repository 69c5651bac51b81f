//! Row-group statistics of the numbers `egt batch` writes to Parquet (the
//! doubles and the row numbers), computed by egt instead of by the Parquet
//! writer.
//!
//! parquet-rs finds a double column's min and max by keying every value as a
//! 64-bit integer (IEEE 754 total order). The baseline x86-64 instruction set
//! that `egt` ships for has no 64-bit integer compare, so that loop runs
//! scalar: 18 % of a one-thread `egt batch` to Parquet (docs/benchmarks.md).
//! The doubles `egt batch` writes are finite or null, and for those a float
//! compare, which the baseline vectorises, gives the same min and max except
//! for the sign of a zero; a block where that or a NaN could matter is
//! rescanned in total order. The row numbers' min and max are the first
//! and the last. The statistics are exactly those parquet-rs writes for a
//! column at `EnabledStatistics::Chunk` (a test compares the files byte for
//! byte).

use arrow_array::{Array, Float64Array, UInt64Array};
use parquet::column::writer::ColumnCloseResult;
use parquet::file::metadata::LevelHistogram;
use parquet::file::statistics::{Statistics, ValueStatistics};

/// What one pass over a column's values found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Scan {
    /// Every value is finite.
    pub finite: bool,
    /// The least and greatest value, when a float compare gives them as
    /// total order does: every value finite, no zero at either end, at least
    /// one value.
    pub bounds: Option<(f64, f64)>,
}

impl Scan {
    /// The scan of two parts of a column, from theirs.
    pub fn and(self, other: Scan) -> Scan {
        Scan {
            finite: self.finite && other.finite,
            // Each part's bounds are neither zero nor NaN: so are the
            // least and the greatest of them.
            bounds: match (self.bounds, other.bounds) {
                (Some((a, b)), Some((c, d))) => Some((a.min(c), b.max(d))),
                _ => None,
            },
        }
    }
}

/// Sets the row-group statistics of a chunk (`close`), written with statistics off,
/// to those parquet-rs computes for `array` at `EnabledStatistics::Chunk`:
/// min, max, null and NaN counts, and the definition levels' histogram.
/// `known`: the [`Scan`] bounds of `array`'s values, if it has no nulls and
/// they were scanned already.
pub(super) fn set_double_statistics(
    close: &mut ColumnCloseResult,
    array: &Float64Array,
    known: Option<(f64, f64)>,
) -> parquet::errors::Result<()> {
    let nulls = array.null_count();
    let bounds = match (array.nulls(), known) {
        (None, Some((min, max))) => Some((min, max, 0)),
        (None, None) => (scan(array.values()).bounds.map(|(min, max)| (min, max, 0)))
            .or_else(|| total_order_bounds(array.iter())),
        (Some(_), _) => total_order_bounds(array.iter()),
    };
    let (min, max, nans) = match bounds {
        Some((min, max, nans)) => (Some(min), Some(max), nans),
        None => (None, None, 0),
    };
    let descr = close.metadata.column_descr_ptr();
    let statistics = ValueStatistics::<f64>::new(min, max, None, Some(nulls as u64), false)
        .with_nan_count((array.len() > nulls).then_some(nans))
        .with_backwards_compatible_min_max(descr.sort_order().is_signed());
    // A flat column: a null's level is 0, a value's the maximum.
    let top = descr.max_def_level();
    let definition = LevelHistogram::try_new(top).map(|mut h| {
        h.increment_by(0, nulls as i64);
        h.increment_by(top, (array.len() - nulls) as i64);
        h
    });
    let repetition = LevelHistogram::try_new(descr.max_rep_level());
    close.metadata = close
        .metadata
        .clone()
        .into_builder()
        .set_statistics(Statistics::Double(statistics))
        .set_definition_level_histogram(definition)
        .set_repetition_level_histogram(repetition)
        .build()?;
    Ok(())
}

/// Sets the row-group statistics of a chunk of row numbers written with
/// statistics off to those parquet-rs computes at `EnabledStatistics::Chunk`:
/// the first and the last as min and max (`egt batch` numbers a block's rows
/// in order, never decreasing) and no nulls. (parquet-rs's min/max of
/// 64-bit integers runs scalar on the baseline x86-64, 3 % of a one-thread
/// batch.)
pub(super) fn set_row_statistics(
    close: &mut ColumnCloseResult,
    rows: &UInt64Array,
) -> parquet::errors::Result<()> {
    let values = rows.values();
    debug_assert!(values.windows(2).all(|w| w[0] <= w[1]), "rows out of order");
    debug_assert_eq!(rows.null_count(), 0, "a null row number");
    let descr = close.metadata.column_descr_ptr();
    // Parquet keeps an unsigned 64-bit integer in INT64, bit for bit.
    let (min, max) = (values.first(), values.last());
    let statistics = ValueStatistics::<i64>::new(
        min.map(|&v| v as i64),
        max.map(|&v| v as i64),
        None,
        Some(0),
        false,
    )
    .with_backwards_compatible_min_max(descr.sort_order().is_signed());
    close.metadata = close
        .metadata
        .clone()
        .into_builder()
        .set_statistics(Statistics::Int64(statistics))
        .build()?;
    Ok(())
}

/// Whether `values` are all finite, and their min and max by float compare,
/// where it gives total order's: not when a value is NaN or infinite, or a
/// zero is at either end (the compare does not tell -0 from +0), or there
/// is no value. Compiled for the instruction set the machine has (pulp's
/// dispatch, as the core's straight-line runs): the baseline x86-64's SSE2
/// compares two doubles at a time, AVX2 four, AVX-512 eight.
pub(super) fn scan(values: &[f64]) -> Scan {
    pulp::Arch::new().dispatch(Scanning(values))
}

/// `take(k, v)` for each vector `v` of `head` in order, `k` the register
/// of [`REGISTERS`] it goes to, in turn.
#[inline(always)]
fn in_turn<V: Copy>(head: &[V], mut take: impl FnMut(usize, V)) {
    let (groups, rest) = head.as_chunks::<REGISTERS>();
    for group in groups {
        for (k, &v) in group.iter().enumerate() {
            take(k, v);
        }
    }
    for (k, &v) in rest.iter().enumerate() {
        take(k, v);
    }
}

/// [`scan`] as a [`pulp::WithSimd`], compiled for each instruction set.
/// Each accumulator is [`REGISTERS`] registers, so that a register's chain
/// of compares waits less on the one before (one register each, the loop
/// was bound by the compares' latency; as arrays of doubles left to the
/// vectoriser, the accumulators were kept on the stack).
#[derive(Clone, Copy)]
struct Scanning<'a>(&'a [f64]);

/// Registers an accumulator of [`Scanning`]: three accumulators, twelve of
/// SSE2's and AVX2's sixteen.
const REGISTERS: usize = 4;

impl pulp::WithSimd for Scanning<'_> {
    type Output = Scan;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> Scan {
        let (head, tail) = S::as_simd_f64s(self.0);
        let mut lo = [simd.splat_f64s(f64::INFINITY); REGISTERS];
        let mut hi = [simd.splat_f64s(f64::NEG_INFINITY); REGISTERS];
        // v * 0 is NaN exactly when v is NaN or infinite: any such sum is NaN.
        let mut odd = [simd.splat_f64s(0.0); REGISTERS];
        let zero = simd.splat_f64s(0.0);
        // A compare and a select: a NaN never replaces a bound.
        let take = |k: usize, v: S::f64s| {
            lo[k] = simd.select_f64s(simd.less_than_f64s(v, lo[k]), v, lo[k]);
            hi[k] = simd.select_f64s(simd.greater_than_f64s(v, hi[k]), v, hi[k]);
            odd[k] = simd.add_f64s(odd[k], simd.mul_f64s(v, zero));
        };
        in_turn(head, take);
        let (mut min, mut max, mut sum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
        let lanes = |v: S::f64s| {
            let mut out = [0.0; 8];
            let n = std::mem::size_of::<S::f64s>() / 8;
            simd.partial_store_f64s(&mut out[..n], v);
            (out, n)
        };
        for k in 0..REGISTERS {
            for (bound, f) in [(lo[k], 0), (hi[k], 1), (odd[k], 2)] {
                let (values, n) = lanes(bound);
                for &x in &values[..n] {
                    match f {
                        0 => min = if x < min { x } else { min },
                        1 => max = if x > max { x } else { max },
                        _ => sum += x,
                    }
                }
            }
        }
        for &v in tail {
            min = if v < min { v } else { min };
            max = if v > max { v } else { max };
            sum += v * 0.0;
        }
        let finite = sum == 0.0;
        let plain = finite && min <= max && min != 0.0 && max != 0.0;
        Scan {
            finite,
            bounds: plain.then_some((min, max)),
        }
    }
}

/// The largest of `values` by a float compare (a NaN is never the largest):
/// -inf when there are none, or only NaNs. Compiled for the instruction set
/// the machine has, as [`scan`] is.
pub(super) fn largest(values: &[f64]) -> f64 {
    pulp::Arch::new().dispatch(Largest(values))
}

/// [`largest`] as a [`pulp::WithSimd`]: an accumulator of [`REGISTERS`]
/// registers, as [`Scanning`]'s.
#[derive(Clone, Copy)]
struct Largest<'a>(&'a [f64]);

impl pulp::WithSimd for Largest<'_> {
    type Output = f64;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> f64 {
        let (head, tail) = S::as_simd_f64s(self.0);
        let mut hi = [simd.splat_f64s(f64::NEG_INFINITY); REGISTERS];
        let take = |k: usize, v: S::f64s| {
            hi[k] = simd.select_f64s(simd.greater_than_f64s(v, hi[k]), v, hi[k]);
        };
        in_turn(head, take);
        let mut max = f64::NEG_INFINITY;
        for h in hi {
            let mut out = [f64::NEG_INFINITY; 8];
            let n = std::mem::size_of::<S::f64s>() / 8;
            simd.partial_store_f64s(&mut out[..n], h);
            for &x in &out[..n] {
                max = if x > max { x } else { max };
            }
        }
        for &v in tail {
            max = if v > max { v } else { max };
        }
        max
    }
}

/// Whether `a` and `b` hold the same doubles bit for bit (so -0 is not 0,
/// and a NaN is its own bits), compared as wide as the machine compares
/// without stopping at the first difference: libc's `memcmp`, which does,
/// was 3.7 % of a one-thread 10^7-row batch checking a grid's repeats.
pub(super) fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && pulp::Arch::new().dispatch(SameBits(a, b))
}

/// [`same_bits`] as a [`pulp::WithSimd`]: the differences' bits gathered in
/// [`REGISTERS`] registers.
#[derive(Clone, Copy)]
struct SameBits<'a>(&'a [f64], &'a [f64]);

impl pulp::WithSimd for SameBits<'_> {
    type Output = bool;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> bool {
        let a: &[u64] = pulp::bytemuck::cast_slice(self.0);
        let b: &[u64] = pulp::bytemuck::cast_slice(self.1);
        let ((va, ta), (vb, tb)) = (S::as_simd_u64s(a), S::as_simd_u64s(b));
        let mut diff = [simd.splat_u64s(0); REGISTERS];
        let ((ga, ra), (gb, rb)) = (va.as_chunks::<REGISTERS>(), vb.as_chunks::<REGISTERS>());
        for (x, y) in ga.iter().zip(gb) {
            for k in 0..REGISTERS {
                diff[k] = simd.or_u64s(diff[k], simd.xor_u64s(x[k], y[k]));
            }
        }
        for (k, (&x, &y)) in ra.iter().zip(rb).enumerate() {
            diff[k] = simd.or_u64s(diff[k], simd.xor_u64s(x, y));
        }
        let mut any = ta.iter().zip(tb).fold(0, |d, (x, y)| d | (x ^ y));
        for d in diff {
            let mut out = [0u64; 8];
            let n = std::mem::size_of::<S::u64s>() / 8;
            simd.partial_store_u64s(&mut out[..n], d);
            any |= out[..n].iter().fold(0, |d, x| d | x);
        }
        any == 0
    }
}

/// Min and max in IEEE 754 total order of the values present, NaNs left out
/// and counted; when every value present is NaN, the least and greatest NaN
/// (parquet-rs's rule). None when no value is present.
fn total_order_bounds(values: impl Iterator<Item = Option<f64>>) -> Option<(f64, f64, u64)> {
    let mut numbers: Option<(f64, f64)> = None;
    let mut nan: Option<(f64, f64)> = None;
    let mut nans = 0u64;
    for v in values.flatten() {
        let slot = if v.is_nan() {
            nans += 1;
            &mut nan
        } else {
            &mut numbers
        };
        *slot = Some(match *slot {
            None => (v, v),
            Some((lo, hi)) => (
                if v.total_cmp(&lo).is_lt() { v } else { lo },
                if v.total_cmp(&hi).is_gt() { v } else { hi },
            ),
        });
    }
    numbers.or(nan).map(|(lo, hi)| (lo, hi, nans))
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use arrow_array::{ArrayRef, Float64Array, StringArray};
    use arrow_schema::{DataType, Field};

    use super::super::{BatchOutput, Known, NumberStatistics, RowNumbers, columnar_file, doubles};

    /// A Parquet file of `blocks` with the doubles' statistics computed by
    /// `by`. Three double columns: the values and their negatives, built as
    /// `egt batch` builds its columns when no value is missing ([`doubles`]:
    /// non-finite values made null, the bounds found on the way passed on;
    /// in odd blocks the negatives' first row failed), and the values as
    /// they are (NaNs and infinities kept).
    fn file(blocks: &[Vec<Option<f64>>], by: NumberStatistics) -> Vec<u8> {
        let fields = vec![
            Field::new("row", DataType::UInt64, false),
            Field::new("torque.c2", DataType::Float64, true),
            Field::new("driving_torque.s1", DataType::Float64, true),
            Field::new("as is", DataType::Float64, true),
            Field::new("warning", DataType::Utf8, true),
        ];
        let (encoder, mut sink) =
            columnar_file(BatchOutput::Parquet, fields, 1, by).unwrap_or_else(|e| panic!("{e}"));
        let mut out = Vec::new();
        let mut first = 0u64;
        for (index, values) in blocks.iter().enumerate() {
            let len = values.len() as u64;
            let negated: Vec<_> = values.iter().map(|v| v.map(|v| -v)).collect();
            let (mut columns, mut known): (Vec<ArrayRef>, _) = (vec![], vec![Known::default()]);
            let mut failed = vec![None; values.len()];
            failed[0] = Some(String::from("failed"));
            let failed = (index % 2 == 1).then_some(failed.as_slice());
            for (column, failed) in [(values.clone(), None), (negated, failed)] {
                let all: Option<Vec<f64>> = column.iter().copied().collect();
                let (array, bounds) = match all {
                    Some(all) => doubles(all.into(), failed),
                    None => (Arc::new(Float64Array::from(column)) as ArrayRef, None),
                };
                columns.push(array);
                known.push(Known {
                    bounds,
                    ..Known::default()
                });
            }
            columns.push(Arc::new(Float64Array::from(values.clone())));
            known.push(Known::default());
            columns.push(Arc::new(StringArray::new_null(values.len())));
            let rows = RowNumbers::Run {
                first,
                len: values.len(),
            };
            first += len;
            let encoded = encoder
                .record_batch(rows, columns, &known, index)
                .unwrap_or_else(|e| panic!("block {index}: {e}"));
            sink.append(encoded, &mut out)
                .unwrap_or_else(|e| panic!("block {index}: {e}"));
        }
        sink.finish(&mut out).unwrap_or_else(|e| panic!("{e}"));
        out
    }

    /// 53 pseudo-random bits a call (a linear congruential generator).
    fn random_bits(mut state: u64) -> impl FnMut() -> u64 {
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            state >> 11
        }
    }

    /// `work` compiled for each instruction set the machine has, and its
    /// answers.
    fn on_every_set<W: pulp::WithSimd + Copy>(work: W) -> Vec<(&'static str, W::Output)> {
        let mut got = vec![("scalar", work.with_simd(pulp::Scalar))];
        if let Some(simd) = pulp::x86::V3::try_new() {
            got.push(("AVX2", work.with_simd(simd)));
        }
        if let Some(simd) = pulp::x86::V4::try_new() {
            got.push(("AVX-512", work.with_simd(simd)));
        }
        got
    }

    /// The scan, the largest value and the bitwise comparison give the same
    /// answers compiled for every instruction set the machine has (the
    /// files' test runs only the one dispatched to), and a plain fold's, on
    /// columns of every length up to 80 with NaNs of either sign,
    /// infinities and zeros of either sign placed at random.
    #[test]
    fn the_scan_agrees_on_every_instruction_set() {
        use super::{Largest, SameBits, Scan, Scanning, largest, same_bits, scan};
        let mut next = random_bits(0x9e37_79b9_7f4a_7c15);
        let odd = [
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
        ];
        for case in 0..4000 {
            let len = case % 81;
            let values: Vec<f64> = (0..len)
                .map(|_| match next() % 40 {
                    0 => odd[(next() % 6) as usize],
                    _ => (next() as f64 / (1u64 << 53) as f64 - 0.5) * 1e3,
                })
                .collect();
            let finite = values.iter().all(|v| v.is_finite());
            let min = values.iter().copied().fold(f64::INFINITY, f64::min);
            let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let plain = finite && len > 0 && min != 0.0 && max != 0.0;
            let expected = Scan {
                finite,
                bounds: plain.then_some((min, max)),
            };
            let mut got = on_every_set(Scanning(&values));
            got.push(("dispatched", scan(&values)));
            for (set, scan) in got {
                assert_eq!(scan, expected, "{set}, case {case}: {values:?}");
            }
            // The largest, NaNs left out (-inf if nothing else).
            let mut got = on_every_set(Largest(&values));
            got.push(("dispatched", largest(&values)));
            for (set, largest) in got {
                assert!(
                    largest == max,
                    "{set}, case {case}: {largest} for {values:?}"
                );
            }
            // The values against themselves, and with one value's bit
            // changed (the sign's too).
            let mut other = values.clone();
            let mut got = on_every_set(SameBits(&values, &other));
            got.push(("dispatched", same_bits(&values, &other)));
            for (set, same) in got {
                assert!(same, "{set}, case {case}: {values:?}");
            }
            if len > 0 {
                let (at, bit) = ((next() % len as u64) as usize, next() % 64);
                other[at] = f64::from_bits(other[at].to_bits() ^ (1 << bit));
                let mut got = on_every_set(SameBits(&values, &other));
                got.push(("dispatched", same_bits(&values, &other)));
                for (set, same) in got {
                    assert!(!same, "{set}, case {case}, bit {bit} of {at}: {values:?}");
                }
            }
        }
    }

    /// egt's statistics are parquet-rs's, the doubles' and the row
    /// numbers', and so are egt's chunks of row numbers and of doubles
    /// without nulls (pages.rs; blocks of one row, of a few, of one page
    /// of doubles and one more, of two, of the rows' page limit (a block),
    /// one more and twice as many; first rows of one- to
    /// three-byte varints; NaNs kept): the files are the same bytes, over
    /// blocks that take the fast path (spanning pages, shorter than a lane
    /// group, one value) and every case it hands to the exact scan (zeros
    /// of either sign at either end, NaNs of either sign, infinities,
    /// nulls, no value at all).
    #[test]
    fn egt_statistics_are_parquets_byte_for_byte() {
        let mut bits = random_bits(0x2545_f491_4f6c_dd1d);
        let mut uniform = move || bits() as f64 / (1u64 << 53) as f64 * 2000.0 - 1000.0;
        let nan = f64::NAN;
        let negative_nan = f64::from_bits(nan.to_bits() | (1 << 63));
        let some = |v: &[f64]| v.iter().map(|&v| Some(v)).collect::<Vec<_>>();
        let mut blocks: Vec<Vec<Option<f64>>> = vec![
            (0..20_000).map(|_| Some(uniform())).collect(),
            (0..9).map(|_| Some(uniform().abs() + 1.0)).collect(),
            some(&[5.0]),
            some(&[3.0, -2.0, 7.5, -0.5, 1.25, 9.0, -8.0]),
            some(&[2.0, 0.0, 1.0, -0.0, 4.0, 3.0, 5.0, 6.0, 7.0, 8.0]),
            some(&[2.0, 0.0, 1.0, 4.0, 3.0, 5.0, 6.0, 7.0, 8.0, 9.0]),
            some(&[-2.0, -0.0, -1.0, -4.0, -3.0, -5.0, -6.0, -7.0, -8.0]),
            some(&[0.0, 0.0]),
            some(&[-0.0]),
            some(&[1.0, nan, -3.0, 2.0, 4.0, 5.0, 6.0, 7.0, 8.0]),
            some(&[negative_nan, nan]),
            some(&[f64::INFINITY, 1.0, f64::NEG_INFINITY]),
            vec![Some(3.0), None, Some(-2.0), None, Some(0.0)],
            vec![None, None, None],
            vec![None, Some(nan)],
        ];
        // Pages of doubles end at 8 192 values, the row numbers' at a block;
        // parquet-rs writes a longer block's (egt's bound, mutation-checked).
        // A column of nulls is parquet-rs's the first time for a length,
        // egt's after (the warnings': 9, 1, 10, 2, 3 and a block twice).
        let page = super::super::pages::PAGE_ROWS;
        for len in [
            8_192,
            8_193,
            16_384,
            page,
            page + 1,
            2 * page,
            page,
            page + 1,
        ] {
            blocks.push((0..len).map(|_| Some(uniform())).collect());
        }
        let egt = file(&blocks, NumberStatistics::Egt);
        let parquet = file(&blocks, NumberStatistics::Parquet);
        // The files would be equal with no statistics on either side.
        let path = std::env::temp_dir().join(format!("egt-stats-{}.parquet", std::process::id()));
        std::fs::write(&path, &egt).unwrap_or_else(|e| panic!("{e}"));
        let opened = std::fs::File::open(&path).unwrap_or_else(|e| panic!("{e}"));
        let reader = parquet::file::serialized_reader::SerializedFileReader::new(opened)
            .unwrap_or_else(|e| panic!("{e}"));
        use parquet::file::reader::FileReader;
        let groups = reader.metadata().row_groups();
        assert_eq!(groups.len(), blocks.len());
        for (g, group) in groups.iter().enumerate() {
            for c in [1, 2, 3] {
                assert!(
                    group.column(c).statistics().is_some(),
                    "row group {g}, column {c}"
                );
            }
        }
        let first = egt.iter().zip(&parquet).position(|(a, b)| a != b);
        assert!(
            egt == parquet,
            "egt's file differs from parquet-rs's at byte {first:?} ({} and {} bytes)",
            egt.len(),
            parquet.len()
        );
    }

    /// A grid's column, compressed and scanned by egt from its repeats
    /// (repeats.rs: only the values its streams hold as literals are read
    /// for its bounds), has parquet-rs's statistics and values: axes with a
    /// zero at an end, -0, a NaN (the column's nulls then, which
    /// parquet-rs writes), plain values, and more values than a page; a
    /// value a row, runs of 100 and runs longer than a page (its pages'
    /// bounds differ); blocks of one page and a part, of a few rows, and
    /// starting inside a run.
    #[test]
    fn a_grids_columns_have_parquets_statistics() {
        use super::super::repeats::Pattern;
        use parquet::file::reader::FileReader;
        // The last axis's values a row each are longer than a page:
        // Snappy's compressor takes those pages, and they are scanned.
        let long: Vec<f64> = (0..10_000).map(|k| 7.0 - k as f64 * 0.001).collect();
        let axes: [&[f64]; 6] = [
            &[-1.0, -2.5, 3.0],
            &[0.0, 1.0, 2.0],
            &[-0.0, -1.0],
            &[1.0, f64::NAN, 2.0],
            &[4.0, 5.0, f64::INFINITY],
            &long,
        ];
        let blocks = [(0, 9000), (9000, 5), (9005, 20_000)];
        for axis in axes {
            for stride in [1, 100, 5000, 20_000] {
                let file = |by: NumberStatistics| {
                    let fields = vec![
                        Field::new("row", DataType::UInt64, false),
                        Field::new("x", DataType::Float64, true),
                    ];
                    let (encoder, mut sink) = columnar_file(BatchOutput::Parquet, fields, 0, by)
                        .unwrap_or_else(|e| panic!("{e}"));
                    let mut out = Vec::new();
                    for (index, &(first, len)) in blocks.iter().enumerate() {
                        let values: Vec<f64> = (first..first + len)
                            .map(|i| axis[(i / stride) % axis.len()])
                            .collect();
                        // As `Encoder::encode` builds the column.
                        let (column, known): (ArrayRef, _) = match by {
                            NumberStatistics::Egt => (
                                Arc::new(Float64Array::new(values.into(), None)),
                                Known {
                                    pattern: Some(Pattern {
                                        first,
                                        stride,
                                        count: axis.len(),
                                    }),
                                    unscanned: true,
                                    ..Known::default()
                                },
                            ),
                            NumberStatistics::Parquet => {
                                let (column, bounds) = doubles(values.into(), None);
                                let known = Known {
                                    bounds,
                                    ..Known::default()
                                };
                                (column, known)
                            }
                        };
                        let rows = RowNumbers::Run {
                            first: first as u64,
                            len,
                        };
                        let known = [Known::default(), known];
                        let encoded = encoder
                            .record_batch(rows, vec![column], &known, index)
                            .unwrap_or_else(|e| panic!("block {index}: {e}"));
                        sink.append(encoded, &mut out)
                            .unwrap_or_else(|e| panic!("block {index}: {e}"));
                    }
                    sink.finish(&mut out).unwrap_or_else(|e| panic!("{e}"));
                    bytes::Bytes::from(out)
                };
                let (egt, parquet) = (file(NumberStatistics::Egt), file(NumberStatistics::Parquet));
                let read = |file: bytes::Bytes| {
                    let reader = parquet::file::serialized_reader::SerializedFileReader::new(file)
                        .unwrap_or_else(|e| panic!("{e}"));
                    let groups = reader.metadata().row_groups().to_vec();
                    let stats: Vec<_> = groups
                        .iter()
                        .map(|g| g.column(1).statistics().cloned())
                        .collect();
                    stats
                };
                let case = format!("axis {axis:?}, stride {stride}");
                assert_eq!(read(egt.clone()), read(parquet.clone()), "{case}");
                let values = |file: bytes::Bytes| {
                    let reader = parquet::arrow::arrow_reader::ParquetRecordBatchReader::try_new(
                        file,
                        1 << 20,
                    )
                    .unwrap_or_else(|e| panic!("{e}"));
                    let batches: Vec<_> = reader
                        .map(|b| b.unwrap_or_else(|e| panic!("{e}")))
                        .collect();
                    batches
                };
                assert_eq!(values(egt), values(parquet), "{case}");
            }
        }
    }
}
