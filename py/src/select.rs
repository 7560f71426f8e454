//! `leeway select --json` of a candidate model on frames: the selection
//! made by the library function the CLI calls ([`leeway_select::select`]),
//! the GIL released while the data are read and the path is walked.

use crate::data::{self, FrameArg, borrow_frames};
use crate::estimate::estimate_document;
use crate::failure::{Failure, class_of};
use crate::model::Model;
use crate::options::{choice, load_options, python_interrupt};
use leeway_estimate::{EstimateError, MAX_LAGS, Method};
use leeway_model::Source;
use leeway_select::{SelectError, SelectOptions};
use pyo3::prelude::*;

/// `Model.select`'s options (keyword names of the CLI's flags).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct SelectArgs {
    pub(crate) method: String,
    pub(crate) lags: usize,
    pub(crate) tolerance: f64,
    pub(crate) step: Option<f64>,
    pub(crate) time_tolerance: f64,
    pub(crate) resample: Option<f64>,
}

/// The selection's options on the bounds `leeway select` applies.
fn select_options(args: &SelectArgs) -> Result<SelectOptions, Failure> {
    let method: Method = choice(&args.method)?;
    if !(1..=MAX_LAGS).contains(&args.lags) {
        return Err(Failure::option(
            format!("lags={} is outside 1..={MAX_LAGS}", args.lags),
            Some("give the disturbances' correlation time in samples".into()),
        ));
    }
    if !(args.tolerance >= 0.0 && args.tolerance.is_finite()) {
        return Err(Failure::option(
            format!("tolerance={} is not a non-negative number", args.tolerance),
            Some("give a fraction such as 0.1".into()),
        ));
    }
    let mut options = SelectOptions {
        tolerance: args.tolerance,
        ..SelectOptions::default()
    };
    options.estimate.method = method;
    options.estimate.lags = args.lags;
    options.estimate.interrupt = Some(python_interrupt());
    Ok(options)
}

/// A selection's failure as the package raises it: the candidate model's
/// problems are `ModelError`s located at its file, a refused option an
/// `OptionError`, the estimator's failures by their code.
fn failure(e: SelectError, file: &str) -> Failure {
    // The estimator's own code is the message's `[code]` prefix.
    let inner = e
        .message
        .strip_prefix('[')
        .and_then(|m| m.split_once(']'))
        .map_or(e.code, |(c, _)| c);
    let class = match e.code {
        "invalid-candidates" | "invalid-model" | "no-candidates" => "ModelError",
        "invalid-option" => "OptionError",
        _ => class_of(inner),
    };
    // Ctrl-C keeps its code: it is raised as `KeyboardInterrupt`.
    let code = if inner == "interrupted" {
        "interrupted"
    } else {
        e.code
    };
    let located = class == "ModelError";
    Failure::classed(
        class,
        &EstimateError {
            code,
            message: e.message,
            hint: e.hint,
        },
        located.then(|| file.to_string()),
    )
}

/// `leeway select --json`'s `selection` of `model` on the frames (held out:
/// `validate`, or each experiment in turn when it is empty), the chosen
/// model's source, and the chosen estimate as `leeway estimate --json`'s
/// document of the chosen model on the same frames.
#[pyfunction]
pub(crate) fn select_json(
    py: Python<'_>,
    model: &Model,
    frames: Vec<FrameArg<'_>>,
    validate: Vec<FrameArg<'_>>,
    args: SelectArgs,
) -> PyResult<(String, String, String)> {
    let options = select_options(&args)?;
    let load = load_options(
        &model.ir,
        args.step,
        Some(args.time_tolerance),
        args.resample,
    )?;
    let borrowed = borrow_frames(&frames)?;
    let held_out = borrow_frames(&validate)?;
    let names: Vec<String> = frames.iter().map(|f| f.0.clone()).collect();
    let answer = py.detach(|| -> Result<(String, String, String), Failure> {
        // Held in memory, as `leeway select` reads its files.
        let (experiments, notes) = data::load(&model.ir, &borrowed, &load)?;
        let validation = if held_out.is_empty() {
            Vec::new()
        } else {
            data::load(&model.ir, &held_out, &load)?.0
        };
        let selection = leeway_select::select(&model.source, &experiments, &validation, &options)
            .map_err(|e| failure(e, &model.file))?;
        let document = serde_json::to_string(&selection)
            .map_err(|e| Failure::option(format!("cannot serialise the selection: {e}"), None))?;
        let chosen = Model::compile_source(selection.chosen_source.clone(), model.file.clone())?;
        let sources: Vec<&dyn Source> = experiments.iter().map(|e| e as &dyn Source).collect();
        let checks = leeway_report::checks::data_checks(&chosen.ir, &sources);
        let mut warnings = chosen.warnings.clone();
        warnings.extend(selection.estimate.warnings.iter().cloned());
        let sizes: Vec<(String, usize)> = sources
            .iter()
            .map(|e| (e.name().to_string(), e.len()))
            .collect();
        let estimate = estimate_document(
            &chosen,
            names,
            &selection.estimate,
            &sizes,
            &checks.heading_gains,
            &notes,
            warnings,
        )?;
        Ok((document, selection.chosen_source, estimate))
    })?;
    Ok(answer)
}
