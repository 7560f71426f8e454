//! Experiments: the data an estimate is computed from.
//!
//! An experiment is a time series of the model's declared signals (states,
//! inputs, heading or rotation columns, measured disturbance components). It
//! is held column by column in memory ([`Experiment`]) or produced on the fly
//! by any [`Source`] (e.g. a simulator streaming 10⁷ samples): estimators only
//! ever visit samples in order, so their memory does not grow with N.
//!
//! Loading validates everything and names the place of every problem;
//! nothing is silently dropped or reordered. Every reader — CSV text
//! ([`csv`]), columns in memory ([`columns`], what the Python package hands
//! over) and Parquet files (`parquet`, behind the cargo feature `parquet`) —
//! is a [`Table`] that feeds the one validating pass ([`validate`]: header
//! and column matching, units, experiments, time steps, gross outliers,
//! finiteness), so every format is checked by the same code and located in
//! its own terms: `file:line:column (name)` for CSV (the physical line an
//! editor shows, also after comment lines, blank lines and quoted cells
//! holding line breaks), `frame: row R, column `c`` for columns (R from 0,
//! positional), `file: row R (row group G, row r), column `c`` for Parquet.
//! A file is either loaded into memory ([`load_csv`], [`load_file_noted`])
//! or, after the same validating pass, visited in passes from a binary copy
//! of its validated samples ([`open_csv`], [`open_file`], [`FileSource`]) so
//! that memory stays flat in N and no pass parses the file again.

mod checks;
pub mod columns;
pub mod csv;
mod experiment;
#[cfg(feature = "parquet")]
pub mod parquet;
mod spill;
pub mod validate;

pub use columns::{Columns, Labels, load_columns, open_columns};
pub use csv::{Records, load_csv, load_csv_noted, open_csv, parse_csv, parse_csv_noted};
pub use experiment::{Experiment, Row, Source};
pub use spill::{CsvSource, FileSource, StreamedFile, open_table};
pub use validate::{
    Block, MAX_RESAMPLE_RATIO, OUTLIER_FACTOR, Places, Table, ZERO_OUTLIER, ZERO_OUTLIER_INPUT,
    load_table,
};

use leeway_structure::ir::{Ir, Rotation};
use std::path::Path;

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
    /// A problem at `location`, with a hint.
    pub fn new(
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

/// Reads a data file as a [`Table`] and hands it to `f`: a Parquet file
/// (extension `.parquet` or the magic bytes `PAR1`, with the `parquet`
/// feature), else CSV text. `what` names the option that gave the file.
pub fn with_table<T>(
    path: &Path,
    what: &str,
    f: impl FnOnce(&mut dyn Table) -> Result<T, DataError>,
) -> Result<T, DataError> {
    #[cfg(feature = "parquet")]
    if parquet::is_parquet(path) {
        return f(&mut parquet::ParquetFile::open(path)?);
    }
    #[cfg(not(feature = "parquet"))]
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"))
    {
        return Err(DataError::new(
            path.display().to_string(),
            "this leeway was built without Parquet support",
            "build it with the cargo feature `parquet` (leeway-cli has it by default), or convert the file to CSV",
        ));
    }
    f(&mut Records::open(path, what)?)
}

/// Loads a data file, CSV or Parquet (see [`with_table`]), into memory with
/// what was noted ([`load_csv_noted`] for CSV).
pub fn load_file_noted(
    path: &Path,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    with_table(path, "--data", |t| load_table(t, ir, options))
}

/// Opens a data file, CSV or Parquet (see [`with_table`]), for streaming
/// ([`open_csv`] for CSV).
pub fn open_file(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<StreamedFile, DataError> {
    with_table(path, "--data", |t| open_table(t, ir, options))
}

/// Opens a data file (`what` names the option that gave it, for the hint).
fn open_path(path: &Path, what: &str) -> Result<(String, std::fs::File), DataError> {
    let file = path.display().to_string();
    match std::fs::File::open(path) {
        Ok(handle) => Ok((file, handle)),
        Err(e) => Err(DataError::new(
            &file,
            format!("cannot read the file: {e}"),
            format!("check the path passed to {what}"),
        )),
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

/// The factor converting a signal's declared unit to the base unit (1 when
/// none is declared).
fn unit_factor(ir: &Ir, signal: &str) -> f64 {
    ir.data_units
        .get(signal)
        .map_or(1.0, |u| leeway_structure::units::factor(u))
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
mod tests;
