//! `leeway estimate --json` of a model on frames: the GIL released while the data are read and estimated.
//! Ctrl-C is asked for by the estimator's `Interrupt` (`options.rs`) and
//! raised as `KeyboardInterrupt`.

use crate::data::{self, FrameArg, borrow_frames};
use crate::failure::Failure;
use crate::model::Model;
use crate::options::{EstimateOptions, load_options};
use leeway_data::LoadOptions;
use leeway_estimate::{DelayRange, ScanBy, estimate, scan_delays};
use leeway_model::Interpreter;
use leeway_report::{DelayScanJson, EstimateReport, Estimated, estimate_report, heading_warnings};
use pyo3::prelude::*;

/// `leeway estimate --json` of `model` on the frames: each frame is
/// `(name, [(column, float64 array)], experiment labels or None)`. The GIL is
/// released from the moment the columns are borrowed until the document is
/// written.
#[pyfunction]
pub(crate) fn estimate_json(
    py: Python<'_>,
    model: &Model,
    frames: Vec<FrameArg<'_>>,
    options: EstimateOptions,
) -> PyResult<String> {
    let runtime_options = options.runtime()?;
    let scan = options.scan()?;
    // `aggregate` changes what the structure compiler keeps: the CLI compiles
    // with it, so does this.
    let model = &*model.for_aggregate(options.aggregate)?;
    let load_options = load_options(
        &model.ir,
        options.step,
        Some(options.time_tolerance),
        options.resample,
    )?;
    let borrowed = borrow_frames(&frames)?;
    let document = py.detach(|| {
        run_estimate(
            model,
            &borrowed,
            &load_options,
            &runtime_options,
            scan.as_ref(),
        )
    })?;
    Ok(document)
}

fn run_estimate(
    model: &Model,
    frames: &[data::Frame<'_>],
    load_options: &LoadOptions,
    options: &leeway_estimate::EstimateOptions,
    scan: Option<&(Vec<DelayRange>, ScanBy)>,
) -> Result<String, Failure> {
    let ir = &model.ir;
    let (loaded, notes) =
        data::load_for_estimate(ir, frames, load_options, options.interrupt.as_ref())?;
    let sources = loaded.sources();
    let mut warnings = model.warnings.clone();
    // The three checks of the data in one visit of each experiment.
    let checks = leeway_report::checks::data_checks(ir, &sources);
    warnings.extend(leeway_report::unit_warnings_from_peaks(
        ir,
        &checks.input_peaks,
    ));
    let gains = checks.heading_gains;
    warnings.extend(heading_warnings(ir, &gains));
    // Worded as the CLI words them: the report finds each one's summary
    // among the estimate's (added below).
    let alerts = leeway_report::feedback::closed_loop_alerts(&checks.closed_loop);
    warnings.extend(alerts.iter().map(|w| w.detail.clone()));
    let (result, scanned) = match scan {
        None => (
            estimate(&Interpreter::new(ir.clone()), &sources, options),
            Vec::new(),
        ),
        Some((ranges, by)) => match scan_delays(ir, &sources, options, ranges, *by) {
            Ok(scans) => match scans.last() {
                Some(last) => (Ok(last.estimate.clone()), scans),
                None => (
                    estimate(&Interpreter::new(ir.clone()), &sources, options),
                    Vec::new(),
                ),
            },
            Err(e) => (Err(e), Vec::new()),
        },
    };
    // A spill file that could not be read back voids whatever was computed.
    if let Some(f) = loaded.failure() {
        return Err(f);
    }
    let mut est = result.map_err(|mut e| {
        if e.code == "too-few-samples" {
            let list: Vec<String> = sources
                .iter()
                .map(|s| format!("`{}`: {} samples", s.name(), s.len()))
                .collect();
            e.message = format!("{} (experiments: {})", e.message, list.join("; "));
        }
        Failure::estimate(&e)
    })?;
    warnings.extend(est.warnings.iter().cloned());
    est.warning_summaries.extend(alerts);
    let experiments: Vec<(String, usize)> = sources
        .iter()
        .map(|e| (e.name().to_string(), e.len()))
        .collect();
    let mut report = estimate_report_of(
        model,
        frames.iter().map(|f| f.name.to_string()).collect(),
        &est,
        &experiments,
        &gains,
        &notes,
        warnings,
    );
    report.delay_scan = scanned.last().map(DelayScanJson::of);
    if scanned.len() > 1 {
        report.delay_scans = scanned.iter().map(DelayScanJson::of).collect();
    }
    json(&report)
}

/// `leeway estimate --json`'s document of an estimate of `model` from the
/// named data (frames or files), with what loading and the data checks found.
pub(crate) fn estimate_document(
    model: &Model,
    data: Vec<String>,
    est: &leeway_estimate::Estimate,
    experiments: &[(String, usize)],
    gains: &[(String, Option<f64>)],
    notes: &[leeway_data::FileNotes],
    warnings: Vec<String>,
) -> Result<String, Failure> {
    json(&estimate_report_of(
        model,
        data,
        est,
        experiments,
        gains,
        notes,
        warnings,
    ))
}

/// The report [`estimate_document`] writes.
fn estimate_report_of(
    model: &Model,
    data: Vec<String>,
    est: &leeway_estimate::Estimate,
    experiments: &[(String, usize)],
    gains: &[(String, Option<f64>)],
    notes: &[leeway_data::FileNotes],
    warnings: Vec<String>,
) -> EstimateReport<serde_json::Value> {
    let ir = &model.ir;
    estimate_report::<serde_json::Value>(
        model.file.clone(),
        data,
        est.method,
        Some(ir.name.clone()),
        Ok(Estimated {
            model: &ir.name,
            estimate: est,
            experiments,
            heading_gains: gains,
            data_notes: notes,
            data_units: &ir.data_units,
        }),
        warnings,
    )
}

/// A report's JSON text.
fn json(report: &EstimateReport<serde_json::Value>) -> Result<String, Failure> {
    report
        .to_json()
        .map_err(|e| Failure::option(format!("cannot serialise the report: {e}"), None))
}
