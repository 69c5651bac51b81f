//! Parquet column chunks that egt encodes itself, where what parquet-rs's
//! writer would spend is out of proportion to what the chunk holds.
//!
//! The row numbers of a wide block count up by one. parquet-rs delta-encodes
//! them value by value, in loops over 64-bit integers that the baseline
//! x86-64 runs scalar: about a fifth of a one-thread `egt batch` to Parquet
//! (docs/benchmarks.md). Their DELTA_BINARY_PACKED page is known from the
//! first number and the count alone: a header, then five bytes a block of
//! 256 (the least delta, 1, and four mini-blocks of bit width 0). egt
//! writes that page, compressed and framed by parquet-rs's own page writer,
//! and the chunk's metadata as parquet-rs's column writer sets it (a test
//! compares the files byte for byte).
//!
//! A double column without nulls is, for the same writer, a list of the
//! rows that hold a value (every row), the values gathered through it into
//! the encoder's buffer, and that buffer copied into the page before
//! Snappy: three passes and two copies, all to put the values after a
//! definition level that says "present" for every row. egt writes those
//! pages (PLAIN, a page's worth of values at a time) straight from the
//! column. A column with nulls (a failed row, a value that is not finite)
//! is rare and still parquet-rs's. A grid's parameter column, whose
//! repeats egt knows, is compressed from them ([`repeats`]).
//!
//! parquet-rs's file writer copies an encoded chunk into the file through a
//! small buffer (into it and out of it), on the thread that writes the file
//! in order, which reads the chunk from the cache of the thread that
//! encoded it.
//! egt's chunks skip that: the writer is given blanks of their length
//! ([`Chunk::append_to_row_group`]), which the file's buffer ([`Splice`])
//! does not keep, and the chunks themselves go to the output in their
//! place.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io::{Read, Write};
use std::sync::Arc;

use parquet::basic::{Compression, Encoding, EncodingMask, PageType};
use parquet::column::page::{CompressedPage, Page, PageWriter};
use parquet::column::writer::ColumnCloseResult;
use parquet::errors::Result;
use parquet::file::metadata::{ColumnChunkMetaData, OffsetIndexBuilder, PageEncodingStats};
use parquet::file::reader::{ChunkReader, Length};
use parquet::file::statistics::{Statistics, ValueStatistics};
use parquet::file::writer::{SerializedPageWriter, SerializedRowGroupWriter, TrackedWrite};
use parquet::schema::types::ColumnDescPtr;

use super::repeats::{self, Pattern, uleb128};
use super::stats::{self, Scan};

/// The compression of every Parquet column `egt batch` writes.
pub(super) const COMPRESSION: Compression = Compression::SNAPPY;

/// The limit of rows a data page `egt batch` sets: a Parquet block's rows
/// (parquet-rs's default is 20 000). The row numbers of a block of at most
/// this many rows take one page, and so do the nulls of a column without a
/// value; pages of doubles end at [`PAGE_BYTES`] before.
pub(super) const PAGE_ROWS: usize = super::COLUMNAR_BLOCK;

/// The data page size limit `egt batch` sets: a page of doubles holds
/// this many bytes of values, 8 192 values. (A block's column is 512 KiB,
/// and the writer's page buffers grow by doubling up to the page; with
/// pages smaller than the default 1 MiB they stay small: docs/benchmarks.md.)
pub(super) const PAGE_BYTES: usize = 64 * 1024;

/// A column chunk encoded by egt, to be appended to its row group.
#[derive(Clone)]
pub(super) struct Chunk {
    /// Its pages, each with its header: each a buffer of its own, of at
    /// most 64 KiB and a few bytes, so that the allocator reuses them
    /// block after block (a chunk's 128 KiB buffer was above mimalloc's
    /// medium sizes, and came from fresh memory the kernel cleared).
    pages: Vec<bytes::Bytes>,
    close: ColumnCloseResult,
}

impl Chunk {
    /// The metadata the chunk will be appended with.
    pub(super) fn close_mut(&mut self) -> &mut ColumnCloseResult {
        &mut self.close
    }

    /// Its length in the file.
    pub(super) fn len(&self) -> u64 {
        self.close.metadata.compressed_size() as u64
    }

    /// Append the chunk to `group`, as the next column, in blanks (the
    /// file's [`Splice`] has a hole for it), and give back its pages for
    /// the hole.
    pub(super) fn append_to_row_group<W: Write + Send>(
        self,
        group: &mut SerializedRowGroupWriter<'_, W>,
    ) -> Result<Vec<bytes::Bytes>> {
        group.append_column(&Blank(self.len()), self.close)?;
        Ok(self.pages)
    }
}

/// A chunk's length in blanks, for parquet-rs's writer to copy.
struct Blank(u64);

impl Length for Blank {
    fn len(&self) -> u64 {
        self.0
    }
}

impl ChunkReader for Blank {
    type T = Blanks;

    fn get_read(&self, start: u64) -> Result<Blanks> {
        Ok(Blanks(self.0.saturating_sub(start)))
    }

    fn get_bytes(&self, start: u64, length: usize) -> Result<bytes::Bytes> {
        let available = self.0.saturating_sub(start).min(length as u64);
        Ok(vec![0; available as usize].into())
    }
}

/// Blanks left to read: a read says it filled the buffer and leaves it as
/// it was (its bytes land in a hole of the [`Splice`]).
struct Blanks(u64);

impl Read for Blanks {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = (buf.len() as u64).min(self.0);
        self.0 -= n;
        Ok(n as usize)
    }
}

/// The bytes parquet-rs's file writer writes (the magic, the chunks it
/// encodes, the page indexes and the footer), kept until they are passed
/// on to the output ([`Splice::drain`]), with holes where egt's chunks go.
#[derive(Default)]
pub(super) struct Splice {
    /// The file position of the next byte written.
    position: u64,
    /// Where egt's chunks go, in order: their start and end in the file.
    holes: VecDeque<(u64, u64)>,
    /// The bytes written outside the holes since the last drain.
    kept: Vec<u8>,
    /// Where in `kept` each hole met since the last drain is.
    marks: Vec<usize>,
}

impl Splice {
    /// A chunk of egt's, of `len` bytes, goes at file position `start`.
    /// Holes are made in the order of the file, ahead of what was written:
    /// one behind is an error (the writer's bytes there are gone).
    pub(super) fn hole(&mut self, start: u64, len: u64) -> Result<()> {
        let after = self.holes.back().map_or(self.position, |&(_, end)| end);
        if start < after {
            return Err(parquet::errors::ParquetError::General(format!(
                "a hole at byte {start} of the Parquet file, behind byte {after}"
            )));
        }
        if len > 0 {
            self.holes.push_back((start, start + len));
        }
        Ok(())
    }

    /// Pass the bytes kept so far on to `out`, with `chunks`, egt's chunks
    /// since the last drain (each as its pages), in their holes.
    pub(super) fn drain(
        &mut self,
        chunks: &[Vec<bytes::Bytes>],
        out: &mut dyn Write,
    ) -> Result<()> {
        let chunks: Vec<_> = (chunks.iter())
            .filter(|c| c.iter().any(|p| !p.is_empty()))
            .collect();
        if chunks.len() != self.marks.len() {
            return Err(parquet::errors::ParquetError::General(format!(
                "{} chunks for {} holes in the Parquet file",
                chunks.len(),
                self.marks.len()
            )));
        }
        // One vectored write (a system call a block, not two a chunk).
        let mut slices = Vec::with_capacity(4 * chunks.len() + 1);
        let mut from = 0;
        for (&mark, chunk) in self.marks.iter().zip(chunks) {
            slices.push(std::io::IoSlice::new(&self.kept[from..mark]));
            slices.extend(chunk.iter().map(|page| std::io::IoSlice::new(page)));
            from = mark;
        }
        slices.push(std::io::IoSlice::new(&self.kept[from..]));
        let mut rest = &mut slices[..];
        std::io::IoSlice::advance_slices(&mut rest, 0);
        while !rest.is_empty() {
            match out.write_vectored(rest) {
                Ok(0) => return Err(std::io::Error::from(std::io::ErrorKind::WriteZero).into()),
                Ok(n) => std::io::IoSlice::advance_slices(&mut rest, n),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
        self.kept.clear();
        self.marks.clear();
        Ok(())
    }
}

impl Write for Splice {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut rest = buf;
        while !rest.is_empty() {
            let n = match self.holes.front() {
                Some(&(start, end)) if self.position >= start => {
                    if self.position == start {
                        self.marks.push(self.kept.len());
                    }
                    let n = (end - self.position).min(rest.len() as u64);
                    if self.position + n == end {
                        self.holes.pop_front();
                    }
                    n as usize
                }
                next => {
                    let n = next.map_or(rest.len() as u64, |&(start, _)| {
                        (start - self.position).min(rest.len() as u64)
                    }) as usize;
                    self.kept.extend_from_slice(&rest[..n]);
                    n
                }
            };
            self.position += n as u64;
            rest = &rest[n..];
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The row numbers `first`, `first + 1`, ... (`len` of them) of column
/// `descr` (a flat required INT64, written DELTA_BINARY_PACKED), with their
/// row-group statistics; None when they would not fit one page, there are
/// none, the last is past `i64::MAX` or the column is not such
/// (parquet-rs writes those).
pub(super) fn row_numbers(descr: &ColumnDescPtr, first: u64, len: usize) -> Result<Option<Chunk>> {
    let flat_required = descr.max_def_level() == 0 && descr.max_rep_level() == 0;
    if len == 0
        || len > PAGE_ROWS
        || !flat_required
        || descr.physical_type() != parquet::basic::Type::INT64
    {
        return Ok(None);
    }
    let Some(last) = first
        .checked_add(len as u64 - 1)
        .filter(|&l| l <= i64::MAX as u64)
    else {
        return Ok(None);
    };
    let mut plain = Vec::with_capacity(16 + 5 * (len - 1).div_ceil(BLOCK));
    consecutive_deltas(first as i64, len, &mut plain);
    let mut buffer = Arc::default();
    let compressed = compress(&mut snap::raw::Encoder::new(), &mut buffer, &plain)?;
    let mut pages = Pages::default();
    pages.push(
        buffer,
        compressed,
        plain.len(),
        len,
        Encoding::DELTA_BINARY_PACKED,
    )?;
    // Parquet keeps an unsigned 64-bit integer in INT64, bit for bit.
    let statistics =
        ValueStatistics::<i64>::new(Some(first as i64), Some(last as i64), None, Some(0), false)
            .with_backwards_compatible_min_max(descr.sort_order().is_signed());
    let statistics = Some(Statistics::Int64(statistics));
    pages
        .finish(descr, Encoding::DELTA_BINARY_PACKED, statistics)
        .map(Some)
}

/// The pages of a chunk being written, each framed by parquet-rs's page
/// writer in a buffer of its own, and what the chunk's metadata needs.
#[derive(Default)]
struct Pages {
    pages: Vec<bytes::Bytes>,
    offsets: OffsetIndexBuilder,
    /// Bytes in the file so far, headers included: compressed, and as they
    /// would be uncompressed.
    compressed: i64,
    uncompressed: i64,
    values: usize,
}

impl Pages {
    /// A data page of version 1 and `rows` values (its levels, if any,
    /// are in the page): the `len` bytes after [`HEADROOM`] in `buffer`,
    /// `plain` bytes compressed. Its header, which parquet-rs's page
    /// writer writes, goes in the headroom: the page is not copied. The
    /// buffer is given back, for its pool.
    fn push(
        &mut self,
        mut buffer: Arc<Vec<u8>>,
        len: usize,
        plain: usize,
        rows: usize,
        encoding: Encoding,
    ) -> Result<Arc<Vec<u8>>> {
        let page = Page::DataPage {
            buf: bytes::Bytes::from_owner(Lent(buffer.clone())).slice(HEADROOM..HEADROOM + len),
            num_values: rows as u32,
            encoding,
            def_level_encoding: Encoding::RLE,
            rep_level_encoding: Encoding::RLE,
            statistics: None,
        };
        let mut sink = TrackedWrite::new(Header::default());
        let spec =
            SerializedPageWriter::new(&mut sink).write_page(CompressedPage::new(page, plain))?;
        let kept = sink.into_inner()?.0;
        let header = spec
            .compressed_size
            .checked_sub(len)
            .filter(|&h| h <= kept.len())
            .ok_or_else(|| {
                parquet::errors::ParquetError::General(format!(
                    "a page header longer than the {HEADROOM} bytes kept for it"
                ))
            })?;
        // The page writer has dropped its share: no copy.
        Arc::make_mut(&mut buffer)[HEADROOM - header..HEADROOM].copy_from_slice(&kept[..header]);
        let page = bytes::Bytes::from_owner(Lent(buffer.clone()));
        self.pages
            .push(page.slice(HEADROOM - header..HEADROOM + len));
        self.offsets
            .append_offset_and_size(self.compressed, spec.compressed_size as i32);
        self.offsets.append_row_count(rows as i64);
        self.compressed += spec.compressed_size as i64;
        self.uncompressed += spec.uncompressed_size as i64;
        self.values += rows;
        Ok(buffer)
    }

    /// The chunk of column `descr`, its pages all `encoding`, with its
    /// metadata and offset index as parquet-rs's column writer sets them
    /// (`statistics`, if any, the row group's).
    fn finish(
        self,
        descr: &ColumnDescPtr,
        encoding: Encoding,
        statistics: Option<Statistics>,
    ) -> Result<Chunk> {
        // The column writer lists RLE (its levels' encoding) for every chunk.
        let encodings = [Encoding::RLE, encoding];
        let mut metadata = ColumnChunkMetaData::builder(descr.clone())
            .set_compression(COMPRESSION)
            .set_encodings_mask(EncodingMask::new_from_encodings(encodings.iter()))
            .set_page_encoding_stats(vec![PageEncodingStats {
                page_type: PageType::DATA_PAGE,
                encoding,
                count: self.pages.len() as i32,
            }])
            .set_total_compressed_size(self.compressed)
            .set_total_uncompressed_size(self.uncompressed)
            .set_num_values(self.values as i64)
            .set_data_page_offset(0);
        if let Some(statistics) = statistics {
            metadata = metadata.set_statistics(statistics);
        }
        let close = ColumnCloseResult {
            bytes_written: self.compressed as u64,
            rows_written: self.values as u64,
            metadata: metadata.build()?,
            bloom_filter: None,
            column_index: None,
            offset_index: Some(self.offsets.build()),
        };
        Ok(Chunk {
            pages: self.pages,
            close,
        })
    }
}

/// The doubles `values` of column `descr` (a flat optional DOUBLE), all
/// present, as PLAIN pages of [`PAGE_BYTES`] each and a last one, without
/// statistics. Where `pattern` says how the values repeat, their Snappy
/// streams are egt's ([`repeats`]), and the [`Scan`] of the column comes
/// with the chunk (from the values the streams hold as literals; a page
/// Snappy's compressor takes is scanned). None when there are none, more
/// than [`PAGE_ROWS`], or the column is not such (parquet-rs writes those).
pub(super) fn doubles(
    descr: &ColumnDescPtr,
    values: &arrow_buffer::ScalarBuffer<f64>,
    pattern: Option<Pattern>,
) -> Result<Option<(Chunk, Option<Scan>)>> {
    let flat_optional = descr.max_def_level() == 1 && descr.max_rep_level() == 0;
    if values.is_empty()
        || values.len() > PAGE_ROWS
        || !flat_optional
        || descr.physical_type() != parquet::basic::Type::DOUBLE
    {
        return Ok(None);
    }
    let mut pages = Pages::default();
    let mut buffers = BUFFERS.with_borrow_mut(std::mem::take);
    let Buffers {
        plain: scratch,
        compressed,
        repeated,
        head,
        firsts,
        snappy,
    } = &mut buffers;
    let mut column: Option<Scan> = None;
    // PLAIN is little-endian, as Arrow holds doubles on this machine.
    #[cfg(target_endian = "little")]
    let bytes = values.inner().as_slice();
    #[cfg(not(target_endian = "little"))]
    let bytes = &values
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect::<Vec<u8>>();
    for (k, page) in bytes.chunks(PAGE_BYTES).enumerate() {
        let rows = page.len() / 8;
        // The definition levels, every one 1; then the values.
        scratch.clear();
        definition_levels(scratch, rows, 1);
        let plain = scratch.len() + page.len();
        let doubles = &values[k * (PAGE_BYTES / 8)..][..rows];
        // A grid's column: its repeats written as such (repeats.rs).
        let pattern = pattern.map(|p| p.skip(k * (PAGE_BYTES / 8)));
        let mut by_pattern = pattern.map(|_| repeated.take());
        let written = match (pattern, by_pattern.as_mut().and_then(Arc::get_mut)) {
            (Some(p), Some(out)) => {
                out.clear();
                out.resize(HEADROOM, 0);
                repeats::compress((scratch, doubles), p, snappy, (head, firsts), out)
                    .map(|literals| (out.len() - HEADROOM, literals))
            }
            _ => None,
        };
        let (buffer, len, pool, page_scan) = match (written, by_pattern) {
            (Some((len, literals)), Some(buffer)) => (buffer, len, &mut *repeated, Some(literals)),
            (_, unused) => {
                if let Some(buffer) = unused {
                    repeated.give(buffer);
                }
                scratch.extend_from_slice(page);
                let mut buffer = compressed.take();
                let len = compress(snappy, &mut buffer, scratch)?;
                let page_scan = pattern.map(|_| stats::scan(doubles));
                (buffer, len, &mut *compressed, page_scan)
            }
        };
        if let Some(page_scan) = page_scan {
            column = Some(column.map_or(page_scan, |c| c.and(page_scan)));
        }
        pool.give(pages.push(buffer, len, plain, rows, Encoding::PLAIN)?);
    }
    BUFFERS.set(buffers);
    let chunk = pages.finish(descr, Encoding::PLAIN, None)?;
    Ok(Some((chunk, column)))
}

/// Column `descr` (flat and optional) of `len` nulls, which parquet-rs
/// wrote with metadata `close`: its page (the definition levels, one RLE
/// run of 0s, and no values) with that metadata. None when the page is not
/// as long as the one parquet-rs wrote, or not alone in the chunk, or the
/// column is not such: parquet-rs writes those.
pub(super) fn nulls(
    descr: &ColumnDescPtr,
    len: usize,
    close: ColumnCloseResult,
) -> Result<Option<Chunk>> {
    let flat_optional = descr.max_def_level() == 1 && descr.max_rep_level() == 0;
    let one_page = close
        .offset_index
        .as_ref()
        .is_some_and(|o| o.page_locations().len() == 1);
    if len == 0 || !flat_optional || !one_page {
        return Ok(None);
    }
    let mut plain = Vec::new();
    definition_levels(&mut plain, len, 0);
    let mut buffer = Arc::default();
    let compressed = compress(&mut snap::raw::Encoder::new(), &mut buffer, &plain)?;
    let mut pages = Pages::default();
    pages.push(buffer, compressed, plain.len(), len, Encoding::PLAIN)?;
    if pages.compressed != close.metadata.compressed_size() {
        return Ok(None);
    }
    Ok(Some(Chunk {
        pages: pages.pages,
        close,
    }))
}

/// The definition levels of a flat optional column's data page (version 1:
/// their length first), `rows` of them all `level` (0 or 1): one RLE run.
fn definition_levels(out: &mut Vec<u8>, rows: usize, level: u8) {
    let start = out.len();
    out.extend_from_slice(&[0; 4]);
    uleb128(out, (rows as u64) << 1);
    out.push(level);
    let len = (out.len() - start - 4) as u32;
    out[start..start + 4].copy_from_slice(&len.to_le_bytes());
}

/// A thread's buffers for the pages of a chunk, kept from chunk to chunk
/// (a block's pages were fresh allocations, which the allocator zeroed or
/// the kernel cleared).
struct Buffers {
    /// A page before Snappy.
    plain: Vec<u8>,
    /// Pages after Snappy's compressor.
    compressed: Pool,
    /// Pages of a grid's column, compressed by egt ([`repeats`]): a pool of
    /// their own, as long as their streams, where `compressed`'s stay as
    /// long as Snappy's compressor wants (growing them again would clear
    /// them).
    repeated: Pool,
    /// The levels and first period of such a page, for Snappy.
    head: Vec<u8>,
    /// The first values of its runs.
    firsts: Vec<f64>,
    snappy: snap::raw::Encoder,
}

impl Default for Buffers {
    fn default() -> Self {
        Buffers {
            plain: Vec::new(),
            compressed: Pool::default(),
            repeated: Pool::default(),
            head: Vec::new(),
            firsts: Vec::new(),
            snappy: snap::raw::Encoder::new(),
        }
    }
}

/// Bytes before a compressed page in its buffer, where its header goes (a
/// data page's header without statistics takes about 20).
const HEADROOM: usize = 64;

/// Buffers of compressed pages, each taken again once the output has
/// written its page (the oldest first: pages go out in order).
#[derive(Default)]
struct Pool(VecDeque<Arc<Vec<u8>>>);

impl Pool {
    /// Buffers kept at most: more pages out at once than egt's blocks in
    /// flight hold are let go.
    const MOST: usize = 256;

    /// A buffer no page is written from any more, or a new one.
    fn take(&mut self) -> Arc<Vec<u8>> {
        if self
            .0
            .front_mut()
            .is_some_and(|b| Arc::get_mut(b).is_some())
        {
            return self.0.pop_front().unwrap_or_default();
        }
        Arc::default()
    }

    /// `buffer`, whose page is out, to be taken again once it is written.
    fn give(&mut self, buffer: Arc<Vec<u8>>) {
        if self.0.len() < Self::MOST {
            self.0.push_back(buffer);
        }
    }
}

/// The start of what parquet-rs's page writer writes: a page's header (the
/// page itself, after it, is not kept).
#[derive(Default)]
struct Header(Vec<u8>);

impl Write for Header {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let room = HEADROOM.saturating_sub(self.0.len());
        self.0.extend_from_slice(&buf[..room.min(buf.len())]);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

thread_local! {
    static BUFFERS: RefCell<Buffers> = RefCell::new(Buffers::default());
}

/// A share of a compressed page, as the bytes of a page.
struct Lent(Arc<Vec<u8>>);

impl AsRef<[u8]> for Lent {
    fn as_ref(&self) -> &[u8] {
        &self.0
    }
}

/// `input` compressed by Snappy, as parquet-rs's codec compresses a page,
/// into `out` after [`HEADROOM`] bytes (grown if need be; copied only if a
/// share of it is still out, which a buffer from a [`Pool`] has not), and
/// its length.
fn compress(
    snappy: &mut snap::raw::Encoder,
    out: &mut Arc<Vec<u8>>,
    input: &[u8],
) -> Result<usize> {
    let buffer = Arc::make_mut(out);
    let need = HEADROOM + snap::raw::max_compress_len(input.len());
    if buffer.len() < need {
        buffer.resize(need, 0);
    }
    snappy
        .compress(input, &mut buffer[HEADROOM..])
        .map_err(|e| parquet::errors::ParquetError::External(Box::new(e)))
}

/// Values a block of DELTA_BINARY_PACKED INT64 as parquet-rs writes it
/// (four mini-blocks of 64).
const BLOCK: usize = 256;

/// The DELTA_BINARY_PACKED encoding of `first`, `first + 1`, ... (`len`
/// of them, at least one): block size, mini-blocks a block, the count and
/// the first value; then, for each block of up to [`BLOCK`] deltas, the
/// least delta (1, zigzag-encoded: 2) and the four mini-blocks' bit widths
/// (0, so no packed bits follow; parquet-rs pads the mini-blocks a last
/// block leaves empty with 0 too).
fn consecutive_deltas(first: i64, len: usize, out: &mut Vec<u8>) {
    uleb128(out, BLOCK as u64);
    uleb128(out, 4);
    uleb128(out, len as u64);
    uleb128(out, ((first << 1) ^ (first >> 63)) as u64);
    for _ in 0..(len - 1).div_ceil(BLOCK) {
        out.extend_from_slice(&[2, 0, 0, 0, 0]);
    }
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::Splice;

    /// Whatever the sizes of the writes, and with drains between blocks, the
    /// output is the file: the bytes kept, each chunk in its hole (holes at
    /// the start, next to one another, of one byte, and at the end).
    #[test]
    fn splice_puts_chunks_in_their_holes_whatever_the_writes() {
        let file: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        let holes = [(0, 10), (10, 5), (100, 1), (500, 300), (999, 1)];
        let hole = |i: usize| holes.iter().any(|&(s, l)| (s..s + l).contains(&i));
        // parquet-rs's writer writes blanks where the holes are.
        let written: Vec<u8> = (file.iter().enumerate())
            .map(|(i, &b)| if hole(i) { 0 } else { b })
            .collect();
        // Each chunk in pages of up to 128 bytes.
        let chunk = |&(s, l): &(usize, usize)| {
            (file[s..s + l].chunks(128))
                .map(bytes::Bytes::copy_from_slice)
                .collect::<Vec<_>>()
        };
        for step in [1, 3, 7, 64, 1000] {
            let mut splice = Splice::default();
            for &(s, l) in &holes {
                splice
                    .hole(s as u64, l as u64)
                    .unwrap_or_else(|e| panic!("{e}"));
            }
            let mut out = Vec::new();
            // Two blocks: the first ends after the fourth hole.
            for (range, drained) in [(0..850, &holes[..4]), (850..1000, &holes[4..])] {
                for piece in written[range].chunks(step) {
                    splice.write_all(piece).unwrap_or_else(|e| panic!("{e}"));
                }
                let chunks: Vec<_> = drained.iter().map(chunk).collect();
                splice
                    .drain(&chunks, &mut out)
                    .unwrap_or_else(|e| panic!("{e}"));
            }
            assert!(out == file, "writes of {step} bytes");
        }
        // A chunk too few or too many is an error, not a broken file.
        let mut splice = Splice::default();
        splice.hole(2, 3).unwrap_or_else(|e| panic!("{e}"));
        splice.write_all(&[1; 8]).unwrap_or_else(|e| panic!("{e}"));
        assert!(splice.drain(&[], &mut Vec::new()).is_err());
        // So is a hole behind what was written, or behind the last hole.
        assert!(splice.hole(7, 1).is_err());
        let mut splice = Splice::default();
        splice.hole(4, 4).unwrap_or_else(|e| panic!("{e}"));
        assert!(splice.hole(6, 1).is_err());
    }
}
