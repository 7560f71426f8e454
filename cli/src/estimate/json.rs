//! The JSON document of `leeway estimate --json`: a contract scripts rely on
//! (docs/json.md). Fields may be added; none is renamed or removed.
//! It is printed for every outcome: on an error the result fields are empty
//! and `errors` says why. The document itself is built by
//! [`leeway_report`], which the Python package's
//! `Estimate.to_json()` shares.

use crate::estimate::args::EstimateArgs;
use crate::estimate::outcome::Outcome;
use crate::problem::{Failure, JsonError};
use leeway_model::warning::Warning;
use leeway_report::Estimated;
use leeway_report::estimate_report_warned;
use leeway_report::{DelayScanJson, EstimateReport};

/// The whole document.
pub type Report = EstimateReport<JsonError>;

/// The document for a result or a failure.
pub fn report(
    args: &EstimateArgs,
    model: Option<String>,
    result: &Result<Outcome, Failure>,
    warnings: Vec<Warning>,
) -> Report {
    let scans = result.as_ref().map_or(&[][..], |o| o.scans.as_slice());
    let result = match result {
        Ok(o) => Ok(Estimated {
            model: &o.model,
            estimate: &o.estimate,
            experiments: &o.experiments,
            heading_gains: &o.heading_gains,
            data_notes: &o.data_notes,
            data_units: &o.data_units,
        }),
        Err(f) => Err(f.json()),
    };
    let mut report = estimate_report_warned(
        args.model.display().to_string(),
        args.data.iter().map(|p| p.display().to_string()).collect(),
        args.options(None).method,
        model,
        result,
        warnings,
    );
    report.delay_scan = scans.last().map(DelayScanJson::of);
    if scans.len() > 1 {
        report.delay_scans = scans.iter().map(DelayScanJson::of).collect();
    }
    report
}
