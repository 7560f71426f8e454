//! What a successful estimate produced, for its text and JSON outputs.

use leeway_estimate::Estimate;

/// What a successful run produced.
pub struct Outcome {
    /// The model's name.
    pub model: String,
    /// The estimate.
    pub estimate: Estimate,
    /// Experiment names with their sample counts.
    pub experiments: Vec<(String, usize)>,
    /// The heading's unit check per experiment (planar heading only).
    pub heading_gains: Vec<(String, Option<f64>)>,
    /// What reading each data file noted (comment lines, jitter, resampling).
    pub data_notes: Vec<leeway_data::FileNotes>,
    /// The declared units, one line each (`delta: column rudder in deg, converted to rad`).
    pub units: Vec<String>,
    /// The declared units by signal, as written.
    pub data_units: std::collections::BTreeMap<String, String>,
    /// `--scan-delay`: the scan whose chosen dead time `estimate` is at.
    pub scans: Vec<leeway_estimate::DelayScan>,
}
