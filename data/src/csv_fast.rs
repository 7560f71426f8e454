//! CSV data files read in parallel: [`CsvFile`], the [`Table`] of a CSV
//! file by path, reading the very rows, values, lines, bytes, counts and
//! errors [`Records`] reads, faster.
//!
//! The file is read in batches (a few MiB per thread), each split at line
//! ends into chunks parsed on their own threads (`csv_chunk`) into the
//! selected columns' values and each row's line and byte; the validating
//! pass then reads rows from there. At most one batch is held, never the
//! file. Whatever a chunk does not take (a quote other than around a whole
//! cell, a row with a cell count other than the header's) is read by the exact reader: a [`Records`]
//! resumed at that line's byte, with the header and the line and
//! comment/blank counts carried, so the quoted cell's value or the error
//! is the one reading the whole file with [`Records`] gives. Files whose
//! lines end in lone CRs, whose header row the fast path would not take,
//! or that are not regular files are read by [`Records`] from the start.

use crate::csv::{MAX_LINE_BYTES, Records, Resume, cell, header_place};
use crate::csv_chunk::{Chunk, Selection, field, parse_chunk, plain_line};
use crate::error::DataError;
use crate::notes::LoadedFile;
use crate::open::open_path;
use crate::options::LoadOptions;
use crate::spill::{StreamedFile, open_table};
use crate::validate::{ParsedRow, Places, Table, load_table};
use leeway_model::experiment::Experiment;
use leeway_structure::ir::Ir;
use std::borrow::Cow;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// Loads one CSV file: one experiment, or several when it has an
/// `experiment` column (each experiment's rows contiguous, in file order).
pub fn load_csv(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<Vec<Experiment>, DataError> {
    load_csv_noted(path, ir, options).map(|f| f.experiments)
}

/// [`load_csv`], also returning what was noted on the way ([`FileNotes`](crate::notes::FileNotes)).
pub fn load_csv_noted(
    path: &Path,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    load_table(&mut CsvFile::open(path, "--data")?, ir, options)
}

/// Opens a CSV file for streaming: one validating pass (every check of
/// [`load_csv`]) that also writes the parsed samples to a temporary spill
/// file (8 bytes per value and row, in the system's temporary directory,
/// removed when the sources are dropped); every later visit reads them from
/// there. Memory is flat in the number of rows. `--resample` is not
/// streamed: use [`load_csv_noted`] for it.
pub fn open_csv(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<StreamedFile, DataError> {
    open_table(&mut CsvFile::open(path, "--data")?, ir, options)
}

/// How a [`CsvFile`] reads: bytes per chunk (one thread's share of a
/// batch) and threads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Batching {
    /// Bytes per chunk (a line longer than a batch is still read whole, up
    /// to [`MAX_LINE_BYTES`]).
    pub chunk: usize,
    /// Threads (chunks per batch), at least 1.
    pub threads: usize,
}

/// At most this many threads parse a batch: past them the validating pass,
/// serial, is the bottleneck.
const MAX_THREADS: usize = 8;

/// The line ends of a file are decided from this many first bytes, as the
/// line filter decides them from its reader's first buffer.
const FIRST_BUFFER: usize = 1 << 16;

impl Default for Batching {
    /// 1 MiB chunks (a thread's start is some 10 µs, its chunk some ms of
    /// work), a thread per core (at most 8).
    fn default() -> Batching {
        Batching {
            chunk: 1 << 20,
            threads: std::thread::available_parallelism()
                .map_or(1, std::num::NonZeroUsize::get)
                .min(MAX_THREADS),
        }
    }
}

/// A CSV data file as a [`Table`]: parsed in parallel batches on the fast
/// path, by [`Records`] from the first line the fast path does not take
/// (see the module's documentation).
pub struct CsvFile {
    headers: Vec<String>,
    header_line: u64,
    read: Reading,
}

enum Reading {
    Fast(Box<Fast>),
    Exact(Box<Records<BufReader<File>>>),
}

/// The fast path's state: the current batch's chunks and the row read.
struct Fast {
    file: String,
    what: String,
    input: File,
    batching: Batching,
    selection: Selection,
    /// Whether the selection is settled (by `select` or the first batch).
    selected: bool,
    /// The batch's text (whole lines) and its first byte in the file.
    text: Vec<u8>,
    text_byte: u64,
    /// Bytes read after the batch's last line end (a partial line).
    carry: Vec<u8>,
    eof: bool,
    /// The batch's chunks with their start in `text`, the chunk read, the
    /// row read in it.
    chunks: Vec<(usize, Chunk)>,
    chunk: usize,
    row: Option<usize>,
    /// Physical, comment and blank lines before the chunk read.
    physical: u64,
    comments: usize,
    blanks: usize,
}

impl CsvFile {
    /// Opens a CSV file (`what` names the option that gave it, for hints)
    /// and reads its header row.
    pub fn open(path: &Path, what: &str) -> Result<CsvFile, DataError> {
        CsvFile::open_with(path, what, Batching::default())
    }

    /// [`CsvFile::open`] with the given batches.
    pub fn open_with(path: &Path, what: &str, batching: Batching) -> Result<CsvFile, DataError> {
        let batching = Batching {
            chunk: batching.chunk.max(1),
            threads: batching.threads.max(1),
        };
        let (file, mut input) = open_path(path, what)?;
        let read_error = |e: std::io::Error| io_failure(&file, what, &e);
        let regular = input.metadata().is_ok_and(|m| m.is_file());
        let want = FIRST_BUFFER.max(batching.chunk.saturating_mul(batching.threads));
        let mut head = Vec::with_capacity(if regular { want } else { 0 });
        if regular {
            (&mut input)
                .take(want as u64)
                .read_to_end(&mut head)
                .map_err(read_error)?;
        }
        let eof = head.len() < want;
        let header = header_end(&head, eof).filter(|_| regular);
        let Some(header_end) = header else {
            // The exact reader from the start (a pipe cannot seek, and
            // nothing of it was read).
            if regular {
                input.seek(SeekFrom::Start(0)).map_err(read_error)?;
            }
            let records = Records::new(&file, BufReader::with_capacity(FIRST_BUFFER, input), what)?;
            return Ok(CsvFile {
                headers: records.headers().to_vec(),
                header_line: records.header_line(),
                read: Reading::Exact(Box::new(records)),
            });
        };
        // The header as the exact reader reads it (messages, BOM, names).
        let records = Records::new(&file, &head[..header_end.byte], what)?;
        let headers = records.headers().to_vec();
        let header_line = records.header_line();
        let (comments, blanks) = records.dropped();
        drop(records);
        // The rest of the head is the first batch's start (kept, not copied).
        head.drain(..header_end.byte);
        let fast = Fast {
            file,
            what: what.to_string(),
            input,
            batching,
            selection: Selection::new(headers.len(), &(0..headers.len()).collect::<Vec<_>>()),
            selected: false,
            text: Vec::new(),
            text_byte: header_end.byte as u64,
            carry: head,
            eof,
            chunks: Vec::new(),
            chunk: 0,
            row: None,
            physical: header_end.physical,
            comments,
            blanks,
        };
        Ok(CsvFile {
            headers,
            header_line,
            read: Reading::Fast(Box::new(fast)),
        })
    }

    /// True while the fast path reads (for tests: a file the fast path
    /// should read whole must still be on it at its end).
    #[cfg(test)]
    pub(crate) fn is_fast(&self) -> bool {
        matches!(self.read, Reading::Fast(_))
    }
}

/// The end of the header row: its byte after the line end, and the
/// physical lines up to it.
struct HeaderEnd {
    byte: usize,
    physical: u64,
}

/// Where the header row (the first line neither blank nor a comment) ends
/// in the file's first bytes `head`, if the fast path may read on from
/// there: the first [`FIRST_BUFFER`] bytes hold a LF (so the filter ends
/// lines at LF), the header row's names are plain or simply quoted (other
/// quotes may hold line ends) and it ends in `head` (`eof`: `head` is the
/// whole file).
fn header_end(head: &[u8], eof: bool) -> Option<HeaderEnd> {
    if !head[..head.len().min(FIRST_BUFFER)].contains(&b'\n') {
        return None;
    }
    let mut pos = 0;
    let mut physical = 0;
    while pos < head.len() {
        let end = head[pos..].iter().position(|b| *b == b'\n');
        if end.is_none() && !eof {
            return None;
        }
        let end = end.map_or(head.len(), |k| pos + k + 1);
        let line = &head[pos..end];
        physical += 1;
        match line.iter().find(|b| !b.is_ascii_whitespace()) {
            None | Some(b'#') => pos = end,
            Some(_) if !plain_line(line) => return None,
            Some(_) => {
                return Some(HeaderEnd {
                    byte: end,
                    physical,
                });
            }
        }
    }
    None
}

/// A read failure, as [`Records`] words it.
fn io_failure(file: &str, what: &str, e: &std::io::Error) -> DataError {
    DataError::new(
        file,
        format!("cannot read the file: {e}"),
        format!("check the path passed to {what}"),
    )
}

impl Fast {
    /// Reads and parses the next batch: false at the file's end.
    fn next_batch(&mut self) -> Result<bool, DataError> {
        self.text_byte += self.text.len() as u64;
        let want = self.batching.chunk.saturating_mul(self.batching.threads);
        self.text.clear();
        self.text.reserve_exact(self.carry.len() + want);
        self.text.append(&mut self.carry);
        // Whole lines: read on until a line end (or the file's end), or
        // past a line the exact reader refuses (the chunk stops there).
        // Only the bytes just read are searched: a line longer than a batch
        // costs its length, not its length squared.
        let mut searched = 0;
        loop {
            if !self.eof {
                // Exactly, for a batch: `read_to_end` would double the
                // buffer. A line longer than a batch grows it as a vector
                // grows (in as many reads as it has batches).
                if searched == 0 {
                    self.text.reserve_exact(want);
                } else {
                    self.text.reserve(want);
                }
                let n = (&mut self.input)
                    .take(want as u64)
                    .read_to_end(&mut self.text)
                    .map_err(|e| io_failure(&self.file, &self.what, &e))?;
                self.eof = n < want;
            }
            let last = memchr::memrchr(b'\n', &self.text[searched..]).map(|k| searched + k);
            match last {
                Some(last) if !self.eof => {
                    self.carry.extend_from_slice(&self.text[last + 1..]);
                    self.text.truncate(last + 1);
                    break;
                }
                None if !self.eof && self.text.len() <= MAX_LINE_BYTES => {
                    searched = self.text.len();
                }
                _ => break,
            }
        }
        // The columns are those of the first batch on.
        self.selected = true;
        if self.text.is_empty() {
            return Ok(false);
        }
        parse_batch(&self.text, &self.selection, self.batching, &mut self.chunks);
        self.chunk = 0;
        self.row = None;
        Ok(true)
    }

    /// The row read and its chunk.
    fn current(&self) -> Option<(usize, &Chunk, usize)> {
        let (start, chunk) = self.chunks.get(self.chunk)?;
        Some((*start, chunk, self.row?))
    }

    /// The physical line of the row read (the header's before any).
    fn line(&self, header_line: u64) -> u64 {
        match self.current() {
            Some((_, chunk, row)) => self.physical + chunk.lines[row] + 1,
            None => header_line,
        }
    }

    /// The text of the row read's line.
    fn line_text(&self) -> &[u8] {
        match self.current() {
            Some((start, chunk, row)) => {
                let (a, b) = chunk.spans[row];
                &self.text[start + a..start + b]
            }
            None => b"",
        }
    }

    /// Where the exact reader goes on after the chunk read, which stopped.
    fn resume_at(&self, start: usize, chunk: &Chunk, stop: usize) -> Resume {
        Resume {
            byte: self.text_byte + (start + stop) as u64,
            physical: self.physical + chunk.physical,
            comments: self.comments + chunk.comments,
            blanks: self.blanks + chunk.blanks,
        }
    }
}

/// Splits a batch at line ends into at most `threads` chunks of about
/// `chunk` bytes and parses them into `chunks` (each with its start in
/// `text`; buffers reused), each on its own thread (the first on this one).
fn parse_batch(
    text: &[u8],
    selection: &Selection,
    batching: Batching,
    chunks: &mut Vec<(usize, Chunk)>,
) {
    let parts = text
        .len()
        .div_ceil(batching.chunk)
        .clamp(1, batching.threads);
    let mut starts = vec![0];
    for k in 1..parts {
        let from = (text.len() * k / parts).max(starts[k - 1]);
        match text[from..].iter().position(|b| *b == b'\n') {
            Some(i) if from + i + 1 < text.len() => starts.push(from + i + 1),
            _ => break,
        }
    }
    let ends: Vec<usize> = starts[1..]
        .iter()
        .copied()
        .chain(std::iter::once(text.len()))
        .collect();
    chunks.resize_with(starts.len(), Default::default);
    let unspawned = std::thread::scope(|s| {
        let mut jobs = chunks.iter_mut().zip(starts.iter().zip(&ends)).enumerate();
        let mut unspawned = Vec::new();
        let mut handles = Vec::new();
        let first = jobs.next();
        for (k, ((start, chunk), (&a, &b))) in jobs {
            *start = a;
            let part = &text[a..b];
            match std::thread::Builder::new()
                .name("leeway-csv".into())
                .spawn_scoped(s, move || parse_chunk(part, selection, chunk))
            {
                Ok(h) => handles.push(h),
                Err(_) => unspawned.push(k),
            }
        }
        if let Some((_, ((start, chunk), (&a, &b)))) = first {
            *start = a;
            parse_chunk(&text[a..b], selection, chunk);
        }
        for h in handles {
            h.join().unwrap_or_else(|p| std::panic::resume_unwind(p));
        }
        unspawned
    });
    // No thread to be had: parsed here.
    for k in unspawned {
        let (start, chunk) = &mut chunks[k];
        parse_chunk(&text[*start..ends[k]], selection, chunk);
    }
}

impl CsvFile {
    /// Advances the fast path; hands over to the exact reader where a chunk
    /// stopped.
    fn next_fast(&mut self) -> Result<bool, DataError> {
        let Reading::Fast(fast) = &mut self.read else {
            return Ok(false);
        };
        loop {
            let Some((start, chunk)) = fast.chunks.get(fast.chunk) else {
                if !fast.next_batch()? {
                    return Ok(false);
                }
                continue;
            };
            let next = fast.row.map_or(0, |r| r + 1);
            if next < chunk.rows() {
                fast.row = Some(next);
                return Ok(true);
            }
            if let Some(stop) = chunk.stop {
                let at = fast.resume_at(*start, chunk, stop);
                return self.hand_over(&at);
            }
            fast.physical += chunk.physical;
            fast.comments += chunk.comments;
            fast.blanks += chunk.blanks;
            fast.chunk += 1;
            fast.row = None;
        }
    }

    /// From `at` on, the exact reader reads the file.
    fn hand_over(&mut self, at: &Resume) -> Result<bool, DataError> {
        let Reading::Fast(fast) = &mut self.read else {
            return Ok(false);
        };
        let (file, what) = (fast.file.clone(), fast.what.clone());
        let mut input = fast
            .input
            .try_clone()
            .map_err(|e| io_failure(&file, &what, &e))?;
        input
            .seek(SeekFrom::Start(at.byte))
            .map_err(|e| io_failure(&file, &what, &e))?;
        let mut records = Records::resume(
            &file,
            BufReader::with_capacity(FIRST_BUFFER, input),
            &what,
            (self.headers.clone(), self.header_line),
            at,
        )?;
        let more = records.next_record();
        self.read = Reading::Exact(Box::new(records));
        more
    }
}

impl Table for CsvFile {
    fn file(&self) -> &str {
        match &self.read {
            Reading::Fast(f) => &f.file,
            Reading::Exact(r) => r.file(),
        }
    }
    fn headers(&self) -> &[String] {
        &self.headers
    }
    fn places(&self) -> &Places {
        &Places::Lines
    }
    fn header_at(&self, column: Option<usize>) -> String {
        header_place(self.file(), self.header_line, column)
    }
    fn first_position(&self) -> u64 {
        self.header_line + 1
    }
    fn next_row(&mut self) -> Result<bool, DataError> {
        match &mut self.read {
            Reading::Fast(_) => self.next_fast(),
            Reading::Exact(r) => r.next_row(),
        }
    }
    fn position(&self) -> u64 {
        match &self.read {
            Reading::Fast(f) => f.line(self.header_line),
            Reading::Exact(r) => r.position(),
        }
    }
    fn offset(&self) -> u64 {
        match &self.read {
            Reading::Fast(f) => f.current().map_or(0, |(start, chunk, row)| {
                f.text_byte + (start + chunk.spans[row].0) as u64
            }),
            Reading::Exact(r) => r.offset(),
        }
    }
    fn number(&self, i: usize, name: &str) -> Result<f64, DataError> {
        match &self.read {
            Reading::Fast(f) => {
                if let Some(v) = self.parsed_row().and_then(|p| p.get(i)) {
                    return Ok(v);
                }
                let line = f.line(self.header_line);
                cell(&f.file, line, field(f.line_text(), i), i, name)
            }
            Reading::Exact(r) => r.number(i, name),
        }
    }
    fn parsed_row(&self) -> Option<ParsedRow<'_>> {
        let Reading::Fast(f) = &self.read else {
            return None;
        };
        let (_, chunk, row) = f.current()?;
        let width = f.selection.width;
        Some(ParsedRow {
            values: chunk.values.get(row * width..(row + 1) * width)?,
            slots: &f.selection.slots,
        })
    }
    fn label(&self, i: usize) -> Result<Cow<'_, [u8]>, DataError> {
        match &self.read {
            Reading::Fast(f) => Ok(Cow::Borrowed(field(f.line_text(), i))),
            Reading::Exact(r) => r.label(i),
        }
    }
    fn select(&mut self, columns: &[usize]) {
        if let Reading::Fast(f) = &mut self.read
            && !f.selected
        {
            f.selection = Selection::new(self.headers.len(), columns);
            f.selected = true;
        }
    }
    fn dropped(&self) -> (usize, usize) {
        match &self.read {
            Reading::Fast(f) => {
                let (c, b) = f
                    .current()
                    .map_or((0, 0), |(_, chunk, row)| chunk.dropped_before(row));
                (f.comments + c, f.blanks + b)
            }
            Reading::Exact(r) => r.dropped(),
        }
    }
}

#[cfg(test)]
mod tests;
