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

use parquet::basic::{Compression, Encoding, EncodingMask, PageType};
use parquet::column::page::{CompressedPage, Page, PageWriter};
use parquet::column::writer::ColumnCloseResult;
use parquet::errors::Result;
use parquet::file::metadata::{ColumnChunkMetaData, OffsetIndexBuilder, PageEncodingStats};
use parquet::file::statistics::{Statistics, ValueStatistics};
use parquet::file::writer::{SerializedPageWriter, SerializedRowGroupWriter, TrackedWrite};
use parquet::schema::types::ColumnDescPtr;

/// The compression of every Parquet column `egt batch` writes.
pub(super) const COMPRESSION: Compression = Compression::SNAPPY;

/// parquet-rs's limit of rows a data page (its default): the row numbers of
/// a block of at most this many rows take one page.
pub(super) const PAGE_ROWS: usize = 20_000;

/// A column chunk encoded by egt, to be appended to its row group.
pub(super) struct Chunk {
    bytes: bytes::Bytes,
    close: ColumnCloseResult,
}

impl Chunk {
    /// Append the chunk to `group`, as the next column.
    pub(super) fn append_to_row_group<W: std::io::Write + Send>(
        self,
        group: &mut SerializedRowGroupWriter<'_, W>,
    ) -> Result<()> {
        group.append_column(&self.bytes, self.close)
    }
}

/// The row numbers `first`, `first + 1`, ... (`len` of them) of column
/// `descr` (a required INT64, written DELTA_BINARY_PACKED), with their
/// row-group statistics; None when they would not fit one page or there
/// are none (parquet-rs writes those).
pub(super) fn row_numbers(descr: &ColumnDescPtr, first: u64, len: usize) -> Result<Option<Chunk>> {
    if len == 0 || len > PAGE_ROWS {
        return Ok(None);
    }
    let last = first + (len as u64 - 1);
    if last > i64::MAX as u64 {
        return Ok(None);
    }
    let mut plain = Vec::with_capacity(16 + 5 * (len - 1).div_ceil(BLOCK));
    consecutive_deltas(first as i64, len, &mut plain);
    let mut compressed = vec![0; snap::raw::max_compress_len(plain.len())];
    let n = snap::raw::Encoder::new()
        .compress(&plain, &mut compressed)
        .map_err(|e| parquet::errors::ParquetError::External(Box::new(e)))?;
    compressed.truncate(n);
    let page = Page::DataPage {
        buf: compressed.into(),
        num_values: len as u32,
        encoding: Encoding::DELTA_BINARY_PACKED,
        def_level_encoding: Encoding::RLE,
        rep_level_encoding: Encoding::RLE,
        statistics: None,
    };
    let mut sink = TrackedWrite::new(Vec::new());
    let spec =
        SerializedPageWriter::new(&mut sink).write_page(CompressedPage::new(page, plain.len()))?;
    let bytes = sink.into_inner()?;
    // Parquet keeps an unsigned 64-bit integer in INT64, bit for bit.
    let statistics =
        ValueStatistics::<i64>::new(Some(first as i64), Some(last as i64), None, Some(0), false)
            .with_backwards_compatible_min_max(descr.sort_order().is_signed());
    // The column writer lists RLE (its levels' encoding) for every chunk.
    let encodings = [Encoding::RLE, Encoding::DELTA_BINARY_PACKED];
    let metadata = ColumnChunkMetaData::builder(descr.clone())
        .set_compression(COMPRESSION)
        .set_encodings_mask(EncodingMask::new_from_encodings(encodings.iter()))
        .set_page_encoding_stats(vec![PageEncodingStats {
            page_type: PageType::DATA_PAGE,
            encoding: Encoding::DELTA_BINARY_PACKED,
            count: 1,
        }])
        .set_total_compressed_size(spec.compressed_size as i64)
        .set_total_uncompressed_size(spec.uncompressed_size as i64)
        .set_num_values(len as i64)
        .set_data_page_offset(spec.offset as i64)
        .set_statistics(Statistics::Int64(statistics))
        .build()?;
    let mut offsets = OffsetIndexBuilder::new();
    offsets.append_offset_and_size(spec.offset as i64, spec.compressed_size as i32);
    offsets.append_row_count(len as i64);
    let close = ColumnCloseResult {
        bytes_written: spec.bytes_written,
        rows_written: len as u64,
        metadata,
        bloom_filter: None,
        column_index: None,
        offset_index: Some(offsets.build()),
    };
    Ok(Some(Chunk {
        bytes: bytes.into(),
        close,
    }))
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

/// `v` as an unsigned LEB128 varint.
fn uleb128(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}
