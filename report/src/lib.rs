//! leeway-report: what the CLI and the Python package both report: the JSON documents of
//! `leeway check --json` ([`check`]) and `leeway estimate --json` (a contract scripts rely on:
//! docs/json.md; fields may be added, none renamed or removed), and
//! the checks of the data that come with it (the heading's unit, angles
//! logged in degrees). Kept here, beside the estimator, so that
//! `leeway.Estimate.to_json()` and the CLI print the same bytes from one
//! piece of code.

pub mod check;

pub mod feedback;

pub mod checks;

pub use checks::{
    heading_alerts, heading_gains, heading_warnings, input_peaks, unit_alerts,
    unit_alerts_from_peaks, unit_warnings, unit_warnings_from_peaks,
};

use leeway_data::FileNotes;
use leeway_estimate::{ColumnEstimate, Diagnostics, Estimate, Method};
use leeway_model::signs::ArgSign;
use leeway_model::warning::Warning;
use serde::Serialize;
use std::collections::BTreeMap;

/// A JSON object whose keys keep the order given (the model's order), not
/// the alphabetical order of a map.
#[derive(Clone, Debug, PartialEq)]
pub struct Ordered<T>(pub Vec<(String, T)>);

impl<T> Default for Ordered<T> {
    fn default() -> Ordered<T> {
        Ordered(Vec::new())
    }
}

impl<T: Serialize> Serialize for Ordered<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// The JSON form of the loading notes (docs/json.md: `data_files`).
#[derive(Debug, serde::Serialize)]
pub struct DataFileJson {
    /// The file as given.
    pub file: String,
    /// Lines skipped as comments (`#`).
    pub comment_lines: usize,
    /// Lines skipped as blank (only whitespace).
    pub blank_lines: usize,
    /// Per experiment: rows read, largest relative step deviation, samples after resampling.
    pub experiments: Vec<DataExperimentJson>,
    /// A joined log's first stamp, ISO-8601 UTC, from which its times count
    /// (omitted for one file).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin: Option<String>,
    /// A joined log's signals as read (omitted for one file).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub signals: Vec<leeway_data::SignalNote>,
}

/// One experiment of [`DataFileJson`].
#[derive(Debug, serde::Serialize)]
pub struct DataExperimentJson {
    /// The experiment's name.
    pub name: String,
    /// Rows read from the file.
    pub rows: usize,
    /// Largest `|Δt − h|/h` over the steps (null without a time column).
    pub max_step_deviation: Option<f64>,
    /// Samples after `--resample` (null when not resampled).
    pub resampled: Option<usize>,
    /// Stretches without samples beyond the gap limit, where the experiment
    /// was split (omitted when none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gaps: Vec<leeway_data::GapNote>,
    /// The pieces a split left, kept (`experiment` named) or dropped
    /// (`experiment` null) (omitted when not split).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pieces: Vec<leeway_data::PieceNote>,
    /// A joined log's stalls: holes within the gap limit, held or
    /// interpolated across (`limit`: the stall threshold; omitted when none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stalls: Vec<leeway_data::GapNote>,
}

/// [`FileNotes`] as JSON.
pub fn data_files_json(notes: &[FileNotes]) -> Vec<DataFileJson> {
    notes
        .iter()
        .map(|f| DataFileJson {
            file: f.file.clone(),
            comment_lines: f.comment_lines,
            blank_lines: f.blank_lines,
            experiments: f
                .experiments
                .iter()
                .map(|e| DataExperimentJson {
                    name: e.experiment.clone(),
                    rows: e.rows,
                    max_step_deviation: e.max_step_deviation,
                    resampled: e.resampled,
                    gaps: e.gaps.clone(),
                    pieces: e.pieces.clone(),
                    stalls: e.stalls.clone(),
                })
                .collect(),
            origin: f.origin.clone(),
            signals: f.signals.clone(),
        })
        .collect()
}

/// What an estimate produced besides θ, for the report: the model, the
/// experiments read and what reading them noted.
#[derive(Clone, Copy, Debug)]
pub struct Estimated<'a> {
    /// The model's name.
    pub model: &'a str,
    /// The estimate.
    pub estimate: &'a Estimate,
    /// Experiment names with their sample counts.
    pub experiments: &'a [(String, usize)],
    /// The heading's unit check per experiment ([`heading_gains`]).
    pub heading_gains: &'a [(String, Option<f64>)],
    /// What reading each data file noted (comment lines, jitter, resampling).
    pub data_notes: &'a [FileNotes],
    /// The units declared in the model's `data { }`, by signal.
    pub data_units: &'a BTreeMap<String, String>,
}

/// The document of `leeway estimate --json`. `E` is the shape of an error
/// (the CLI's model diagnostics or located problems).
#[derive(Debug, Serialize)]
pub struct EstimateReport<E> {
    /// `model Name`, or null when the model did not compile (set whenever it
    /// compiled, also on a data or estimate error).
    pub model: Option<String>,
    /// The model file as given.
    pub file: String,
    /// The data files as given.
    pub data: Vec<String>,
    /// `ls`, `iv1`, `iv2` or `iv3`.
    pub method: &'static str,
    /// Experiments and their sample counts.
    experiments: Vec<ExperimentJson>,
    /// θ by name, in the model's order (held parameters at their nominal value).
    estimates: Ordered<f64>,
    /// Standard errors of θ (null for held parameters).
    std_errors: Ordered<Option<f64>>,
    /// The covariance of θ, `{row: {column: number or null}}` in the model's
    /// order (the sandwich the standard errors come from; null where a
    /// parameter was not estimated).
    covariance: Ordered<Ordered<Option<f64>>>,
    /// θ with status and meaning.
    parameters: Vec<Column>,
    /// The nuisance parameters (moments of the unmeasured disturbances times θ).
    nuisance: Vec<Column>,
    /// `{disturbance: {component: {mean, std_error}}}` for unmeasured media.
    disturbances: Ordered<Ordered<Moment>>,
    /// Per experiment, the sign of every modulus argument.
    sign_patterns: Vec<SignPattern>,
    /// How the estimate was computed (an empty object on error).
    diagnostics: serde_json::Value,
    /// Per data file: comment lines skipped, time-stamp jitter, resampling.
    data_files: Vec<DataFileJson>,
    /// `{signal: unit}` as declared in the model's `data { }` (values converted to base units).
    data_units: Ordered<String>,
    /// Model warnings, data checks, estimator warnings, each in full.
    pub warnings: Vec<String>,
    /// The same warnings, each with its one-line summary, help line and
    /// whether it can bias the estimate (docs/json.md: `warning_summaries`).
    pub warning_summaries: Vec<Warning>,
    /// Facts worth knowing that need no action (e.g. pointwise moduli crossing zero).
    notes: Vec<String>,
    /// Why nothing was estimated.
    pub errors: Vec<E>,
    /// `--scan-delay`: the curve of the criterion over the candidate dead
    /// times and the one chosen (absent without a scan).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delay_scan: Option<DelayScanJson>,
    /// Every scan, in order, when several inputs were scanned (the last is
    /// `delay_scan`; omitted for one).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub delay_scans: Vec<DelayScanJson>,
}

/// A dead-time scan as `estimate --json` gives it (docs/json.md).
#[derive(Debug, Serialize)]
pub struct DelayScanJson {
    /// The input scanned.
    pub input: String,
    /// `fit` or `residual`.
    pub by: &'static str,
    /// The dead time chosen, in samples.
    pub samples: usize,
    /// In seconds.
    pub seconds: f64,
    /// Every candidate: `samples`, `seconds`, `criterion` (%, null when
    /// undefined), `error` (null, or why no estimate there).
    pub curve: Vec<leeway_estimate::ScanPoint>,
}

impl DelayScanJson {
    /// The JSON of a scan.
    pub fn of(scan: &leeway_estimate::DelayScan) -> DelayScanJson {
        let chosen = scan.points.get(scan.chosen);
        DelayScanJson {
            input: scan.input.clone(),
            by: leeway_estimate::Named::name(scan.by),
            samples: chosen.map_or(0, |p| p.samples),
            seconds: chosen.map_or(0.0, |p| p.seconds),
            curve: scan.points.clone(),
        }
    }
}

#[derive(Debug, Serialize)]
struct ExperimentJson {
    name: String,
    samples: usize,
}

#[derive(Debug, Serialize)]
struct Column {
    name: String,
    /// `theta`, `rho` or `lambda`.
    kind: &'static str,
    value: Option<f64>,
    std_error: Option<f64>,
    /// `estimated`, `held at nominal`, `held at 0`, `dropped`.
    status: String,
    /// What the value estimates.
    estimates: String,
    /// For a parameter that estimates an aggregate, the sum it stands for
    /// (`X_uu + W_uu`); null otherwise.
    aggregate: Option<String>,
}

#[derive(Debug, Serialize)]
struct Moment {
    mean: f64,
    std_error: Option<f64>,
}

#[derive(Debug, Serialize)]
struct SignPattern {
    experiment: String,
    /// `{argument: "+" | "-"}` for the arguments the predictor fixes.
    pattern: Ordered<&'static str>,
    arguments: Vec<Argument>,
    /// Arguments relative to a measured medium, evaluated pointwise by IV3.
    pointwise: Vec<Argument>,
}

#[derive(Debug, Serialize)]
struct Argument {
    argument: String,
    sign: &'static str,
    /// Fraction of the samples with the other sign (0 when paper A7 holds).
    minority_fraction: f64,
}

#[derive(Debug, Serialize)]
struct DiagnosticsJson<'a> {
    #[serde(flatten)]
    estimator: &'a Diagnostics,
    /// Gain of `Δψ/h` on the yaw rate per experiment (≈ 1 when consistent).
    heading_gains: Ordered<Option<f64>>,
}

/// `+` or `-` for a sign.
pub fn sign_symbol(s: i8) -> &'static str {
    if s < 0 { "-" } else { "+" }
}

fn argument(a: &ArgSign) -> Argument {
    Argument {
        argument: a.argument.clone(),
        sign: sign_symbol(a.sign),
        minority_fraction: a.minority_fraction,
    }
}

fn column(c: &ColumnEstimate, aggregates: &[String]) -> Column {
    Column {
        aggregate: aggregate_of(c, aggregates),
        name: c.name.clone(),
        kind: c.kind,
        value: c.value,
        std_error: c.std_error,
        status: c.status.clone(),
        estimates: c.estimates.clone(),
    }
}

/// What an estimated parameter stands for when it is an aggregate (`X_uu +
/// W_uu`): its column estimates more than itself, or the estimator's
/// diagnostics name it (`X_uu estimates …`).
pub fn aggregate_of(c: &ColumnEstimate, aggregates: &[String]) -> Option<String> {
    if c.kind != "theta" || c.value.is_none() || c.status.starts_with("held") {
        return None;
    }
    if c.status == "aggregate" {
        return Some(c.estimates.clone());
    }
    if c.estimates != c.name && !c.estimates.is_empty() {
        return Some(c.estimates.clone());
    }
    let prefix = format!("{} estimates ", c.name);
    aggregates.iter().find_map(|a| {
        let rest = a.strip_prefix(&prefix)?;
        // The remark in parentheses is said once, in the diagnostics.
        Some(rest.split(" (").next().unwrap_or(rest).to_string())
    })
}

/// The means of the unmeasured disturbances grouped by disturbance, in the
/// estimator's order.
fn disturbances(e: &Estimate) -> Ordered<Ordered<Moment>> {
    let mut out: Vec<(String, Ordered<Moment>)> = Vec::new();
    for m in &e.disturbances {
        let moment = Moment {
            mean: m.mean,
            std_error: m.std_error,
        };
        match out.iter_mut().find(|(d, _)| *d == m.disturbance) {
            Some((_, comps)) => comps.0.push((m.component.clone(), moment)),
            None => out.push((
                m.disturbance.clone(),
                Ordered(vec![(m.component.clone(), moment)]),
            )),
        }
    }
    Ordered(out)
}

impl<E> EstimateReport<E> {
    /// Everything an estimate reports: θ with its errors and covariance,
    /// the columns, disturbances, sign patterns, diagnostics and what
    /// loading noted.
    fn fill(&mut self, o: &Estimated<'_>) {
        let e = o.estimate;
        let r = self;
        r.model = Some(o.model.to_string());
        r.notes = e.notes.clone();
        r.data_files = data_files_json(o.data_notes);
        r.data_units = Ordered(
            o.data_units
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect(),
        );
        r.experiments = o
            .experiments
            .iter()
            .map(|(name, samples)| ExperimentJson {
                name: name.clone(),
                samples: *samples,
            })
            .collect();
        r.estimates = Ordered(e.parameters.iter().cloned().zip(e.theta.clone()).collect());
        r.std_errors = Ordered(
            e.parameters
                .iter()
                .cloned()
                .zip(e.std_errors.clone())
                .collect(),
        );
        r.covariance = Ordered(
            e.parameters
                .iter()
                .zip(&e.covariance)
                .map(|(name, row)| {
                    let row = e.parameters.iter().cloned().zip(row.clone()).collect();
                    (name.clone(), Ordered(row))
                })
                .collect(),
        );
        r.parameters = e
            .columns
            .iter()
            .filter(|c| c.kind == "theta")
            .map(|c| column(c, &e.diagnostics.aggregates))
            .collect();
        r.nuisance = e
            .columns
            .iter()
            .filter(|c| c.kind != "theta")
            .map(|c| column(c, &e.diagnostics.aggregates))
            .collect();
        r.disturbances = disturbances(e);
        r.sign_patterns = e
            .sign_patterns
            .iter()
            .map(|s| SignPattern {
                experiment: s.experiment.clone(),
                pattern: Ordered(
                    s.arguments
                        .iter()
                        .map(|a| (a.argument.clone(), sign_symbol(a.sign)))
                        .collect(),
                ),
                arguments: s.arguments.iter().map(argument).collect(),
                pointwise: s.pointwise.iter().map(argument).collect(),
            })
            .collect();
        let diagnostics = DiagnosticsJson {
            estimator: &e.diagnostics,
            heading_gains: Ordered(o.heading_gains.to_vec()),
        };
        // Plain structs of strings and numbers always serialise; an empty object
        // is the documented shape on error should that ever change.
        r.diagnostics = serde_json::to_value(&diagnostics)
            .unwrap_or_else(|_| serde_json::Value::Object(serde_json::Map::new()));
    }
}

/// The document for a result (`Ok`) or the errors that stopped it. `model`
/// names the model when it compiled (also on a data or estimate error);
/// `file` and `data` name the model and data files as given; `warnings` are
/// given in full (each estimator warning keeps its summary).
pub fn estimate_report<E>(
    file: String,
    data: Vec<String>,
    method: Method,
    model: Option<String>,
    result: Result<Estimated<'_>, Vec<E>>,
    warnings: Vec<String>,
) -> EstimateReport<E> {
    let estimate = result.as_ref().ok().map(|o| o.estimate);
    let warnings = warnings.iter().map(|w| summary_of(w, estimate)).collect();
    estimate_report_warned(file, data, method, model, result, warnings)
}

/// [`estimate_report`] with every warning structured.
pub fn estimate_report_warned<E>(
    file: String,
    data: Vec<String>,
    method: Method,
    model: Option<String>,
    result: Result<Estimated<'_>, Vec<E>>,
    warnings: Vec<Warning>,
) -> EstimateReport<E> {
    let mut r = EstimateReport {
        model,
        file,
        data,
        method: method.name(),
        experiments: Vec::new(),
        estimates: Ordered::default(),
        std_errors: Ordered::default(),
        covariance: Ordered::default(),
        parameters: Vec::new(),
        nuisance: Vec::new(),
        disturbances: Ordered::default(),
        sign_patterns: Vec::new(),
        diagnostics: serde_json::Value::Object(serde_json::Map::new()),
        data_files: Vec::new(),
        data_units: Ordered::default(),
        warnings: warnings.iter().map(|w| w.detail.clone()).collect(),
        warning_summaries: warnings,
        notes: Vec::new(),
        errors: Vec::new(),
        delay_scan: None,
        delay_scans: Vec::new(),
    };
    let o = match result {
        Ok(o) => o,
        Err(errors) => {
            r.errors = errors;
            return r;
        }
    };
    r.fill(&o);
    r
}

impl<E: Serialize> EstimateReport<E> {
    /// The document as the CLI prints it (pretty, two-space indent, no
    /// trailing newline).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }
}

/// The structured form of a warning given in full: the estimator's own
/// where it made it, otherwise the text as its own summary.
fn summary_of(detail: &str, estimate: Option<&Estimate>) -> Warning {
    estimate
        .and_then(|e| e.warning_summaries.iter().find(|w| w.detail == detail))
        .cloned()
        .unwrap_or_else(|| Warning::plain("warning", detail))
}
