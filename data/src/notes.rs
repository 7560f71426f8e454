//! What loading noticed besides the samples (comment lines, time stamps), for the user to see.

use leeway_model::experiment::Experiment;

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
