//! The estimators of the paper: `ls`, `iv1`, `iv2`, `iv3`.
//!
//! Each experiment is visited in order; per pass the regressors `Φ(k−1)`
//! (from data), the instruments `Z(k−1)` and the target (`(y(k) − y(k−1))/h`
//! for `der`, `y(k)` for `next`) feed shifted moment sums per output, so
//! memory is `O(n_ϑ²)` whatever N. Columns split into blocks of outputs that
//! share no parameter (usually one block per output), each solved on its own.
//!
//! Instruments (paper §V-B, SPEC §5): the nominal model is simulated with the
//! known input; its noise-free regressors are the instruments, centred per
//! experiment (default), pooled, or not. Rotation entries come from a heading
//! anchored to the previous measurement, `ψ_z(k) = y_ψ(k−1) + h·r_sim(k−1)`
//! (with a measured `R`: the measurement one sample earlier); measured
//! disturbances enter as their experiment mean. The estimate is refined by
//! re-simulating with it (Young's refined IV) until it settles. Equations
//! start at k = 2 so no instrument uses a same-sample measurement.

use crate::moments::{CrossMoments, LongRun, MomentAccumulator};
use leeway_model::experiment::Source;
use leeway_model::model::{HeadingRotation, Model, Signals, planar_rotation, rotated};
use leeway_model::signs::{ExperimentSigns, SignCounter, plain_sign_args, set_pointwise_signs};
use leeway_structure::exact::Q;
use leeway_structure::grammar::EquationKind;
pub use leeway_structure::identify::Centring;
use leeway_structure::identify::{
    Analysis, ExperimentStructure, Patterns, constant_parameters, linear_text, patterns_text,
    verdict,
};
use leeway_structure::ir::{ColumnKind, Ir, PredictorKind, Rotation};
use nalgebra::{DMatrix, DVector};

use std::collections::BTreeMap;

mod accumulate;
mod cache;
mod covariance;
mod disturbances;
pub mod moments;
mod options;
mod outcome;
mod own;
mod pass;
mod plan;
mod record;
mod refine;
mod report;
mod solve;
mod walk;

use accumulate::*;
pub use options::*;
pub use outcome::*;
use pass::*;
pub use pass::{
    ExperimentFacts, FactsRequest, LocalPasses, PassRequest, PassRunner, PassSummary, Passes,
    PrefixRows, decode, encode,
};
pub use plan::{PlanKey, StructuralPlan};
use record::*;
use solve::*;
pub use walk::REGRESSOR_LIMIT;
use walk::*;

#[derive(Clone, Debug)]
struct Block {
    outputs: Vec<usize>,
    /// Structurally kept predictor columns of the block, in column order.
    cols: Vec<usize>,
}

/// The estimator for one model, method and set of experiments.
struct Estimator<'a> {
    ir: &'a Ir,
    options: &'a EstimateOptions,
    kind: PredictorKind,
    /// The centring used (the option, or the model's default).
    centring: Centring,
    /// Constant θ columns (`X_0`): under pooled centring their instrument,
    /// the constant, is not centred.
    constant_cols: Vec<bool>,
    n_cols: usize,
    blocks: Vec<Block>,
    block_of_output: Vec<usize>,
    /// Structurally dropped θ held at nominal (aggregation).
    held: Vec<(usize, f64)>,
    /// Preference rank of each column (lower = kept first).
    preference: Vec<usize>,
    nominal: Vec<f64>,
    infos: Vec<ExperimentInfo>,
    /// What each kept column estimates, as (column, coefficient) in predictor columns.
    meaning: BTreeMap<usize, Vec<(usize, f64)>>,
    /// What each predictor column estimates, as the report states it.
    column_texts: std::sync::Arc<[String]>,
    warnings: Vec<String>,
    unexcited: Vec<String>,
    aggregates: Vec<String>,
    /// Runs the passes over the data (here, or on workers).
    passes: &'a dyn Passes,
    /// Every experiment's name and length, in order.
    facts: Vec<ExperimentFacts>,
}

/// The largest nominal value accepted: with a regressor within
/// [`REGRESSOR_LIMIT`] their product stays far inside `f64`'s range, so a
/// first simulation cannot overflow from θ alone.
pub const NOMINAL_LIMIT: f64 = 1e145;

/// Every nominal value finite and within ±[`NOMINAL_LIMIT`], the first one
/// that is not named (`given`: from the options, else the model's
/// `nominal { }`): such a θ only overflows the instrument simulation.
fn check_nominal(ir: &Ir, nominal: &[f64], given: bool) -> Result<(), EstimateError> {
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

/// The error `interrupted` when the options' interrupt asks to stop.
fn stop_if_interrupted(options: &EstimateOptions) -> Result<(), EstimateError> {
    match &options.interrupt {
        Some(i) if i.requested() => Err(err(
            "interrupted",
            "the estimate was interrupted",
            "run it again to the end for a result",
        )),
        _ => Ok(()),
    }
}

impl Estimator<'_> {
    /// One pass over the data, the interrupt asked before and after it.
    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        stop_if_interrupted(self.options)?;
        let summaries = self.passes.pass(request)?;
        stop_if_interrupted(self.options)?;
        Ok(summaries)
    }
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
/// implementation that computes each summary as [`PassRunner`] does gives
/// the same bits as [`estimate`], wherever it runs.
pub fn estimate_with(
    model: &dyn Model,
    passes: &dyn Passes,
    options: &EstimateOptions,
) -> Result<Estimate, EstimateError> {
    let ir = model.ir();
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
        for a in &s.arguments {
            if a.minority_fraction > 0.0 {
                let msg = format!(
                    "experiment `{}`: {} has sign {} in {:.1}% of the samples and the other sign in {:.2}% (paper A7 requires one sign per experiment)",
                    s.experiment,
                    a.argument,
                    if a.sign > 0 { "+" } else { "-" },
                    100.0 * (1.0 - a.minority_fraction),
                    100.0 * a.minority_fraction
                );
                if options.strict {
                    return Err(err(
                        "sign-violation",
                        msg,
                        "run experiments with a static offset large enough that the argument keeps its sign, or drop --strict to estimate anyway",
                    ));
                }
                warnings.push(msg);
            }
        }
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
        if !crossing.is_empty() {
            notes.push(format!(
                "experiment `{}`: {} cross zero; their moduli are evaluated pointwise, as the simulation does (within the noise of zero, measurement noise biases |x| slightly upwards)",
                s.experiment,
                crossing.join(", ")
            ));
        }
        infos.push(info);
        sign_patterns.push(s);
    }
    for (f, info) in facts.iter().zip(&infos) {
        if info.frozen.is_some() {
            warnings.push(format!(
                "experiment `{}`: the heading barely varied (circular std {:.3} rad): R is treated as constant there (paper Remark 2)",
                f.name,
                info.spread.max(0.0)
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
    estimate.notes = notes;
    Ok(estimate)
}
