//! How files are loaded: step, time tolerance, resampling, and the rules
//! those options obey whoever gives them (the CLI, Python).

use crate::gaps::GapLimit;
use leeway_structure::ir::Ir;

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
    /// The longest step resampling may interpolate across: a longer one
    /// splits the experiment ([`GapLimit`]; by default 5 median steps).
    pub max_gap: GapLimit,
    /// Windows of a joined log to keep (`--keep FROM..TO`): seconds from
    /// its first stamp, either end open. Empty: the whole log (or the
    /// manifest's own `[[keep]]` windows).
    pub keep: Vec<(Option<f64>, Option<f64>)>,
}

impl Default for LoadOptions {
    fn default() -> LoadOptions {
        LoadOptions {
            step: None,
            time_tolerance: DEFAULT_TIME_TOLERANCE,
            resample: None,
            max_gap: GapLimit::default(),
            keep: Vec::new(),
        }
    }
}

/// Sample times (`step`, `resample`) in seconds: from a microsecond to a
/// day (11.6 days at most).
pub const STEP_RANGE: (f64, f64) = (1e-6, 1e6);

/// Whether `h` is a sample time leeway accepts (within [`STEP_RANGE`]).
pub fn sample_time_ok(h: f64) -> bool {
    h.is_finite() && (STEP_RANGE.0..=STEP_RANGE.1).contains(&h)
}

/// Whether `tolerance` is a relative step tolerance leeway accepts: a
/// fraction in (0, 0.5). From one half on, a dropped sample (a 100 % step)
/// could pass for jitter.
pub fn time_tolerance_ok(tolerance: f64) -> bool {
    tolerance > 0.0 && tolerance < 0.5
}

/// The hint for a time tolerance out of range.
pub const TIME_TOLERANCE_HINT: &str =
    "write 0.05 for 5 %; 0.5 or more would accept a dropped sample";

/// Load options that cannot be used with a model, each front end naming the
/// options in its own syntax (`--step 0.1`, `step=0.1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LoadOptionError {
    /// `step` or `resample` (the option) outside [`STEP_RANGE`].
    SampleTime {
        /// `step` or `resample`.
        option: &'static str,
        /// The value given.
        value: f64,
    },
    /// A time tolerance outside (0, 0.5).
    TimeTolerance(f64),
    /// A gap limit that is not positive and finite, or under 1.5 steps.
    MaxGap(GapLimit),
    /// `step` differs from the model's own `step`.
    StepConflict {
        /// The step given.
        given: f64,
        /// The model's.
        declared: f64,
    },
    /// `resample` differs from the sample time (the model's `step`, or the
    /// `step` given).
    ResampleConflict {
        /// The resampling step given.
        given: f64,
        /// The sample time.
        declared: f64,
    },
}

impl LoadOptions {
    /// These options with the gap limit `max_gap`, which must be positive
    /// and finite ([`GapLimit::is_valid`]).
    pub fn with_max_gap(self, max_gap: GapLimit) -> Result<LoadOptions, LoadOptionError> {
        if !max_gap.is_valid() {
            return Err(LoadOptionError::MaxGap(max_gap));
        }
        Ok(LoadOptions { max_gap, ..self })
    }
    /// The load options for `ir`: `step` and `resample` within
    /// [`STEP_RANGE`], the time tolerance within (0, 0.5), `step` equal to
    /// the model's own `step` and `resample` to the sample time when both
    /// are given — a conflict is an error, never silently resolved.
    pub fn for_model(
        ir: &Ir,
        step: Option<f64>,
        time_tolerance: f64,
        resample: Option<f64>,
    ) -> Result<LoadOptions, LoadOptionError> {
        for (option, value) in [("step", step), ("resample", resample)] {
            if let Some(value) = value
                && !sample_time_ok(value)
            {
                return Err(LoadOptionError::SampleTime { option, value });
            }
        }
        if !time_tolerance_ok(time_tolerance) {
            return Err(LoadOptionError::TimeTolerance(time_tolerance));
        }
        let differs = |a: f64, b: f64| (a - b).abs() > 1e-9 * a.abs();
        if let (Some(declared), Some(given)) = (ir.step, step)
            && differs(declared, given)
        {
            return Err(LoadOptionError::StepConflict { given, declared });
        }
        if let (Some(declared), Some(given)) = (ir.step.or(step), resample)
            && differs(declared, given)
        {
            return Err(LoadOptionError::ResampleConflict { given, declared });
        }
        Ok(LoadOptions {
            step,
            time_tolerance,
            resample,
            max_gap: GapLimit::default(),
            keep: Vec::new(),
        })
    }
}
