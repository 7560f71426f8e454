//! Parquet data files (the cargo feature `parquet`): read with the
//! `parquet` crate's low-level column readers (no Arrow), row group by row
//! group and, within a group, [`BATCH`] rows at a time, so memory is a
//! batch of the columns the model reads, whatever the file's size. The
//! rows feed the same validating pass as CSV text, and every problem is
//! located by the row of the file, the row group and the row within it
//! (all from 0) and the column: `run.parquet: row 1234 (row group 1, row
//! 210), column `u``.
//!
//! Columns of physical type DOUBLE, FLOAT, INT32 and INT64 are read as
//! `f64` (an INT64 beyond ±2⁵³, which `f64` cannot hold exactly, is an
//! error). An INT64 TIMESTAMP column (milli-, micro- or nanoseconds, what
//! pandas writes for `datetime64`) is read as seconds since the file's first
//! stamp: the difference is taken in integers, then divided once, so the
//! times carry no rounding from large epoch values; a null is an error, as an empty CSV cell is; the experiment
//! column may be of any type (text, or numbers printed as text). Pages
//! compressed with Snappy, Zstandard, LZ4 or gzip are read.

use super::validate::{Places, Table, finite, missing, not_a_number};
use super::{DataError, open_path};
use parquet::column::reader::{ColumnReader, ColumnReaderImpl};
use parquet::data_type::DataType;
use parquet::file::reader::{FileReader, SerializedFileReader};
use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

/// Rows decoded at a time per column.
pub const BATCH: usize = 4096;

/// The largest integer every smaller one of which `f64` holds exactly: 2⁵³.
const EXACT: i64 = 1 << 53;

/// True when `path` names a Parquet file: its extension is `.parquet`, or
/// its first bytes are the magic `PAR1`.
pub fn is_parquet(path: &Path) -> bool {
    use std::io::Read;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"))
    {
        return true;
    }
    let mut magic = [0u8; 4];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok()
        && &magic == b"PAR1"
}

/// One decoded cell.
#[derive(Clone, Copy, Debug)]
enum Cell {
    /// A number (DOUBLE, FLOAT, INT32, INT64 within ±2⁵³).
    Num(f64),
    /// An INT64 beyond ±2⁵³.
    Big(i64),
    /// Text (BYTE_ARRAY, FIXED_LEN_BYTE_ARRAY): a range of the batch's text.
    Text(usize, usize),
    /// A BOOLEAN.
    Bool(bool),
    /// An INT96 (a legacy timestamp).
    Int96,
    /// A null.
    Null,
}

/// One column's decoded batch.
#[derive(Debug, Default)]
struct Batch {
    cells: Vec<Cell>,
    text: Vec<u8>,
}

/// A Parquet file read as a [`Table`].
pub struct ParquetFile {
    file: String,
    reader: SerializedFileReader<std::fs::File>,
    headers: Vec<String>,
    places: Places,
    /// The columns read (all until [`Table::select`] narrows them).
    selected: Vec<bool>,
    /// The next row group to open.
    group: usize,
    /// Readers of the current row group, per column (`None`: not read).
    readers: Vec<Option<ColumnReader>>,
    /// Rows of the current group not yet decoded.
    remaining: u64,
    batches: Vec<Batch>,
    /// Per column: units per second of an INT64 TIMESTAMP column, and the
    /// file's first stamp once read (what its seconds count from).
    stamps: Vec<Option<(f64, Option<i64>)>>,
    /// Rows in the current batch, and the current row's index in it.
    rows: usize,
    index: usize,
    /// The position of the batch's first row.
    batch_start: u64,
    started: bool,
}

impl std::fmt::Debug for ParquetFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParquetFile")
            .field("file", &self.file)
            .field("headers", &self.headers)
            .finish_non_exhaustive()
    }
}

/// The hint for a file the reader cannot decode.
const DAMAGED: &str = "a Parquet file ends with its metadata and the magic bytes PAR1, and a copy or a write cut short loses them: write the file again (pandas: df.to_parquet(path); pyarrow: pyarrow.parquet.write_table)";

impl ParquetFile {
    /// Opens a file and reads its metadata (the footer): a file that is
    /// not Parquet, is cut short or is damaged is one error naming it.
    pub fn open(path: &Path) -> Result<ParquetFile, DataError> {
        let (file, handle) = open_path(path, "--data")?;
        let size = handle.metadata().map(|m| m.len()).unwrap_or(0);
        if size == 0 {
            return Err(DataError::new(
                &file,
                "not a Parquet file: it is empty",
                DAMAGED,
            ));
        }
        let reader = guarded(|| SerializedFileReader::new(handle))
            .and_then(|r| r.map_err(|e| reason(&e)))
            .map_err(|e| {
                DataError::new(
                    &file,
                    format!("not a Parquet file, or a damaged one: {e}"),
                    DAMAGED,
                )
            })?;
        let metadata = reader.metadata();
        let schema = metadata.file_metadata().schema_descr();
        let headers: Vec<String> = (0..schema.num_columns())
            .map(|i| schema.column(i).path().string())
            .collect();
        let mut starts = Vec::with_capacity(metadata.num_row_groups());
        let mut start = 0u64;
        for g in metadata.row_groups() {
            starts.push(start);
            start += u64::try_from(g.num_rows()).unwrap_or(0);
        }
        let stamps = (0..schema.num_columns())
            .map(|i| stamp_units(&schema.column(i)).map(|per_second| (per_second, None)))
            .collect();
        let table = ParquetFile {
            file,
            headers,
            stamps,
            places: Places::Groups(Arc::from(starts)),
            selected: vec![true; schema.num_columns()],
            group: 0,
            readers: Vec::new(),
            remaining: 0,
            batches: (0..schema.num_columns())
                .map(|_| Batch::default())
                .collect(),
            rows: 0,
            index: 0,
            batch_start: 0,
            started: false,
            reader,
        };
        super::validate::unique_headers(&table.headers, |i| table.header_at(Some(i)))?;
        Ok(table)
    }

    /// Opens the next row group's readers; false after the last group.
    fn next_group(&mut self) -> Result<bool, DataError> {
        if self.group >= self.reader.num_row_groups() {
            return Ok(false);
        }
        let g = self.group;
        self.group += 1;
        let at = self.batch_start + self.rows as u64;
        let group = self
            .reader
            .get_row_group(g)
            .map_err(|e| self.damaged(at, None, &reason(&e)))?;
        self.remaining = u64::try_from(group.metadata().num_rows()).unwrap_or(0);
        let mut readers = Vec::with_capacity(self.headers.len());
        for (i, wanted) in self.selected.iter().enumerate() {
            readers.push(if *wanted {
                Some(
                    group
                        .get_column_reader(i)
                        .map_err(|e| self.damaged(at, Some(i), &reason(&e)))?,
                )
            } else {
                None
            });
        }
        drop(group);
        self.readers = readers;
        Ok(true)
    }

    /// Decodes the next batch of the current group (opening groups as
    /// needed); false at the end of the file.
    fn next_batch(&mut self) -> Result<bool, DataError> {
        self.batch_start += self.rows as u64;
        self.rows = 0;
        self.index = 0;
        while self.remaining == 0 {
            if !self.next_group()? {
                return Ok(false);
            }
        }
        let want = usize::try_from(self.remaining).map_or(BATCH, |r| r.min(BATCH));
        let schema = self.reader.metadata().file_metadata().schema_descr_ptr();
        for i in 0..self.headers.len() {
            let Some(reader) = self.readers[i].as_mut() else {
                continue;
            };
            let column = schema.column(i);
            if column.max_rep_level() > 0 {
                return Err(DataError::new(
                    self.places
                        .at(&self.file, self.batch_start, Some((i, &self.headers[i]))),
                    format!(
                        "column `{}` is a list (repeated); leeway reads one value per row",
                        self.headers[i]
                    ),
                    "store one scalar per row and column",
                ));
            }
            let max_def = column.max_def_level();
            let batch = &mut self.batches[i];
            let stamp = self.stamps[i].as_mut();
            let read = guarded(|| fill(reader, max_def, want, batch, stamp))
                .and_then(|r| r.map_err(|e| reason(&e)));
            match read {
                Ok(n) if n == want => {}
                Ok(n) => {
                    let at = self.batch_start + n as u64;
                    return Err(self.damaged(
                        at,
                        Some(i),
                        &format!("the column chunk ends after {n} of {want} rows"),
                    ));
                }
                Err(e) => return Err(self.damaged(self.batch_start, Some(i), &e)),
            }
        }
        self.remaining -= want as u64;
        self.rows = want;
        Ok(true)
    }

    /// A decoding failure at `position` (in column `column`).
    fn damaged(&self, position: u64, column: Option<usize>, why: &str) -> DataError {
        let (what, hint) = if why.contains("isabled feature") || why.contains("not supported") {
            (
                format!("cannot decode the Parquet data, its compression is not read here: {why}"),
                "this leeway reads pages compressed with Snappy, Zstandard, LZ4 or gzip (or none): write the file with one of them (pyarrow's default is Snappy)",
            )
        } else {
            (
                format!("cannot decode the Parquet data (a damaged file?): {why}"),
                DAMAGED,
            )
        };
        DataError::new(
            self.places.at(
                &self.file,
                position,
                column.map(|i| (i, self.headers[i].as_str())),
            ),
            what,
            hint,
        )
    }

    /// The current cell of column `i`.
    fn cell(&self, i: usize) -> Cell {
        self.batches[i]
            .cells
            .get(self.index)
            .copied()
            .unwrap_or(Cell::Null)
    }

    /// The physical type of column `i`, for messages.
    fn type_name(&self, i: usize) -> String {
        let schema = self.reader.metadata().file_metadata().schema_descr();
        schema.column(i).physical_type().to_string()
    }
}

/// A parquet error's text without its `Parquet error: ` prefix.
fn reason(e: &parquet::errors::ParquetError) -> String {
    let text = e.to_string();
    text.strip_prefix("Parquet error: ")
        .map_or(text.clone(), str::to_string)
}

/// Runs a call into the parquet crate, turning a panic on a malformed file
/// into an error: a damaged file must never crash leeway.
fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| (*s).to_string()))
            .unwrap_or_else(|| "the decoder stopped on malformed data".to_string())
    })
}

/// Units per second of an INT64 TIMESTAMP column (the logical type, or the
/// legacy converted types); `None` for any other column.
fn stamp_units(column: &parquet::schema::types::ColumnDescriptor) -> Option<f64> {
    use parquet::basic::{ConvertedType, LogicalType, TimeUnit, Type};
    if column.physical_type() != Type::INT64 {
        return None;
    }
    match column.logical_type_ref() {
        Some(LogicalType::Timestamp(t)) => Some(match t.unit {
            TimeUnit::MILLIS => 1e3,
            TimeUnit::MICROS => 1e6,
            TimeUnit::NANOS => 1e9,
        }),
        _ => match column.converted_type() {
            ConvertedType::TIMESTAMP_MILLIS => Some(1e3),
            ConvertedType::TIMESTAMP_MICROS => Some(1e6),
            _ => None,
        },
    }
}

/// Decodes `n` rows of a column into `out`.
fn fill(
    reader: &mut ColumnReader,
    max_def: i16,
    n: usize,
    out: &mut Batch,
    stamp: Option<&mut (f64, Option<i64>)>,
) -> parquet::errors::Result<usize> {
    out.cells.clear();
    out.text.clear();
    match reader {
        ColumnReader::DoubleColumnReader(r) => typed(r, max_def, n, out, |v, _| Cell::Num(*v)),
        ColumnReader::FloatColumnReader(r) => {
            typed(r, max_def, n, out, |v, _| Cell::Num(f64::from(*v)))
        }
        ColumnReader::Int32ColumnReader(r) => {
            typed(r, max_def, n, out, |v, _| Cell::Num(f64::from(*v)))
        }
        ColumnReader::Int64ColumnReader(r) if stamp.is_some() => {
            let Some((per_second, origin)) = stamp else {
                unreachable!("guarded by the match arm")
            };
            typed(r, max_def, n, out, |v, _| {
                let first = *origin.get_or_insert(*v);
                // In integers first: no rounding from the epoch's magnitude.
                match v.checked_sub(first) {
                    #[allow(clippy::cast_precision_loss)]
                    Some(d) => Cell::Num(d as f64 / *per_second),
                    None => Cell::Big(*v),
                }
            })
        }
        ColumnReader::Int64ColumnReader(r) => typed(r, max_def, n, out, |v, _| {
            if (-EXACT..=EXACT).contains(v) {
                // Exact: |v| ≤ 2⁵³.
                #[allow(clippy::cast_precision_loss)]
                Cell::Num(*v as f64)
            } else {
                Cell::Big(*v)
            }
        }),
        ColumnReader::BoolColumnReader(r) => typed(r, max_def, n, out, |v, _| Cell::Bool(*v)),
        ColumnReader::Int96ColumnReader(r) => typed(r, max_def, n, out, |_, _| Cell::Int96),
        ColumnReader::ByteArrayColumnReader(r) => typed(r, max_def, n, out, |v, text| {
            let start = text.len();
            text.extend_from_slice(v.data());
            Cell::Text(start, text.len())
        }),
        ColumnReader::FixedLenByteArrayColumnReader(r) => typed(r, max_def, n, out, |v, text| {
            let start = text.len();
            text.extend_from_slice(v.data());
            Cell::Text(start, text.len())
        }),
    }
}

/// Decodes `n` rows of a typed column: nulls (definition level below the
/// maximum) become [`Cell::Null`], values go through `convert`.
fn typed<T: DataType>(
    reader: &mut ColumnReaderImpl<T>,
    max_def: i16,
    n: usize,
    out: &mut Batch,
    mut convert: impl FnMut(&T::T, &mut Vec<u8>) -> Cell,
) -> parquet::errors::Result<usize> {
    let mut values: Vec<T::T> = Vec::with_capacity(n);
    let mut defs: Vec<i16> = Vec::with_capacity(n);
    let mut rows = 0;
    while rows < n {
        let (records, _, _) = reader.read_records(
            n - rows,
            (max_def > 0).then_some(&mut defs),
            None,
            &mut values,
        )?;
        if records == 0 {
            break;
        }
        rows += records;
    }
    if max_def > 0 {
        let mut next = values.iter();
        for d in &defs {
            let cell = match (*d == max_def).then(|| next.next()).flatten() {
                Some(v) => convert(v, &mut out.text),
                None => Cell::Null,
            };
            out.cells.push(cell);
        }
    } else {
        for v in &values {
            let cell = convert(v, &mut out.text);
            out.cells.push(cell);
        }
    }
    Ok(rows.min(out.cells.len()))
}

impl Table for ParquetFile {
    fn file(&self) -> &str {
        &self.file
    }
    fn headers(&self) -> &[String] {
        &self.headers
    }
    fn places(&self) -> &Places {
        &self.places
    }
    fn header_at(&self, column: Option<usize>) -> String {
        match column.and_then(|i| self.headers.get(i)) {
            Some(c) => format!("{}: schema, column `{c}`", self.file),
            None => format!("{}: schema", self.file),
        }
    }
    fn first_position(&self) -> u64 {
        0
    }
    fn select(&mut self, columns: &[usize]) {
        for (i, s) in self.selected.iter_mut().enumerate() {
            *s = columns.contains(&i);
        }
    }
    fn next_row(&mut self) -> Result<bool, DataError> {
        if self.started && self.index + 1 < self.rows {
            self.index += 1;
            return Ok(true);
        }
        self.started = true;
        self.next_batch()
    }
    fn position(&self) -> u64 {
        self.batch_start + self.index as u64
    }
    fn number(&self, i: usize, name: &str) -> Result<f64, DataError> {
        let at = || self.at(self.position(), Some((i, name)));
        let text_hint = || {
            format!(
                "the column holds {} values; leeway reads numbers from DOUBLE, FLOAT, INT32 and INT64 columns: write it as numbers",
                self.type_name(i)
            )
        };
        match self.cell(i) {
            Cell::Num(v) => finite(v, at),
            Cell::Big(v) => Err(DataError::new(
                at(),
                format!(
                    "{v} is beyond ±2⁵³ (9007199254740992): a 64-bit float cannot hold it exactly"
                ),
                "leeway reads every value as a 64-bit float and will not round one silently: store the column as DOUBLE, or in a unit that keeps it within ±2⁵³",
            )),
            Cell::Null => Err(missing(at(), "null (a missing value)")),
            Cell::Text(a, b) => Err(not_a_number(
                at(),
                &String::from_utf8_lossy(&self.batches[i].text[a..b]),
                &text_hint(),
            )),
            Cell::Bool(v) => Err(not_a_number(at(), &v.to_string(), &text_hint())),
            Cell::Int96 => Err(not_a_number(at(), "INT96", &text_hint())),
        }
    }
    fn label(&self, i: usize) -> Result<Cow<'_, [u8]>, DataError> {
        Ok(match self.cell(i) {
            Cell::Num(v) => Cow::Owned(v.to_string().into_bytes()),
            Cell::Big(v) => Cow::Owned(v.to_string().into_bytes()),
            Cell::Text(a, b) => Cow::Borrowed(&self.batches[i].text[a..b]),
            Cell::Bool(v) => Cow::Owned(v.to_string().into_bytes()),
            Cell::Int96 => {
                return Err(not_a_number(
                    self.at(self.position(), Some((i, &self.headers[i]))),
                    "INT96",
                    "name experiments by text or integers",
                ));
            }
            Cell::Null => {
                return Err(missing(
                    self.at(self.position(), Some((i, &self.headers[i]))),
                    "null (a missing value)",
                ));
            }
        })
    }
}
