//! The one validating pass every reader feeds: a [`Table`] (CSV records,
//! columns in memory, Parquet row groups) hands over rows, and `scan`
//! checks them — the model's columns found by name (`data { }` mapping),
//! declared units converted to base units, every cell a finite number,
//! experiments split into contiguous blocks, time steps against the mean
//! step, gross outliers — and locates every problem in the table's own
//! terms ([`Places`]). Each experiment is a contiguous [`Block`] with its
//! start, first row and row count. [`load_table`] holds the validated
//! experiments in memory (`load_csv`, `load_columns`, `load_file_noted`);
//! `open_table` (in `spill`) streams them through a binary copy (`open_csv`,
//! `open_columns`, `open_file`). No check exists anywhere else.

use crate::checks::{BlockTimes, Extremes, Outlier, TimeScan, sample_time};
pub use crate::checks::{OUTLIER_FACTOR, ZERO_OUTLIER, ZERO_OUTLIER_INPUT};
use crate::error::DataError;
use crate::notes::{FileNotes, GapNote, LoadedFile, PieceNote, TimeNotes};
use crate::options::LoadOptions;
use crate::signals::{Role, required_signals, unit_factor};
use leeway_model::experiment::{Experiment, MIN_SAMPLES, Row, Source, column_name};
use leeway_model::number::short_number as num;
use leeway_structure::ir::{Ir, Rotation};
use std::path::Path;

/// How a table names the place of a row in messages. A row's *position* is
/// what the validating pass records and what [`Places::at`] renders.
#[derive(Clone, Debug, PartialEq)]
pub enum Places {
    /// CSV text: positions are physical lines, from 1 (`file:line`,
    /// `file:line:column (name)`, the column from 1).
    Lines,
    /// Columns in memory: positions are rows, from 0, positional as pandas'
    /// `iloc` (`frame: row R`, `frame: row R, column `c``).
    Rows,
    /// A Parquet file: positions are rows of the file, from 0, in row groups
    /// that start at these rows (`file: row R (row group G, row r)`, then
    /// `, column `c``; groups and rows within a group from 0).
    Groups(std::sync::Arc<[u64]>),
}

impl Places {
    /// Where the row at `position` is, naming column `column` (index, name)
    /// when given.
    pub fn at(&self, file: &str, position: u64, column: Option<(usize, &str)>) -> String {
        let row = match self {
            Places::Lines => {
                return match column {
                    Some((i, name)) => format!("{file}:{position}:{} ({name})", i + 1),
                    None => format!("{file}:{position}"),
                };
            }
            Places::Rows => format!("{file}: row {position}"),
            Places::Groups(starts) if starts.is_empty() => {
                format!("{file}: row {position} (the file has no row groups)")
            }
            Places::Groups(starts) => {
                let g = starts.partition_point(|s| *s <= position).saturating_sub(1);
                let first = starts.get(g).copied().unwrap_or(0);
                format!(
                    "{file}: row {position} (row group {g}, row {})",
                    position - first
                )
            }
        };
        match column {
            Some((_, name)) => format!("{row}, column `{name}`"),
            None => row,
        }
    }
}

/// A table of named columns read row by row: what the validating pass
/// reads. Implemented by CSV [`Records`](crate::csv::Records), in-memory
/// [`Columns`](crate::columns::Columns) and, with the `parquet` feature, Parquet
/// files. Every method that reads a cell returns the located reason when
/// it cannot give a value.
pub trait Table {
    /// The table as named in messages (file or frame).
    fn file(&self) -> &str;
    /// The column names, in order.
    fn headers(&self) -> &[String];
    /// How positions are named.
    fn places(&self) -> &Places;
    /// The place of the header (or schema), naming column `column` when given.
    fn header_at(&self, column: Option<usize>) -> String;
    /// The position a first row would have (where "no samples" is located).
    fn first_position(&self) -> u64;
    /// Advances to the next row: `false` at the end.
    fn next_row(&mut self) -> Result<bool, DataError>;
    /// The current row's position.
    fn position(&self) -> u64;
    /// Where the current row starts in the file (bytes for CSV; the position otherwise).
    fn offset(&self) -> u64 {
        self.position()
    }
    /// Cell `i` of the current row as a finite number (`name`: the column's
    /// name in messages).
    fn number(&self, i: usize, name: &str) -> Result<f64, DataError>;
    /// The current row's cells that are already parsed (the CSV fast
    /// path's chunk, a Parquet batch's plain columns), so that reading them
    /// needs no call of [`Table::number`] each; `None` where the table
    /// keeps none.
    fn parsed_row(&self) -> Option<ParsedRow<'_>> {
        None
    }
    /// Cell `i` of the current row as a label (an experiment's name).
    fn label(&self, i: usize) -> Result<std::borrow::Cow<'_, [u8]>, DataError>;
    /// The type of column `i` when it holds dates or times (read as
    /// seconds since its first stamp, which only a time column may be).
    fn stamps(&self, _i: usize) -> Option<String> {
        None
    }
    /// For a date or time column once its first stamp is read: that stamp
    /// in nanoseconds since the Unix epoch (what its seconds count from).
    fn stamp_origin(&self, _i: usize) -> Option<i64> {
        None
    }
    /// Only these columns will be read (a columnar format may skip the
    /// others); called once, before the first row.
    fn select(&mut self, _columns: &[usize]) {}
    /// Comment and blank lines dropped so far (CSV only).
    fn dropped(&self) -> (usize, usize) {
        (0, 0)
    }
    /// Where the row at `position` is, naming a column when given.
    fn at(&self, position: u64, column: Option<(usize, &str)>) -> String {
        self.places().at(self.file(), position, column)
    }
}

/// A row's cells parsed ahead ([`Table::parsed_row`]): `values[slots[i]]`
/// is column `i`'s value, NaN where the cell was left to
/// [`Table::number`] (a parsed value is finite).
#[derive(Clone, Copy, Debug)]
pub struct ParsedRow<'a> {
    pub(crate) values: &'a [f64],
    pub(crate) slots: &'a [Option<usize>],
}

impl ParsedRow<'_> {
    /// Column `i`'s value where it was parsed: what [`Table::number`] gives.
    #[inline(always)]
    pub(crate) fn get(&self, i: usize) -> Option<f64> {
        let slot = (*self.slots.get(i)?)?;
        let v = *self.values.get(slot)?;
        (!v.is_nan()).then_some(v)
    }
}

/// Cell `i` of the current row as a finite number: from the row parsed
/// ahead where it holds it, else through [`Table::number`].
#[inline(always)]
fn number_of(
    table: &dyn Table,
    parsed: Option<ParsedRow>,
    i: usize,
    name: &str,
) -> Result<f64, DataError> {
    match parsed.and_then(|p| p.get(i)) {
        Some(v) => Ok(v),
        None => table.number(i, name),
    }
}

/// The hint for a value that is not a finite number.
const NOT_FINITE_HINT: &str = "NaN and infinite values are not accepted; remove or repair the sample, leeway does not interpolate";

/// A value that is not finite (`raw`: as the table holds it).
pub fn not_finite(at: String, raw: &str) -> DataError {
    DataError::new(
        at,
        format!("`{raw}` is not a finite number"),
        NOT_FINITE_HINT,
    )
}

/// A missing value (`what`: "empty cell", "null").
pub fn missing(at: String, what: &str) -> DataError {
    DataError::new(
        at,
        what,
        "every sample needs every signal; leeway does not fill gaps",
    )
}

/// A value that is not a number (`raw`: as the table holds it).
pub fn not_a_number(at: String, raw: &str, hint: &str) -> DataError {
    DataError::new(
        at,
        format!("`{}` is not a number", raw.escape_debug()),
        hint,
    )
}

/// `v` when finite, else the located reason (the value shown as Rust
/// prints it: `NaN`, `inf`, `-inf`).
pub fn finite(v: f64, at: impl FnOnce() -> String) -> Result<f64, DataError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(not_finite(at(), &format!("{v:?}")))
    }
}

/// Every column named once: a repeated name is an error at its second place.
pub fn unique_headers(headers: &[String], at: impl Fn(usize) -> String) -> Result<(), DataError> {
    // Each name's first column: a header of a million cells is checked in
    // a moment, not in quadratic time.
    let mut first = std::collections::BTreeMap::new();
    for (i, h) in headers.iter().enumerate() {
        if let Some(&j) = first.get(h.as_str()) {
            return Err(DataError::new(
                at(i),
                format!(
                    "column `{h}` appears twice (columns {} and {})",
                    j + 1,
                    i + 1
                ),
                "rename one of them; leeway will not guess which is meant",
            ));
        }
        first.insert(h.as_str(), i);
    }
    Ok(())
}

/// Where each model signal is read from in a table's rows.
#[derive(Clone, Debug)]
struct Layout {
    /// `(role, column index, column name, unit factor)`.
    cols: Vec<(Role, usize, String, f64)>,
    time_col: Option<usize>,
    time_factor: f64,
    exp_col: Option<usize>,
}

impl Layout {
    /// Finds every signal the model reads from data among the table's
    /// columns; a missing one is an error at the header.
    fn new(table: &dyn Table, ir: &Ir) -> Result<Layout, DataError> {
        let headers = table.headers();
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
                        table.header_at(None),
                        format!("missing column `{col}`{mapped}"),
                        format!(
                            "the header has: {}. Name the column `{col}`, or map it in the model: data {{ {signal} = \"<column>\" }}",
                            leeway_structure::grammar::join_capped(headers, ", ")
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
        layout.check_stamps(table)?;
        Ok(layout)
    }

    /// Dates and times are read as seconds since their first stamp: right
    /// for the time column (in seconds), never for a signal's value.
    fn check_stamps(&self, table: &dyn Table) -> Result<(), DataError> {
        for (_, i, name, _) in &self.cols {
            if let Some(kind) = table.stamps(*i) {
                return Err(DataError::new(
                    table.header_at(Some(*i)),
                    format!("column `{name}` holds dates or times ({kind}), not a signal's values"),
                    "only the time column may hold dates or times; store the signal as numbers (DOUBLE)",
                ));
            }
        }
        if let Some(i) = self.time_col
            && let Some(kind) = table.stamps(i)
            && self.time_factor != 1.0
        {
            return Err(DataError::new(
                table.header_at(Some(i)),
                format!(
                    "the time column holds dates or times ({kind}), which are read in seconds, but the model declares another unit for it"
                ),
                "drop the time unit from the model's data { } block, or store the time as numbers in that unit",
            ));
        }
        Ok(())
    }

    /// Reads the current row's signals into `buf` (declared units converted
    /// to the model's base units, once, here) and returns its time stamp.
    fn read(
        &self,
        table: &dyn Table,
        places: &[usize],
        buf: &mut RowBuf,
    ) -> Result<Option<f64>, DataError> {
        let parsed = table.parsed_row();
        for ((_, i, name, factor), &place) in self.cols.iter().zip(places) {
            buf.set(place, number_of(table, parsed, *i, name)? * factor);
        }
        match self.time_col {
            Some(i) => Ok(Some(
                number_of(table, parsed, i, "time")? * self.time_factor,
            )),
            None => Ok(None),
        }
    }
}

/// The number of rotation columns read from data (a measured `R`), else 0.
pub(super) fn measured_rotation(ir: &Ir) -> usize {
    if matches!(ir.rotation, Rotation::Measured { .. }) {
        ir.rotation_vars.len()
    } else {
        0
    }
}

/// A row's values in one buffer: states, inputs, rotation variables,
/// disturbance components and heading side by side. Each column's place in
/// it is found once ([`RowBuf::place`]): a match on the role of every value
/// of every row cost more than the rest of reading it.
pub(super) struct RowBuf {
    values: Vec<f64>,
    /// Where the inputs, rotation, disturbances and heading begin.
    at: [usize; 4],
}

impl RowBuf {
    pub(super) fn new(ir: &Ir) -> RowBuf {
        RowBuf::sized(
            ir.states.len(),
            ir.inputs.len(),
            measured_rotation(ir),
            ir.components.len(),
        )
    }
    pub(super) fn sized(states: usize, inputs: usize, rotation: usize, comp: usize) -> RowBuf {
        let at = [
            states,
            states + inputs,
            states + inputs + rotation,
            states + inputs + rotation + comp,
        ];
        RowBuf {
            values: vec![0.0; at[3] + 1],
            at,
        }
    }
    /// Where `role`'s value is kept.
    pub(super) fn place(&self, role: &Role) -> usize {
        match *role {
            Role::State(i) => i,
            Role::Input(i) => self.at[0] + i,
            Role::Rotation(i) => self.at[1] + i,
            Role::Disturbance(i) => self.at[2] + i,
            Role::Heading => self.at[3],
        }
    }
    /// Sets the value at `place` (one [`RowBuf::place`] gave).
    #[inline(always)]
    pub(super) fn set(&mut self, place: usize, v: f64) {
        if let Some(slot) = self.values.get_mut(place) {
            *slot = v;
        }
    }
    /// The value at `place`.
    #[inline(always)]
    pub(super) fn get(&self, place: usize) -> f64 {
        self.values.get(place).copied().unwrap_or(0.0)
    }
    #[inline(always)]
    pub(super) fn row(&self) -> Row<'_> {
        let [i, r, d, h] = self.at;
        Row {
            states: &self.values[..i],
            inputs: &self.values[i..r],
            rotation: &self.values[r..d],
            disturbances: &self.values[d..h],
            heading: self.values[h],
        }
    }
}

/// One experiment of a file as the validating pass found it: what visiting
/// it again needs, and what was noted.
#[derive(Clone, Debug)]
pub struct Block {
    /// The experiment's name.
    pub name: String,
    /// Where its first row starts: the physical byte offset in a CSV
    /// file, the first row's position otherwise.
    pub start: u64,
    /// Its first row's position (see [`Places`]): the physical line in a
    /// CSV file, the row from 0 otherwise.
    pub first: u64,
    /// Rows (samples).
    pub rows: usize,
    /// Sample time.
    pub h: f64,
    pub(super) times: TimeScan,
    pub(super) extremes: Vec<Extremes>,
}

/// A validated table: its experiments' blocks and the notes.
#[derive(Clone, Debug)]
pub(super) struct Scanned {
    /// The header's place.
    header_at: String,
    pub(super) blocks: Vec<Block>,
    pub(super) notes: FileNotes,
}

/// What the validating pass hands on for each sample: its block, its
/// position, its values and its time stamp.
pub(super) type Sink<'a> = dyn FnMut(usize, u64, &Row, Option<f64>) -> Result<(), DataError> + 'a;

/// The validating pass over one table: every check (cells, columns, units,
/// experiments contiguous, time stamps, gross outliers), in one read with
/// reused buffers; `sink(block, position, row, time)` sees every sample.
pub(super) fn scan(
    table: &mut dyn Table,
    ir: &Ir,
    options: &LoadOptions,
    sink: &mut Sink,
) -> Result<Scanned, DataError> {
    let layout = Layout::new(table, ir)?;
    let used: Vec<usize> = layout
        .cols
        .iter()
        .map(|c| c.1)
        .chain(layout.time_col)
        .chain(layout.exp_col)
        .collect();
    table.select(&used);
    let file = table.file().to_string();
    let mut blocks = read_blocks(table, &layout, ir, &file, sink)?;
    let (comment_lines, blank_lines) = table.dropped();
    let mut notes = FileNotes {
        file,
        comment_lines,
        blank_lines,
        ..FileNotes::default()
    };
    if blocks.is_empty() {
        return Err(DataError::new(
            table.at(table.first_position(), None),
            "the file has a header but no samples",
            "record at least a few hundred samples per experiment",
        ));
    }
    for block in &mut blocks {
        check_block(table, &layout, block)?;
        let time_at =
            |position: u64| table.at(position, Some((layout.time_col.unwrap_or(0), "time")));
        let (h, deviation) = sample_time(
            table.file(),
            ir,
            BlockTimes {
                times: &block.times,
                rows: block.rows,
                first: block.first,
            },
            &time_at,
            options,
        )?;
        block.h = h;
        notes.experiments.push(TimeNotes {
            experiment: block.name.clone(),
            rows: block.rows,
            max_step_deviation: deviation,
            ..TimeNotes::default()
        });
    }
    Ok(Scanned {
        header_at: table.header_at(None),
        blocks,
        notes,
    })
}

/// Reads every row once: each experiment a block (its rows together, in
/// order: one that resumes after another is an error), its time stamps and
/// each column's extremes kept, every sample handed to `sink`.
fn read_blocks(
    table: &mut dyn Table,
    layout: &Layout,
    ir: &Ir,
    file: &str,
    sink: &mut Sink,
) -> Result<Vec<Block>, DataError> {
    let base_name = Path::new(file)
        .file_stem()
        .map_or(file.to_string(), |s| s.to_string_lossy().to_string());
    let mut blocks: Vec<Block> = Vec::new();
    let mut finished: std::collections::HashSet<Vec<u8>> = std::collections::HashSet::new();
    let mut current: Option<Vec<u8>> = None;
    let mut buf = RowBuf::new(ir);
    let places: Vec<usize> = layout.cols.iter().map(|c| buf.place(&c.0)).collect();
    let n_cols = layout.cols.len();
    while table.next_row()? {
        let line = table.position();
        let t = layout.read(table, &places, &mut buf)?;
        let label = match layout.exp_col {
            Some(i) => table.label(i)?,
            None => std::borrow::Cow::Borrowed(base_name.as_bytes()),
        };
        let exp_name: &[u8] = &label;
        if current.as_deref() != Some(exp_name) {
            let name = String::from_utf8_lossy(exp_name).into_owned();
            if finished.contains(exp_name) {
                return Err(DataError::new(
                    table.at(line, Some((layout.exp_col.unwrap_or(0), "experiment"))),
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
                start: table.offset(),
                first: line,
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
        for (extremes, &place) in block.extremes.iter_mut().zip(&places) {
            extremes.push(buf.get(place), line);
        }
        sink(b, line, &buf.row(), t)?;
    }
    Ok(blocks)
}

/// An experiment long enough, and no gross outlier in any column.
fn check_block(table: &dyn Table, layout: &Layout, block: &Block) -> Result<(), DataError> {
    let n = block.rows;
    if n < MIN_SAMPLES {
        return Err(DataError::new(
            table.at(block.first, None),
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
            return Err(outlier_error(table, block, o, found.len() - 1, (*i, name)));
        }
    }
    Ok(())
}

/// The error of a gross outlier, saying how far it lies from the rest.
fn outlier_error(
    table: &dyn Table,
    block: &Block,
    o: &Outlier,
    others: usize,
    (i, name): (usize, &str),
) -> DataError {
    let more = match others {
        0 => String::new(),
        m => format!(" ({m} more in this column)"),
    };
    let (v, lo, hi) = (o.value, o.lo, o.hi);
    let why = if hi > lo {
        format!(
            "the other samples of experiment `{}` lie in [{}, {}], and this one is {} times that range away",
            block.name,
            num(lo),
            num(hi),
            num(if v > hi {
                (v - hi) / (hi - lo)
            } else {
                (lo - v) / (hi - lo)
            })
        )
    } else if let Some(bound) = o.zero_bound {
        format!(
            "every other sample of experiment `{}` is 0 (the column is constant), and this one exceeds {} in magnitude",
            block.name,
            num(bound)
        )
    } else {
        format!(
            "every other sample of experiment `{}` is {} (the column is constant, a sensor stuck?), and this one is {} times that value away",
            block.name,
            num(lo),
            num((v - lo).abs() / lo.abs())
        )
    };
    DataError::new(
        table.at(o.line, Some((i, name))),
        format!("`{name}` = {} is a gross outlier: {why}{more}", num(v)),
        format!(
            "repair or remove the sample (leeway does not drop or interpolate samples); a value more than {OUTLIER_FACTOR:e} times the spread of the rest of its column (or, for a constant column, its value) away is taken for a logging error"
        ),
    )
}

/// `e` (stamped `times`) resampled every `step` seconds, split at every
/// stretch without samples longer than `options.max_gap` rather than
/// interpolated across it: the pieces long enough become experiments
/// (`name/1`, `name/2`, … when split), the others are dropped; both are
/// noted in `notes`. `first` locates the experiment in messages.
fn resample_split(
    ir: &Ir,
    e: Experiment,
    times: &[f64],
    step: f64,
    options: &LoadOptions,
    first: &str,
    notes: &mut TimeNotes,
) -> Result<Vec<Experiment>, DataError> {
    let span = times[times.len() - 1] - times[0];
    let count = span / step + 1.0;
    if count > MAX_RESAMPLE_RATIO * e.len() as f64 {
        return Err(DataError::new(
            first,
            format!(
                "--resample {step} would make {count:.0} samples of experiment `{}` from its {} rows; at most {MAX_RESAMPLE_RATIO} per row",
                e.name,
                e.len()
            ),
            "choose a resampling step near the logger's own step",
        ));
    }
    let limit = options.max_gap.seconds(&crate::gaps::steps(times), step);
    let holes = crate::gaps::holes(times, limit);
    let mut bounds = vec![0];
    for &i in &holes {
        notes.gaps.push(GapNote {
            signal: None,
            from: times[i],
            to: times[i + 1],
            limit,
        });
        bounds.push(i + 1);
    }
    bounds.push(times.len());
    let mut kept = Vec::new();
    for (j, w) in bounds.windows(2).enumerate() {
        let mut piece =
            crate::resample::resample(ir, &e.slice(w[0]..w[1]), &times[w[0]..w[1]], step);
        let note = PieceNote {
            experiment: None,
            from: times[w[0]],
            to: times[w[1] - 1],
            samples: piece.len(),
        };
        if !holes.is_empty() {
            piece.name = format!("{}/{}", e.name, j + 1);
        }
        if piece.len() >= MIN_SAMPLES {
            if !holes.is_empty() {
                notes.pieces.push(PieceNote {
                    experiment: Some(piece.name.clone()),
                    ..note
                });
            }
            kept.push(piece);
        } else if !holes.is_empty() {
            notes.pieces.push(note);
        }
    }
    if kept.is_empty() {
        let why = if holes.is_empty() {
            String::new()
        } else {
            format!(
                " (split at {} gaps longer than {})",
                holes.len(),
                num(limit)
            )
        };
        return Err(DataError::new(
            first,
            format!(
                "experiment `{}` has fewer than {MIN_SAMPLES} samples at --resample {step}{why}",
                e.name
            ),
            "choose a smaller --resample step, or raise the gap limit if the holes are known to be harmless",
        ));
    }
    notes.resampled = Some(kept.iter().map(Experiment::len).sum());
    Ok(kept)
}

/// Most samples `--resample` may make per row read: a finer grid only
/// interpolates, and memory would follow the grid.
pub const MAX_RESAMPLE_RATIO: f64 = 100.0;
/// Loads a table into memory through the validating pass (resampled under
/// `options.resample`): what every `load_*` function of this module does
/// after opening its format.
pub fn load_table(
    table: &mut dyn Table,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    let mut held: Vec<(Experiment, Vec<f64>)> = Vec::new();
    let scanned = scan(table, ir, options, &mut |b, _, row, t| {
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
            if times.len() != e.len() {
                return Err(DataError::new(
                    scanned.header_at.clone(),
                    "--resample needs a time column, and the file has none",
                    format!(
                        "add a `{}` column of time stamps (or map one with data {{ time = \"<column>\" }}), or drop --resample",
                        column_name(ir, "time")
                    ),
                ));
            }
            let first = table.at(block.first, None);
            out.extend(resample_split(
                ir, e, &times, step, options, &first, time_notes,
            )?);
            continue;
        }
        out.push(e);
    }
    Ok(LoadedFile {
        experiments: out,
        notes,
    })
}
