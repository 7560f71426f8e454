//! The entry points: [`estimate`] on data at hand, [`estimate_with`] on passes run anywhere.

use crate::checked_facts::{ReadFacts, read_facts};
use crate::estimator::Estimator;
use crate::estimator::stop_if_interrupted;
use crate::local::LocalPasses;
use crate::method::{Initial, Instruments, Method};
use crate::options::EstimateOptions;
use crate::outcome::{Estimate, EstimateError, err};
use crate::protocol::Passes;
use leeway_model::experiment::Source;
use leeway_model::model::Model;
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
    check_subsample(options)?;
    stop_if_interrupted(options)?;
    let read = read_facts(ir, passes, options)?;
    // A refinement on a subsample, when asked for, begins this one.
    let Some(fraction) = options
        .refine_subsample
        .filter(|_| refines_from_bootstrap(options))
    else {
        return estimate_from(model, passes, options, nominal, read);
    };
    let head = crate::subsample::refine_on_head(model, passes, options, &nominal, fraction)?;
    let mut report = head.report;
    let mut estimate = match head.start {
        Some(start) => {
            let warm = EstimateOptions {
                start: Some(start),
                ..options.clone()
            };
            match estimate_from(model, passes, &warm, nominal.clone(), read.clone()) {
                // Its estimate's simulation diverges on the whole records:
                // begin from the bootstrap, as without a subsample.
                Err(e) if e.code == "nominal-diverges" => {
                    report.used = false;
                    report.why_not = Some(
                        "the simulation of its estimate diverges on the whole records".to_string(),
                    );
                    estimate_from(model, passes, options, nominal, read)?
                }
                other => other?,
            }
        }
        None => estimate_from(model, passes, options, nominal, read)?,
    };
    estimate.diagnostics.subsample = Some(report);
    Ok(estimate)
}

/// The estimate from the facts `read`: the structural analysis, the
/// refinement and the report.
fn estimate_from(
    model: &dyn Model,
    passes: &dyn Passes,
    options: &EstimateOptions,
    nominal: Vec<f64>,
    read: ReadFacts,
) -> Result<Estimate, EstimateError> {
    let mut est = Estimator::new(
        model,
        options,
        options.method.predictor(),
        nominal,
        read.infos,
        &read.sign_patterns,
        read.warnings,
        passes,
        read.facts,
    )?;
    est.check_length()?;
    let mut estimate = est.run(read.sign_patterns)?;
    let mut notes = read.notes;
    notes.extend(same_estimate_note(model.ir(), options.method));
    estimate.notes = notes;
    Ok(estimate)
}

/// The estimate is a refined IV from the delayed bootstrap, the only one a
/// refinement on a subsample can begin (a warm start already begins
/// elsewhere; least squares and delayed instruments do not refine).
fn refines_from_bootstrap(options: &EstimateOptions) -> bool {
    options.method != Method::Ls
        && options.instruments == Instruments::Simulated
        && options.initial == Initial::Delayed
        && options.start.is_none()
        && options.max_refinements > 0
}

/// A subsample's fraction, if any, is in (0, 1].
fn check_subsample(options: &EstimateOptions) -> Result<(), EstimateError> {
    match options.refine_subsample {
        Some(f) if !(f > 0.0 && f <= 1.0) => Err(err(
            "invalid-option",
            format!("the subsample to refine on is {f} of the samples: it must be in (0, 1]"),
            "give a fraction such as 0.1 (the first tenth of every experiment)",
        )),
        _ => Ok(()),
    }
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
