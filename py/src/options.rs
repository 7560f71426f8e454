//! The estimator's options as `leeway.estimate` takes them, read on the rules the CLI follows.

use crate::failure::Failure;
use leeway_data::{DEFAULT_TIME_TOLERANCE, LoadOptionError, LoadOptions, TIME_TOLERANCE_HINT};
use leeway_estimate::Named;
use leeway_structure::ir::Ir;
use pyo3::prelude::*;

/// The estimator's options as `leeway.estimate` takes them (keyword names
/// of the CLI's flags, values as their strings).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct EstimateOptions {
    pub(crate) method: String,
    pub(crate) instruments: String,
    pub(crate) initial: String,
    pub(crate) centring: Option<String>,
    pub(crate) combine: String,
    pub(crate) nominal: Option<Vec<f64>>,
    pub(crate) aggregate: bool,
    pub(crate) strict: bool,
    pub(crate) lags: usize,
    pub(crate) max_refinements: usize,
    pub(crate) runaway_guard: bool,
    pub(crate) step: Option<f64>,
    pub(crate) time_tolerance: f64,
    pub(crate) resample: Option<f64>,
    /// `scan_delay="tau_x=0..2s"`: the dead-time scan (`--scan-delay`).
    #[pyo3(default)]
    pub(crate) scan_delay: Option<String>,
    /// `scan_by="fit"` or `"residual"` (`--scan-by`).
    #[pyo3(default)]
    pub(crate) scan_by: Option<String>,
    /// `refine_subsample=0.1` (`--refine-subsample`).
    #[pyo3(default)]
    pub(crate) refine_subsample: Option<f64>,
}

/// The value named `given` of a named option, or an `OptionError` listing
/// the names.
pub(crate) fn choice<T: Named>(given: &str) -> Result<T, Failure> {
    T::from_name(given).map_err(|e| {
        let names = e.names.join(", ");
        Failure::option(
            format!("{}={given:?} is not one of {names}", e.option),
            Some(format!("{} is one of {names}", e.option)),
        )
    })
}

/// Ctrl-C during an estimate: Python runs its SIGINT handler only when
/// asked while native code holds the thread, so the estimator asks between
/// passes (from the calling thread, the main one for an interactive user);
/// the handler's `KeyboardInterrupt` is raised when the estimate has stopped
/// (`interrupted`, see `failure.rs`).
pub(crate) fn python_interrupt() -> leeway_estimate::Interrupt {
    leeway_estimate::Interrupt::new(|| Python::attach(|py| py.check_signals().is_err()))
}

impl EstimateOptions {
    /// The load options these options give, checked against the model.
    pub(crate) fn load_options(&self, ir: &Ir) -> Result<LoadOptions, Failure> {
        load_options(ir, self.step, Some(self.time_tolerance), self.resample)
    }

    /// The dead-time scan asked for, if any: its range read as the CLI
    /// reads `--scan-delay`, and its criterion.
    pub(crate) fn scan(
        &self,
    ) -> Result<Option<(Vec<leeway_estimate::DelayRange>, leeway_estimate::ScanBy)>, Failure> {
        let Some(text) = &self.scan_delay else {
            return Ok(None);
        };
        let range = leeway_estimate::DelayRange::parse_list(text).map_err(|m| {
            Failure::option(
                format!("scan_delay: {m}"),
                Some("give the input and a range of dead times, e.g. scan_delay=\"tau_x=0..20\" (samples) or \"tau_x=0..2s\" (seconds); several inputs separated by commas are scanned one after another".into()),
            )
        })?;
        let by = choice(self.scan_by.as_deref().unwrap_or("fit"))?;
        Ok(Some((range, by)))
    }

    /// The estimator's options, on the bounds the CLI applies
    /// ([`leeway_estimate::EstimateOptions::validate`]).
    pub(crate) fn runtime(&self) -> Result<leeway_estimate::EstimateOptions, Failure> {
        let options = leeway_estimate::EstimateOptions {
            method: choice(&self.method)?,
            instruments: choice(&self.instruments)?,
            initial: choice(&self.initial)?,
            centring: self.centring.as_deref().map(choice).transpose()?,
            combine: choice(&self.combine)?,
            nominal: self.nominal.clone(),
            max_refinements: self.max_refinements,
            aggregate: self.aggregate,
            strict: self.strict,
            lags: self.lags,
            runaway_guard: self.runaway_guard,
            refine_subsample: self.refine_subsample,
            interrupt: Some(python_interrupt()),
            ..leeway_estimate::EstimateOptions::default()
        };
        options
            .validate()
            .map_err(|e| Failure::option(e.to_string(), None))?;
        Ok(options)
    }
}

/// How data are read: `step`, `time_tolerance` (`None`: the default) and
/// `resample` ([`LoadOptions::for_model`], as in the CLI), the problems
/// worded with Python's keywords.
pub(crate) fn load_options(
    ir: &Ir,
    step: Option<f64>,
    time_tolerance: Option<f64>,
    resample: Option<f64>,
) -> Result<LoadOptions, Failure> {
    let tolerance = time_tolerance.unwrap_or(DEFAULT_TIME_TOLERANCE);
    LoadOptions::for_model(ir, step, tolerance, resample).map_err(|e| match e {
        LoadOptionError::SampleTime { option, value } => Failure::option(
            format!(
                "{option}={value} is outside 1e-6..=1e6 seconds, the sample times leeway accepts"
            ),
            None,
        ),
        LoadOptionError::TimeTolerance(v) => Failure::option(
            format!("time_tolerance={v} is not a fraction in (0, 0.5)"),
            Some(TIME_TOLERANCE_HINT.into()),
        ),
        LoadOptionError::MaxGap(g) => Failure::option(
            format!("max_gap={g} is not a positive number of seconds"),
            Some("give the longest hole to interpolate across, in seconds, e.g. max_gap=2.0".into()),
        ),
        LoadOptionError::StepConflict { given, declared } => Failure::option(
            format!("step={given} conflicts with the model's `step {declared}`"),
            Some("drop step= (the model's step is used), or change `step` in the model".into()),
        ),
        LoadOptionError::ResampleConflict { given, declared } => Failure::option(
            format!(
                "resample={given} conflicts with the sample time {declared} (the model's `step` or step=)"
            ),
            Some(format!("resample at the model's step: resample={declared}")),
        ),
    })
}
