//! Options as flags: how data are read (sample times, the time tolerance)
//! and option values by name, on the rules of leeway-data and
//! leeway-estimate, which Python follows too.

use crate::problem::Problem;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use leeway_data::gaps::GapLimit;
use leeway_data::{
    DEFAULT_TIME_TOLERANCE, LoadOptionError, LoadOptions, STEP_RANGE, TIME_TOLERANCE_HINT,
    sample_time_ok, time_tolerance_ok,
};
use leeway_estimate::{MAX_REFINEMENTS, Named};
use leeway_structure::ir::Ir;

/// How data files with time stamps are read: shared by `estimate` and `validate`.
#[derive(Debug, Clone, clap::Args)]
pub struct TimeArgs {
    /// Largest relative deviation of a time step from the nominal (mean) step,
    /// as a fraction in (0, 0.5): 0.05 accepts ±5 % logger jitter and still
    /// rejects a dropped sample (a 100 % step).
    #[arg(long, value_name = "TOL", default_value_t = leeway_data::DEFAULT_TIME_TOLERANCE, value_parser = tolerance)]
    pub time_tolerance: f64,
    /// Interpolate every experiment linearly onto a uniform grid of H seconds
    /// from its first time stamp (needs a time column; the heading along the short arc).
    #[arg(long, value_name = "H", value_parser = positive)]
    pub resample: Option<f64>,
    /// The longest stretch without samples that `--resample` and a joined
    /// log (a `.toml` manifest) may interpolate across, in seconds; a
    /// longer one splits the experiment. Default: 5 steps of each signal's
    /// own median step.
    #[arg(long, value_name = "SECONDS", value_parser = positive)]
    pub max_gap: Option<f64>,
    /// Keep only these windows of a joined log (a manifest or a bag), in
    /// seconds from its first stamp: `--keep 0..700 --keep 850..` (either
    /// end may be left open; several are joined). A manifest with its own
    /// `[[keep]]` windows is an error with this option: one place says.
    #[arg(long, value_name = "FROM..TO", value_parser = window, action = clap::ArgAction::Append)]
    pub keep: Vec<(Option<f64>, Option<f64>)>,
}

/// `--keep FROM..TO`: seconds, either end open, `FROM < TO`.
pub fn window(s: &str) -> Result<(Option<f64>, Option<f64>), String> {
    let shape = || format!("`{s}` is not a window FROM..TO in seconds (e.g. 0..700, or 850..)");
    let (a, b) = s.split_once("..").ok_or_else(shape)?;
    let end = |t: &str| -> Result<Option<f64>, String> {
        let t = t.trim();
        if t.is_empty() {
            return Ok(None);
        }
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(shape()),
        }
    };
    let (a, b) = (end(a)?, end(b)?);
    match (a, b) {
        (None, None) => Err(format!("`{s}` keeps everything: give FROM, TO or both")),
        (Some(x), Some(y)) if y <= x => Err(format!("`{s}` is empty: TO must come after FROM")),
        _ => Ok((a, b)),
    }
}

/// `--time-tolerance`: a fraction in (0, 0.5) ([`time_tolerance_ok`]).
pub fn tolerance(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if time_tolerance_ok(v) => Ok(v),
        Ok(v) if (0.5..50.0).contains(&v) => Err(format!(
            "`{s}` is not a fraction in (0, 0.5) ({TIME_TOLERANCE_HINT})"
        )),
        _ => Err(format!(
            "`{s}` is not a fraction in (0, 0.5): the relative step tolerance, e.g. 0.05 for 5 %"
        )),
    }
}

/// The load options of a command ([`LoadOptions::for_model`]), its
/// conflicts with the model in the CLI's words.
pub fn load_options(
    ir: &Ir,
    step: Option<f64>,
    time: Option<&TimeArgs>,
) -> Result<LoadOptions, Problem> {
    let tolerance = time.map_or(DEFAULT_TIME_TOLERANCE, |t| t.time_tolerance);
    let resample = time.and_then(|t| t.resample);
    let max_gap = time
        .and_then(|t| t.max_gap)
        .map_or(GapLimit::default(), GapLimit::Seconds);
    let keep = time.map_or(Vec::new(), |t| t.keep.clone());
    LoadOptions::for_model(ir, step, tolerance, resample)
        .and_then(|o| o.with_max_gap(max_gap))
        .map(|o| LoadOptions { keep, ..o })
        .map_err(|e| {
        let (message, help) = match e {
            LoadOptionError::SampleTime { option, value } => (
                format!("--{option} {value} is outside 1e-6..=1e6 seconds, the sample times leeway accepts"),
                "give a sample time in seconds".to_string(),
            ),
            LoadOptionError::TimeTolerance(v) => (
                format!("--time-tolerance {v} is not a fraction in (0, 0.5)"),
                TIME_TOLERANCE_HINT.to_string(),
            ),
            LoadOptionError::MaxGap(g) => (
                format!("--max-gap {g} is not a positive number of seconds"),
                "give the longest hole to interpolate across, in seconds, e.g. --max-gap 2".to_string(),
            ),
            LoadOptionError::StepConflict { given, declared } => (
                format!("--step {given} conflicts with the model's `step {declared}`"),
                "drop --step (the model's step is used), or change `step` in the model".into(),
            ),
            LoadOptionError::ResampleConflict { given, declared } => (
                format!("--resample {given} conflicts with the sample time {declared} (the model's `step` or --step)"),
                format!("resample at the model's step: --resample {declared}"),
            ),
        };
        Problem::error("invalid-option", message).help(help)
    })
}

pub fn refinements(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(v) if v <= MAX_REFINEMENTS => Ok(v),
        Ok(_) => Err(format!("`{s}` is not in 0..={MAX_REFINEMENTS}")),
        Err(_) => Err(format!("`{s}` is not a whole number")),
    }
}

/// A fraction in (0, 1] (`--refine-subsample`).
pub fn fraction(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!("`{s}` is not a fraction in (0, 1], such as 0.1")),
    }
}

/// A sample time in seconds within [`STEP_RANGE`] (`--step`, `--resample`).
pub fn positive(s: &str) -> Result<f64, String> {
    let (lo, hi) = STEP_RANGE;
    match s.trim().parse::<f64>() {
        Ok(v) if sample_time_ok(v) => Ok(v),
        Ok(v) if v.is_finite() && v > 0.0 => Err(format!(
            "`{s}` s is outside {lo:e}..={hi:e} seconds, the sample times leeway accepts"
        )),
        _ => Err(format!("`{s}` is not a positive number of seconds")),
    }
}

/// A named option's values ([`Named`]) as a clap parser: the names and
/// their help from the one table Python reads too.
pub fn choices<T: Named + Clone + Send + Sync>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(
        T::CHOICES
            .iter()
            .map(|c| PossibleValue::new(c.name).help(c.help)),
    )
    .try_map(|name| T::from_name(&name))
}
