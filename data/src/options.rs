//! How files are loaded: step, time tolerance, resampling.

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
