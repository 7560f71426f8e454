//! Columns in memory (what the Python package hands over from a DataFrame
//! or an Arrow table): read as a [`Table`] by the same validating pass as a
//! file, without a text pass, and located by positional row (from 0, as
//! pandas' `iloc`): `frame: row R, column `c``. The values are bit for bit
//! those a CSV file of the same numbers gives; a frame is loaded
//! ([`load_columns`]) or streamed through the spill ([`open_columns`]).

use crate::error::DataError;
use crate::notes::LoadedFile;
use crate::options::LoadOptions;
use crate::spill::{StreamedFile, open_table};
use crate::validate::Places;
use crate::validate::{Table, finite, load_table};
use leeway_model::experiment::column_name;
use leeway_structure::ir::Ir;
use std::borrow::Cow;

/// Rows between two questions to an interrupt.
const INTERRUPT_ROWS: usize = 1 << 15;

/// The message of a validation stopped by its interrupt.
pub const INTERRUPTED: &str = "reading the frame was interrupted";

/// The experiment labels of a frame's rows.
#[derive(Clone, Copy, Debug)]
pub enum Labels<'a> {
    /// One label per row.
    PerRow(&'a [String]),
    /// Per row an index into `names` (what `pandas.factorize` gives): the
    /// labels then take memory per experiment, not per row. A code outside
    /// `names` (factorize's −1 for a missing label) is a located error.
    Coded {
        /// One per row.
        codes: &'a [i64],
        /// The distinct labels.
        names: &'a [String],
    },
}

impl Labels<'_> {
    fn len(&self) -> usize {
        match self {
            Labels::PerRow(l) => l.len(),
            Labels::Coded { codes, .. } => codes.len(),
        }
    }
    /// Row `k`'s label, `None` where it has none.
    fn get(&self, k: usize) -> Option<&str> {
        match self {
            Labels::PerRow(l) => l.get(k).map(String::as_str),
            Labels::Coded { codes, names } => codes
                .get(k)
                .and_then(|c| usize::try_from(*c).ok())
                .and_then(|c| names.get(c))
                .map(String::as_str),
        }
    }
}

/// Named float columns of equal length, with optional experiment labels per
/// row, read row by row.
#[derive(Clone, Debug)]
pub struct Columns<'a> {
    name: String,
    headers: Vec<String>,
    columns: Vec<&'a [f64]>,
    labels: Option<Labels<'a>>,
    /// Asked every [`INTERRUPT_ROWS`] rows of the validating pass.
    interrupt: Option<leeway_model::interrupt::Interrupt>,
    rows: usize,
    /// The current row, `None` before the first.
    row: Option<usize>,
}

impl<'a> Columns<'a> {
    /// Columns named `columns` (`name` names the frame in messages), and
    /// `labels` (one per row) as the column `label_column`. Every column
    /// must have as many rows as the first, and each name must appear once.
    pub fn new(
        name: &str,
        columns: &[(&str, &'a [f64])],
        labels: Option<(&str, Labels<'a>)>,
    ) -> Result<Columns<'a>, DataError> {
        let rows = columns
            .first()
            .map(|(_, c)| c.len())
            .or(labels.map(|(_, l)| l.len()))
            .unwrap_or(0);
        let lengths = columns
            .iter()
            .map(|(n, c)| (*n, c.len()))
            .chain(labels.map(|(n, l)| (n, l.len())));
        for (column, len) in lengths {
            if len != rows {
                return Err(DataError::new(
                    name,
                    format!("column `{column}` has {len} rows, the others {rows}"),
                    "every column of a frame needs one value per row",
                ));
            }
        }
        let mut headers: Vec<String> = columns.iter().map(|(n, _)| n.to_string()).collect();
        headers.extend(labels.map(|(n, _)| n.to_string()));
        let table = Columns {
            name: name.to_string(),
            headers,
            columns: columns.iter().map(|(_, c)| *c).collect(),
            labels: labels.map(|(_, l)| l),
            interrupt: None,
            rows,
            row: None,
        };
        crate::validate::unique_headers(&table.headers, |i| table.header_at(Some(i)))?;
        Ok(table)
    }
    /// These columns, their reading stopped by `interrupt` (a large frame's
    /// validation takes seconds): the row after it says stop is the error
    /// [`INTERRUPTED`].
    pub fn interruptible(mut self, interrupt: Option<leeway_model::interrupt::Interrupt>) -> Self {
        self.interrupt = interrupt;
        self
    }
    /// The current row (0 before the first).
    fn k(&self) -> usize {
        self.row.unwrap_or(0)
    }
}

impl Table for Columns<'_> {
    fn file(&self) -> &str {
        &self.name
    }
    fn headers(&self) -> &[String] {
        &self.headers
    }
    fn places(&self) -> &Places {
        &Places::Rows
    }
    fn header_at(&self, column: Option<usize>) -> String {
        match column.and_then(|i| self.headers.get(i)) {
            Some(c) => format!("{}: header, column `{c}`", self.name),
            None => format!("{}: header", self.name),
        }
    }
    fn first_position(&self) -> u64 {
        0
    }
    fn next_row(&mut self) -> Result<bool, DataError> {
        let next = self.row.map_or(0, |k| k + 1);
        if next.is_multiple_of(INTERRUPT_ROWS)
            && self.interrupt.as_ref().is_some_and(|i| i.requested())
        {
            return Err(DataError::new(
                &self.name,
                INTERRUPTED,
                "run it again to the end",
            ));
        }
        self.row = Some(next.min(self.rows));
        Ok(next < self.rows)
    }
    fn position(&self) -> u64 {
        self.k() as u64
    }
    fn number(&self, i: usize, name: &str) -> Result<f64, DataError> {
        let k = self.k();
        match self.columns.get(i) {
            Some(c) => finite(c[k], || self.at(k as u64, Some((i, name)))),
            // The label column named as a signal.
            None => Err(crate::validate::not_a_number(
                self.at(k as u64, Some((i, name))),
                &String::from_utf8_lossy(&self.label(i)?),
                "hand over the column as numbers",
            )),
        }
    }
    fn label(&self, i: usize) -> Result<Cow<'_, [u8]>, DataError> {
        let k = self.k();
        Ok(match self.columns.get(i) {
            Some(c) => Cow::Owned(c[k].to_string().into_bytes()),
            None => match self.labels.as_ref().map(|l| l.get(k)) {
                Some(Some(label)) => Cow::Borrowed(label.as_bytes()),
                Some(None) => {
                    let at = self.at(k as u64, Some((i, &self.headers[i])));
                    return Err(crate::validate::missing(at, "missing experiment label"));
                }
                None => Cow::Borrowed(&b""[..]),
            },
        })
    }
}

/// The data columns a model reads (after `data { }` mapping), time first,
/// each once: what a caller holding a wide frame needs to hand over (other
/// columns are ignored, as a file's are; the experiment column is not
/// among them: its labels are handed over apart).
pub fn model_columns(ir: &Ir) -> Vec<String> {
    let mut columns: Vec<String> = vec![column_name(ir, "time")];
    for (signal, _) in crate::signals::required_signals(ir) {
        let c = column_name(ir, &signal);
        if !columns.contains(&c) {
            columns.push(c);
        }
    }
    columns
}

/// The table of a frame: its columns and, as the column
/// `column_name(ir, "experiment")`, its labels.
pub fn frame<'a>(
    name: &str,
    columns: &[(&str, &'a [f64])],
    experiment: Option<Labels<'a>>,
    ir: &Ir,
) -> Result<Columns<'a>, DataError> {
    let label_column = column_name(ir, "experiment");
    Columns::new(
        name,
        columns,
        experiment.map(|l| (label_column.as_str(), l)),
    )
}

/// Loads columns in memory exactly as [`load_csv_noted`](crate::csv_fast::load_csv_noted)
/// loads a file of the same values: the model's columns found by name
/// (`data { }` mapping, [`column_name`]), declared units, time steps,
/// experiments split on `experiment` (the labels, one per row, named
/// `column_name(ir, "experiment")`), gross outliers, finiteness, and the
/// same errors, located as `name: row R, column `c`` (R from 0,
/// positional). Other columns are ignored, as a file's are.
pub fn load_columns(
    name: &str,
    columns: &[(&str, &[f64])],
    experiment: Option<Labels<'_>>,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    load_table(&mut frame(name, columns, experiment, ir)?, ir, options)
}

/// Opens columns for streaming as [`open_file`](crate::file::open_file) opens a
/// file: the same validating pass as [`load_columns`], whose validated
/// samples go to a temporary spill file that every pass reads back; memory
/// then stays flat in the rows (a copy of a large frame would double it).
pub fn open_columns(
    name: &str,
    columns: &[(&str, &[f64])],
    experiment: Option<Labels<'_>>,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<StreamedFile, DataError> {
    open_table(&mut frame(name, columns, experiment, ir)?, ir, options)
}
