//! The facts pass of an estimate, checked: the sign patterns and what the
//! estimator needs of every experiment, and the warnings and notes they give.

use crate::estimator::stop_if_interrupted;
use crate::options::EstimateOptions;
use crate::outcome::{EstimateError, err};
use crate::protocol::{ExperimentFacts, FactsRequest, Passes};
use crate::record::ExperimentInfo;
use leeway_model::signs::ExperimentSigns;
use leeway_model::warning::Warning;
use leeway_structure::ir::Ir;

/// What the facts pass says of every experiment, checked: their sign
/// patterns and what the estimator needs of each, and the warnings and
/// notes they give.
#[derive(Clone)]
pub(crate) struct ReadFacts {
    pub(crate) facts: Vec<ExperimentFacts>,
    pub(crate) infos: Vec<ExperimentInfo>,
    pub(crate) sign_patterns: Vec<ExperimentSigns>,
    pub(crate) warnings: Vec<Warning>,
    pub(crate) notes: Vec<String>,
}

/// The facts pass through `passes`, and what it says checked.
pub(crate) fn read_facts(
    ir: &Ir,
    passes: &dyn Passes,
    options: &EstimateOptions,
) -> Result<ReadFacts, EstimateError> {
    let facts = passes.facts(&FactsRequest::new(options))?;
    stop_if_interrupted(options)?;
    if facts.is_empty() {
        return Err(err(
            "no-data",
            "no experiment given",
            "pass at least one --data file",
        ));
    }
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
    Ok(ReadFacts {
        facts,
        infos,
        sign_patterns,
        warnings,
        notes,
    })
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
