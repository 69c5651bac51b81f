//! Parquet and Arrow IPC: a block's columns as Arrow arrays, encoded in
//! worker tasks by parquet-rs's column writers (or as an Arrow record
//! batch), and appended to the file in order.

use std::io::Write;

use egt_core::batch::BatchPlan;
use egt_core::numerics::linalg::COND_WARN;

use super::{BatchOutput, COLUMNAR_BLOCK, Encoded, warning_at};

/// A block's parameters or results, row- or column-major.
#[derive(Clone, Copy)]
pub(super) struct Matrix<'a> {
    pub(super) data: &'a [f64],
    /// `data` as an Arrow buffer, when the block lends it: whole columns
    /// of a column-major block are then slices of it, not copies.
    pub(super) shared: Option<&'a arrow_buffer::Buffer>,
    /// Columns and rows.
    pub(super) width: usize,
    pub(super) rows: usize,
    /// Column-major.
    pub(super) columns: bool,
}

impl Matrix<'_> {
    /// Row `r`, column `c`.
    #[inline]
    pub(super) fn at(&self, r: usize, c: usize) -> f64 {
        if self.columns {
            self.data[c * self.rows + r]
        } else {
            self.data[r * self.width + c]
        }
    }

    /// Column `c`, in row order.
    pub(super) fn column(&self, c: usize) -> arrow_buffer::ScalarBuffer<f64> {
        match (self.columns, self.shared) {
            (true, Some(b)) => arrow_buffer::ScalarBuffer::new(b.clone(), c * self.rows, self.rows),
            (true, None) => self.data[c * self.rows..][..self.rows].to_vec().into(),
            (false, _) => (self.data[c..].iter().step_by(self.width))
                .take(self.rows)
                .copied()
                .collect::<Vec<f64>>()
                .into(),
        }
    }

    /// Whether a row's value in column `c` is above `limit`.
    pub(super) fn any_above(&self, c: usize, limit: f64) -> bool {
        if self.columns {
            self.data[c * self.rows..][..self.rows]
                .iter()
                .any(|&x| x > limit)
        } else {
            (self.data[c..].iter().step_by(self.width))
                .take(self.rows)
                .any(|&x| x > limit)
        }
    }
}

/// One block of solved rows, for the columnar writers.
pub(super) struct Block<'a> {
    /// Its place among all blocks (the Parquet row group's index).
    pub(super) index: usize,
    pub(super) first_row: usize,
    pub(super) state: Option<&'a str>,
    pub(super) varied: &'a [(String, usize)],
    /// `params` holds the varied columns only, in `varied`'s order.
    pub(super) varied_only: bool,
    pub(super) params: Matrix<'a>,
    pub(super) results: Matrix<'a>,
    /// The plan's positions among the output columns, and its selected outputs.
    pub(super) positions: (&'a [usize], &'a [usize]),
    pub(super) messages: &'a [Option<String>],
    /// Some of `messages` are set.
    pub(super) any_failed: bool,
    /// Every row's condition numbers are below the warning's
    /// ([`egt_core::batch::Solved::bounded`]).
    pub(super) bounded: bool,
}

/// Parquet or Arrow IPC output: the CSV's columns, typed (row as an
/// unsigned integer, numbers as doubles, texts as strings), with nulls where
/// the CSV leaves a cell empty; one record batch (Parquet row group) per
/// block. Blocks are encoded in worker tasks ([`Encoder`], shared) and
/// appended in order ([`Sink`], the main thread's).
pub(super) fn columnar(
    kind: BatchOutput,
    states: bool,
    varied: &[(String, usize)],
    header: &[String],
    design: Option<String>,
) -> anyhow::Result<(Encoder, Sink)> {
    use arrow_schema::{DataType, Field};
    let mut fields = vec![Field::new("row", DataType::UInt64, false)];
    if states {
        fields.push(Field::new("state", DataType::Utf8, false));
    }
    for (name, _) in varied {
        fields.push(Field::new(name, DataType::Float64, true));
    }
    for name in header {
        fields.push(Field::new(name, DataType::Float64, true));
    }
    fields.push(Field::new("warning", DataType::Utf8, true));
    fields.push(Field::new("error", DataType::Utf8, true));
    let parameters: Vec<&str> = varied.iter().map(|v| v.0.as_str()).collect();
    columnar_file(kind, fields, header.len(), &parameters, design)
}

/// Values of a design at most written into a Parquet file's metadata
/// ([`design_metadata`]): 1 MiB of text or so.
const DESIGN_VALUES: usize = 1 << 16;

/// The design of a batch as JSON, for a Parquet file's key-value metadata
/// (`egt.design`): `--set`'s values, `--vary`'s arrays and `--grid`'s axes,
/// in order, and `--state`'s states; None for a `--rows` file, or a design
/// of more than [`DESIGN_VALUES`] values.
pub(super) fn design_metadata(args: &super::Args) -> Option<String> {
    let count: usize = (args.vary.iter().chain(&args.grid))
        .map(|(_, v)| v.len())
        .sum();
    if args.rows.is_some() || count > DESIGN_VALUES {
        return None;
    }
    let arrays = |a: &[(String, Vec<f64>)]| -> Vec<serde_json::Value> {
        (a.iter())
            .map(|(name, values)| serde_json::json!({ "name": name, "values": values }))
            .collect()
    };
    let set: serde_json::Map<String, serde_json::Value> = (args.set.iter())
        .map(|(name, v)| (name.clone(), serde_json::json!(v)))
        .collect();
    let design = serde_json::json!({
        "set": set,
        "vary": arrays(&args.vary),
        "grid": arrays(&args.grid),
        "state": args.state,
    });
    serde_json::to_string(&design).ok()
}

/// The CSV's long form of `--specs` (one row per output of each line),
/// typed: row, name, quantity, value (null on a failed line) and error.
pub(super) fn long_columnar(kind: BatchOutput) -> anyhow::Result<(Encoder, Sink)> {
    use arrow_schema::{DataType, Field};
    let fields = vec![
        Field::new("row", DataType::UInt64, false),
        Field::new("name", DataType::Utf8, false),
        Field::new("quantity", DataType::Utf8, false),
        Field::new("value", DataType::Float64, true),
        Field::new("error", DataType::Utf8, true),
    ];
    columnar_file(kind, fields, 0, &[], None)
}

/// The data page size limit of a Parquet file: a page of doubles holds
/// this many bytes of values, 8 192 values. (A block's column is 512 KiB,
/// and the writer's page buffers grow by doubling up to the page; with
/// pages smaller than the default 1 MiB they stay small: docs/performance.md (history: git log -p -- docs/benchmarks.md).)
pub(super) const PAGE_BYTES: usize = 64 * 1024;

/// parquet-rs's settings for a file of the columns of `schema`, of which
/// `parameters` are a design's varied parameters (measured on a 10^6-row
/// grid of a 6-link chain, 2 threads):
/// - Snappy, but not for the solver's doubles, which it hardly shrinks
///   (a computed double's low bits are noise) and spends time on;
/// - a varied parameter's column plain, and Snappy-compressed: a grid's or
///   a zip's values repeat (in runs, or in short cycles), which Snappy
///   finds. (Dictionary-encoded, the file was 15 % smaller, but hashing
///   every value took a fifth more CPU time.)
/// - the row numbers delta-encoded (they count up by one: a few bytes a
///   page);
/// - pages of 64 KiB rather than the default 1 MiB (the writer's page
///   buffers grow by doubling up to the page; with smaller pages they stay
///   small), and at most a block's rows;
/// - the numbers' statistics the row group's, not each page's: a row group
///   is a block (65 536 rows);
/// - the design (`--set`, `--vary`, `--grid`, `--state`) as JSON in the
///   file's key-value metadata, under `egt.design` ([`design_metadata`]).
fn parquet_properties(
    schema: &arrow_schema::Schema,
    parameters: &[&str],
    design: Option<String>,
) -> parquet::file::properties::WriterProperties {
    use arrow_schema::DataType;
    use parquet::basic::{Compression, Encoding};
    use parquet::file::properties::{EnabledStatistics, WriterProperties, WriterVersion};
    use parquet::schema::types::ColumnPath;
    let mut props = WriterProperties::builder()
        .set_writer_version(WriterVersion::PARQUET_1_0)
        .set_data_page_size_limit(PAGE_BYTES)
        .set_data_page_row_count_limit(COLUMNAR_BLOCK)
        .set_compression(Compression::SNAPPY)
        .set_dictionary_enabled(false)
        .set_column_encoding(ColumnPath::from("row"), Encoding::DELTA_BINARY_PACKED)
        .set_key_value_metadata(design.map(|d| {
            vec![parquet::file::metadata::KeyValue::new(
                "egt.design".to_string(),
                d,
            )]
        }));
    for field in schema.fields() {
        let path = || ColumnPath::from(field.name().as_str());
        if let DataType::Float64 | DataType::UInt64 = field.data_type() {
            props = props.set_column_statistics_enabled(path(), EnabledStatistics::Chunk);
        }
        if field.data_type() == &DataType::Float64 && !parameters.contains(&field.name().as_str()) {
            props = props.set_column_compression(path(), Compression::UNCOMPRESSED);
        }
    }
    props.build()
}

/// An encoder and a sink for the columns `fields` (`outputs` of them the
/// solver's, `parameters` a design's varied parameters; `design` the
/// Parquet file's `egt.design` metadata).
fn columnar_file(
    kind: BatchOutput,
    fields: Vec<arrow_schema::Field>,
    outputs: usize,
    parameters: &[&str],
    design: Option<String>,
) -> anyhow::Result<(Encoder, Sink)> {
    let schema = std::sync::Arc::new(arrow_schema::Schema::new(fields));
    let (factory, sink) = if kind == BatchOutput::Parquet {
        let props = parquet_properties(&schema, parameters, design);
        // The Arrow writer adds the Arrow schema to the file's metadata;
        // its lower half lets row groups be encoded in parallel.
        let (writer, factory) =
            parquet::arrow::ArrowWriter::try_new(Vec::new(), schema.clone(), Some(props))?
                .into_serialized_writer()?;
        (Some(factory), Sink::Parquet(Box::new(writer)))
    } else {
        let writer = arrow_ipc::writer::FileWriter::try_new(Vec::new(), &schema)?;
        (None, Sink::Arrow(Box::new(writer)))
    };
    let encoder = Encoder {
        schema,
        outputs,
        factory,
        null_arrays: std::sync::Mutex::default(),
    };
    Ok((encoder, sink))
}

/// Turns a block into Parquet column chunks or an Arrow record batch.
pub(super) struct Encoder {
    schema: arrow_schema::SchemaRef,
    /// Output columns (after row, state and the varied parameters).
    outputs: usize,
    /// Parquet's column writers, for each row group. None for Arrow IPC.
    factory: Option<parquet::arrow::arrow_writer::ArrowRowGroupWriterFactory>,
    /// Arrays of nulls only, of a type and a length ([`Encoder::null_column`]).
    null_arrays: std::sync::Mutex<Vec<arrow_array::ArrayRef>>,
}

/// A column of doubles, null where a value is not finite or its row
/// `failed` (None when no row of the block did; no null buffer when there
/// are no nulls).
fn doubles(
    values: arrow_buffer::ScalarBuffer<f64>,
    failed: Option<&[Option<String>]>,
) -> arrow_array::ArrayRef {
    let missing = |r: usize| failed.is_some_and(|f| f[r].is_some()) || !values[r].is_finite();
    let nulls = (failed.is_some() || !values.iter().all(|v| v.is_finite()))
        .then(|| {
            (0..values.len())
                .map(|r| !missing(r))
                .collect::<Vec<bool>>()
        })
        .filter(|valid| valid.contains(&false))
        .map(arrow_buffer::NullBuffer::from);
    let values = match &nulls {
        // Null slots hold 0 (never a NaN or an inf a reader might take up).
        Some(n) => values
            .iter()
            .enumerate()
            .map(|(r, &v)| if n.is_valid(r) { v } else { 0.0 })
            .collect::<Vec<f64>>()
            .into(),
        None => values,
    };
    std::sync::Arc::new(arrow_array::Float64Array::new(values, nulls))
}

/// A column of optional texts: all null without building one by one when
/// `text` gives none (the usual block: no warning, no error).
fn texts<'a>(
    len: usize,
    text: impl Fn(usize) -> Option<std::borrow::Cow<'a, str>>,
) -> arrow_array::ArrayRef {
    use arrow_array::StringArray;
    let first = (0..len).find(|&r| text(r).is_some());
    std::sync::Arc::new(match first {
        None => StringArray::new_null(len),
        Some(_) => StringArray::from_iter((0..len).map(text)),
    })
}

impl Encoder {
    /// Whether blocks become Parquet column chunks (else Arrow batches).
    pub(super) fn parquet(&self) -> bool {
        self.factory.is_some()
    }

    pub(super) fn encode(&self, plan: &BatchPlan, b: &Block<'_>) -> anyhow::Result<Encoded> {
        use arrow_array::{ArrayRef, StringArray, UInt64Array};
        use std::sync::Arc;
        let (params, results) = (b.params, b.results);
        let len = b.messages.len();
        let mut columns: Vec<ArrayRef> = Vec::with_capacity(self.schema.fields().len());
        let first = b.first_row as u64;
        columns.push(Arc::new(UInt64Array::from_iter_values(
            first..first + len as u64,
        )));
        if let Some(s) = b.state {
            columns.push(Arc::new(StringArray::from_iter_values(
                std::iter::repeat_n(s, len),
            )));
        }
        for (j, &(_, c)) in b.varied.iter().enumerate() {
            let values = params.column(if b.varied_only { j } else { c });
            columns.push(doubles(values, None));
        }
        let failed = |r: usize| b.messages[r].is_some();
        let any_failed = b.any_failed.then_some(b.messages);
        // Which of this plan's outputs fills each output column, if any.
        let mut source = vec![None; self.outputs];
        for (&pos, &i) in b.positions.0.iter().zip(b.positions.1) {
            source[pos] = Some(i);
        }
        for src in source {
            columns.push(match src {
                Some(i) => doubles(results.column(i), any_failed),
                None => self.null_column(&arrow_schema::DataType::Float64, len),
            });
        }
        // Most blocks have no row past the warning's limit: a scan of the
        // condition columns finds so, with no test row by row.
        let warned = !b.bounded
            && (plan.condition_columns().iter()).any(|&c| results.any_above(c, COND_WARN));
        columns.push(if warned {
            texts(len, |r| {
                if failed(r) {
                    None
                } else {
                    warning_at(plan, |c| results.at(r, c)).map(std::borrow::Cow::Owned)
                }
            })
        } else {
            self.null_column(&arrow_schema::DataType::Utf8, len)
        });
        columns.push(if b.any_failed {
            texts(len, |r| {
                b.messages[r].as_deref().map(std::borrow::Cow::Borrowed)
            })
        } else {
            self.null_column(&arrow_schema::DataType::Utf8, len)
        });
        self.record_batch(columns, b.index)
    }

    /// An array of `len` nulls of type `of`, one for every block of that
    /// length (a new one was 64 KiB of offsets to clear for a text column,
    /// every block).
    pub(super) fn null_column(
        &self,
        of: &arrow_schema::DataType,
        len: usize,
    ) -> arrow_array::ArrayRef {
        let mut kept = self.null_arrays.lock().unwrap_or_else(|e| e.into_inner());
        let found = kept.iter().find(|a| a.len() == len && a.data_type() == of);
        if let Some(array) = found {
            return array.clone();
        }
        let array = arrow_array::new_null_array(of, len);
        kept.push(array.clone());
        array
    }

    /// The columns, in the schema's order, as one Arrow record batch, or
    /// as the Parquet column chunks of row group `index` (encoded by
    /// parquet-rs's column writers).
    pub(super) fn record_batch(
        &self,
        columns: Vec<arrow_array::ArrayRef>,
        index: usize,
    ) -> anyhow::Result<Encoded> {
        let batch = arrow_array::RecordBatch::try_new(self.schema.clone(), columns)?;
        let Some(factory) = &self.factory else {
            return Ok(Encoded::Arrow(batch));
        };
        let writers = factory.create_column_writers(index)?;
        // Every column is flat: one leaf, so one writer, a column.
        anyhow::ensure!(
            writers.len() == batch.num_columns(),
            "a nested Parquet column"
        );
        let mut chunks = Vec::with_capacity(writers.len());
        for ((mut writer, array), field) in
            (writers.into_iter().zip(batch.columns())).zip(self.schema.fields())
        {
            for leaf in parquet::arrow::arrow_writer::compute_leaves(field, array)? {
                writer.write(&leaf)?;
            }
            chunks.push(writer.close()?);
        }
        Ok(Encoded::Parquet(chunks))
    }
}

/// The columnar files being written: each writes into a buffer that is
/// drained to the output after every block, so memory stays one wave of
/// blocks whatever the batch.
pub(super) enum Sink {
    Parquet(Box<parquet::file::writer::SerializedFileWriter<Vec<u8>>>),
    Arrow(Box<arrow_ipc::writer::FileWriter<Vec<u8>>>),
}

impl Sink {
    /// Append an encoded block and pass the bytes written so far on to `out`.
    pub(super) fn append(&mut self, encoded: Encoded, out: &mut dyn Write) -> anyhow::Result<()> {
        let bytes = match (self, encoded) {
            (Sink::Parquet(w), Encoded::Parquet(chunks)) => {
                let mut group = w.next_row_group()?;
                for chunk in chunks {
                    chunk.append_to_row_group(&mut group)?;
                }
                group.close()?;
                // (The writer counts the bytes it wrote, not those its
                // buffer holds: the buffer may be drained.)
                w.flush()?;
                w.inner_mut()
            }
            (Sink::Arrow(w), Encoded::Arrow(batch)) => {
                w.write(&batch)?;
                w.get_mut()
            }
            _ => anyhow::bail!("a block encoded for another output format"),
        };
        out.write_all(bytes)?;
        bytes.clear();
        Ok(())
    }

    /// Write the footer.
    pub(super) fn finish(self, out: &mut dyn Write) -> anyhow::Result<()> {
        let bytes = match self {
            Sink::Parquet(w) => w.into_inner()?,
            Sink::Arrow(mut w) => {
                w.finish()?;
                w.into_inner()?
            }
        };
        out.write_all(&bytes)?;
        Ok(())
    }
}
