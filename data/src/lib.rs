//! leeway-data: experiments from files and frames, validated.
//!
//! An experiment is a time series of the model's declared signals (states,
//! inputs, heading or rotation columns, measured disturbance components). It
//! is held column by column in memory
//! ([`Experiment`](leeway_model::experiment::Experiment)) or produced on the
//! fly by any [`Source`](leeway_model::experiment::Source) (e.g. a simulator
//! streaming 10⁷ samples): estimators only ever visit samples in order, so
//! their memory does not grow with N.
//!
//! Loading validates everything and names the place of every problem;
//! nothing is silently dropped or reordered. Every reader — CSV files
//! ([`csv_fast`], parsed in parallel, exact by [`csv`]'s reader where its
//! fast path does not go) and CSV text ([`csv`]), columns in memory ([`columns`], what the Python package hands
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
//!
//! The only IO is reading data files and their spill files. The feature
//! `parquet` is on in leeway-cli and the Python package.

mod checks;
pub mod columns;
pub mod csv;
mod csv_chunk;
pub mod csv_fast;
pub mod error;
pub mod file;
pub mod gaps;
pub mod input;
pub mod notes;
mod open;
pub mod options;
#[cfg(feature = "parquet")]
pub mod parquet;
pub mod rates;
pub mod resample;
pub mod signals;
mod spill;
pub mod validate;
pub mod write;

pub use columns::{Columns, Labels, load_columns, open_columns};
pub use csv::{MAX_LINE_BYTES, Records, parse_csv, parse_csv_noted};
pub use csv_fast::{Batching, CsvFile, load_csv, load_csv_noted, open_csv};
pub use error::DataError;
pub use file::{load_file_noted, open_file, with_table};
pub use notes::{FileNotes, GapNote, LoadedFile, PieceNote, SignalNote, TimeNotes};
pub use options::{
    DEFAULT_TIME_TOLERANCE, LoadOptionError, LoadOptions, STEP_RANGE, TIME_TOLERANCE_HINT,
    sample_time_ok, time_tolerance_ok,
};
pub use signals::{HeadingGainSums, heading_gain};
pub use spill::{CsvSource, FileSource, StreamedFile, open_table};
pub use validate::{
    Block, MAX_RESAMPLE_RATIO, OUTLIER_FACTOR, ParsedRow, Places, Table, ZERO_OUTLIER,
    ZERO_OUTLIER_INPUT, load_table,
};
pub use write::write_csv;

#[cfg(test)]
mod tests;
