//! CSV text: the line filter (comment and blank lines dropped and
//! counted, CRLF folded, physical lines kept), [`Records`] (a [`Table`] of
//! the file's records: the exact reader) and the entry points for text in
//! memory. Files by path are read by [`CsvFile`](crate::csv_fast::CsvFile),
//! which hands whatever its fast path does not take to [`Records`].
//!
//! The filter drops comment and blank lines outside quoted cells and keeps
//! one entry per run of dropped lines, so the csv crate's positions map back
//! to physical lines and bytes: every error names the line an editor shows.
//! CRLF outside quotes is folded to `" \n"` and a lone CR (classic Mac OS
//! line ends) to `"\n"`, both of the same length, so records start on their
//! own line and byte offsets stay those of the file.
//!
//! A line, and a record (a quoted cell may run over lines), holds at most
//! [`MAX_LINE_BYTES`]: the filter never holds more, and a longer one is an
//! error at its line and byte, so a file without line ends (a binary file,
//! `/dev/zero`) costs 1 MiB, not all memory.

use crate::error::DataError;
use crate::notes::LoadedFile;
use crate::open::open_path;
use crate::options::LoadOptions;
use crate::validate::Places;
use crate::validate::{Table, load_table, missing, not_a_number, not_finite, unique_headers};
use leeway_model::experiment::Experiment;
use leeway_structure::ir::Ir;
use std::path::Path;

/// The most bytes of a CSV line, its line end included, and of a record
/// (a quoted cell may run over lines): 1 MiB. A longer one is an error at
/// its line and byte, never read whole.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Parses CSV text (see [`load_csv`](crate::csv_fast::load_csv)); `file`
/// names it in errors.
pub fn parse_csv(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
) -> Result<Vec<Experiment>, DataError> {
    parse_csv_noted(file, text, ir, options).map(|f| f.experiments)
}

/// [`parse_csv`], also returning what was noted on the way ([`FileNotes`](crate::notes::FileNotes)).
pub fn parse_csv_noted(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    load_table(&mut Records::new(file, text, "--data")?, ir, options)
}

/// A reader that drops comment lines (first non-blank character `#`) and
/// blank lines (only whitespace) outside quoted cells, counts them, and
/// remembers where it dropped them, so that the csv reader's line and byte
/// positions map back to the file's physical lines and bytes. Its memory is
/// the current line plus one entry per run of dropped lines, never the file:
/// a line or a record longer than [`MAX_LINE_BYTES`] stops it ([`Overlong`]).
struct Filter<R> {
    inner: R,
    line: Vec<u8>,
    pos: usize,
    in_quotes: bool,
    /// Physical lines and bytes consumed, from where reading started.
    physical: u64,
    byte: u64,
    /// Lines and bytes served to the csv reader.
    kept: u64,
    kept_bytes: u64,
    /// `(first kept line after a drop, physical − kept)`, increasing.
    line_jumps: Vec<(u64, u64)>,
    /// `(kept byte of a line after a drop, physical − kept)`, increasing.
    byte_jumps: Vec<(u64, u64)>,
    comments: usize,
    blanks: usize,
    error: Option<std::io::Error>,
    /// How the file ends its lines, once its first line end is read.
    ends: Option<LineEnds>,
    /// Where the csv reader stands after the kept lines served (a quoted
    /// cell open or not), as its own state machine reads them.
    quoting: Quoting,
    /// The record being served: its first physical line, its first byte,
    /// its bytes so far.
    record: (u64, u64, usize),
    /// The line or record that stopped the filter, for the message.
    overlong: Option<Overlong>,
}

/// A line or a record longer than [`MAX_LINE_BYTES`]: where it starts.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Overlong {
    /// A record over several lines (a quoted cell not closed), not one line.
    record: bool,
    /// Its first physical line (from 1).
    line: u64,
    /// Its first byte in the file.
    byte: u64,
}

impl Overlong {
    /// The located error.
    fn error(self, file: &str) -> DataError {
        let limit = MAX_LINE_BYTES;
        if self.record {
            DataError::new(
                format!("{file}:{}", self.line),
                format!(
                    "a record longer than 1 MiB: the quoted cell opened in it (from byte {}) is not closed within {limit} bytes",
                    self.byte
                ),
                "a quote at the start of a cell runs to the next quote, over line ends: close the cell, or remove the stray quote",
            )
        } else {
            DataError::new(
                format!("{file}:{}", self.line),
                format!(
                    "a line longer than 1 MiB: no line end within {limit} bytes from byte {}",
                    self.byte
                ),
                "a CSV data file holds one row per line: is it a binary file (a Parquet file is read as one when its name ends in .parquet), or text without line ends?",
            )
        }
    }
}

/// The csv reader's state at a byte, as far as a record's end goes: its
/// state machine (csv-core's, with `"` quoting and doubled quotes, no
/// escape) reduced to what decides whether a line end ends the record.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Quoting {
    /// At the start of a cell: a quote opens a quoted cell.
    Start,
    /// In an unquoted cell (a quote is a character like any).
    Plain,
    /// In a quoted cell: a line end is part of it.
    Quoted,
    /// Just after a quote in a quoted cell: closed, unless a quote follows.
    Closed,
}

impl Quoting {
    /// The state after the kept line `line` (its line end included).
    fn after(self, line: &[u8]) -> Quoting {
        line.iter().fold(self, |state, &b| match (state, b) {
            (Quoting::Quoted, b'"') => Quoting::Closed,
            (Quoting::Quoted, _) => Quoting::Quoted,
            (Quoting::Start | Quoting::Closed, b'"') => Quoting::Quoted,
            (_, b',' | b'\n') => Quoting::Start,
            (_, _) => Quoting::Plain,
        })
    }
}

impl<R: std::io::BufRead> Filter<R> {
    fn new(inner: R) -> Filter<R> {
        Filter {
            inner,
            line: Vec::new(),
            pos: 0,
            in_quotes: false,
            physical: 0,
            byte: 0,
            kept: 0,
            kept_bytes: 0,
            line_jumps: Vec::new(),
            byte_jumps: Vec::new(),
            comments: 0,
            blanks: 0,
            error: None,
            ends: None,
            quoting: Quoting::Start,
            record: (0, 0, 0),
            overlong: None,
        }
    }
    /// A filter that starts reading at the start of a line, `at.byte`
    /// bytes and `at.physical` physical lines into a file whose line ends
    /// are LF or CRLF and whose header row has `cells` cells, with the
    /// comment and blank lines met before counted. It first serves a
    /// stand-in header row of `cells` empty cells, which the csv reader
    /// reads as its header (so every later row must have as many cells, as
    /// in the file, and a UTF-8 BOM is only stripped from that stand-in);
    /// its lines and bytes then map to the file's as if the csv reader had
    /// read the file from its start.
    fn resumed(inner: R, cells: usize, at: &Resume) -> Filter<R> {
        let mut line = vec![b','; cells.saturating_sub(1)];
        if line.is_empty() {
            // One cell: a space, as an empty line is no record to csv.
            line.push(b' ');
        }
        line.push(b'\n');
        let stand_in = line.len() as u64;
        Filter {
            line,
            physical: at.physical,
            byte: at.byte,
            kept: 1,
            kept_bytes: stand_in,
            // Kept line 2 is the physical line after `at.physical`, kept
            // byte `stand_in` is `at.byte` (never less: the header row, of
            // `cells` cells and a line end, is before it).
            line_jumps: vec![(1, at.physical.wrapping_sub(1))],
            byte_jumps: vec![(0, at.byte.wrapping_sub(stand_in))],
            comments: at.comments,
            blanks: at.blanks,
            ends: Some(LineEnds::Feed),
            ..Filter::new(inner)
        }
    }
    /// The physical line (from 1) of a kept line (from 1).
    fn physical_line(&self, kept: u64) -> u64 {
        let i = self.line_jumps.partition_point(|(k, _)| *k <= kept);
        kept.wrapping_add(if i == 0 { 0 } else { self.line_jumps[i - 1].1 })
    }
    /// The physical byte offset of a kept byte offset at the start of a line.
    fn physical_byte(&self, kept: u64) -> u64 {
        let i = self.byte_jumps.partition_point(|(k, _)| *k <= kept);
        // Wrapping: a resumed filter's first jump may be "negative" (see
        // `Filter::resumed`); the sum is the physical byte all the same.
        kept.wrapping_add(if i == 0 { 0 } else { self.byte_jumps[i - 1].1 })
    }
    /// Reads the next kept line into `self.line`; false at the end.
    fn next_line(&mut self) -> std::io::Result<bool> {
        let mut dropped = false;
        loop {
            self.line.clear();
            self.pos = 0;
            let n = read_line(&mut self.inner, &mut self.line, &mut self.ends)?;
            if n == 0 {
                return Ok(false);
            }
            self.physical += 1;
            let start = self.byte;
            self.byte += n as u64;
            if n > MAX_LINE_BYTES {
                return Err(self.stop(Overlong {
                    record: false,
                    line: self.physical,
                    byte: start,
                }));
            }
            if !self.in_quotes {
                match self.line.iter().find(|b| !b.is_ascii_whitespace()) {
                    None => {
                        self.blanks += 1;
                        dropped = true;
                        continue;
                    }
                    Some(b'#') => {
                        self.comments += 1;
                        dropped = true;
                        continue;
                    }
                    Some(_) => {}
                }
            }
            self.kept += 1;
            if dropped {
                self.line_jumps.push((self.kept, self.physical - self.kept));
                self.byte_jumps
                    .push((self.kept_bytes, start - self.kept_bytes));
            }
            self.kept_bytes += n as u64;
            let quotes = self.line.iter().filter(|b| **b == b'"').count();
            if quotes % 2 == 1 {
                self.in_quotes = !self.in_quotes;
            }
            // The record this line belongs to, bounded as a line is.
            if self.quoting != Quoting::Quoted {
                self.record = (self.physical, start, 0);
            }
            self.record.2 += n;
            if self.record.2 > MAX_LINE_BYTES {
                let (line, byte, _) = self.record;
                return Err(self.stop(Overlong {
                    record: true,
                    line,
                    byte,
                }));
            }
            // CRLF outside quotes becomes " \n" (same length, so byte offsets
            // hold; the space is trimmed): the csv reader then ends records
            // at `\n` only and its positions count lines as an editor does.
            // A lone CR (classic Mac OS line ends) becomes `\n` likewise.
            let len = self.line.len();
            if !self.in_quotes && self.line.ends_with(b"\r\n") {
                self.line[len - 2] = b' ';
            } else if !self.in_quotes
                && self.ends == Some(LineEnds::Return)
                && self.line.ends_with(b"\r")
            {
                self.line[len - 1] = b'\n';
            }
            self.quoting = match (quotes, self.quoting) {
                // No quote: the state only tells a quoted cell (it goes on)
                // from any other (the line end ends the record).
                (0, Quoting::Quoted) => Quoting::Quoted,
                (0, _) => Quoting::Start,
                _ => self.quoting.after(&self.line),
            };
            return Ok(true);
        }
    }
    /// Stops at an overlong line or record: kept for the message, and an
    /// error for the csv reader, which stops.
    fn stop(&mut self, overlong: Overlong) -> std::io::Error {
        self.overlong = Some(overlong);
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "a line or record longer than 1 MiB",
        )
    }
}

/// How a file ends its lines, decided by its first line end.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LineEnds {
    /// `\n` or `\r\n` (a CR elsewhere is part of the line, as before).
    Feed,
    /// A lone `\r`: files from classic Mac OS tools.
    Return,
}

/// Appends one physical line to `line`, with its end, and returns the bytes
/// read: at most [`MAX_LINE_BYTES`] + 1, so that a longer line is told
/// without being read whole. How the file ends its lines (`ends`) is
/// decided from its first buffer: a CR without any LF there is a file of
/// returns; anything else ends lines at LF (a CR then is part of a line, as
/// it always was).
fn read_line<R: std::io::BufRead>(
    inner: &mut R,
    line: &mut Vec<u8>,
    ends: &mut Option<LineEnds>,
) -> std::io::Result<usize> {
    let ends = match *ends {
        Some(e) => e,
        None => {
            let first = inner.fill_buf()?;
            let decided = if !first.contains(&b'\n') && first.contains(&b'\r') {
                LineEnds::Return
            } else {
                LineEnds::Feed
            };
            *ends = Some(decided);
            decided
        }
    };
    let mut bounded = std::io::Read::take(inner, MAX_LINE_BYTES as u64 + 1);
    match ends {
        LineEnds::Feed => std::io::BufRead::read_until(&mut bounded, b'\n', line),
        LineEnds::Return => std::io::BufRead::read_until(&mut bounded, b'\r', line),
    }
}

impl<R: std::io::BufRead> std::io::Read for Filter<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.pos >= self.line.len() {
            match self.next_line() {
                Ok(true) => {}
                Ok(false) => return Ok(0),
                Err(e) => {
                    // Kept for the message: csv would only say "I/O error".
                    let kind = e.kind();
                    self.error = Some(e);
                    return Err(std::io::Error::from(kind));
                }
            }
        }
        let n = buf.len().min(self.line.len() - self.pos);
        buf[..n].copy_from_slice(&self.line[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// Where a reader resumes in a file: the byte where a line starts, the
/// physical lines before it, and the comment and blank lines among them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Resume {
    pub(crate) byte: u64,
    pub(crate) physical: u64,
    pub(crate) comments: usize,
    pub(crate) blanks: usize,
}

/// A CSV file read record by record through the line filter (comment and
/// blank lines dropped and counted, CRLF folded, physical lines kept): the
/// reader of data files (`estimate`, `validate`) and of `simulate`'s input,
/// so every CSV file leeway reads follows the same rules and every problem
/// is located the same way (`file:line`, `file:line:column (name)`). It holds
/// one record, never the file.
pub struct Records<R: std::io::BufRead> {
    file: String,
    what: String,
    reader: csv::Reader<Filter<R>>,
    record: csv::ByteRecord,
    headers: Vec<String>,
    header_line: u64,
    line: u64,
}

impl Records<std::io::BufReader<std::fs::File>> {
    /// Opens a file (`what` names the option that gave it, for the hint).
    pub fn open(path: &Path, what: &str) -> Result<Self, DataError> {
        let (file, handle) = open_path(path, what)?;
        Records::new(
            &file,
            std::io::BufReader::with_capacity(1 << 16, handle),
            what,
        )
    }
}

impl<R: std::io::BufRead> Records<R> {
    /// Reads the header row (after any comment and blank lines); the header
    /// must name each column once. `what` names the option that gave the
    /// file (`--data`, `--input`), for the hint of a read failure.
    pub fn new(file: &str, input: R, what: &str) -> Result<Self, DataError> {
        let mut reader = csv_builder()
            .has_headers(true)
            .from_reader(Filter::new(input));
        let headers: Vec<String> = match reader.byte_headers() {
            Ok(h) => h
                .iter()
                .map(|c| String::from_utf8_lossy(c).into_owned())
                .collect(),
            Err(e) => {
                if let Some(d) = io_error(file, what, &reader, &e) {
                    return Err(d);
                }
                let line = reader.get_ref().physical_line(1);
                return Err(DataError::new(
                    format!("{file}:{line}"),
                    format!("cannot read the header row: {e}"),
                    "the first row names the columns",
                ));
            }
        };
        let header_line = if headers.is_empty() || reader.get_ref().kept == 0 {
            reader.get_ref().physical + 1
        } else {
            reader.get_ref().physical_line(1)
        };
        if reader.get_ref().kept == 0 {
            return Err(DataError::new(
                format!("{file}:{header_line}"),
                "the file has no header row (it is empty, or only comments and blank lines)",
                "the first row names the columns",
            ));
        }
        unique_headers(&headers, |i| header_place(file, header_line, Some(i)))?;
        Ok(Records::reading(file, what, reader, headers, header_line))
    }
    /// Reads on from the start of a line of a file whose header row
    /// (`headers`, on physical line `header_line`) was read before, as if
    /// this reader had read the file from its start: the same rows, values,
    /// lines, bytes, counts and errors. `input` reads from `at.byte`; the
    /// file's line ends are LF or CRLF.
    pub(crate) fn resume(
        file: &str,
        input: R,
        what: &str,
        (headers, header_line): (Vec<String>, u64),
        at: &Resume,
    ) -> Result<Self, DataError> {
        let mut reader =
            csv_builder()
                .has_headers(true)
                .from_reader(Filter::resumed(input, headers.len(), at));
        // The filter's stand-in header row, served from memory.
        if let Err(e) = reader.byte_headers() {
            return Err(io_error(file, what, &reader, &e).unwrap_or_else(|| {
                DataError::new(
                    file,
                    format!("cannot read the file: {e}"),
                    format!("check the path passed to {what}"),
                )
            }));
        }
        Ok(Records::reading(file, what, reader, headers, header_line))
    }
    /// A reader whose header row (`headers`, on physical line
    /// `header_line`) has been read.
    fn reading(
        file: &str,
        what: &str,
        reader: csv::Reader<Filter<R>>,
        headers: Vec<String>,
        header_line: u64,
    ) -> Self {
        Records {
            file: file.to_string(),
            what: what.to_string(),
            reader,
            record: csv::ByteRecord::new(),
            headers,
            header_line,
            line: header_line,
        }
    }
    /// The header's physical line.
    pub fn header_line(&self) -> u64 {
        self.header_line
    }
    /// The column of a header name.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.headers.iter().position(|h| h == name)
    }
    /// Advances to the next record: `false` at the end; a malformed row (a
    /// cell count other than the header's, an unclosed quote) or a read
    /// failure is a located error.
    pub fn next_record(&mut self) -> Result<bool, DataError> {
        let file = self.file.as_str();
        match self.reader.read_byte_record(&mut self.record) {
            Ok(true) => {}
            Ok(false) => return Ok(false),
            Err(e) => {
                if let Some(d) = io_error(file, &self.what, &self.reader, &e) {
                    return Err(d);
                }
                let at = e.position().map_or(self.reader.get_ref().physical, |p| {
                    self.reader.get_ref().physical_line(p.line())
                });
                let what = match e.kind() {
                    csv::ErrorKind::UnequalLengths {
                        expected_len, len, ..
                    } => format!("malformed row: {len} cells, the header has {expected_len}"),
                    _ => format!("malformed row: {e}"),
                };
                return Err(DataError::new(
                    format!("{file}:{at}"),
                    what,
                    "every row needs as many cells as the header",
                ));
            }
        }
        let pos = self.record.position().map_or(1, csv::Position::line);
        self.line = self.reader.get_ref().physical_line(pos);
        Ok(true)
    }
    /// The current record's physical line.
    pub fn line(&self) -> u64 {
        self.line
    }
    /// The current record's physical byte offset.
    fn byte(&self) -> u64 {
        let pos = self.record.position().map_or(0, csv::Position::byte);
        self.reader.get_ref().physical_byte(pos)
    }
    /// The raw bytes of cell `i` of the current record (empty if absent).
    pub fn raw(&self, i: usize) -> &[u8] {
        self.record.get(i).unwrap_or(b"")
    }
}

/// A read failure met by the csv reader, with the filter's own message (csv
/// would only say "I/O error").
fn io_error<R: std::io::BufRead>(
    file: &str,
    what: &str,
    r: &csv::Reader<Filter<R>>,
    e: &csv::Error,
) -> Option<DataError> {
    if let csv::ErrorKind::Io(io) = e.kind() {
        if let Some(overlong) = r.get_ref().overlong {
            return Some(overlong.error(file));
        }
        let why = r
            .get_ref()
            .error
            .as_ref()
            .map_or(io.to_string(), ToString::to_string);
        return Some(DataError::new(
            file,
            format!("cannot read the file: {why}"),
            format!("check the path passed to {what}"),
        ));
    }
    None
}
impl<R: std::io::BufRead> Table for Records<R> {
    fn file(&self) -> &str {
        &self.file
    }
    fn headers(&self) -> &[String] {
        &self.headers
    }
    fn places(&self) -> &Places {
        &Places::Lines
    }
    fn header_at(&self, column: Option<usize>) -> String {
        header_place(&self.file, self.header_line, column)
    }
    fn first_position(&self) -> u64 {
        self.header_line + 1
    }
    fn next_row(&mut self) -> Result<bool, DataError> {
        self.next_record()
    }
    fn position(&self) -> u64 {
        self.line
    }
    fn offset(&self) -> u64 {
        self.byte()
    }
    fn number(&self, i: usize, name: &str) -> Result<f64, DataError> {
        cell(&self.file, self.line, self.raw(i), i, name)
    }
    fn label(&self, i: usize) -> Result<std::borrow::Cow<'_, [u8]>, DataError> {
        Ok(std::borrow::Cow::Borrowed(self.raw(i)))
    }
    fn dropped(&self) -> (usize, usize) {
        let f = self.reader.get_ref();
        (f.comments, f.blanks)
    }
}

/// One cell (`bytes`, trimmed, as the csv reader splits it) as a finite
/// number, or the located reason it is not. The exact reading every CSV
/// value goes through or is proven equal to (the fast path's cells that it
/// does not parse itself come here too); the cell's text is only built for
/// a message.
pub(crate) fn cell(
    file: &str,
    line: u64,
    bytes: &[u8],
    i: usize,
    name: &str,
) -> Result<f64, DataError> {
    let raw = || String::from_utf8_lossy(bytes);
    let loc = || Places::Lines.at(file, line, Some((i, name)));
    match std::str::from_utf8(bytes).ok().map(str::parse::<f64>) {
        Some(Ok(v)) if v.is_finite() => Ok(v),
        Some(Ok(_)) => Err(not_finite(loc(), &raw())),
        _ if bytes.is_empty() => Err(missing(loc(), "empty cell")),
        _ => Err(not_a_number(
            loc(),
            &raw(),
            "use a plain decimal such as 0.25 or -1.5e-3",
        )),
    }
}

/// Where a CSV file's header row is (`file:line`), naming column `column`
/// (from 0) when given (`file:line:column`, the column from 1).
pub(crate) fn header_place(file: &str, line: u64, column: Option<usize>) -> String {
    match column {
        Some(i) => format!("{file}:{line}:{}", i + 1),
        None => format!("{file}:{line}"),
    }
}

fn csv_builder() -> csv::ReaderBuilder {
    let mut b = csv::ReaderBuilder::new();
    b.flexible(false)
        .trim(csv::Trim::All)
        .terminator(csv::Terminator::Any(b'\n'));
    b
}
