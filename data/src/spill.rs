//! Streaming a validated file: the validating pass writes every row's
//! values to a binary spill file, and each pass over an experiment
//! ([`FileSource`]) reads them back from there, whatever the format read.
//!
//! Each row is its values in base units, little-endian, after its position
//! where that cannot be told from the row's index (a CSV file's line), in a
//! temporary file removed when the sources are dropped. A visit reads its
//! block back a chunk of 8192 rows at a time (one read each), so the
//! values are the validated ones bit for bit, no pass parses text again, a
//! file rewritten after validation changes nothing, and memory does not grow
//! with the file.

use crate::error::DataError;
use crate::notes::FileNotes;
use crate::options::LoadOptions;
use crate::signals::{Role, required_signals};
use crate::validate::{Block, Places, RowBuf, Table, measured_rotation, scan};
use leeway_model::experiment::{Row, Source};
use leeway_structure::ir::Ir;

/// The validated samples of a file, as the validating pass parsed them:
/// per row its position where it cannot be told from the row's index
/// (`u64`: the physical line of a CSV file, which comment and blank lines
/// move; the rows of a Parquet file or a frame are positions `first`,
/// `first + 1`, … and are not stored) and the layout's values (`f64`, base
/// units), little-endian, in a temporary file removed when the last
/// [`FileSource`] of the file is dropped. Later passes read these bytes
/// instead of parsing the text again: the values are the validated ones, bit
/// for bit, and a file rewritten after validation changes nothing.
#[derive(Debug)]
struct Spill {
    file: tempfile::NamedTempFile,
    /// Values per row (the layout's columns).
    width: usize,
    /// Where the rows' positions are: stored in each row, or the first
    /// row's, the others following it one by one.
    positions: Positions,
}

/// How a spill's rows know their positions.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Positions {
    /// Each row begins with its position (CSV: lines that comment and blank
    /// lines move).
    InRows,
    /// Row `r` of the spill is at position `first + r` (Parquet files and
    /// frames: every row a sample).
    Consecutive { first: u64 },
}

impl Spill {
    /// Bytes per row: the position where it is stored, and the values.
    fn record(&self) -> u64 {
        let position = u64::from(self.positions == Positions::InRows);
        8 * (position + self.width as u64)
    }
}

/// Writes validated rows to a [`Spill`].
struct SpillWriter {
    out: std::io::BufWriter<std::fs::File>,
    /// Where positions go; a consecutive file's first position is taken
    /// from its first row.
    positions: Positions,
    /// Rows written.
    rows: u64,
    bytes: Vec<u8>,
    /// Each spilled value's part of a row (states, inputs, rotation,
    /// disturbances, heading) and index there, found once from its role.
    places: Vec<(usize, usize)>,
}

impl SpillWriter {
    fn push(&mut self, line: u64, row: &Row) -> std::io::Result<()> {
        use std::io::Write;
        let heading = [row.heading];
        let parts = [
            row.states,
            row.inputs,
            row.rotation,
            row.disturbances,
            &heading,
        ];
        self.bytes.clear();
        match self.positions {
            Positions::InRows => self.bytes.extend_from_slice(&line.to_le_bytes()),
            Positions::Consecutive { .. } if self.rows == 0 => {
                self.positions = Positions::Consecutive { first: line };
            }
            // Positions not stored are told by the row's index: a table
            // whose rows skip one would have its samples misplaced.
            Positions::Consecutive { first } if first + self.rows != line => {
                return Err(std::io::Error::other(format!(
                    "row {} is at position {line}, not {}",
                    self.rows + 1,
                    first + self.rows
                )));
            }
            Positions::Consecutive { .. } => {}
        }
        self.rows += 1;
        for &(part, i) in &self.places {
            let v = parts[part][i];
            self.bytes.extend_from_slice(&v.to_le_bytes());
        }
        self.out.write_all(&self.bytes)
    }
}

/// Where each role's value is in a row: its part (states, inputs,
/// rotation, disturbances, heading) and index there.
fn row_places(roles: &[Role]) -> Vec<(usize, usize)> {
    roles
        .iter()
        .map(|role| match *role {
            Role::State(i) => (0, i),
            Role::Input(i) => (1, i),
            Role::Rotation(i) => (2, i),
            Role::Disturbance(i) => (3, i),
            Role::Heading => (4, 0),
        })
        .collect()
}

/// An experiment of a file visited in passes: the validating pass wrote
/// its samples to a spill file ([`open_table`], [`open_csv`](crate::csv_fast::open_csv),
/// [`open_file`](crate::file::open_file)), and each [`Source::visit`] reads them
/// back from there (binary, buffered; no text is parsed again), in flat
/// memory whatever N.
#[derive(Debug)]
pub struct FileSource {
    file: String,
    /// How the file's positions are named.
    places: Places,
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

impl FileSource {
    /// The experiment's block (name, first row, rows, step).
    pub fn block(&self) -> &Block {
        &self.block
    }
    /// The file as named in messages.
    pub fn file(&self) -> &str {
        &self.file
    }
    /// The spill file's path (for tests of its removal).
    #[cfg(test)]
    pub(super) fn spill_path(&self) -> std::path::PathBuf {
        self.spill.file.path().to_path_buf()
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
        // Rows are read a chunk at a time (one read of a few hundred KiB),
        // then decoded one by one into the row handed to `f`.
        let width = record as usize;
        let rows = self.block.rows;
        let mut chunk = vec![0u8; width * READ_ROWS.min(rows.saturating_sub(from).max(1))];
        let mut buf = RowBuf::sized(self.n_states, self.n_inputs, self.n_rotation, self.n_comp);
        let places: Vec<usize> = self.roles.iter().map(|r| buf.place(r)).collect();
        let mut k = from;
        while k < rows {
            let n = READ_ROWS.min(rows - k);
            let bytes = &mut chunk[..n * width];
            if let Err(e) = handle.read_exact(bytes) {
                return self.fail(lost(format!("rows {} to {} of {rows}: {e}", k + 1, k + n)));
            }
            for row in bytes.chunks_exact(width) {
                let (line, values) = match self.spill.positions {
                    Positions::InRows => {
                        let (line, values) = row.split_at(8);
                        (u64::from_le_bytes(word(line)), values)
                    }
                    Positions::Consecutive { first } => (first + self.first_record + k as u64, row),
                };
                for (&place, v) in places.iter().zip(values.chunks_exact(8)) {
                    buf.set(place, f64::from_le_bytes(word(v)));
                }
                if !f(k, line, &buf.row()) {
                    return;
                }
                k += 1;
            }
        }
    }
}

/// The first eight bytes of `b`.
#[inline(always)]
fn word(b: &[u8]) -> [u8; 8] {
    let mut w = [0u8; 8];
    w.copy_from_slice(&b[..8]);
    w
}

/// Rows of the spill read at a time.
const READ_ROWS: usize = 1 << 13;

impl Source for FileSource {
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
    fn visit_head(&self, n: usize, f: &mut dyn FnMut(&Row)) {
        // Read no further than the head: a subsample costs its own share.
        let mut left = n;
        if left > 0 {
            self.read(0, &mut |_, _, row| {
                f(row);
                left -= 1;
                left > 0
            });
        }
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
            Some(position) => self.places.at(&self.file, position, None),
            None => format!(
                "{}: experiment `{}`, sample {}",
                self.file,
                self.block.name,
                k + 1
            ),
        }
    }
}

/// The former name of [`FileSource`], from when only CSV files were streamed.
pub type CsvSource = FileSource;

/// A validated file visited in passes: one [`FileSource`] per experiment.
#[derive(Debug)]
pub struct StreamedFile {
    /// The experiments, in file order.
    pub sources: Vec<FileSource>,
    /// Comment and blank lines, time-stamp jitter.
    pub notes: FileNotes,
}

/// Opens a table for streaming: one validating pass (every check of
/// [`load_table`](crate::validate::load_table)) that also writes the validated samples
/// to a temporary spill file (8 bytes per value and row, in the system's
/// temporary directory, removed when the sources are dropped); every later
/// visit reads them from there. Memory is flat in the number of rows.
/// `--resample` is not streamed: load the table for it.
pub fn open_table(
    table: &mut dyn Table,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<StreamedFile, DataError> {
    let file = table.file().to_string();
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
    let positions = match table.places() {
        Places::Lines => Positions::InRows,
        Places::Rows | Places::Groups(_) => Positions::Consecutive { first: 0 },
    };
    let mut writer = SpillWriter {
        out: std::io::BufWriter::with_capacity(1 << 16, spill_file.reopen().map_err(spill_error)?),
        positions,
        rows: 0,
        bytes: Vec::new(),
        places: Vec::new(),
    };
    // Every signal the model reads from data, in a fixed order.
    let roles: Vec<Role> = required_signals(ir).into_iter().map(|(_, r)| r).collect();
    writer.places = row_places(&roles);
    let scanned = scan(table, ir, options, &mut |_, position, row, _| {
        writer.push(position, row).map_err(spill_error)
    })?;
    std::io::Write::flush(&mut writer.out).map_err(spill_error)?;
    let positions = writer.positions;
    drop(writer);
    let spill = std::sync::Arc::new(Spill {
        file: spill_file,
        width: roles.len(),
        positions,
    });
    let places = table.places().clone();
    let mut first_record = 0u64;
    let sources = scanned
        .blocks
        .into_iter()
        .map(|block| {
            let first = first_record;
            first_record += block.rows as u64;
            FileSource {
                file: file.clone(),
                places: places.clone(),
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
