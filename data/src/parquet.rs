//! Parquet data files (the cargo feature `parquet`): read with the
//! `parquet` crate's low-level column readers (no Arrow), row group by row
//! group and, within a group, [`BATCH`] rows at a time, so memory is a
//! batch of the columns the model reads, whatever the file's size. The
//! rows feed the same validating pass as CSV text, and every problem is
//! located by the row of the file, the row group and the row within it
//! (all from 0) and the column: `run.parquet: row 1234 (row group 1, row
//! 210), column `u``.
//!
//! A number is read as what its logical type says it is, or refused; it is
//! never read as another number (`Reading`): DOUBLE and FLOAT as they are;
//! signed integers (INT32, INT64) and unsigned ones (`UINT_8` … `UINT_64`,
//! stored in the same bits) as their value, an integer beyond ±2⁵³, which
//! `f64` cannot hold exactly, an error; a DECIMAL (stored as INT32, INT64 or
//! bytes) as its unscaled integer divided by `10^scale` — one correctly
//! rounded division, so the same bits as the decimal text in a CSV file —
//! with an unscaled value beyond ±2⁵³ an error. Dates and times (TIMESTAMP,
//! DATE, TIME) are read only as the time column, as seconds since the file's
//! first stamp: the difference is taken in integers, then divided once, so
//! the times carry no rounding from large epoch values. Other logical types
//! (INTERVAL, FLOAT16, UUID, JSON, …) and INT96 are refused by name. A null
//! is an error, as an empty CSV cell is; the experiment column may be of any
//! type (text, or numbers printed as text). Pages compressed with Snappy,
//! Zstandard, LZ4 or gzip are read, and a page's CRC-32, where the writer
//! stored one, is verified: a flipped bit is an error, not a changed number.
//!
//! A damaged file is one error: a panic inside the decoder (a damaged
//! footer's assertions included) is caught and reported as one, with the
//! panic hook quiet for that call only. The tests run a seeded mutation
//! campaign over a checksummed file.

use crate::error::DataError;
use crate::open::open_path;
use crate::validate::{ParsedRow, Places, Table, finite, missing, not_a_number};
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
/// it is a regular file whose first bytes are the magic `PAR1`. A pipe or
/// a device is not looked into: the bytes read would be gone for the CSV
/// reader (and a pipe without a writer would wait).
pub fn is_parquet(path: &Path) -> bool {
    use std::io::Read;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"))
    {
        return true;
    }
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let mut magic = [0u8; 4];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok()
        && &magic == b"PAR1"
}

/// How a column's stored values are read as numbers, from its physical
/// and logical types: never as another number.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Reading {
    /// DOUBLE, FLOAT or a signed integer: the value.
    Plain,
    /// An unsigned integer stored in the bits of an INT32 or INT64.
    Unsigned,
    /// A DECIMAL: the unscaled integer over `10^scale`.
    Decimal { scale: i32 },
    /// Dates and times, as seconds since the column's first stamp.
    Stamp(StampUnit),
    /// A logical type that is not a number leeway reads, by name.
    Refused(&'static str),
}

/// What one stored unit of a date or time column is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum StampUnit {
    /// This many units a second (milli-, micro-, nanoseconds).
    PerSecond(i64),
    /// A day (DATE).
    Day,
}

/// Exact powers of ten: every one up to 10²² is an `f64` exactly.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// One decoded cell.
#[derive(Clone, Copy, Debug)]
enum Cell {
    /// A number read exactly (or correctly rounded, as text would be).
    Num(f64),
    /// An integer beyond ±2⁵³ (an unscaled value and its scale), or a stamp
    /// too far from the first.
    Big(i128),
    /// Text (BYTE_ARRAY, FIXED_LEN_BYTE_ARRAY): a range of the batch's text.
    Text(usize, usize),
    /// A BOOLEAN.
    Bool(bool),
    /// An INT96 (a legacy timestamp), or a decimal wider than 128 bits.
    Unreadable,
    /// A null.
    Null,
}

/// One column's decoded batch.
#[derive(Debug, Default)]
struct Batch {
    cells: Vec<Cell>,
    text: Vec<u8>,
    /// A DOUBLE column's batch without nulls, as stored (then `cells` is
    /// empty): most columns, read without a cell each.
    doubles: Vec<f64>,
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
    /// Per column: how its values are read.
    readings: Vec<Reading>,
    /// Per column: the first stamp of a date or time column once read (what
    /// its seconds count from).
    origins: Vec<Option<i64>>,
    /// Rows in the current batch, and the current row's index in it.
    rows: usize,
    index: usize,
    /// The position of the batch's first row.
    batch_start: u64,
    started: bool,
    /// The batch's plain columns (DOUBLE without nulls, read as stored)
    /// row by row, `plain_width` values a row, NaN where a value is not
    /// finite (`number` refuses it with its place); each column's place in
    /// a row. What [`Table::parsed_row`] hands the validating pass, so that
    /// it reads a row without a call of [`Table::number`] a value.
    plain: Vec<f64>,
    plain_width: usize,
    plain_slots: Vec<Option<usize>>,
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
        // Asked before opening: a pipe without a writer would wait.
        if let Ok(m) = std::fs::metadata(path)
            && !m.is_file()
        {
            return Err(DataError::new(
                path.display().to_string(),
                "not a regular file (a directory, a pipe or a device): a Parquet file is read from its end",
                "save the Parquet data to a file and name that file",
            ));
        }
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
        // A list's values sit in a leaf `name.list.element`: it is named by
        // its field, so that reading it says it is a list, not missing.
        let headers: Vec<String> = (0..schema.num_columns())
            .map(|i| {
                let column = schema.column(i);
                match column.path().parts().first() {
                    Some(field) if column.max_rep_level() > 0 => field.clone(),
                    _ => column.path().string(),
                }
            })
            .collect();
        let mut starts = Vec::with_capacity(metadata.num_row_groups());
        let mut start = 0u64;
        for g in metadata.row_groups() {
            starts.push(start);
            start += u64::try_from(g.num_rows()).unwrap_or(0);
        }
        let readings = (0..schema.num_columns())
            .map(|i| reading(&schema.column(i)))
            .collect();
        let table = ParquetFile {
            file,
            headers,
            readings,
            origins: vec![None; schema.num_columns()],
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
            plain: Vec::new(),
            plain_width: 0,
            plain_slots: vec![None; schema.num_columns()],
            reader,
        };
        crate::validate::unique_headers(&table.headers, |i| table.header_at(Some(i)))?;
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
        // A damaged footer can make the crate panic here (a negative
        // offset is an assertion): a damaged file is an error, not a crash.
        let group = guarded(|| self.reader.get_row_group(g))
            .and_then(|r| r.map_err(|e| reason(&e)))
            .map_err(|e| self.damaged(at, None, &e))?;
        self.remaining = u64::try_from(group.metadata().num_rows()).unwrap_or(0);
        let mut readers = Vec::with_capacity(self.headers.len());
        for (i, wanted) in self.selected.iter().enumerate() {
            readers.push(if *wanted {
                Some(
                    guarded(|| group.get_column_reader(i))
                        .and_then(|r| r.map_err(|e| reason(&e)))
                        .map_err(|e| self.damaged(at, Some(i), &e))?,
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
            let (reading, origin) = (self.readings[i], &mut self.origins[i]);
            let read = guarded(|| fill(reader, max_def, want, batch, reading, origin))
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
        self.gather_plain();
        Ok(true)
    }

    /// Lays the batch's plain columns into `plain`, row by row: those
    /// whose values [`Table::number`] takes as stored (a refused column's
    /// values are never handed over).
    fn gather_plain(&mut self) {
        let rows = self.rows;
        let mut width = 0;
        for (i, slot) in self.plain_slots.iter_mut().enumerate() {
            let read = self.readers.get(i).is_some_and(Option::is_some);
            let refused = matches!(self.readings[i], Reading::Refused(_));
            let plain = read && !refused && self.batches[i].doubles.len() >= rows;
            *slot = plain.then(|| {
                width += 1;
                width - 1
            });
        }
        self.plain_width = width;
        self.plain.clear();
        self.plain.resize(rows * width, f64::NAN);
        for (batch, slot) in self.batches.iter().zip(&self.plain_slots) {
            let Some(slot) = *slot else { continue };
            for (row, &v) in self.plain[slot..]
                .iter_mut()
                .step_by(width)
                .zip(&batch.doubles[..rows])
            {
                // Left to `number`, which refuses it with its place.
                *row = if v.is_finite() { v } else { f64::NAN };
            }
        }
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
        let batch = &self.batches[i];
        if let Some(&v) = batch.doubles.get(self.index) {
            return Cell::Num(v);
        }
        batch.cells.get(self.index).copied().unwrap_or(Cell::Null)
    }

    /// A value beyond ±2⁵³ as written: a decimal's unscaled integer with
    /// its point put back.
    fn big_text(&self, i: usize, v: i128) -> String {
        match self.readings[i] {
            Reading::Decimal { scale } if scale > 0 => {
                let digits = v.unsigned_abs().to_string();
                let scale = usize::try_from(scale).unwrap_or(0);
                let digits = format!("{digits:0>width$}", width = scale + 1);
                let (whole, fraction) = digits.split_at(digits.len() - scale);
                let sign = if v < 0 { "-" } else { "" };
                format!("{sign}{whole}.{fraction}")
            }
            _ => v.to_string(),
        }
    }

    /// The type of column `i`, for messages: its logical type where it has
    /// one, with its physical type (`DECIMAL(18, 6) (INT64)`).
    fn type_name(&self, i: usize) -> String {
        use parquet::basic::{ConvertedType, LogicalType as L};
        let schema = self.reader.metadata().file_metadata().schema_descr();
        let column = schema.column(i);
        let physical = column.physical_type();
        let logical = match column.logical_type_ref() {
            Some(L::Timestamp(t)) => format!("TIMESTAMP({:?})", t.unit),
            Some(L::Time(t)) => format!("TIME({:?})", t.unit),
            Some(L::Date) => "DATE".to_string(),
            Some(L::Decimal(d)) => format!("DECIMAL({}, {})", d.precision, d.scale),
            Some(L::Integer(i)) => {
                format!("{}INT{}", if i.is_signed { "" } else { "U" }, i.bit_width)
            }
            Some(l) => format!("{l:?}").to_uppercase(),
            None if column.converted_type() != ConvertedType::NONE => {
                column.converted_type().to_string()
            }
            None => return physical.to_string(),
        };
        format!("{logical} ({physical})")
    }
}

/// A parquet error's text without its `Parquet error: ` prefix.
fn reason(e: &parquet::errors::ParquetError) -> String {
    let text = e.to_string();
    text.strip_prefix("Parquet error: ")
        .map_or(text.clone(), str::to_string)
}

std::thread_local! {
    /// Set while [`guarded`] runs a call: its panic is an error, not news.
    static GUARDED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs a call into the parquet crate, turning a panic on a malformed file
/// into an error: a damaged file must never crash leeway, nor print a
/// panic message beside its one clear error (the panic hook, wrapped once,
/// stays quiet for a guarded call and speaks for every other panic).
fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static QUIET_HOOK: std::sync::Once = std::sync::Once::new();
    QUIET_HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !GUARDED.with(std::cell::Cell::get) {
                previous(info);
            }
        }));
    });
    let outer = GUARDED.with(|g| g.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    GUARDED.with(|g| g.set(outer));
    result.map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| (*s).to_string()))
            .unwrap_or_else(|| "the decoder stopped on malformed data".to_string())
    })
}

/// How a column's values are read, from its logical type (or the legacy
/// converted type of older writers).
fn reading(column: &parquet::schema::types::ColumnDescriptor) -> Reading {
    use parquet::basic::{ConvertedType as C, LogicalType as L, TimeUnit, Type};
    let per_second = |unit: &TimeUnit| {
        StampUnit::PerSecond(match unit {
            TimeUnit::MILLIS => 1_000,
            TimeUnit::MICROS => 1_000_000,
            TimeUnit::NANOS => 1_000_000_000,
        })
    };
    match (column.logical_type_ref(), column.converted_type()) {
        (Some(L::Timestamp(t) | L::Time(t)), _) => Reading::Stamp(per_second(&t.unit)),
        (Some(L::Date), _) | (_, C::DATE) => Reading::Stamp(StampUnit::Day),
        (_, C::TIMESTAMP_MILLIS | C::TIME_MILLIS) => Reading::Stamp(StampUnit::PerSecond(1_000)),
        (_, C::TIMESTAMP_MICROS | C::TIME_MICROS) => {
            Reading::Stamp(StampUnit::PerSecond(1_000_000))
        }
        (Some(L::Decimal(d)), _) => Reading::Decimal { scale: d.scale },
        (_, C::DECIMAL) => Reading::Decimal {
            scale: column.type_scale(),
        },
        (Some(L::Integer(i)), _) if !i.is_signed => Reading::Unsigned,
        (_, C::UINT_8 | C::UINT_16 | C::UINT_32 | C::UINT_64) => Reading::Unsigned,
        (Some(L::Float16), _) => Reading::Refused("FLOAT16 (half-precision) values"),
        (_, C::INTERVAL) => Reading::Refused("INTERVAL values"),
        (Some(L::Uuid), _) => Reading::Refused("UUIDs"),
        (Some(L::Json | L::Bson | L::Variant(_)), _) => Reading::Refused("documents"),
        (Some(L::Unknown), _) => Reading::Refused("nulls only (the null type)"),
        _ if column.physical_type() == Type::INT96 => {
            Reading::Refused("INT96 values (a legacy timestamp)")
        }
        _ => Reading::Plain,
    }
}

/// An integer as a cell: exact within ±2⁵³, else [`Cell::Big`].
fn integer(v: i128) -> Cell {
    if (-i128::from(EXACT)..=i128::from(EXACT)).contains(&v) {
        // Exact: |v| ≤ 2⁵³.
        #[allow(clippy::cast_precision_loss)]
        Cell::Num(v as f64)
    } else {
        Cell::Big(v)
    }
}

/// A decimal's value: its unscaled integer over `10^scale`, correctly
/// rounded — the same bits as its decimal text read from a CSV file. An
/// unscaled integer and a power of ten that are both exact take one
/// division; any other is read from its text (`unscaled`e`-scale`), which
/// Rust's parser rounds correctly too. An unscaled integer beyond ±2⁵³ is
/// refused as an integer is (the digits beyond a float's are dropped
/// otherwise).
fn decimal(unscaled: i128, scale: i32) -> Cell {
    match integer(unscaled) {
        Cell::Num(v) => match usize::try_from(scale).ok().and_then(|s| POW10.get(s)) {
            Some(p) => Cell::Num(v / p),
            None => format!("{unscaled}e{}", -i64::from(scale))
                .parse()
                .map_or(Cell::Unreadable, Cell::Num),
        },
        other => other,
    }
}

/// A decimal stored as bytes: a big-endian two's complement integer (at
/// most 16 bytes: wider ones are [`Cell::Unreadable`]).
fn decimal_bytes(bytes: &[u8], scale: i32) -> Cell {
    if bytes.is_empty() || bytes.len() > 16 {
        return Cell::Unreadable;
    }
    let fill = if bytes[0] & 0x80 != 0 { 0xff } else { 0 };
    let mut wide = [fill; 16];
    wide[16 - bytes.len()..].copy_from_slice(bytes);
    decimal(i128::from_be_bytes(wide), scale)
}

/// A date or time as seconds since the column's first stamp `origin` (set
/// by the first): the difference in integers first, then one division, so
/// large epoch values add no rounding.
fn stamp(v: i64, unit: StampUnit, origin: &mut Option<i64>) -> Cell {
    let first = *origin.get_or_insert(v);
    let Some(d) = v.checked_sub(first) else {
        return Cell::Big(i128::from(v));
    };
    #[allow(clippy::cast_precision_loss)]
    match unit {
        StampUnit::PerSecond(n) => Cell::Num(d as f64 / n as f64),
        // |d| < 2³² days: d·86400 < 2⁴⁹, exact.
        StampUnit::Day => Cell::Num(d as f64 * 86_400.0),
    }
}

/// Decodes `n` rows of a column into `out`, each read as `reading` says
/// (`origin`: a date or time column's first stamp).
fn fill(
    reader: &mut ColumnReader,
    max_def: i16,
    n: usize,
    out: &mut Batch,
    reading: Reading,
    origin: &mut Option<i64>,
) -> parquet::errors::Result<usize> {
    out.cells.clear();
    out.text.clear();
    out.doubles.clear();
    // An UINT's value is its stored bits read unsigned: the casts below.
    #[allow(clippy::cast_sign_loss)]
    match reader {
        ColumnReader::DoubleColumnReader(r) => {
            let (values, defs, rows) = records(r, max_def, n)?;
            if defs.iter().all(|d| *d == max_def) {
                out.doubles = values;
                return Ok(rows.min(out.doubles.len()));
            }
            Ok(cells(values, &defs, max_def, rows, out, |v, _| {
                Cell::Num(*v)
            }))
        }
        ColumnReader::FloatColumnReader(r) => {
            typed(r, max_def, n, out, |v, _| Cell::Num(f64::from(*v)))
        }
        ColumnReader::Int32ColumnReader(r) => typed(r, max_def, n, out, |v, _| match reading {
            Reading::Stamp(unit) => stamp(i64::from(*v), unit, origin),
            Reading::Unsigned => Cell::Num(f64::from(*v as u32)),
            Reading::Decimal { scale } => decimal(i128::from(*v), scale),
            Reading::Plain | Reading::Refused(_) => Cell::Num(f64::from(*v)),
        }),
        ColumnReader::Int64ColumnReader(r) => typed(r, max_def, n, out, |v, _| match reading {
            Reading::Stamp(unit) => stamp(*v, unit, origin),
            Reading::Unsigned => integer(i128::from(*v as u64)),
            Reading::Decimal { scale } => decimal(i128::from(*v), scale),
            Reading::Plain | Reading::Refused(_) => integer(i128::from(*v)),
        }),
        ColumnReader::BoolColumnReader(r) => typed(r, max_def, n, out, |v, _| Cell::Bool(*v)),
        ColumnReader::Int96ColumnReader(r) => typed(r, max_def, n, out, |_, _| Cell::Unreadable),
        ColumnReader::ByteArrayColumnReader(r) => {
            typed(r, max_def, n, out, |v, text| bytes(v.data(), reading, text))
        }
        ColumnReader::FixedLenByteArrayColumnReader(r) => {
            typed(r, max_def, n, out, |v, text| bytes(v.data(), reading, text))
        }
    }
}

/// A cell stored as bytes: a decimal's value, else text.
fn bytes(data: &[u8], reading: Reading, text: &mut Vec<u8>) -> Cell {
    if let Reading::Decimal { scale } = reading {
        return decimal_bytes(data, scale);
    }
    let start = text.len();
    text.extend_from_slice(data);
    Cell::Text(start, text.len())
}

/// Decodes `n` rows of a typed column: nulls (definition level below the
/// maximum) become [`Cell::Null`], values go through `convert`.
fn typed<T: DataType>(
    reader: &mut ColumnReaderImpl<T>,
    max_def: i16,
    n: usize,
    out: &mut Batch,
    convert: impl FnMut(&T::T, &mut Vec<u8>) -> Cell,
) -> parquet::errors::Result<usize> {
    let (values, defs, rows) = records(reader, max_def, n)?;
    Ok(cells(values, &defs, max_def, rows, out, convert))
}

/// The next `n` rows of a typed column: its values, their definition
/// levels (none for a required column) and how many rows were read.
fn records<T: DataType>(
    reader: &mut ColumnReaderImpl<T>,
    max_def: i16,
    n: usize,
) -> parquet::errors::Result<(Vec<T::T>, Vec<i16>, usize)> {
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
    Ok((values, defs, rows))
}

/// The cells of `rows` read rows: nulls where the definition level is
/// below the maximum, the values through `convert`.
fn cells<T>(
    values: Vec<T>,
    defs: &[i16],
    max_def: i16,
    rows: usize,
    out: &mut Batch,
    mut convert: impl FnMut(&T, &mut Vec<u8>) -> Cell,
) -> usize {
    if max_def > 0 {
        let mut next = values.iter();
        for d in defs {
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
    rows.min(out.cells.len())
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
    fn parsed_row(&self) -> Option<ParsedRow<'_>> {
        let w = self.plain_width;
        Some(ParsedRow {
            values: self.plain.get(self.index * w..(self.index + 1) * w)?,
            slots: &self.plain_slots,
        })
    }
    fn number(&self, i: usize, name: &str) -> Result<f64, DataError> {
        let at = || self.at(self.position(), Some((i, name)));
        let text_hint = || {
            format!(
                "the column holds {} values; leeway reads numbers from DOUBLE, FLOAT, integer and DECIMAL columns: write it as numbers",
                self.type_name(i)
            )
        };
        if let Reading::Refused(what) = self.readings[i] {
            return Err(DataError::new(
                at(),
                format!(
                    "column `{name}` holds {what} ({}), not numbers leeway reads",
                    self.type_name(i)
                ),
                "write the column as DOUBLE (pandas: df[c].astype(\"float64\")); leeway does not convert other types",
            ));
        }
        // Most columns: a DOUBLE without nulls, its value finite.
        if let Some(v) = self.parsed_row().and_then(|p| p.get(i)) {
            return Ok(v);
        }
        match self.cell(i) {
            Cell::Num(v) => finite(v, at),
            Cell::Big(v) => Err(DataError::new(
                at(),
                format!(
                    "{} is beyond ±2⁵³ (9007199254740992): a 64-bit float cannot hold it exactly",
                    self.big_text(i, v)
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
            Cell::Unreadable => Err(not_a_number(at(), &self.type_name(i), &text_hint())),
        }
    }
    fn stamps(&self, i: usize) -> Option<String> {
        matches!(self.readings.get(i), Some(Reading::Stamp(_))).then(|| self.type_name(i))
    }
    fn stamp_origin(&self, i: usize) -> Option<i64> {
        let first = (*self.origins.get(i)?)?;
        match self.readings.get(i)? {
            Reading::Stamp(StampUnit::PerSecond(n)) => first.checked_mul(1_000_000_000 / n),
            Reading::Stamp(StampUnit::Day) => first.checked_mul(86_400_000_000_000),
            _ => None,
        }
    }
    fn label(&self, i: usize) -> Result<Cow<'_, [u8]>, DataError> {
        Ok(match self.cell(i) {
            Cell::Num(v) => Cow::Owned(v.to_string().into_bytes()),
            Cell::Big(v) => Cow::Owned(self.big_text(i, v).into_bytes()),
            Cell::Text(a, b) => Cow::Borrowed(&self.batches[i].text[a..b]),
            Cell::Bool(v) => Cow::Owned(v.to_string().into_bytes()),
            Cell::Unreadable => {
                return Err(not_a_number(
                    self.at(self.position(), Some((i, &self.headers[i]))),
                    &self.type_name(i),
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

#[cfg(test)]
mod tests {
    //! Every logical type read as what it means, or refused with a located
    //! error: files written here with the crate's own writer.
    use super::*;
    use parquet::data_type::{ByteArray, FixedLenByteArray, Int32Type, Int64Type};
    use parquet::file::properties::WriterProperties;
    use parquet::file::writer::SerializedFileWriter;
    use parquet::schema::parser::parse_message_type;

    /// One column: its schema line (`required int32 x (DATE)`) and values.
    enum Values {
        I32(Vec<i32>),
        I64(Vec<i64>),
        Fixed(Vec<Vec<u8>>),
        Bytes(Vec<Vec<u8>>),
        /// An optional DOUBLE column (`None`: a null).
        F64(Vec<Option<f64>>),
    }

    fn write(path: &Path, columns: &[(&str, Values)]) {
        let fields: Vec<&str> = columns.iter().map(|(f, _)| *f).collect();
        let schema = Arc::new(
            parse_message_type(&format!("message t {{ {} }}", fields.join(" ")))
                .unwrap_or_else(|e| panic!("{e}")),
        );
        let props = WriterProperties::builder().build();
        let file = std::fs::File::create(path).unwrap_or_else(|e| panic!("{e}"));
        let mut writer = SerializedFileWriter::new(file, schema, Arc::new(props))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut group = writer.next_row_group().unwrap_or_else(|e| panic!("{e}"));
        for (_, values) in columns {
            let mut col = group
                .next_column()
                .unwrap_or_else(|e| panic!("{e}"))
                .unwrap_or_else(|| panic!("a column"));
            let written = match values {
                Values::I32(v) => col.typed::<Int32Type>().write_batch(v, None, None),
                Values::I64(v) => col.typed::<Int64Type>().write_batch(v, None, None),
                Values::Fixed(v) => {
                    let v: Vec<FixedLenByteArray> = v
                        .iter()
                        .map(|b| FixedLenByteArray::from(ByteArray::from(b.clone())))
                        .collect();
                    col.typed::<parquet::data_type::FixedLenByteArrayType>()
                        .write_batch(&v, None, None)
                }
                Values::Bytes(v) => {
                    let v: Vec<ByteArray> = v.iter().map(|b| ByteArray::from(b.clone())).collect();
                    col.typed::<parquet::data_type::ByteArrayType>()
                        .write_batch(&v, None, None)
                }
                Values::F64(v) => {
                    let present: Vec<f64> = v.iter().flatten().copied().collect();
                    let defs: Vec<i16> = v.iter().map(|x| i16::from(x.is_some())).collect();
                    col.typed::<parquet::data_type::DoubleType>().write_batch(
                        &present,
                        Some(&defs),
                        None,
                    )
                }
            };
            written.unwrap_or_else(|e| panic!("{e}"));
            col.close().unwrap_or_else(|e| panic!("{e}"));
        }
        group.close().unwrap_or_else(|e| panic!("{e}"));
        writer.close().unwrap_or_else(|e| panic!("{e}"));
    }

    /// Every row of column `i` read as a number (or the first error).
    fn numbers(path: &Path, i: usize) -> Result<Vec<f64>, DataError> {
        let mut t = ParquetFile::open(path)?;
        let name = t.headers()[i].clone();
        let mut out = Vec::new();
        while t.next_row()? {
            let v = number_as_handed_over(&t, i, &name)?;
            out.push(v);
        }
        Ok(out)
    }

    /// Cell `i` of the current row through [`Table::number`], after
    /// checking that the value [`Table::parsed_row`] hands over (if any)
    /// is its bits, and that a cell `number` refuses is never handed over.
    fn number_as_handed_over(t: &ParquetFile, i: usize, name: &str) -> Result<f64, DataError> {
        let ahead = t.parsed_row().and_then(|p| p.get(i));
        let v = t.number(i, name);
        match &v {
            Ok(v) => assert!(
                ahead.is_none_or(|a| a.to_bits() == v.to_bits()),
                "row {}: handed over {ahead:?}, read {v}",
                t.position()
            ),
            Err(e) => assert!(
                ahead.is_none(),
                "row {}: handed over {ahead:?}, yet {e}",
                t.position()
            ),
        }
        v
    }

    #[test]
    fn plain_doubles_are_handed_over_as_number_reads_them() {
        // Three batches and a bit; an infinity and a NaN (refused by
        // `number` with their place) and a null (its batch read cell by
        // cell) in some of them.
        let n = 3 * BATCH + 5;
        let a: Vec<Option<f64>> = (0..n)
            .map(|k| {
                Some(match k {
                    17 => f64::INFINITY,
                    5000 => f64::NAN,
                    _ => k as f64 * 0.1 - 3.0,
                })
            })
            .collect();
        let b: Vec<Option<f64>> = (0..n)
            .map(|k| (k != 2 * BATCH + 1).then_some(-(k as f64)))
            .collect();
        let c: Vec<Option<f64>> = (0..n).map(|k| Some(k as f64 / 7.0)).collect();
        let (_dir, path) = scratch("plain.parquet");
        write(
            &path,
            &[
                ("optional double a;", Values::F64(a.clone())),
                ("optional double b;", Values::F64(b.clone())),
                ("optional double c;", Values::F64(c.clone())),
            ],
        );
        let mut t = ParquetFile::open(&path).unwrap_or_else(|e| panic!("{e}"));
        let (mut handed, mut refused) = ([0usize; 3], [0usize; 3]);
        while t.next_row().unwrap_or_else(|e| panic!("{e}")) {
            let k = usize::try_from(t.position()).unwrap_or(usize::MAX);
            for (i, column) in [&a, &b, &c].iter().enumerate() {
                handed[i] += usize::from(t.parsed_row().and_then(|p| p.get(i)).is_some());
                match number_as_handed_over(&t, i, "x") {
                    Ok(v) => assert_eq!(Some(v.to_bits()), column[k].map(f64::to_bits)),
                    Err(_) => refused[i] += 1,
                }
            }
        }
        // `a`: all but its infinity and NaN; `b`: all but the batch with
        // its null (read cell by cell, its null refused); `c`: every value.
        assert_eq!(refused, [2, 1, 0]);
        assert_eq!(handed, [n - 2, n - BATCH, n]);
    }

    /// A file path in a fresh directory, removed with the returned guard.
    fn scratch(name: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::Builder::new()
            .prefix("leeway-parquet-")
            .tempdir()
            .unwrap_or_else(|e| panic!("{e}"));
        let path = dir.path().join(name);
        (dir, path)
    }

    #[test]
    fn streamed_samples_are_located_at_their_rows_of_the_file() {
        // The spill of a Parquet file stores no positions: each sample's
        // is told from its index, counted from its experiment's first row.
        use leeway_model::experiment::Source;
        let (_path_dir, path) = scratch("streamed.parquet");
        let n = 20i64;
        let per_run = |v: i64| Values::I64((0..2 * n).map(|_| v).collect());
        let runs = (0..2 * n)
            .map(|k| if k < n { b"a".to_vec() } else { b"b".to_vec() })
            .collect();
        write(
            &path,
            &[
                (
                    "required int64 time;",
                    Values::I64((0..2 * n).map(|k| k % n).collect()),
                ),
                ("required int64 u;", per_run(1)),
                ("required int64 r;", per_run(2)),
                ("required int64 delta;", per_run(35)),
                ("required binary experiment (UTF8);", Values::Bytes(runs)),
            ],
        );
        let src = "model M { state u, r input delta der u = X*u + T*delta der r = N*r step 1.0 }";
        let ir = leeway_structure::compile(src, &leeway_structure::CompileOptions::default())
            .ir
            .unwrap_or_else(|| panic!("the test model compiles"));
        let streamed = crate::file::open_file(&path, &ir, &crate::options::LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let file = path.display();
        let [a, b] = &streamed.sources[..] else {
            panic!("two experiments")
        };
        assert_eq!(a.locate(0), format!("{file}: row 0 (row group 0, row 0)"));
        assert_eq!(
            a.locate(19),
            format!("{file}: row 19 (row group 0, row 19)")
        );
        assert_eq!(b.locate(3), format!("{file}: row 23 (row group 0, row 23)"));
        let mut rows = 0;
        b.visit(&mut |row| {
            assert_eq!((row.states, row.inputs), (&[1.0, 2.0][..], &[35.0][..]));
            rows += 1;
        });
        assert_eq!(rows, 20);
        assert!(b.failure().is_none());
    }

    #[test]
    fn unsigned_integers_are_read_unsigned() {
        let (_path_dir, path) = scratch("unsigned.parquet");
        // 3000000037 stored in an INT32's bits; 2⁵³ and 2⁶⁴−40 in an INT64's.
        #[allow(clippy::cast_possible_wrap)]
        let u32s = vec![3_000_000_037u32 as i32, 7];
        #[allow(clippy::cast_possible_wrap)]
        let u64s = vec![1i64 << 53, (u64::MAX - 39) as i64];
        write(
            &path,
            &[
                ("required int32 a (INTEGER(32,false));", Values::I32(u32s)),
                ("required int64 b (INTEGER(64,false));", Values::I64(u64s)),
            ],
        );
        assert_eq!(numbers(&path, 0).ok(), Some(vec![3_000_000_037.0, 7.0]));
        let e = numbers(&path, 1)
            .err()
            .unwrap_or_else(|| panic!("2⁶⁴−40 accepted"));
        assert!(e.to_string().contains("18446744073709551576"), "{e}");
        assert!(
            e.to_string()
                .contains("row 1 (row group 0, row 1), column `b`"),
            "{e}"
        );
    }

    #[test]
    fn decimals_are_read_with_their_scale_as_their_text_would_be() {
        let (_path_dir, path) = scratch("decimal.parquet");
        let texts = ["37.382572", "-0.000001", "0.020100", "123456789.123456"];
        let unscaled: Vec<i64> = texts
            .iter()
            .map(|t| t.replace('.', "").parse().unwrap_or_else(|e| panic!("{e}")))
            .collect();
        let as_i32: Vec<i32> = unscaled[..3].iter().map(|v| *v as i32).collect();
        // FIXED_LEN_BYTE_ARRAY(9) and BYTE_ARRAY: big-endian two's complement.
        let fixed: Vec<Vec<u8>> = unscaled
            .iter()
            .map(|v| {
                let mut nine = vec![if *v < 0 { 0xff } else { 0 }];
                nine.extend(v.to_be_bytes());
                nine
            })
            .collect();
        let minimal: Vec<Vec<u8>> = unscaled
            .iter()
            .map(|v| {
                let b = v.to_be_bytes();
                // The shortest two's complement form, as writers store it.
                let skip = (0..7)
                    .take_while(|&k| {
                        (b[k] == 0 && b[k + 1] & 0x80 == 0)
                            || (b[k] == 0xff && b[k + 1] & 0x80 != 0)
                    })
                    .count();
                b[skip..].to_vec()
            })
            .collect();
        write(
            &path,
            &[
                (
                    "required int64 a (DECIMAL(18,6));",
                    Values::I64(unscaled.clone()),
                ),
                (
                    "required fixed_len_byte_array(9) b (DECIMAL(20,6));",
                    Values::Fixed(fixed),
                ),
                ("required binary c (DECIMAL(20,6));", Values::Bytes(minimal)),
            ],
        );
        let expected: Vec<f64> = texts
            .iter()
            .map(|t| t.parse().unwrap_or_else(|e| panic!("{e}")))
            .collect();
        for i in 0..3 {
            let got = numbers(&path, i).unwrap_or_else(|e| panic!("{e}"));
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&expected), "column {i}: {got:?}");
        }
        let (_small_dir, small) = scratch("decimal32.parquet");
        write(
            &small,
            &[("required int32 a (DECIMAL(9,6));", Values::I32(as_i32))],
        );
        assert_eq!(numbers(&small, 0).ok(), Some(expected[..3].to_vec()));
        // An unscaled value beyond 2⁵³ is refused, shown as the decimal it is.
        let (_wide_dir, wide) = scratch("decimal-wide.parquet");
        write(
            &wide,
            &[(
                "required int64 a (DECIMAL(18,2));",
                Values::I64(vec![123_456_789_012_345_678]),
            )],
        );
        let e = numbers(&wide, 0)
            .err()
            .unwrap_or_else(|| panic!("accepted"));
        assert!(e.to_string().contains("1234567890123456.78"), "{e}");
    }

    #[test]
    fn dates_and_times_are_seconds_since_the_first() {
        let (_path_dir, path) = scratch("dates.parquet");
        write(
            &path,
            &[
                (
                    "required int32 d (DATE);",
                    Values::I32(vec![20_000, 20_001, 20_003]),
                ),
                (
                    "required int32 t (TIME(MILLIS,false));",
                    Values::I32(vec![1_000, 1_250, 1_500]),
                ),
                (
                    "required int64 s (TIMESTAMP(MICROS,true));",
                    Values::I64(vec![
                        1_795_392_000_000_000,
                        1_795_392_000_100_000,
                        1_795_392_000_200_000,
                    ]),
                ),
            ],
        );
        assert_eq!(numbers(&path, 0).ok(), Some(vec![0.0, 86_400.0, 259_200.0]));
        assert_eq!(numbers(&path, 1).ok(), Some(vec![0.0, 0.25, 0.5]));
        assert_eq!(numbers(&path, 2).ok(), Some(vec![0.0, 0.1, 0.2]));
        let t = ParquetFile::open(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!((0..3).all(|i| t.stamps(i).is_some()));
    }

    #[test]
    fn other_logical_types_are_refused_by_name() {
        let (_path_dir, path) = scratch("refused.parquet");
        write(
            &path,
            &[
                (
                    "required fixed_len_byte_array(2) h (FLOAT16);",
                    Values::Fixed(vec![vec![0, 60]]),
                ),
                (
                    "required fixed_len_byte_array(16) u (UUID);",
                    Values::Fixed(vec![vec![1; 16]]),
                ),
            ],
        );
        for (i, what) in [(0, "FLOAT16"), (1, "UUID")] {
            let e = numbers(&path, i)
                .err()
                .unwrap_or_else(|| panic!("{what} accepted"));
            assert!(
                e.to_string().contains(what) && e.to_string().contains("row 0"),
                "{e}"
            );
        }
    }

    #[test]
    fn a_flipped_bit_in_a_checksummed_page_is_an_error() {
        // Written by pyarrow with `write_page_checksum=True` (the crate's
        // writer stores no CRC): 2000 INT64 values k·7919, one row group.
        let good = std::fs::read(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/checksummed.parquet"),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let (_path_dir, path) = scratch("crc.parquet");
        std::fs::write(&path, &good).unwrap_or_else(|e| panic!("{e}"));
        let values: Vec<f64> = (0..2000).map(|k| f64::from(k * 7919)).collect();
        assert_eq!(numbers(&path, 0).ok(), Some(values.clone()));
        // One bit flipped at a time all over the pages (past the magic,
        // before the footer): an error each time, never a changed number.
        let tail = &good[good.len() - 8..good.len() - 4];
        let footer = u32::from_le_bytes([tail[0], tail[1], tail[2], tail[3]]) as usize;
        let (mut changed, mut refused) = (0, 0);
        for at in (4..good.len() - 8 - footer).step_by(61) {
            let mut bad = good.clone();
            bad[at] ^= 0x10;
            std::fs::write(&path, &bad).unwrap_or_else(|e| panic!("{e}"));
            match numbers(&path, 0) {
                Ok(read) => changed += usize::from(read != values),
                Err(_) => refused += 1,
            }
        }
        assert_eq!(
            changed, 0,
            "flipped bits read as other numbers ({refused} refused)"
        );
        assert!(refused > 100, "{refused}");
    }

    /// Seeded mutations of the checksummed file: flipped bits, overwritten
    /// runs and duplicated ranges anywhere before the footer, cuts, and
    /// flipped bits in the footer. `LEEWAY_FUZZ_PARQUET=N` runs N cases (the
    /// default is CI's short budget).
    #[test]
    fn mutated_files_are_an_error_or_the_same_numbers_never_a_panic_or_a_hang() {
        use rand::{RngExt, SeedableRng};
        let cases: usize = std::env::var("LEEWAY_FUZZ_PARQUET")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(300);
        let good = std::fs::read(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/checksummed.parquet"),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let values: Vec<f64> = (0..2000).map(|k| f64::from(k * 7919)).collect();
        let tail = &good[good.len() - 8..good.len() - 4];
        let footer =
            good.len() - 8 - u32::from_le_bytes([tail[0], tail[1], tail[2], tail[3]]) as usize;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(22);
        let (_path_dir, path) = scratch("fuzz.parquet");
        // (errors, same numbers, other numbers) for pages, and for footers.
        let (mut pages, mut footers) = ([0usize; 3], [0usize; 3]);
        let mut slowest = std::time::Duration::ZERO;
        for case in 0..cases {
            let mut bad = good.clone();
            let in_footer = case % 5 == 4;
            match case % 5 {
                0 => {
                    for _ in 0..rng.random_range(1..=4) {
                        let at = rng.random_range(4..footer);
                        bad[at] ^= 1 << rng.random_range(0..8);
                    }
                }
                1 => {
                    let at = rng.random_range(4..footer - 16);
                    for b in &mut bad[at..at + rng.random_range(1..=16)] {
                        *b = rng.random();
                    }
                }
                2 => {
                    let from = rng.random_range(4..footer - 64);
                    let to = rng.random_range(4..footer - 64);
                    let len = rng.random_range(1..=64);
                    let copy = bad[from..from + len].to_vec();
                    bad[to..to + len].copy_from_slice(&copy);
                }
                3 => bad.truncate(rng.random_range(0..good.len())),
                _ => {
                    let at = rng.random_range(footer..good.len());
                    bad[at] ^= 1 << rng.random_range(0..8);
                }
            }
            std::fs::write(&path, &bad).unwrap_or_else(|e| panic!("{e}"));
            let started = std::time::Instant::now();
            let read = std::panic::catch_unwind(|| numbers(&path, 0));
            slowest = slowest.max(started.elapsed());
            let outcome = match read {
                Err(_) => panic!("case {case}: a panic escaped the reader"),
                Ok(Err(_)) => 0,
                Ok(Ok(v)) if v == values => 1,
                Ok(Ok(_)) => 2,
            };
            let counts = if in_footer { &mut footers } else { &mut pages };
            counts[outcome] += 1;
        }
        eprintln!(
            "{cases} mutations: pages (error, same, changed) {pages:?}, footer {footers:?}, slowest read {slowest:?}"
        );
        // Pages carry their CRC: no mutation there may change a number. The
        // footer has no checksum in the format (a changed scale or type
        // there is a valid, different file), so it is only counted.
        assert_eq!(pages[2], 0, "page mutations read as other numbers");
        assert!(slowest < std::time::Duration::from_secs(5), "{slowest:?}");
    }

    /// A fixture written by pyarrow (tests/data).
    fn fixture(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(name)
    }

    #[test]
    fn a_list_column_is_named_by_its_field_and_refused_as_a_list() {
        // Regression: `a` (a list of doubles) was reported as a missing column.
        let path = fixture("list.parquet");
        let t = ParquetFile::open(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(t.headers(), ["time", "a"]);
        let e = numbers(&path, 1)
            .err()
            .unwrap_or_else(|| panic!("a list read"));
        assert!(e.to_string().contains("column `a` is a list"), "{e}");
    }

    #[test]
    fn a_file_without_row_groups_is_located_as_such() {
        // Regression: located at "row group 0", which the file does not have.
        let t =
            ParquetFile::open(&fixture("no-row-groups.parquet")).unwrap_or_else(|e| panic!("{e}"));
        let at = t.at(t.first_position(), None);
        assert!(at.ends_with("row 0 (the file has no row groups)"), "{at}");
    }
}
