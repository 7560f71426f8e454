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
    /// A joined log's first stamp, ISO-8601 UTC: what its noted times
    /// count from (`None` for one file).
    #[serde(default)]
    pub origin: Option<String>,
    /// A joined log's signals as read, one per model signal (empty for one file).
    #[serde(default)]
    pub signals: Vec<SignalNote>,
}

/// One signal of a joined log as its source had it.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SignalNote {
    /// The model's signal.
    pub signal: String,
    /// Where it was read: `file:column`, or a bag's `file:topic.field.path`.
    pub source: String,
    /// Its samples.
    pub samples: usize,
    /// Its median step, seconds.
    pub median_step: f64,
    /// Its first and last stamps, seconds from the origin.
    pub first: f64,
    /// See `first`.
    pub last: f64,
    /// Samples whose stamp repeated the previous one (the later kept).
    pub repeated_stamps: usize,
    /// `hold` or `linear` (`angle` for a heading) between samples.
    pub between: String,
    /// What the grid read of it (docs/logs.md, "On the grid"): at the grid
    /// time, or its mean over the step and of how many samples.
    #[serde(default)]
    pub on_grid: String,
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
    /// Stretches without samples longer than the gap limit, where the
    /// experiment was split rather than interpolated across.
    #[serde(default)]
    pub gaps: Vec<GapNote>,
    /// The pieces a split left, kept or dropped (empty when not split).
    #[serde(default)]
    pub pieces: Vec<PieceNote>,
    /// Stalls of a joined log's signals: holes within the gap limit but
    /// longer than the signal's stall threshold (`limit`), held or
    /// interpolated across.
    #[serde(default)]
    pub stalls: Vec<GapNote>,
}

/// A stretch without samples that split an experiment: times in seconds,
/// as the file's time column reads (for a joined log: since its first stamp).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GapNote {
    /// The signal that had no samples (for one file: every column).
    pub signal: Option<String>,
    /// The last stamp before the hole.
    pub from: f64,
    /// The first stamp after it.
    pub to: f64,
    /// The limit it exceeded, in seconds.
    pub limit: f64,
}

/// A piece of an experiment split at its gaps.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PieceNote {
    /// The experiment it became (`None`: dropped as too short).
    pub experiment: Option<String>,
    /// Its first time, in the times of [`GapNote`].
    pub from: f64,
    /// Its last time.
    pub to: f64,
    /// Its samples on the grid.
    pub samples: usize,
}

/// A loaded file: its experiments and what was noted while reading it.
#[derive(Clone, Debug)]
pub struct LoadedFile {
    /// The experiments, in file order.
    pub experiments: Vec<Experiment>,
    /// Comment lines, time-stamp jitter, resampling.
    pub notes: FileNotes,
}
