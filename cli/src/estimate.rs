//! `leeway estimate MODEL --data A.csv [--data B.csv]... --method iv3`:
//! load and validate the experiments, estimate θ and the nuisance parameters,
//! and print the table, disturbance means, sign patterns, diagnostics and
//! warnings — or one JSON document (docs/json.md). Exit 0 on success
//! (warnings allowed), 1 when the data cannot support the model, 2 on any
//! model, data or option error.

pub mod args;
mod json;
pub mod outcome;
mod text;

use crate::data::{DataSet, open_data};
use crate::estimate::args::EstimateArgs;
use crate::estimate::outcome::Outcome;
use crate::model::load;
use crate::options::load_options;
use crate::output::{Status, err, headline, out, print_json, stderr_style, warning_text};
use crate::problem::{Failure, Problem};
use leeway_estimate::{Bound, DelayRange, estimate, scan_delays};
use leeway_model::Interpreter;
use leeway_model::warning::Warning;
use leeway_report::checks::{data_checks, heading_alerts, unit_alerts_from_peaks};
use leeway_report::feedback::closed_loop_alerts;

/// Runs `leeway estimate`.
pub fn run(args: &EstimateArgs) -> Status {
    let mut warnings = Vec::new();
    let mut model = None;
    let mut result = execute(args, &mut warnings, &mut model);
    if args.strict
        && result.is_ok()
        && let Some(f) = biasing_failure(&warnings)
    {
        result = Err(f);
    }
    if args.json {
        print_json(&json::report(args, model, &result, warnings));
    } else {
        let style = stderr_style();
        if let Ok(o) = &result {
            out(&text::render(o));
        }
        for w in &warnings {
            err(&warning_text(style, w, args.verbose));
        }
        if let Ok(o) = &result {
            for n in &o.estimate.notes {
                err(&headline(style, "note", None, n));
            }
        }
        if let Err(f) = &result {
            err(&f.render(style, "estimated"));
        }
    }
    match &result {
        Ok(_) => Status::Success,
        Err(f) => f.status(),
    }
}

/// Warnings of the model, the data checks and the estimator go to `warnings`,
/// in that order, also when a later step fails; the model's name goes to
/// `model` as soon as it compiles (the JSON names it also on a data error).
fn execute(
    args: &EstimateArgs,
    warnings: &mut Vec<Warning>,
    model_name: &mut Option<String>,
) -> Result<Outcome, Failure> {
    let loaded = load(&args.model, args.aggregate)?;
    let ir = loaded.ir;
    *model_name = Some(ir.name.clone());
    let load_options = load_options(&ir, args.step, Some(&args.time))?;
    check_scan(&ir, &args.scan_delay)?;
    let nominal = match &args.nominal {
        Some(path) => Some(crate::params::read(path, &ir, "--nominal")?),
        None => None,
    };
    let (data, data_notes) = open_data(&ir, &args.data, &load_options)?;
    let sources = data.sources();
    warnings.extend(
        loaded
            .warnings
            .into_iter()
            .map(|w| Warning::plain("model", w)),
    );
    // The three checks of the data in one visit of each experiment.
    let checks = data_checks(&ir, &sources);
    warnings.extend(unit_alerts_from_peaks(&ir, &checks.input_peaks));
    let gains = checks.heading_gains;
    warnings.extend(heading_alerts(&ir, &gains));
    warnings.extend(closed_loop_alerts(&checks.closed_loop));
    let options = args.options(nominal);
    let (result, scans) = if args.scan_delay.is_empty() {
        (
            estimate(&Interpreter::new(ir.clone()), &sources, &options),
            Vec::new(),
        )
    } else {
        match scan_delays(&ir, &sources, &options, &args.scan_delay, args.scan_by) {
            Ok(scans) => {
                // Never empty (one scan a range); the plain estimate otherwise.
                let result = match scans.last() {
                    Some(last) => Ok(last.estimate.clone()),
                    None => estimate(&Interpreter::new(ir.clone()), &sources, &options),
                };
                (result, scans)
            }
            Err(e) => (Err(e), Vec::new()),
        }
    };
    // A file that changed between passes voids whatever was computed.
    if let Some(p) = data.failure() {
        return Err(Failure::from(p));
    }
    let est = result.map_err(|e| Failure::from(Problem::estimate(&located(e, &data))))?;
    warnings.extend(est.warning_summaries.iter().cloned());
    Ok(Outcome {
        model: ir.name.clone(),
        experiments: sources
            .iter()
            .map(|e| (e.name().to_string(), e.len()))
            .collect(),
        heading_gains: gains,
        estimate: est,
        data_notes,
        units: crate::units::unit_lines(&ir),
        data_units: ir.data_units.clone(),
        scans,
    })
}

/// A `--scan-delay` range checked before any work where the model decides
/// its grid (samples, or seconds with a declared `step`); one in seconds on
/// a model without `step` is checked against the data's sample time.
fn check_scan(ir: &leeway_structure::ir::Ir, ranges: &[DelayRange]) -> Result<(), Failure> {
    let mut seen: Vec<&str> = Vec::new();
    for range in ranges {
        if seen.contains(&range.input.as_str()) {
            return Err(Failure::from(
                Problem::error(
                    "invalid-option",
                    format!("--scan-delay: `{}` is scanned twice", range.input),
                )
                .help("scan each input once"),
            ));
        }
        seen.push(&range.input);
        check_one_scan(ir, range)?;
    }
    Ok(())
}

/// One `--scan-delay` range checked (see [`check_scan`]).
fn check_one_scan(ir: &leeway_structure::ir::Ir, range: &DelayRange) -> Result<(), Failure> {
    let seconds = matches!(range.lo, Bound::Seconds(_)) || matches!(range.hi, Bound::Seconds(_));
    let Some(h) = ir.step.or((!seconds).then_some(1.0)) else {
        return Ok(());
    };
    range.candidates(ir, h).map(|_| ()).map_err(|m| {
        Failure::from(
            Problem::error("invalid-option", format!("--scan-delay: {m}"))
                .help("scan an input of the model over at most 200 dead times, e.g. --scan-delay tau=0..20 or tau=0..2s"),
        )
    })
}

/// Under `--strict`, the failure of a run whose warnings can bias the
/// estimate (sign violations, parameters held for lack of excitation, unit
/// mistakes, an estimate that does not reproduce its data).
fn biasing_failure(warnings: &[Warning]) -> Option<Failure> {
    let biasing: Vec<&Warning> = warnings.iter().filter(|w| w.can_bias).collect();
    let first = biasing.first()?;
    let more = match biasing.len() {
        1 => String::new(),
        n => format!(" (and {} more)", n - 1),
    };
    let mut p = Problem::error(
        "biasing-warning",
        format!(
            "--strict: a warning can bias the estimate: {}{more}",
            first.summary
        ),
    )
    .help("see the warnings above for what to do, or drop --strict to estimate anyway");
    p.status = Status::Unsupported;
    Some(Failure::from(p))
}

/// An estimator's error with the data's places: `too-few-samples` names every
/// experiment with its file and sample count.
fn located(
    mut e: leeway_estimate::EstimateError,
    data: &DataSet,
) -> leeway_estimate::EstimateError {
    if e.code == "too-few-samples" {
        let list: Vec<String> = data
            .sources()
            .iter()
            .zip(data.files())
            .map(|(s, f)| format!("`{}` in {f}: {} samples", s.name(), s.len()))
            .collect();
        e.message = format!("{} (experiments: {})", e.message, list.join("; "));
    }
    e
}
