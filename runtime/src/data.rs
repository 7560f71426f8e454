//! Experiments: the data an estimate is computed from.
//!
//! An experiment is a time series of the model's declared signals (states,
//! inputs, heading or rotation columns, measured disturbance components). It
//! is held column by column in memory ([`Experiment`]) or produced on the fly
//! by any [`Source`] (e.g. a simulator streaming 10⁷ samples): estimators only
//! ever visit samples in order, so their memory does not grow with N.
//!
//! CSV loading validates everything and names the place of every problem
//! (`file:row:column`, the physical line an editor shows, also after
//! comment lines, blank lines and quoted cells holding line breaks); nothing
//! is silently dropped or reordered. A file is either loaded into memory
//! ([`load_csv`]) or, after the same validating pass, visited in passes
//! from a binary copy of its validated samples ([`open_csv`], [`CsvSource`])
//! so that memory stays flat in N and no pass parses the text again.

use leeway_structure::ir::{Ir, Rotation};
use std::path::Path;

/// One sample as estimators read it.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// Measured states.
    pub states: &'a [f64],
    /// Inputs.
    pub inputs: &'a [f64],
    /// Measured heading (planar rotation; 0 otherwise).
    pub heading: f64,
    /// Measured rotation columns (measured `R`; empty otherwise).
    pub rotation: &'a [f64],
    /// Disturbance components by global index; measured ones from the data,
    /// unmeasured ones 0.
    pub disturbances: &'a [f64],
}

/// A sequence of samples that can be visited any number of times, in order.
pub trait Source: Sync {
    /// The experiment's name (file, or value of the `experiment` column).
    fn name(&self) -> &str;
    /// Number of samples.
    fn len(&self) -> usize;
    /// True when there are no samples.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The sample time `h`.
    fn step(&self) -> f64;
    /// Calls `f` on every sample in order.
    fn visit(&self, f: &mut dyn FnMut(&Row));
    /// Where sample `k` (from 0) comes from, for messages: `file:line` for a
    /// file, the experiment and sample otherwise.
    fn locate(&self, k: usize) -> String {
        format!("experiment `{}`, sample {}", self.name(), k + 1)
    }
}

/// An experiment held in memory, column by column.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// Name.
    pub name: String,
    /// Sample time.
    pub h: f64,
    /// `states[i][k]`.
    pub states: Vec<Vec<f64>>,
    /// `inputs[i][k]`.
    pub inputs: Vec<Vec<f64>>,
    /// Heading per sample (planar rotation), else empty.
    pub heading: Vec<f64>,
    /// `rotation[c][k]` for a measured `R`.
    pub rotation: Vec<Vec<f64>>,
    /// `disturbances[c][k]` for measured components; empty for unmeasured ones.
    pub disturbances: Vec<Vec<f64>>,
}

impl Experiment {
    /// An empty experiment shaped for a model.
    pub fn new(ir: &Ir, name: &str, h: f64) -> Experiment {
        Experiment {
            name: name.to_string(),
            h,
            states: vec![Vec::new(); ir.states.len()],
            inputs: vec![Vec::new(); ir.inputs.len()],
            heading: Vec::new(),
            rotation: vec![
                Vec::new();
                if matches!(ir.rotation, Rotation::Measured { .. }) {
                    ir.rotation_vars.len()
                } else {
                    0
                }
            ],
            disturbances: vec![Vec::new(); ir.components.len()],
        }
    }
    /// Appends one sample (`heading` ignored without a planar rotation,
    /// `disturbances` read only for measured components).
    pub fn push(&mut self, ir: &Ir, row: &Row) {
        for (c, v) in self.states.iter_mut().zip(row.states) {
            c.push(*v);
        }
        for (c, v) in self.inputs.iter_mut().zip(row.inputs) {
            c.push(*v);
        }
        if matches!(ir.rotation, Rotation::Planar { .. }) {
            self.heading.push(row.heading);
        }
        for (c, v) in self.rotation.iter_mut().zip(row.rotation) {
            c.push(*v);
        }
        for (i, comp) in ir.components.iter().enumerate() {
            if ir.disturbances[comp.disturbance].measured {
                self.disturbances[i].push(row.disturbances.get(i).copied().unwrap_or(0.0));
            }
        }
    }
    /// The first `n` samples.
    pub fn truncated(&self, n: usize) -> Experiment {
        let cut = |v: &Vec<Vec<f64>>| v.iter().map(|c| c[..n.min(c.len())].to_vec()).collect();
        Experiment {
            name: self.name.clone(),
            h: self.h,
            states: cut(&self.states),
            inputs: cut(&self.inputs),
            heading: self.heading[..n.min(self.heading.len())].to_vec(),
            rotation: cut(&self.rotation),
            disturbances: cut(&self.disturbances),
        }
    }
}

impl Source for Experiment {
    fn name(&self) -> &str {
        &self.name
    }
    fn len(&self) -> usize {
        self.states.first().map_or(0, Vec::len)
    }
    fn step(&self) -> f64 {
        self.h
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        let mut states = vec![0.0; self.states.len()];
        let mut inputs = vec![0.0; self.inputs.len()];
        let mut rotation = vec![0.0; self.rotation.len()];
        let mut dist = vec![0.0; self.disturbances.len()];
        for k in 0..self.len() {
            for (d, c) in states.iter_mut().zip(&self.states) {
                *d = c[k];
            }
            for (d, c) in inputs.iter_mut().zip(&self.inputs) {
                *d = c[k];
            }
            for (d, c) in rotation.iter_mut().zip(&self.rotation) {
                *d = c[k];
            }
            for (d, c) in dist.iter_mut().zip(&self.disturbances) {
                *d = c.get(k).copied().unwrap_or(0.0);
            }
            let heading = self.heading.get(k).copied().unwrap_or(0.0);
            f(&Row {
                states: &states,
                inputs: &inputs,
                heading,
                rotation: &rotation,
                disturbances: &dist,
            });
        }
    }
}

/// A data problem, with its place.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{location}: {message}")]
pub struct DataError {
    /// `file`, `file:row` or `file:row:column`.
    pub location: String,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: String,
}

impl DataError {
    fn new(
        location: impl Into<String>,
        message: impl Into<String>,
        hint: impl Into<String>,
    ) -> DataError {
        DataError {
            location: location.into(),
            message: message.into(),
            hint: hint.into(),
        }
    }
}

/// The data column a model signal is read from (`data { }` mapping or its own name).
pub fn column_name(ir: &Ir, signal: &str) -> String {
    ir.data_columns
        .get(signal)
        .cloned()
        .unwrap_or_else(|| signal.to_string())
}

/// The signals a model reads from data, as (signal name, role).
#[derive(Clone, Debug, PartialEq, Eq)]
enum Role {
    State(usize),
    Input(usize),
    Heading,
    Rotation(usize),
    Disturbance(usize),
}

fn required_signals(ir: &Ir) -> Vec<(String, Role)> {
    let mut v: Vec<(String, Role)> = Vec::new();
    v.extend(
        ir.states
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), Role::State(i))),
    );
    v.extend(
        ir.inputs
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), Role::Input(i))),
    );
    match &ir.rotation {
        Rotation::Planar { heading, .. } => v.push((heading.clone(), Role::Heading)),
        Rotation::Measured { .. } => v.extend(
            ir.rotation_vars
                .iter()
                .enumerate()
                .map(|(i, s)| (s.clone(), Role::Rotation(i))),
        ),
        Rotation::None => {}
    }
    for (i, c) in ir.components.iter().enumerate() {
        if ir.disturbances[c.disturbance].measured {
            v.push((c.name.clone(), Role::Disturbance(i)));
        }
    }
    v
}

/// The smallest number of samples an experiment may have.
pub const MIN_SAMPLES: usize = 10;

/// The default relative tolerance of each time step against the nominal
/// step: covers a logger's jitter, still catches a dropped sample (a 100 %
/// step error).
pub const DEFAULT_TIME_TOLERANCE: f64 = 0.05;

/// Options of CSV loading.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Sample time to use when the model declares none and there is no time column.
    pub step: Option<f64>,
    /// Largest relative deviation `|Δt − h|/h` of a time step from the nominal
    /// step `h` (the mean step of the experiment), as a fraction.
    pub time_tolerance: f64,
    /// Resample every experiment onto a uniform grid of this step (seconds),
    /// by linear interpolation (needs a time column).
    pub resample: Option<f64>,
}

impl Default for LoadOptions {
    fn default() -> LoadOptions {
        LoadOptions {
            step: None,
            time_tolerance: DEFAULT_TIME_TOLERANCE,
            resample: None,
        }
    }
}

/// What loading a file did besides reading samples, for the user to see:
/// nothing is skipped, tolerated or converted silently.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FileNotes {
    /// The file as named in messages.
    pub file: String,
    /// Lines skipped because their first non-blank character is `#`.
    pub comment_lines: usize,
    /// Lines skipped because they hold only whitespace.
    pub blank_lines: usize,
    /// Per experiment of the file, in order.
    pub experiments: Vec<TimeNotes>,
}

/// How one experiment's time stamps were read.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TimeNotes {
    /// The experiment's name.
    pub experiment: String,
    /// Rows read from the file.
    pub rows: usize,
    /// The largest `|Δt − h|/h` over its steps, when there is a time column
    /// (0 for exactly uniform stamps, up to the tolerance otherwise).
    pub max_step_deviation: Option<f64>,
    /// Samples after resampling (`None` when not resampled).
    pub resampled: Option<usize>,
}

/// A loaded file: its experiments and what was noted while reading it.
#[derive(Clone, Debug)]
pub struct LoadedFile {
    /// The experiments, in file order.
    pub experiments: Vec<Experiment>,
    /// Comment lines, time-stamp jitter, resampling.
    pub notes: FileNotes,
}

/// Loads one CSV file: one experiment, or several when it has an
/// `experiment` column (each experiment's rows contiguous, in file order).
pub fn load_csv(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<Vec<Experiment>, DataError> {
    load_csv_noted(path, ir, options).map(|f| f.experiments)
}

/// [`load_csv`], also returning what was noted on the way ([`FileNotes`]).
pub fn load_csv_noted(
    path: &Path,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    let file = path.display().to_string();
    let handle = std::fs::File::open(path).map_err(|e| {
        DataError::new(
            &file,
            format!("cannot read the file: {e}"),
            "check the path passed to --data",
        )
    })?;
    read_noted(&file, std::io::BufReader::new(handle), ir, options)
}

/// Parses CSV text (see [`load_csv`]); `file` names it in errors.
pub fn parse_csv(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
) -> Result<Vec<Experiment>, DataError> {
    parse_csv_noted(file, text, ir, options).map(|f| f.experiments)
}

/// A reader that drops comment lines (first non-blank character `#`) and
/// blank lines (only whitespace) outside quoted cells, counts them, and
/// remembers where it dropped them, so that the csv reader's line and byte
/// positions map back to the file's physical lines and bytes. Its memory is
/// the current line plus one entry per run of dropped lines, never the file.
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
        }
    }
    /// The physical line (from 1) of a kept line (from 1).
    fn physical_line(&self, kept: u64) -> u64 {
        let i = self.line_jumps.partition_point(|(k, _)| *k <= kept);
        kept + if i == 0 { 0 } else { self.line_jumps[i - 1].1 }
    }
    /// The physical byte offset of a kept byte offset at the start of a line.
    fn physical_byte(&self, kept: u64) -> u64 {
        let i = self.byte_jumps.partition_point(|(k, _)| *k <= kept);
        kept + if i == 0 { 0 } else { self.byte_jumps[i - 1].1 }
    }
    /// Reads the next kept line into `self.line`; false at the end.
    fn next_line(&mut self) -> std::io::Result<bool> {
        let mut dropped = false;
        loop {
            self.line.clear();
            self.pos = 0;
            let n = self.inner.read_until(b'\n', &mut self.line)?;
            if n == 0 {
                return Ok(false);
            }
            self.physical += 1;
            let start = self.byte;
            self.byte += n as u64;
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
            // CRLF outside quotes becomes " \n" (same length, so byte offsets
            // hold; the space is trimmed): the csv reader then ends records
            // at `\n` only and its positions count lines as an editor does.
            let len = self.line.len();
            if !self.in_quotes && self.line.ends_with(b"\r\n") {
                self.line[len - 2] = b' ';
            }
            return Ok(true);
        }
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
        let file = path.display().to_string();
        let handle = std::fs::File::open(path).map_err(|e| {
            DataError::new(
                &file,
                format!("cannot read the file: {e}"),
                format!("check the path passed to {what}"),
            )
        })?;
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
        for (i, h) in headers.iter().enumerate() {
            if let Some(j) = headers[..i].iter().position(|g| g == h) {
                return Err(DataError::new(
                    format!("{file}:{header_line}:{}", i + 1),
                    format!(
                        "column `{h}` appears twice (columns {} and {})",
                        j + 1,
                        i + 1
                    ),
                    "rename one of them; leeway will not guess which is meant",
                ));
            }
        }
        Ok(Records {
            file: file.to_string(),
            what: what.to_string(),
            reader,
            record: csv::ByteRecord::new(),
            headers,
            header_line,
            line: header_line,
        })
    }
    /// The column names.
    pub fn headers(&self) -> &[String] {
        &self.headers
    }
    /// The header's physical line.
    pub fn header_line(&self) -> u64 {
        self.header_line
    }
    /// The file as named in messages.
    pub fn file(&self) -> &str {
        &self.file
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
    /// Cell `i` of the current record as a finite number, or the located
    /// reason it is not (`name` is the column's name in the message).
    pub fn number(&self, i: usize, name: &str) -> Result<f64, DataError> {
        cell(&self.file, self.line, &self.record, i, name)
    }
    /// Comment lines and blank lines dropped so far.
    pub fn dropped(&self) -> (usize, usize) {
        let f = self.reader.get_ref();
        (f.comments, f.blanks)
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

/// Where each model signal is read from in a file's records.
#[derive(Clone, Debug)]
struct Layout {
    /// `(role, column index, column name, unit factor)`.
    cols: Vec<(Role, usize, String, f64)>,
    time_col: Option<usize>,
    time_factor: f64,
    exp_col: Option<usize>,
}

/// The number of rotation columns read from data (a measured `R`), else 0.
fn measured_rotation(ir: &Ir) -> usize {
    if matches!(ir.rotation, Rotation::Measured { .. }) {
        ir.rotation_vars.len()
    } else {
        0
    }
}

/// One sample's values, reused from row to row.
struct RowBuf {
    states: Vec<f64>,
    inputs: Vec<f64>,
    rotation: Vec<f64>,
    dist: Vec<f64>,
    heading: f64,
}

impl RowBuf {
    fn new(ir: &Ir) -> RowBuf {
        RowBuf {
            states: vec![0.0; ir.states.len()],
            inputs: vec![0.0; ir.inputs.len()],
            rotation: vec![0.0; measured_rotation(ir)],
            dist: vec![0.0; ir.components.len()],
            heading: 0.0,
        }
    }
    fn row(&self) -> Row<'_> {
        Row {
            states: &self.states,
            inputs: &self.inputs,
            heading: self.heading,
            rotation: &self.rotation,
            disturbances: &self.dist,
        }
    }
}

/// One cell as a finite number, or the located reason it is not.
fn cell(
    file: &str,
    line: u64,
    record: &csv::ByteRecord,
    i: usize,
    name: &str,
) -> Result<f64, DataError> {
    let bytes = record.get(i).unwrap_or(b"");
    let raw = String::from_utf8_lossy(bytes);
    let loc = || format!("{file}:{line}:{} ({name})", i + 1);
    match std::str::from_utf8(bytes).ok().map(str::parse::<f64>) {
        Some(Ok(v)) if v.is_finite() => Ok(v),
        Some(Ok(_)) => Err(DataError::new(
            loc(),
            format!("`{raw}` is not a finite number"),
            "NaN and infinite values are not accepted; remove or repair the sample, leeway does not interpolate",
        )),
        _ if bytes.is_empty() => Err(DataError::new(
            loc(),
            "empty cell",
            "every sample needs every signal; leeway does not fill gaps",
        )),
        _ => Err(DataError::new(
            loc(),
            format!("`{}` is not a number", raw.escape_debug()),
            "use a plain decimal such as 0.25 or -1.5e-3",
        )),
    }
}

/// Reads one record's signals into `buf` (declared units converted to the
/// model's base units, once, here); returns its time stamp when asked
/// (visits after the validating pass do not need it).
fn parse_row(
    file: &str,
    line: u64,
    record: &csv::ByteRecord,
    layout: &Layout,
    buf: &mut RowBuf,
    with_time: bool,
) -> Result<Option<f64>, DataError> {
    for (role, i, name, factor) in &layout.cols {
        let v = cell(file, line, record, *i, name)? * factor;
        match role {
            Role::State(s) => buf.states[*s] = v,
            Role::Input(s) => buf.inputs[*s] = v,
            Role::Heading => buf.heading = v,
            Role::Rotation(s) => buf.rotation[*s] = v,
            Role::Disturbance(s) => buf.dist[*s] = v,
        }
    }
    match layout.time_col {
        Some(i) if with_time => Ok(Some(
            cell(file, line, record, i, "time")? * layout.time_factor,
        )),
        _ => Ok(None),
    }
}

fn csv_builder() -> csv::ReaderBuilder {
    let mut b = csv::ReaderBuilder::new();
    b.flexible(false)
        .trim(csv::Trim::All)
        .terminator(csv::Terminator::Any(b'\n'));
    b
}

/// The most extreme samples of each signal column kept for the outlier check.
const EXTREMES: usize = 17;

/// How far outside the range of the bulk of a column a sample must lie to be
/// a gross outlier, in multiples of that range (see `Extremes`).
pub const OUTLIER_FACTOR: f64 = 1e4;

/// The gross-outlier bound for a column that is otherwise exactly 0, for
/// states, the heading, rotation entries and measured disturbances (base
/// units m/s, rad, rad/s: no physical value comes near).
pub const ZERO_OUTLIER: f64 = 1e6;

/// The same for inputs (forces, angles and rates in the user's units).
pub const ZERO_OUTLIER_INPUT: f64 = 1e12;

/// A gross outlier found by [`Extremes::outliers`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Outlier {
    value: f64,
    line: u64,
    /// The bulk's range (equal ends for a constant column).
    lo: f64,
    hi: f64,
    /// The bound it broke, for a constant column of 0: `Some(bound)`.
    zero_bound: Option<f64>,
}

/// The [`EXTREMES`] largest and smallest values of one column, with their
/// physical lines: enough to find isolated gross outliers in one pass and
/// flat memory.
///
/// The rule: with `K = min(16, (n − 1)/4)`, the bulk of the column is the
/// range `[lo, hi]` of its values without the `K` smallest and `K` largest;
/// a value farther than [`OUTLIER_FACTOR`] × `(hi − lo)` outside it is a gross
/// outlier. A real zigzag (the rudder switching between ±35°, held for many
/// samples each time) has its extremes inside the bulk, and any physical
/// excursion held for more than `K` samples is part of the bulk. The rule is
/// scale-free: units do not change it.
///
/// A column constant apart from at most `K` samples (`hi = lo = c`: a
/// sensor stuck at one value) has no spread to compare with; there a value
/// farther than [`OUTLIER_FACTOR`] × `|c|` from `c` is a gross outlier (still
/// scale-free), and when `c = 0`, one beyond an absolute bound in base units:
/// [`ZERO_OUTLIER`] for states, heading, rotation and measured disturbances
/// (speeds in m/s, angles in rad, rates in rad/s), [`ZERO_OUTLIER_INPUT`]
/// for inputs, whose units are the user's. A short pulse on a column that is
/// otherwise zero (a thruster kick) stays accepted.
#[derive(Clone, Debug, Default)]
struct Extremes {
    /// Largest first.
    high: Vec<(f64, u64)>,
    /// Smallest first.
    low: Vec<(f64, u64)>,
}

impl Extremes {
    fn push(&mut self, v: f64, line: u64) {
        if self.high.len() < EXTREMES || v > self.high[EXTREMES - 1].0 {
            let i = self.high.partition_point(|(x, _)| *x >= v);
            self.high.insert(i, (v, line));
            self.high.truncate(EXTREMES);
        }
        if self.low.len() < EXTREMES || v < self.low[EXTREMES - 1].0 {
            let i = self.low.partition_point(|(x, _)| *x <= v);
            self.low.insert(i, (v, line));
            self.low.truncate(EXTREMES);
        }
    }
    /// The gross outliers among `n` samples, by line (`zero_bound`: the
    /// absolute bound of a column that is otherwise 0).
    fn outliers(&self, n: usize, zero_bound: f64) -> Vec<Outlier> {
        let k = ((n.saturating_sub(1)) / 4).min(EXTREMES - 1);
        if k == 0 || self.high.len() <= k || self.low.len() <= k {
            return Vec::new();
        }
        let (lo, hi) = (self.low[k].0, self.high[k].0);
        let w = hi - lo;
        if !w.is_finite() || w < 0.0 {
            return Vec::new();
        }
        // A spread to compare with, else the constant's own magnitude, else
        // (a column of zeros) the absolute bound.
        let (far, bound) = if w > 0.0 {
            (OUTLIER_FACTOR * w, None)
        } else if lo != 0.0 {
            (OUTLIER_FACTOR * lo.abs(), None)
        } else {
            (zero_bound, Some(zero_bound))
        };
        let mut out: Vec<Outlier> = self.high[..k]
            .iter()
            .filter(|(x, _)| *x - hi > far)
            .chain(self.low[..k].iter().filter(|(x, _)| lo - *x > far))
            .map(|(x, l)| Outlier {
                value: *x,
                line: *l,
                lo,
                hi,
                zero_bound: bound,
            })
            .collect();
        out.sort_by_key(|o| o.line);
        out
    }
}

/// What one pass found about one experiment's time stamps: enough to check
/// them against the mean step without holding them.
#[derive(Clone, Debug, Default)]
struct TimeScan {
    first: Option<f64>,
    last: f64,
    /// First non-increasing step: `(step, line)`.
    backwards: Option<(f64, u64)>,
    /// Smallest and largest step, first occurrence: `(step, line)`.
    min: Option<(f64, u64)>,
    max: Option<(f64, u64)>,
}

impl TimeScan {
    fn push(&mut self, t: f64, line: u64) {
        if self.first.is_some() {
            let dt = t - self.last;
            if dt <= 0.0 && self.backwards.is_none() {
                self.backwards = Some((dt, line));
            }
            if self.min.is_none_or(|(m, _)| dt < m) {
                self.min = Some((dt, line));
            }
            if self.max.is_none_or(|(m, _)| dt > m) {
                self.max = Some((dt, line));
            }
        } else {
            self.first = Some(t);
        }
        self.last = t;
    }
}

/// One experiment of a file as the validating pass found it: what visiting
/// it again needs, and what was noted.
#[derive(Clone, Debug)]
pub struct Block {
    /// The experiment's name.
    pub name: String,
    /// Physical byte offset of its first row.
    pub start: u64,
    /// Physical line of its first row.
    pub first_line: u64,
    /// Rows (samples).
    pub rows: usize,
    /// Sample time.
    pub h: f64,
    times: TimeScan,
    extremes: Vec<Extremes>,
}

/// A validated file: its experiments' blocks and the notes.
#[derive(Clone, Debug)]
struct Scanned {
    header_line: u64,
    blocks: Vec<Block>,
    notes: FileNotes,
}

/// What the validating pass hands on for each sample: its block, its
/// physical line, its values and its time stamp.
type Sink<'a> = dyn FnMut(usize, u64, &Row, Option<f64>) -> Result<(), DataError> + 'a;

/// The validating pass over one file: every check (cells, header, columns,
/// units, experiments contiguous, time stamps, gross outliers), in one read
/// with reused buffers; `sink(block, line, row, time)` sees every sample.
fn scan<R: std::io::BufRead>(
    file: &str,
    input: R,
    ir: &Ir,
    options: &LoadOptions,
    sink: &mut Sink,
) -> Result<Scanned, DataError> {
    let mut records = Records::new(file, input, "--data")?;
    let header_line = records.header_line();
    let headers = records.headers().to_vec();
    let find = |name: &str| headers.iter().position(|h| h == name);
    let mut cols: Vec<(Role, usize, String, f64)> = Vec::new();
    for (signal, role) in required_signals(ir) {
        let col = column_name(ir, &signal);
        match find(&col) {
            Some(i) => cols.push((role, i, col, unit_factor(ir, &signal))),
            None => {
                let mapped = if col != signal {
                    format!(" (mapped from `{signal}` by the model's data block)")
                } else {
                    String::new()
                };
                return Err(DataError::new(
                    format!("{file}:{header_line}"),
                    format!("missing column `{col}`{mapped}"),
                    format!(
                        "the header has: {}. Name the column `{col}`, or map it in the model: data {{ {signal} = \"<column>\" }}",
                        leeway_structure::grammar::join_capped(&headers, ", ")
                    ),
                ));
            }
        }
    }
    let layout = Layout {
        cols,
        time_col: find(&column_name(ir, "time")),
        time_factor: unit_factor(ir, "time"),
        exp_col: find(&column_name(ir, "experiment")),
    };
    let base_name = Path::new(file)
        .file_stem()
        .map_or(file.to_string(), |s| s.to_string_lossy().to_string());
    let mut blocks: Vec<Block> = Vec::new();
    let mut finished: std::collections::HashSet<Vec<u8>> = std::collections::HashSet::new();
    let mut current: Option<Vec<u8>> = None;
    let mut buf = RowBuf::new(ir);
    let n_cols = layout.cols.len();
    while records.next_record()? {
        let line = records.line();
        let t = parse_row(file, line, &records.record, &layout, &mut buf, true)?;
        let exp_name: &[u8] = match layout.exp_col {
            Some(i) => records.raw(i),
            None => base_name.as_bytes(),
        };
        if current.as_deref() != Some(exp_name) {
            let name = String::from_utf8_lossy(exp_name).into_owned();
            if finished.contains(exp_name) {
                return Err(DataError::new(
                    format!(
                        "{file}:{line}:{} (experiment)",
                        layout.exp_col.map_or(0, |i| i + 1)
                    ),
                    format!("experiment `{name}` resumes after another experiment started"),
                    "keep the rows of one experiment together, in time order",
                ));
            }
            if let Some(c) = current.take() {
                finished.insert(c);
            }
            current = Some(exp_name.to_vec());
            blocks.push(Block {
                name,
                start: records.byte(),
                first_line: line,
                rows: 0,
                h: 0.0,
                times: TimeScan::default(),
                extremes: vec![Extremes::default(); n_cols + 1],
            });
        }
        let b = blocks.len() - 1;
        let block = &mut blocks[b];
        block.rows += 1;
        if let Some(t) = t {
            block.times.push(t, line);
        }
        for (j, (role, ..)) in layout.cols.iter().enumerate() {
            let v = match role {
                Role::State(s) => buf.states[*s],
                Role::Input(s) => buf.inputs[*s],
                Role::Heading => buf.heading,
                Role::Rotation(s) => buf.rotation[*s],
                Role::Disturbance(s) => buf.dist[*s],
            };
            block.extremes[j].push(v, line);
        }
        sink(b, line, &buf.row(), t)?;
    }
    let (comment_lines, blank_lines) = records.dropped();
    let mut notes = FileNotes {
        file: file.to_string(),
        comment_lines,
        blank_lines,
        experiments: Vec::new(),
    };
    if blocks.is_empty() {
        return Err(DataError::new(
            format!("{file}:{}", header_line + 1),
            "the file has a header but no samples",
            "record at least a few hundred samples per experiment",
        ));
    }
    for block in &mut blocks {
        let n = block.rows;
        if n < MIN_SAMPLES {
            return Err(DataError::new(
                format!("{file}:{}", block.first_line),
                format!(
                    "experiment `{}` has {n} samples; at least {MIN_SAMPLES} are needed",
                    block.name
                ),
                "an estimate needs many more samples than parameters; record a longer experiment",
            ));
        }
        for (j, (role, i, name, _)) in layout.cols.iter().enumerate() {
            let zero_bound = match role {
                Role::Input(_) => ZERO_OUTLIER_INPUT,
                _ => ZERO_OUTLIER,
            };
            let found = block.extremes[j].outliers(n, zero_bound);
            if let Some(o) = found.first() {
                let more = match found.len() - 1 {
                    0 => String::new(),
                    m => format!(" ({m} more in this column)"),
                };
                let (v, lo, hi) = (o.value, o.lo, o.hi);
                let why = if hi > lo {
                    format!(
                        "the other samples of experiment `{}` lie in [{lo:e}, {hi:e}], and this one is {:.1e} times that range away",
                        block.name,
                        if v > hi {
                            (v - hi) / (hi - lo)
                        } else {
                            (lo - v) / (hi - lo)
                        }
                    )
                } else if let Some(bound) = o.zero_bound {
                    format!(
                        "every other sample of experiment `{}` is 0 (the column is constant), and this one exceeds {bound:e} in magnitude",
                        block.name
                    )
                } else {
                    format!(
                        "every other sample of experiment `{}` is {lo:e} (the column is constant, a sensor stuck?), and this one is {:.1e} times that value away",
                        block.name,
                        (v - lo).abs() / lo.abs()
                    )
                };
                return Err(DataError::new(
                    format!("{file}:{}:{} ({name})", o.line, i + 1),
                    format!("`{name}` = {v:e} is a gross outlier: {why}{more}"),
                    format!(
                        "repair or remove the sample (leeway does not drop or interpolate samples); a value more than {OUTLIER_FACTOR:e} times the spread of the rest of its column (or, for a constant column, its value) away is taken for a logging error"
                    ),
                ));
            }
        }
        let time_column = layout.time_col.map_or(0, |c| c + 1);
        let (h, deviation) = sample_time(file, ir, block, time_column, options)?;
        block.h = h;
        notes.experiments.push(TimeNotes {
            experiment: block.name.clone(),
            rows: n,
            max_step_deviation: deviation,
            resampled: None,
        });
    }
    Ok(Scanned {
        header_line,
        blocks,
        notes,
    })
}

/// Most samples `--resample` may make per row read: a finer grid only
/// interpolates, and memory would follow the grid.
pub const MAX_RESAMPLE_RATIO: f64 = 100.0;

/// [`parse_csv`], also returning what was noted on the way ([`FileNotes`]).
pub fn parse_csv_noted(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    read_noted(file, text, ir, options)
}

/// Loads a file into memory through the validating pass.
fn read_noted<R: std::io::BufRead>(
    file: &str,
    input: R,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    let mut held: Vec<(Experiment, Vec<f64>)> = Vec::new();
    let scanned = scan(file, input, ir, options, &mut |b, _, row, t| {
        if held.len() <= b {
            held.push((Experiment::new(ir, "", 0.0), Vec::new()));
        }
        let (e, times) = &mut held[b];
        e.push(ir, row);
        if let Some(t) = t {
            times.push(t);
        }
        Ok(())
    })?;
    let mut notes = scanned.notes;
    let mut out = Vec::new();
    for ((mut e, times), (block, time_notes)) in held
        .into_iter()
        .zip(scanned.blocks.iter().zip(notes.experiments.iter_mut()))
    {
        e.name = block.name.clone();
        e.h = block.h;
        if let Some(step) = options.resample {
            let first_line = block.first_line;
            if times.len() != e.len() {
                return Err(DataError::new(
                    format!("{file}:{}", scanned.header_line),
                    "--resample needs a time column, and the file has none",
                    format!(
                        "add a `{}` column of time stamps (or map one with data {{ time = \"<column>\" }}), or drop --resample",
                        column_name(ir, "time")
                    ),
                ));
            }
            let span = times[times.len() - 1] - times[0];
            let count = span / step + 1.0;
            if count > MAX_RESAMPLE_RATIO * e.len() as f64 {
                return Err(DataError::new(
                    format!("{file}:{first_line}"),
                    format!(
                        "--resample {step} would make {count:.0} samples of experiment `{}` from its {} rows; at most {MAX_RESAMPLE_RATIO} per row",
                        e.name,
                        e.len()
                    ),
                    "choose a resampling step near the logger's own step",
                ));
            }
            e = crate::resample::resample(ir, &e, &times, step);
            if e.len() < MIN_SAMPLES {
                return Err(DataError::new(
                    format!("{file}:{first_line}"),
                    format!(
                        "experiment `{}` has {} samples at --resample {step}; at least {MIN_SAMPLES} are needed",
                        e.name,
                        e.len()
                    ),
                    "choose a smaller --resample step",
                ));
            }
            time_notes.resampled = Some(e.len());
        }
        out.push(e);
    }
    Ok(LoadedFile {
        experiments: out,
        notes,
    })
}

/// The validated samples of a file, as the validating pass parsed them:
/// per row its physical line (`u64`) and the layout's values (`f64`, base
/// units), little-endian, in a temporary file removed when the last
/// [`CsvSource`] of the file is dropped. Later passes read these bytes
/// instead of parsing the text again: the values are the validated ones, bit
/// for bit, and a file rewritten after validation changes nothing.
#[derive(Debug)]
struct Spill {
    file: tempfile::NamedTempFile,
    /// Values per row (the layout's columns).
    width: usize,
}

impl Spill {
    /// Bytes per row: the line and the values.
    fn record(&self) -> u64 {
        8 * (1 + self.width as u64)
    }
}

/// Writes validated rows to a [`Spill`].
struct SpillWriter {
    out: std::io::BufWriter<std::fs::File>,
    bytes: Vec<u8>,
}

impl SpillWriter {
    fn push(&mut self, line: u64, roles: &[Role], row: &Row) -> std::io::Result<()> {
        use std::io::Write;
        self.bytes.clear();
        self.bytes.extend_from_slice(&line.to_le_bytes());
        for role in roles {
            let v = match role {
                Role::State(s) => row.states[*s],
                Role::Input(s) => row.inputs[*s],
                Role::Heading => row.heading,
                Role::Rotation(s) => row.rotation[*s],
                Role::Disturbance(s) => row.disturbances[*s],
            };
            self.bytes.extend_from_slice(&v.to_le_bytes());
        }
        self.out.write_all(&self.bytes)
    }
}

/// An experiment of a CSV file visited in passes: the validating pass wrote
/// its samples to a spill file ([`open_csv`]), and each [`Source::visit`]
/// reads them back from there (binary, buffered; no text is parsed again),
/// in flat memory whatever N.
#[derive(Debug)]
pub struct CsvSource {
    file: String,
    /// What each value of a spilled row is.
    roles: Vec<Role>,
    block: Block,
    spill: std::sync::Arc<Spill>,
    /// The block's first row in the spill.
    first_record: u64,
    n_states: usize,
    n_inputs: usize,
    n_rotation: usize,
    n_comp: usize,
    /// A problem met while reading the spill file back (it vanished or the
    /// disk failed); visiting then stops short.
    failure: std::sync::Mutex<Option<DataError>>,
}

impl CsvSource {
    /// The experiment's block (name, first row, rows, step).
    pub fn block(&self) -> &Block {
        &self.block
    }
    /// The file as named in messages.
    pub fn file(&self) -> &str {
        &self.file
    }
    /// A problem met by a later pass, if any (the spill file could not be read).
    pub fn failure(&self) -> Option<DataError> {
        self.failure.lock().ok().and_then(|f| f.clone())
    }
    fn fail(&self, e: DataError) {
        if let Ok(mut f) = self.failure.lock()
            && f.is_none()
        {
            *f = Some(e);
        }
    }
    /// Reads the rows from `from` on, `f(index, physical line, row)` on each;
    /// stops at the first problem (recorded) or when `f` returns false.
    fn read(&self, from: usize, f: &mut dyn FnMut(usize, u64, &Row) -> bool) {
        use std::io::{Read, Seek, SeekFrom};
        let lost = |why: String| {
            DataError::new(
                &self.file,
                format!(
                    "cannot read back the validated samples of experiment `{}`: {why}",
                    self.block.name
                ),
                "the temporary copy of the data (in the system's temporary directory, TMPDIR) was removed or could not be read; check that directory and run again",
            )
        };
        let record = self.spill.record();
        let mut handle = match self.spill.file.reopen() {
            Ok(h) => h,
            Err(e) => return self.fail(lost(e.to_string())),
        };
        if let Err(e) = handle.seek(SeekFrom::Start((self.first_record + from as u64) * record)) {
            return self.fail(lost(e.to_string()));
        }
        let mut input = std::io::BufReader::with_capacity(1 << 16, handle);
        let mut bytes = vec![0u8; 8 * (1 + self.spill.width)];
        let mut buf = RowBuf {
            states: vec![0.0; self.n_states],
            inputs: vec![0.0; self.n_inputs],
            rotation: vec![0.0; self.n_rotation],
            dist: vec![0.0; self.n_comp],
            heading: 0.0,
        };
        let word = |b: &[u8], i: usize| -> [u8; 8] {
            let mut w = [0u8; 8];
            w.copy_from_slice(&b[8 * i..8 * i + 8]);
            w
        };
        for k in from..self.block.rows {
            if let Err(e) = input.read_exact(&mut bytes) {
                return self.fail(lost(format!("row {} of {}: {e}", k + 1, self.block.rows)));
            }
            let line = u64::from_le_bytes(word(&bytes, 0));
            for (j, role) in self.roles.iter().enumerate() {
                let v = f64::from_le_bytes(word(&bytes, j + 1));
                match role {
                    Role::State(s) => buf.states[*s] = v,
                    Role::Input(s) => buf.inputs[*s] = v,
                    Role::Heading => buf.heading = v,
                    Role::Rotation(s) => buf.rotation[*s] = v,
                    Role::Disturbance(s) => buf.dist[*s] = v,
                }
            }
            if !f(k, line, &buf.row()) {
                return;
            }
        }
    }
}

impl Source for CsvSource {
    fn name(&self) -> &str {
        &self.block.name
    }
    fn len(&self) -> usize {
        self.block.rows
    }
    fn step(&self) -> f64 {
        self.block.h
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        self.read(0, &mut |_, _, row| {
            f(row);
            true
        });
    }
    fn locate(&self, k: usize) -> String {
        let mut at = None;
        if k < self.block.rows {
            self.read(k, &mut |_, line, _| {
                at = Some(line);
                false
            });
        }
        match at {
            Some(line) => format!("{}:{line}", self.file),
            None => format!(
                "{}: experiment `{}`, sample {}",
                self.file,
                self.block.name,
                k + 1
            ),
        }
    }
}

/// A validated file visited in passes: one [`CsvSource`] per experiment.
#[derive(Debug)]
pub struct StreamedFile {
    /// The experiments, in file order.
    pub sources: Vec<CsvSource>,
    /// Comment and blank lines, time-stamp jitter.
    pub notes: FileNotes,
}

/// Opens a CSV file for streaming: one validating pass (every check of
/// [`load_csv`]) that also writes the parsed samples to a temporary spill
/// file (8 bytes per value and row, in the system's temporary directory,
/// removed when the sources are dropped); every later visit reads them from
/// there. Memory is flat in the number of rows. `--resample` is not
/// streamed: use [`load_csv_noted`] for it.
pub fn open_csv(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<StreamedFile, DataError> {
    let file = path.display().to_string();
    let handle = std::fs::File::open(path).map_err(|e| {
        DataError::new(
            &file,
            format!("cannot read the file: {e}"),
            "check the path passed to --data",
        )
    })?;
    let spill_error = |e: std::io::Error| {
        DataError::new(
            &file,
            format!("cannot write the temporary copy of the validated samples: {e}"),
            format!(
                "leeway streams a file through a binary copy in the system's temporary directory ({}); free space there or point TMPDIR elsewhere",
                std::env::temp_dir().display()
            ),
        )
    };
    let spill_file = tempfile::Builder::new()
        .prefix("leeway-spill-")
        .tempfile()
        .map_err(spill_error)?;
    let mut writer = SpillWriter {
        out: std::io::BufWriter::with_capacity(1 << 16, spill_file.reopen().map_err(spill_error)?),
        bytes: Vec::new(),
    };
    let input = std::io::BufReader::with_capacity(1 << 16, handle);
    // Every signal the model reads from data, in a fixed order.
    let roles: Vec<Role> = required_signals(ir).into_iter().map(|(_, r)| r).collect();
    let scanned = scan(&file, input, ir, options, &mut |_, line, row, _| {
        writer.push(line, &roles, row).map_err(spill_error)
    })?;
    std::io::Write::flush(&mut writer.out).map_err(spill_error)?;
    drop(writer);
    let spill = std::sync::Arc::new(Spill {
        file: spill_file,
        width: roles.len(),
    });
    let mut first_record = 0u64;
    let sources = scanned
        .blocks
        .into_iter()
        .map(|block| {
            let first = first_record;
            first_record += block.rows as u64;
            CsvSource {
                file: file.clone(),
                roles: roles.clone(),
                block: Block {
                    extremes: Vec::new(),
                    ..block
                },
                spill: spill.clone(),
                first_record: first,
                n_states: ir.states.len(),
                n_inputs: ir.inputs.len(),
                n_rotation: measured_rotation(ir),
                n_comp: ir.components.len(),
                failure: std::sync::Mutex::new(None),
            }
        })
        .collect();
    Ok(StreamedFile {
        sources,
        notes: scanned.notes,
    })
}

/// The factor converting a signal's declared unit to the base unit (1 when
/// none is declared).
fn unit_factor(ir: &Ir, signal: &str) -> f64 {
    ir.data_units
        .get(signal)
        .map_or(1.0, |u| leeway_structure::units::factor(u))
}

/// The sample time of one experiment and the largest relative deviation of
/// its steps from it (`None` without time stamps). The nominal step is the
/// mean step; every step must lie within `options.time_tolerance` of it, in
/// relative terms. The worst step is the smallest or the largest, which the
/// validating pass kept with their lines.
fn sample_time(
    file: &str,
    ir: &Ir,
    block: &Block,
    time_column: usize,
    options: &LoadOptions,
) -> Result<(f64, Option<f64>), DataError> {
    let declared = ir.step.or(options.step);
    let first_line = block.first_line;
    let t = &block.times;
    let (Some(first), Some(min), Some(max)) = (t.first, t.min, t.max) else {
        let h = declared.ok_or_else(|| {
            DataError::new(
                file,
                "no sample time: the model declares no `step` and the data have no `time` column",
                "declare `step h` in the model or add a `time` column",
            )
        })?;
        return Ok((h, None));
    };
    // The nominal step is the mean step, the best estimate of a uniform h
    // under jitter. A gap shifts the mean of a short record, so that good
    // steps may fall outside the tolerance too: the error names the worst
    // step, which is the gap.
    let mean = (t.last - first) / (block.rows - 1) as f64;
    let tol = options.time_tolerance;
    let at = |line: u64| format!("{file}:{line}:{time_column} (time)");
    let hint = "leeway needs uniformly sampled data: a larger jitter may be allowed with --time-tolerance, \
                --resample H interpolates onto a uniform grid, or split the log into experiments at the gaps";
    if let Some((dt, line)) = t.backwards {
        return Err(DataError::new(
            at(line),
            format!("time does not increase: step {dt} s here"),
            hint,
        ));
    }
    let dev = |dt: f64| (dt - mean).abs() / mean;
    // The first of the two on a tie, as a scan in file order would find it.
    let (dmin, dmax) = (dev(min.0), dev(max.0));
    let ((dt, line), worst) = if dmax > dmin || (dmax == dmin && max.1 < min.1) {
        (max, dmax)
    } else {
        (min, dmin)
    };
    // Resampling interpolates over any spacing; only the order matters then.
    if options.resample.is_none() && worst > tol {
        return Err(DataError::new(
            at(line),
            format!(
                "inconsistent sample time: step {dt} s here, {:.1} % off the nominal (mean) step {mean} s; the tolerance is {:.1} %",
                100.0 * worst,
                100.0 * tol
            ),
            hint,
        ));
    }
    // Under resampling the grid step is the sample time, checked against the
    // model's step by the caller.
    let h = options.resample.unwrap_or(mean);
    if let Some(d) = declared
        && (h - d).abs() > 1e-3 * d
    {
        let what = if options.resample.is_some() {
            format!("--resample {h} conflicts with the model's step {d}")
        } else {
            format!("the data are sampled every {mean} s but the model declares step {d}")
        };
        return Err(DataError::new(
            format!("{file}:{first_line}:{time_column} (time)"),
            what,
            "make `step` in the model match the data, or resample the data (--resample H)",
        ));
    }
    Ok((declared.unwrap_or(h), Some(worst)))
}

/// Unit check of a heading that integrates a yaw rate: the least-squares gain
/// of `Δψ/h` on `r` (≈ 1 when consistent, ≈ 57.3 when ψ is in degrees and r
/// in rad/s). `None` without a planar heading or with too little yaw motion.
pub fn heading_gain(ir: &Ir, e: &dyn Source) -> Option<f64> {
    let Rotation::Planar { integrates, .. } = &ir.rotation else {
        return None;
    };
    let h = e.step();
    // A log may wrap its heading at ±π (radians) or ±180 (degrees), or not at
    // all. Fit the gain of Δψ/h on r under each hypothesis (removing whole
    // periods from every step) and keep the one that explains Δψ/h best: a
    // threshold on the step size would mistake large steps in degrees for
    // wraps in radians. One visit accumulates all three.
    let periods = [None, Some(2.0 * std::f64::consts::PI), Some(360.0)];
    let mut sums = [(0.0, 0.0, 0.0); 3];
    let mut prev: Option<(f64, f64)> = None;
    e.visit(&mut |row| {
        let r = row.states.get(*integrates).copied().unwrap_or(0.0);
        if let Some((psi1, r1)) = prev {
            for (period, (sxy, sxx, syy)) in periods.iter().zip(sums.iter_mut()) {
                let mut d = row.heading - psi1;
                if let Some(p) = period {
                    d -= p * (d / p).round();
                }
                let y = d / h;
                *sxy += r1 * y;
                *sxx += r1 * r1;
                *syy += y * y;
            }
        }
        prev = Some((row.heading, r));
    });
    sums.into_iter()
        .filter(|(_, sxx, _)| *sxx > 1e-12)
        .map(|(sxy, sxx, syy)| {
            let gain = sxy / sxx;
            (gain, syy - gain * sxy)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(gain, _)| gain)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(data: &str) -> Ir {
        let src = format!(
            "model M {{ state u, r input delta der u = X*u + T*delta der r = N*r {data} }}"
        );
        leeway_structure::compile(&src, &leeway_structure::CompileOptions::default())
            .ir
            .unwrap_or_else(|| panic!("the test model compiles"))
    }

    fn rows(from: usize, n: usize) -> String {
        (from..from + n)
            .map(|k| format!("{k}.0,1,0.5,35\n"))
            .collect()
    }

    #[test]
    fn comment_lines_are_skipped_counted_and_rows_keep_their_line_numbers() {
        let ir = model("step 1.0");
        // Comments before the header, between rows (indented too), and a bad
        // cell on physical line 16.
        let mut text = String::from("# logger v2\n# ship: Test\ntime,u,r,delta\n");
        text.push_str(&rows(0, 5));
        text.push_str("  # pause\n");
        text.push_str(&rows(5, 5));
        text.push_str("10.0,1,x,35\n");
        let err = parse_csv("c.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("the cell `x` is an error"));
        assert_eq!(err.location, "c.csv:15:3 (r)");
        let ok = text.replace("10.0,1,x,35\n", "");
        let loaded = parse_csv_noted("c.csv", ok.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(loaded.notes.comment_lines, 3);
        assert_eq!(loaded.experiments[0].len(), 10);
        // A missing column is located on the header's physical line.
        let err = parse_csv(
            "c.csv",
            ok.replace("delta", "rudder").as_bytes(),
            &ir,
            &LoadOptions::default(),
        )
        .err()
        .unwrap_or_else(|| panic!("a missing column is an error"));
        assert_eq!(err.location, "c.csv:3");
    }

    #[test]
    fn declared_units_are_converted_to_base_units() {
        let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
        let mut text = String::from("time,u,r,rudder\n");
        for k in 0..12 {
            text.push_str(&format!("{},1,{k}.5,35\n", 500 * k));
        }
        let e = parse_csv("u.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let e = &e[0];
        assert_eq!(e.h, 0.5);
        assert_eq!(e.inputs[0][0], 35.0f64.to_radians());
        assert_eq!(e.states[1][3], 3.5f64.to_radians());
        assert_eq!(e.states[0][3], 1.0);
    }

    #[test]
    fn a_dropped_sample_is_located_and_names_the_options() {
        let ir = model("");
        let mut text = String::from("time,u,r,delta\n");
        for k in (0..20).filter(|k| *k != 7) {
            text.push_str(&format!("{},1,0,0\n", f64::from(k) * 0.5));
        }
        let err = parse_csv("d.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("a dropped sample is an error"));
        // Rows 0..6 sit on lines 2..8; the row after the gap is on line 9.
        assert_eq!(err.location, "d.csv:9:1 (time)");
        assert!(err.hint.contains("--time-tolerance") && err.hint.contains("--resample"));
    }

    fn error_of(text: &str) -> DataError {
        parse_csv(
            "b.csv",
            text.as_bytes(),
            &model("step 1.0"),
            &LoadOptions::default(),
        )
        .err()
        .unwrap_or_else(|| panic!("an error expected in:\n{text}"))
    }

    #[test]
    fn blank_lines_are_counted_and_rows_keep_their_physical_line() {
        let ir = model("step 1.0");
        // Blank lines (empty, spaces, CRLF) before the header and between rows.
        let mut text = String::from("\n  \ntime,u,r,delta\n");
        text.push_str(&rows(0, 5));
        text.push_str("\n \t \r\n");
        text.push_str(&rows(5, 5));
        let loaded = parse_csv_noted("b.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(loaded.notes.blank_lines, 4);
        assert_eq!(loaded.experiments[0].len(), 10);
        // Line 1, 2 blank, 3 header, 4..8 rows, 9 and 10 blank, 11.. rows.
        text.push_str("10.0,1,x,35\n");
        assert_eq!(error_of(&text).location, "b.csv:16:3 (r)");
    }

    #[test]
    fn a_quoted_cell_holding_line_breaks_keeps_later_rows_on_their_line() {
        let mut text = String::from("time,u,r,delta,note\n");
        for k in 0..12 {
            let note = if k == 3 {
                "\"two\n# not a comment\n\nlines\""
            } else {
                "ok"
            };
            text.push_str(&format!("{k}.0,1,0.5,35,{note}\n"));
        }
        assert!(
            parse_csv(
                "q.csv",
                text.as_bytes(),
                &model("step 1.0"),
                &LoadOptions::default()
            )
            .is_ok()
        );
        text.push_str("12.0,1,0.5,bad,ok\n");
        // 1 header, rows 0..2 on 2..4, row 3 on 5..8, rows 4..11 on 9..16.
        assert_eq!(error_of(&text).location, "b.csv:17:4 (delta)");
    }

    #[test]
    fn crlf_line_ends_read_like_lf() {
        let ir = model("step 1.0");
        let text = format!("time,u,r,delta\n{}", rows(0, 12)).replace('\n', "\r\n");
        let a = parse_csv("c.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let b = parse_csv(
            "c.csv",
            text.replace("\r\n", "\n").as_bytes(),
            &ir,
            &LoadOptions::default(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(a, b);
        // Rows keep their lines under CRLF (csv alone puts a record after a
        // CRLF on the line before).
        let bad = text.replacen("\r\n0.0,1,", "\r\n,1,", 1);
        assert_eq!(error_of(&bad).location, "b.csv:2:1 (time)");
        let bad = text.replace("5.0,1,0.5,35", "5.0,1,0.5,x");
        assert_eq!(error_of(&bad).location, "b.csv:7:4 (delta)");
    }

    #[test]
    fn a_gross_outlier_is_located_by_row_and_a_zigzag_is_not_one() {
        // A zigzag: rudder ±35, switching every 7 samples; u varies a little.
        let zigzag = |spike: Option<(usize, f64)>| {
            let mut text = String::from("time,u,r,delta\n");
            for k in 0..200 {
                let delta = if (k / 7) % 2 == 0 { 35.0 } else { -35.0 };
                let mut u = 5.0 + 0.01 * (k % 13) as f64;
                if let Some((at, v)) = spike
                    && at == k
                {
                    u = v;
                }
                text.push_str(&format!("{k}.0,{u:e},{},{delta}\n", 0.01 * (k % 5) as f64));
            }
            text
        };
        let ir = model("step 1.0");
        assert!(
            parse_csv(
                "z.csv",
                zigzag(None).as_bytes(),
                &ir,
                &LoadOptions::default()
            )
            .is_ok()
        );
        for v in [1e6, -1e9, 1e300] {
            let err = parse_csv(
                "z.csv",
                zigzag(Some((57, v))).as_bytes(),
                &ir,
                &LoadOptions::default(),
            )
            .err()
            .unwrap_or_else(|| panic!("u = {v} is an outlier"));
            assert_eq!(err.location, "z.csv:59:2 (u)", "{err}");
            assert!(err.message.contains("gross outlier"), "{err}");
        }
        // Scale-free: the same data in other units give the same verdicts.
        let scaled = |text: &str, f: f64| -> String {
            text.lines()
                .enumerate()
                .map(|(i, l)| {
                    if i == 0 {
                        return format!("{l}\n");
                    }
                    let c: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(0.0)).collect();
                    format!("{},{:e},{:e},{}\n", c[0], c[1] * f, c[2] * f, c[3])
                })
                .collect()
        };
        for f in [1e-8, 1e-4, 1e4, 1e8] {
            assert!(
                parse_csv(
                    "z.csv",
                    scaled(&zigzag(None), f).as_bytes(),
                    &ir,
                    &LoadOptions::default()
                )
                .is_ok()
            );
            let err = parse_csv(
                "z.csv",
                scaled(&zigzag(Some((57, 1e6))), f).as_bytes(),
                &ir,
                &LoadOptions::default(),
            )
            .err()
            .unwrap_or_else(|| panic!("the outlier at × {f}"));
            assert_eq!(err.location, "z.csv:59:2 (u)");
        }
    }

    #[test]
    fn a_stuck_sensor_with_a_spike_is_an_outlier() {
        // Issue 10 (the gap of the spread rule): a column constant apart from
        // a few samples has no spread; a spike far from the constant, or far
        // from 0 for a column of zeros, is still named by its row.
        let log = |u: &dyn Fn(usize) -> f64, delta: &dyn Fn(usize) -> f64| {
            let mut text = String::from("# a log\ntime,u,r,delta\n");
            for k in 0..200 {
                text.push_str(&format!(
                    "{k}.0,{:e},{},{:e}\n",
                    u(k),
                    0.01 * (k % 5) as f64,
                    delta(k)
                ));
            }
            text
        };
        let ir = model("step 1.0");
        let check =
            |text: String| parse_csv("s.csv", text.as_bytes(), &ir, &LoadOptions::default());
        let varying = |k: usize| 35.0 * ((k / 7) % 2) as f64;
        for (c, spike) in [
            (5.0, 1e300),
            (5.0, -1e6),
            (5e-8, 5e-3),
            (0.0, 1e300),
            (0.0, -2e6),
        ] {
            let err = check(log(&|k| if k == 57 { spike } else { c }, &varying))
                .err()
                .unwrap_or_else(|| panic!("{c} with {spike} at row 57"));
            assert_eq!(err.location, "s.csv:60:2 (u)", "{err}");
            assert!(err.message.contains("is a gross outlier"), "{err}");
            assert!(err.message.contains("the column is constant"), "{err}");
        }
        // Within the bound: a stuck sensor with small deviations, a pulse.
        for (c, spike) in [(5.0, 20.0), (5.0, -4e4), (0.0, 35.0), (0.0, 9e5)] {
            assert!(
                check(log(
                    &|k| if (57..60).contains(&k) { spike } else { c },
                    &varying
                ))
                .is_ok(),
                "{c} with {spike}"
            );
        }
        // Inputs are in the user's units: a thruster kick of 16 samples on a
        // zero column is data; only beyond 1e12 is a zero column's sample a glitch.
        let kick = |k: usize| if (100..116).contains(&k) { 2e6 } else { 0.0 };
        assert!(check(log(&|k| 5.0 + 0.01 * (k % 3) as f64, &kick)).is_ok());
        let glitch = |k: usize| if k == 120 { 1e13 } else { 0.0 };
        let err = check(log(&|k| 5.0 + 0.01 * (k % 3) as f64, &glitch))
            .err()
            .unwrap_or_else(|| panic!("1e13 on a zero input"));
        assert_eq!(err.location, "s.csv:123:4 (delta)", "{err}");
        assert!(err.message.contains("exceeds 1e12 in magnitude"), "{err}");
    }

    #[test]
    fn streaming_visits_give_the_values_of_loading_bit_for_bit() {
        let ir = model("step 1.0");
        let mut text = String::from("# head\ntime,u,r,delta,experiment\n");
        for k in 0..40 {
            let e = if k < 25 { "a" } else { "b" };
            text.push_str(&format!(
                "{k}.0,{},{},{},{e}\n",
                1.0 / (k + 1) as f64,
                0.1 * k as f64,
                (k as f64).sin()
            ));
            if k % 9 == 0 {
                text.push_str("\n# pause\n");
            }
        }
        let path = std::env::temp_dir().join(format!("leeway-stream-{}.csv", std::process::id()));
        std::fs::write(&path, &text).unwrap_or_else(|e| panic!("{e}"));
        let held = load_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let streamed =
            open_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(held.len(), 2);
        assert_eq!(streamed.sources.len(), 2);
        for (h, s) in held.iter().zip(&streamed.sources) {
            assert_eq!((h.name(), h.len(), h.step()), (s.name(), s.len(), s.step()));
            let mut a: Vec<u64> = Vec::new();
            let mut b: Vec<u64> = Vec::new();
            h.visit(&mut |r| a.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
            // Twice: every visit reads the spill again.
            for _ in 0..2 {
                b.clear();
                s.visit(&mut |r| b.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
                assert_eq!(a, b);
            }
            assert!(s.failure().is_none());
        }
        // Sample 3 of `b` (row k = 28) sits on line 36: 2 before the header,
        // 28 rows, and 2 dropped lines after rows 0, 9, 18 and 27.
        assert_eq!(
            streamed.sources[1].locate(3),
            format!("{}:{}", path.display(), 2 + 29 + 2 * 4)
        );
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn resampling_far_finer_than_the_log_is_refused_before_it_allocates() {
        let ir = model("");
        let text = format!("time,u,r,delta\n{}", rows(0, 12));
        let options = LoadOptions {
            resample: Some(1e-3),
            ..LoadOptions::default()
        };
        let err = parse_csv("r.csv", text.as_bytes(), &ir, &options)
            .err()
            .unwrap_or_else(|| panic!("11001 samples from 12 rows is refused"));
        assert_eq!(err.location, "r.csv:2");
        assert!(err.message.contains("at most 100 per row"), "{err}");
    }

    #[test]
    fn later_passes_read_the_validated_samples_and_the_spill_is_removed() {
        // Passes read the binary copy the validating pass wrote: a file
        // rewritten after validation changes nothing (it used to stop the
        // visit with "the file changed while it was being read").
        let ir = model("step 1.0");
        let path = std::env::temp_dir().join(format!("leeway-changed-{}.csv", std::process::id()));
        let text = format!("time,u,r,delta\n{}", rows(0, 20));
        std::fs::write(&path, &text).unwrap_or_else(|e| panic!("{e}"));
        let held = load_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let streamed =
            open_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(&path, format!("time,u,r,delta\n{}", rows(0, 5)))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut a: Vec<u64> = Vec::new();
        let mut b: Vec<u64> = Vec::new();
        held[0].visit(&mut |r| a.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
        streamed.sources[0]
            .visit(&mut |r| b.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
        assert_eq!(a.len(), 20 * 3);
        assert_eq!(a, b);
        assert!(streamed.sources[0].failure().is_none());
        assert_eq!(
            streamed.sources[0].locate(19),
            format!("{}:21", path.display())
        );
        assert_eq!(
            streamed.sources[0].locate(20),
            format!(
                "{}: experiment `{}`, sample 21",
                path.display(),
                streamed.sources[0].name()
            )
        );
        // The spill file is removed with the sources.
        let spill = streamed.sources[0].spill.file.path().to_path_buf();
        assert!(spill.exists());
        drop(streamed);
        assert!(!spill.exists(), "{}", spill.display());
        let _ = std::fs::remove_file(&path);
    }
}
