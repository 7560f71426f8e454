//! The entry points: [`estimate`] on data at hand, [`estimate_with`] on passes run anywhere.

use crate::estimator::Estimator;
use crate::estimator::stop_if_interrupted;
use crate::local::LocalPasses;
use crate::method::Method;
use crate::options::EstimateOptions;
use crate::outcome::{Estimate, EstimateError, err};
use crate::protocol::{FactsRequest, Passes};
use leeway_model::experiment::Source;
use leeway_model::model::Model;
use leeway_model::signs::ExperimentSigns;
use leeway_model::warning::Warning;
use leeway_structure::ir::Ir;

/// The largest nominal value accepted: with a regressor within
/// [`REGRESSOR_LIMIT`](crate::walk::REGRESSOR_LIMIT) their product stays far inside `f64`'s range, so a
/// first simulation cannot overflow from θ alone.
pub const NOMINAL_LIMIT: f64 = 1e145;

/// Every nominal value finite and within ±[`NOMINAL_LIMIT`], the first one
/// that is not named (`given`: from the options, else the model's
/// `nominal { }`): such a θ only overflows the instrument simulation.
pub(crate) fn check_nominal(ir: &Ir, nominal: &[f64], given: bool) -> Result<(), EstimateError> {
    let wrong = ir
        .parameters
        .iter()
        .zip(nominal)
        .find(|(_, v)| !v.is_finite() || v.abs() > NOMINAL_LIMIT);
    let Some((p, v)) = wrong else {
        return Ok(());
    };
    let source = if given {
        "the nominal values given (--nominal)"
    } else {
        "the model's `nominal { }` block"
    };
    Err(err(
        "invalid-nominal",
        format!(
            "the nominal value of `{}` is {v:e} in {source}: nominal values must be finite and within ±1e145",
            p.name
        ),
        "give a physically plausible nominal θ (a rough guess of each parameter's size is enough)",
    ))
}

/// Estimates θ (and nuisance parameters) of `model` from the experiments.
pub fn estimate(
    model: &dyn Model,
    experiments: &[&dyn Source],
    options: &EstimateOptions,
) -> Result<Estimate, EstimateError> {
    let passes = LocalPasses::new(model, experiments).interruptible(options.interrupt.clone());
    estimate_with(model, &passes, options)
}

/// Estimates like [`estimate`], with every pass over the data run by
/// `passes`: each pass is mapped over the experiments (their summaries are
/// small and independent of the experiments' lengths), and this driver
/// combines them in experiment order, solves and broadcasts the next θ. An
/// implementation that computes each summary as [`PassRunner`](crate::runner::PassRunner) does gives
/// the same bits as [`estimate`], wherever it runs.
pub fn estimate_with(
    model: &dyn Model,
    passes: &dyn Passes,
    options: &EstimateOptions,
) -> Result<Estimate, EstimateError> {
    let ir = model.ir();
    let nominal = nominal_values(ir, options)?;
    check_start(ir, options)?;
    stop_if_interrupted(options)?;
    let facts = passes.facts(&FactsRequest::new(options))?;
    stop_if_interrupted(options)?;
    if facts.is_empty() {
        return Err(err(
            "no-data",
            "no experiment given",
            "pass at least one --data file",
        ));
    }
    let kind = options.method.predictor();
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    // Sign patterns, measured means, bounds and heading spread, in one visit each.
    let mut sign_patterns = Vec::new();
    let mut infos = Vec::new();
    for f in &facts {
        if let Some(why) = &f.delay_error {
            return Err(err(
                "invalid-delay",
                why.clone(),
                "give the dead time in steps, or in seconds that are a whole number of this record's sample times",
            ));
        }
        let Some((s, info)) = f.read.clone() else {
            return Err(err(
                "too-few-samples",
                format!(
                    "experiment `{}` has {} samples; at least {} are needed",
                    f.name,
                    f.len,
                    leeway_model::experiment::MIN_SAMPLES
                ),
                "record a longer experiment",
            ));
        };
        warnings.extend(sign_violations(&s, options.strict)?);
        notes.extend(crossing_note(ir, &s));
        infos.push(info);
        sign_patterns.push(s);
    }
    for (f, info) in facts.iter().zip(&infos) {
        if info.frozen.is_some() {
            warnings.push(Warning::plain(
                "constant-heading",
                format!(
                    "experiment `{}`: the heading barely varied (circular std {:.3} rad): R is treated as constant there (paper Remark 2)",
                    f.name,
                    info.spread.max(0.0)
                ),
            ));
        }
    }
    let mut est = Estimator::new(
        model,
        options,
        kind,
        nominal,
        infos,
        &sign_patterns,
        warnings,
        passes,
        facts,
    )?;
    est.check_length()?;
    let mut estimate = est.run(sign_patterns)?;
    notes.extend(same_estimate_note(ir, options.method));
    estimate.notes = notes;
    Ok(estimate)
}

/// Said once when other methods must give this very estimate: on a model
/// with no disturbance the basic, augmented and measured predictors have the
/// same columns and the same instruments, so IV1, IV2 and IV3 coincide (LS
/// differs: it has no instruments).
fn same_estimate_note(ir: &Ir, method: Method) -> Option<String> {
    (ir.disturbances.is_empty() && method != Method::Ls).then(|| {
        "iv1, iv2 and iv3 give this same estimate on this model: it has no disturbance, so their predictors and instruments coincide (ls differs: it has no instruments)".to_string()
    })
}

/// The nominal θ: the options' (one value per parameter), else the model's;
/// every value checked ([`check_nominal`]).
fn nominal_values(ir: &Ir, options: &EstimateOptions) -> Result<Vec<f64>, EstimateError> {
    let nominal = match &options.nominal {
        Some(v) if v.len() == ir.parameters.len() => v.clone(),
        Some(v) => {
            return Err(err(
                "invalid-nominal",
                format!(
                    "the nominal model has {} values, the model {} parameters",
                    v.len(),
                    ir.parameters.len()
                ),
                "give one value per parameter",
            ));
        }
        None => ir.parameters.iter().map(|p| p.nominal).collect(),
    };
    check_nominal(ir, &nominal, options.nominal.is_some())?;
    Ok(nominal)
}

/// A warm start, if any, has one value per parameter and disturbance component.
fn check_start(ir: &Ir, options: &EstimateOptions) -> Result<(), EstimateError> {
    if let Some(start) = &options.start
        && (start.theta.len() != ir.parameters.len() || start.means.len() != ir.components.len())
    {
        return Err(err(
            "invalid-start",
            format!(
                "the warm start has {} θ values and {} disturbance means, the model {} parameters and {} disturbance components",
                start.theta.len(),
                start.means.len(),
                ir.parameters.len(),
                ir.components.len()
            ),
            "build the start from an estimate of the same model (Start::from_estimate)",
        ));
    }
    Ok(())
}

/// Minority fraction from which a sign violation can bias the estimate badly
/// (its summary says so).
const LARGE_VIOLATION: f64 = 0.01;

/// The warnings of an experiment whose sign arguments do not keep one sign
/// (paper A7), or (`strict`) the error of the first.
fn sign_violations(s: &ExperimentSigns, strict: bool) -> Result<Vec<Warning>, EstimateError> {
    let mut warnings = Vec::new();
    for a in &s.arguments {
        if a.minority_fraction > 0.0 {
            let how = if a.minority_fraction >= LARGE_VIOLATION {
                "can be badly biased"
            } else {
                "may be slightly biased"
            };
            let summary = format!(
                "experiment `{}`: {} changes sign ({:.1} % of samples, paper A7): terms in |{}| {how}",
                s.experiment,
                a.argument,
                100.0 * a.minority_fraction,
                a.argument
            );
            let help = format!(
                "split the run where {} changes sign, or keep its sign with a steady offset; --strict makes this an error",
                a.argument
            );
            let msg = format!(
                "experiment `{}`: {} has sign {} in {:.1}% of the samples and the other sign in {:.2}% (paper A7 requires one sign per experiment)",
                s.experiment,
                a.argument,
                if a.sign > 0 { "+" } else { "-" },
                100.0 * (1.0 - a.minority_fraction),
                100.0 * a.minority_fraction
            );
            if strict {
                return Err(err(
                    "sign-violation",
                    msg,
                    "split the experiment where the argument changes sign, or run experiments with a static offset large enough that it keeps its sign, or drop --strict to estimate anyway",
                ));
            }
            warnings.push(Warning::new("sign-violation", summary, help, msg).biasing());
        }
    }
    Ok(warnings)
}

/// The note on an experiment's pointwise sign arguments that cross zero, if any.
fn crossing_note(ir: &Ir, s: &ExperimentSigns) -> Option<String> {
    let crossing: Vec<String> = s
        .pointwise
        .iter()
        .zip(&s.crossings)
        .filter(|(a, _)| {
            a.minority_fraction > 0.0
                && ir
                    .sign_args
                    .iter()
                    .any(|x| x.pointwise && x.name == a.argument)
        })
        .map(|(a, n)| {
            format!(
                "{} ({n} sign change{}, {:.1}% of the samples of the minority sign)",
                a.argument,
                if *n == 1 { "" } else { "s" },
                100.0 * a.minority_fraction
            )
        })
        .collect();
    (!crossing.is_empty()).then(|| {
        format!(
            "experiment `{}`: {} cross zero; their moduli are evaluated pointwise, as the simulation does (within the noise of zero, measurement noise biases |x| slightly upwards)",
            s.experiment,
            crossing.join(", ")
        )
    })
}
