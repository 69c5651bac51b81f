//! Snappy streams of a Parquet page whose values repeat in a pattern egt
//! knows: a parameter column of a grid or zip.
//!
//! Row `i` of a product design holds value `(i / stride) % count` of each
//! axis: runs of `stride` equal values, and the whole repeating after
//! `stride * count` rows. Snappy's own compressor finds those repeats by
//! hashing the bytes and comparing, which cost more on such a column than
//! on a column of results that does not compress. Told the pattern, egt
//! writes the stream itself:
//! - runs of at least [`SHORT_RUNS`] rows: a literal for a run's first
//!   value, and copies of the value before for the rest of it;
//! - shorter runs (the last axis's, a row each): Snappy's compressor, on
//!   the first period only, where neighbouring values share bytes;
//! - after the first period: copies of the period before.
//!
//! Every copy is checked against the bytes first (a comparison, which runs
//! at memory speed): a pattern that does not hold gives no stream, never a
//! wrong one. The stream differs from the one Snappy's compressor writes
//! for the same bytes, decodes to the same bytes (tested against the `snap`
//! crate's decoder; Apache Arrow's C++ reader reads the files in the Python
//! tests), and is at most a quarter longer (tested), shorter on the grid of
//! docs/benchmarks.md.

use super::stats::{Scan, same_bits, scan};

/// How a column of a product design repeats from its first row on: value
/// `(first + i) / stride % count` of its axis at row `i`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Pattern {
    /// The design row of the column's first value.
    pub(super) first: usize,
    /// Rows a value of the axis holds for.
    pub(super) stride: usize,
    /// Values of the axis.
    pub(super) count: usize,
}

impl Pattern {
    /// The same column from `rows` rows further on.
    pub(super) fn skip(self, rows: usize) -> Self {
        Pattern {
            first: self.first.wrapping_add(rows),
            ..self
        }
    }
}

/// Bytes a value.
const VALUE: usize = 8;

/// Runs shorter than this are left to Snappy's compressor, with the rest
/// of the first period: a run's own literal and copies (12 bytes for 64
/// values) are longer than what Snappy finds in a few short runs of
/// neighbouring values, which share bytes.
const SHORT_RUNS: usize = 64;

/// Onto the end of `out`, the Snappy (raw) stream of `prefix` followed by
/// `values` (as PLAIN holds them: little-endian), which repeat as `pattern`
/// says, and the [`Scan`] of the values the stream holds as literals: every
/// other value is a copy of one of them, checked, so that scan is the
/// page's. None, with what was added to `out` of no use, if a repeat the
/// pattern claims is not in the values, or if the pattern saves nothing
/// (each value once in the page): Snappy's own compressor is the one to use
/// then. A first period of short runs is compressed by `snappy` (through
/// `scratch`), which finds what repeats inside it; a run's first value is
/// gathered in `firsts`.
pub(super) fn compress(
    (prefix, doubles): (&[u8], &[f64]),
    pattern: Pattern,
    snappy: &mut snap::raw::Encoder,
    (scratch, firsts): (&mut Vec<u8>, &mut Vec<f64>),
    out: &mut Vec<u8>,
) -> Option<Scan> {
    let Pattern { stride, count, .. } = pattern;
    if stride == 0 || count == 0 || cfg!(target_endian = "big") {
        return None;
    }
    let values = arrow_buffer::ToByteSlice::to_byte_slice(doubles);
    let n = doubles.len();
    // Values of one period; none after it when it is longer than the page.
    let period = stride.saturating_mul(count);
    if stride < SHORT_RUNS && period >= n {
        return None;
    }
    let head = period.min(n);
    // Everything after the first period repeats the period before.
    let back = head * VALUE;
    if head < n && !same_bits(&doubles[head..], &doubles[..n - head]) {
        return None;
    }
    let total = prefix.len() + values.len();
    let base = out.len();
    let stream = Stream { prefix, values };
    // The start of the bytes not yet in the stream (a literal to come),
    // counted in the prefix and values together.
    let mut literal = prefix.len() + back;
    let literals = if stride < SHORT_RUNS {
        // Snappy's stream of the prefix and the first period, with the
        // whole page's length in place of theirs (a varint as long or
        // longer, put where theirs ends).
        scratch.clear();
        scratch.extend_from_slice(prefix);
        scratch.extend_from_slice(&values[..back]);
        let mut length = Vec::with_capacity(10);
        uleb128(&mut length, total as u64);
        let mut theirs = Vec::with_capacity(10);
        uleb128(&mut theirs, scratch.len() as u64);
        let at = length.len() - theirs.len();
        out.resize(base + at + snap::raw::max_compress_len(scratch.len()), 0);
        let written = snappy.compress(scratch, &mut out[base + at..]).ok()?;
        out.truncate(base + at + written);
        out[base..base + length.len()].copy_from_slice(&length);
        scan(&doubles[..head])
    } else {
        uleb128(out, total as u64);
        literal = 0;
        firsts.clear();
        // The page may start inside a run; the others start whole.
        let (mut i, mut into) = (0, pattern.first % stride);
        while i < head {
            let end = head.min(i.saturating_add(stride - into));
            into = 0;
            firsts.push(doubles[i]);
            if end - i > 1 {
                // The run's values after its first, each the same as the
                // one before: the bytes equal themselves one value on.
                if !same_bits(&doubles[i + 1..end], &doubles[i..end - 1]) {
                    return None;
                }
                stream.literal(out, literal, prefix.len() + (i + 1) * VALUE);
                copy(out, VALUE, (end - i - 1) * VALUE);
                literal = prefix.len() + end * VALUE;
            }
            i = end;
        }
        scan(firsts)
    };
    if head < n {
        stream.literal(out, literal, prefix.len() + back);
        copy(out, back, values.len() - back);
        literal = total;
    }
    stream.literal(out, literal, total);
    Some(literals)
}

/// The bytes a stream holds: the prefix, then the values.
struct Stream<'a> {
    prefix: &'a [u8],
    values: &'a [u8],
}

impl Stream<'_> {
    /// A literal of the bytes from `start` to `end` (none if they are none).
    fn literal(&self, out: &mut Vec<u8>, start: usize, end: usize) {
        if start >= end {
            return;
        }
        let n = (end - start - 1) as u32;
        if n < 60 {
            out.push((n as u8) << 2);
        } else {
            let bytes = n.to_le_bytes();
            let len = 4 - (n.leading_zeros() / 8) as usize;
            out.push(((59 + len) as u8) << 2);
            out.extend_from_slice(&bytes[..len]);
        }
        let p = self.prefix.len();
        if start < p {
            out.extend_from_slice(&self.prefix[start..end.min(p)]);
        }
        if end > p {
            out.extend_from_slice(&self.values[start.max(p) - p..end - p]);
        }
    }
}

/// Copies of `len` bytes from `offset` bytes back, in pieces of at most 64
/// (as Snappy's compressor splits them: none shorter than 4). The pieces of
/// 64 are all alike: one is written, then doubled.
fn copy(out: &mut Vec<u8>, offset: usize, mut len: usize) {
    if len >= 68 {
        let pieces = (len - 68) / 64 + 1;
        let (bytes, n) = piece(offset, 64);
        let start = out.len();
        let end = start + pieces * n;
        out.reserve(pieces * n);
        out.extend_from_slice(&bytes[..n]);
        while out.len() < end {
            let more = (out.len() - start).min(end - out.len());
            out.extend_from_within(start..start + more);
        }
        len -= pieces * 64;
    }
    if len > 64 {
        let (bytes, n) = piece(offset, 60);
        out.extend_from_slice(&bytes[..n]);
        len -= 60;
    }
    let (bytes, n) = piece(offset, len);
    out.extend_from_slice(&bytes[..n]);
}

/// One copy element of 1 to 64 bytes, the shortest form for its offset,
/// and its length.
fn piece(offset: usize, len: usize) -> ([u8; 5], usize) {
    debug_assert!((1..=64).contains(&len) && offset > 0);
    let mut bytes = [0; 5];
    if (4..12).contains(&len) && offset < 2048 {
        bytes[0] = 0b01 | (((len - 4) as u8) << 2) | (((offset >> 8) as u8) << 5);
        bytes[1] = offset as u8;
        (bytes, 2)
    } else if let Ok(offset) = u16::try_from(offset) {
        bytes[0] = 0b10 | (((len - 1) as u8) << 2);
        bytes[1..3].copy_from_slice(&offset.to_le_bytes());
        (bytes, 3)
    } else {
        // A page is at most a few hundred KiB: the offset fits 32 bits.
        bytes[0] = 0b11 | (((len - 1) as u8) << 2);
        bytes[1..5].copy_from_slice(&(offset as u32).to_le_bytes());
        (bytes, 5)
    }
}

/// `v` as an unsigned LEB128 varint.
pub(super) fn uleb128(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

#[cfg(test)]
mod tests {
    use super::{Pattern, compress as compress_with, scan};

    /// A stream of `values` after `prefix` into `out`, if the pattern
    /// holds; then the scan of its literals is the page's.
    fn compress(prefix: &[u8], values: &[f64], pattern: Pattern, out: &mut Vec<u8>) -> bool {
        let mut snappy = snap::raw::Encoder::new();
        out.clear();
        let scratch = (&mut Vec::new(), &mut Vec::new());
        let got = compress_with((prefix, values), pattern, &mut snappy, scratch, out);
        if let Some(literals) = got {
            assert_eq!(
                literals,
                scan(values),
                "{pattern:?}, {} values",
                values.len()
            );
        }
        got.is_some()
    }

    /// Rows `first..first + n` of a column of `count` values a `stride`
    /// rows each: a grid axis from -10 to -100, as `--grid` spaces it.
    fn column(first: usize, n: usize, stride: usize, count: usize) -> Vec<f64> {
        let (a, b) = (-10.0, -100.0);
        let value = |k: usize| a + (b - a) * k as f64 / (count.max(2) - 1) as f64;
        (first..first + n)
            .map(|i| value((i / stride) % count))
            .collect()
    }

    /// The bytes of PLAIN doubles.
    fn bytes(values: &[f64]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    /// Snappy's decoder gives back the prefix and the values, for every
    /// stride, count, first row and length of page; a stream is given
    /// unless the page holds no whole period and runs too short to copy,
    /// and it is never much longer than Snappy's own.
    #[test]
    fn streams_decode_to_the_page() {
        let prefix = [4, 0, 0, 0, 0x80, 0x80, 0x01, 1];
        let mut decoder = snap::raw::Decoder::new();
        let mut out = Vec::new();
        let mut written = 0;
        for stride in [1, 2, 7, 8, 63, 64, 65, 1000, usize::MAX / 2] {
            for count in [1, 2, 5, 13, 1000] {
                for first in [0, 1, 5, 999, 12_345] {
                    for n in [1, 2, 7, 8, 9, 63, 100, 1001, 8192] {
                        let values = column(first, n, stride, count);
                        let pattern = Pattern {
                            first,
                            stride,
                            count,
                        };
                        let repeats = stride >= 64 || stride.saturating_mul(count) < n;
                        assert_eq!(compress(&prefix, &values, pattern, &mut out), repeats);
                        if !repeats {
                            continue;
                        }
                        written += 1;
                        let page = decoder
                            .decompress_vec(&out)
                            .unwrap_or_else(|e| panic!("{pattern:?} n {n}: {e}"));
                        assert!(
                            page[..8] == prefix && page[8..] == bytes(&values),
                            "{pattern:?} n {n}"
                        );
                        let snappy = snap::raw::Encoder::new()
                            .compress_vec(&[&prefix[..], &bytes(&values)].concat())
                            .unwrap_or_else(|e| panic!("{e}"));
                        assert!(
                            out.len() <= snappy.len() + snappy.len() / 4 + 16,
                            "{pattern:?} n {n}: {} bytes, Snappy's {}",
                            out.len(),
                            snappy.len()
                        );
                    }
                }
            }
        }
        assert!(written > 1000);
        // Without a prefix, and with a prefix longer than a short literal.
        for prefix in [&[][..], &[7; 100][..]] {
            let values = column(3, 5000, 1, 700);
            let pattern = Pattern {
                first: 3,
                stride: 1,
                count: 700,
            };
            assert!(compress(prefix, &values, pattern, &mut out));
            let page = decoder
                .decompress_vec(&out)
                .unwrap_or_else(|e| panic!("{e}"));
            assert!(page == [prefix, &bytes(&values)].concat());
        }
        // The literals' scan where a value is not finite, or a zero is the
        // least or the greatest (the compare does not tell -0 from +0).
        for axis in [[-1.0, 0.0, 2.0], [1.0, f64::NAN, 3.0], [-0.0, 1.0, 2.0]] {
            for stride in [1, 70] {
                let values: Vec<f64> = (0..8192).map(|i| axis[(i / stride) % 3]).collect();
                let pattern = Pattern {
                    first: 0,
                    stride,
                    count: 3,
                };
                assert!(compress(&prefix, &values, pattern, &mut out));
            }
        }
    }

    /// A repeat the pattern claims and the values do not hold gives no
    /// stream: a value changed inside a run, at the end of the first two
    /// runs (the page starts 10 rows into the first), in a later period, or
    /// the last, with and without a period in the page; a pattern off by a
    /// row.
    #[test]
    fn a_claim_the_bytes_do_not_hold_gives_no_stream() {
        let mut out = Vec::new();
        for count in [5, 1000] {
            let pattern = Pattern {
                first: 10,
                stride: 70,
                count,
            };
            let values = column(10, 3000, 70, count);
            assert!(compress(&[], &values, pattern, &mut out));
            for value in [3, 59, 129, 2000, values.len() - 1] {
                let mut changed = values.clone();
                changed[value] = f64::from_bits(changed[value].to_bits() ^ 1);
                let wrong = compress(&[], &changed, pattern, &mut out);
                assert!(!wrong, "count {count}, value {value}");
            }
            assert!(!compress(&[], &values, pattern.skip(1), &mut out));
        }
        // Short runs: only the periods after the first are claimed.
        let short = Pattern {
            first: 0,
            stride: 2,
            count: 5,
        };
        let mut values = column(0, 300, 2, 5);
        assert!(compress(&[], &values, short, &mut out));
        values[200] = f64::from_bits(values[200].to_bits() ^ 1);
        assert!(!compress(&[], &values, short, &mut out));
        let zero = Pattern { stride: 0, ..short };
        assert!(!compress(&[], &values, zero, &mut out));
    }
}
