//! The estimator for one model, method and set of experiments: what every phase shares.

use crate::method::Combine;
use crate::options::EstimateOptions;
use crate::outcome::{EstimateError, err};
use crate::plan::Block;
use crate::plan::{MIN_EQUATIONS_PER_COLUMN, PlanKey, StructuralPlan};
use crate::protocol::{ExperimentFacts, PassRequest, PassSummary, Passes};
use crate::record::ExperimentInfo;
use leeway_model::model::Model;
use leeway_model::signs::ExperimentSigns;
use leeway_model::warning::Warning;
use leeway_structure::exact::Q;
use leeway_structure::identify::Centring;
use leeway_structure::identify::ExperimentStructure;
use leeway_structure::ir::{Ir, PredictorKind};
use std::collections::BTreeMap;

/// The estimator for one model, method and set of experiments.
pub(crate) struct Estimator<'a> {
    pub(crate) ir: &'a Ir,
    pub(crate) options: &'a EstimateOptions,
    pub(crate) kind: PredictorKind,
    /// The centring used (the option, or the model's default).
    pub(crate) centring: Centring,
    /// Constant θ columns (`X_0`): under pooled centring their instrument,
    /// the constant, is not centred.
    pub(crate) constant_cols: Vec<bool>,
    pub(crate) n_cols: usize,
    pub(crate) blocks: Vec<Block>,
    pub(crate) block_of_output: Vec<usize>,
    /// Structurally dropped θ held at nominal (aggregation).
    pub(crate) held: Vec<(usize, f64)>,
    /// Preference rank of each column (lower = kept first).
    pub(crate) preference: Vec<usize>,
    pub(crate) nominal: Vec<f64>,
    pub(crate) infos: Vec<ExperimentInfo>,
    /// What each kept column estimates, as (column, coefficient) in predictor columns.
    pub(crate) meaning: BTreeMap<usize, Vec<(usize, f64)>>,
    /// What each predictor column estimates, as the report states it.
    pub(crate) column_texts: std::sync::Arc<[String]>,
    pub(crate) warnings: Vec<Warning>,
    pub(crate) unexcited: Vec<String>,
    pub(crate) aggregates: Vec<String>,
    /// Runs the passes over the data (here, or on workers).
    pub(crate) passes: &'a dyn Passes,
    /// Every experiment's name and length, in order.
    pub(crate) facts: Vec<ExperimentFacts>,
}

impl Estimator<'_> {
    /// One pass over the data, the interrupt asked before and after it.
    pub(crate) fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        stop_if_interrupted(self.options)?;
        let summaries = self.passes.pass(request)?;
        stop_if_interrupted(self.options)?;
        Ok(summaries)
    }
}

impl<'a> Estimator<'a> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        model: &'a dyn Model,
        options: &'a EstimateOptions,
        kind: PredictorKind,
        nominal: Vec<f64>,
        infos: Vec<ExperimentInfo>,
        signs: &[ExperimentSigns],
        warnings: Vec<Warning>,
        passes: &'a dyn Passes,
        facts: Vec<ExperimentFacts>,
    ) -> Result<Estimator<'a>, EstimateError> {
        let ir = model.ir();
        let centring = options
            .centring
            .unwrap_or_else(|| Centring::for_model(ir, kind));
        let n_cols = ir.predictors.get(kind).len();
        let exps: Vec<ExperimentStructure> = signs
            .iter()
            .zip(&infos)
            .map(|(s, info)| ExperimentStructure {
                varying: s
                    .pointwise
                    .iter()
                    .filter(|a| a.minority_fraction > 0.0)
                    .filter_map(|a| ir.sign_args.iter().position(|x| x.name == a.argument))
                    .collect(),
                pattern: s.pattern.clone(),
                frozen_rotation: info.frozen.as_ref().map(|v| {
                    v.iter()
                        .map(|x| Q::from_float(*x).unwrap_or_default())
                        .collect()
                }),
            })
            .collect();
        let key = PlanKey {
            kind,
            centring,
            aggregate: options.aggregate,
            nominal: nominal.iter().map(|v| v.to_bits()).collect(),
            experiments: exps,
        };
        let plan = match passes.known_plan(&key) {
            Some(plan) => plan,
            None => {
                let plan = std::sync::Arc::new(StructuralPlan::new(
                    ir, options, kind, centring, &nominal, &infos, signs, &key,
                )?);
                passes.keep_plan(key, plan.clone());
                plan
            }
        };
        let StructuralPlan {
            constant_cols,
            blocks,
            block_of_output,
            held,
            preference,
            meaning,
            column_texts,
            aggregates,
        } = (*plan).clone();
        Ok(Estimator {
            ir,
            options,
            kind,
            centring,
            constant_cols,
            n_cols,
            blocks,
            block_of_output,
            held,
            preference,
            nominal,
            infos,
            meaning,
            column_texts,
            warnings,
            unexcited: Vec::new(),
            aggregates,
            passes,
            facts,
        })
    }

    pub(super) fn combine(&self) -> Combine {
        self.options.combine
    }

    /// Refuses records too short for the number of columns estimated together.
    pub(super) fn check_length(&self) -> Result<(), EstimateError> {
        let equations: usize = self.facts.iter().map(|f| f.len.saturating_sub(2)).sum();
        if let Some(block) = self.blocks.iter().max_by_key(|b| b.cols.len()) {
            let needed = MIN_EQUATIONS_PER_COLUMN * block.cols.len();
            if equations < needed {
                let outputs: Vec<&str> = block
                    .outputs
                    .iter()
                    .map(|o| self.ir.states[*o].as_str())
                    .collect();
                return Err(err(
                    "too-few-samples",
                    format!(
                        "{equations} equations for {} columns estimated together (outputs {}): at least {needed} are needed",
                        block.cols.len(),
                        outputs.join(", ")
                    ),
                    "record longer experiments (hundreds of samples per parameter give useful standard errors)",
                ));
            }
        }
        Ok(())
    }
}

/// The error `interrupted` when the options' interrupt asks to stop.
pub(crate) fn stop_if_interrupted(options: &EstimateOptions) -> Result<(), EstimateError> {
    match &options.interrupt {
        Some(i) if i.requested() => Err(err(
            "interrupted",
            "the estimate was interrupted",
            "run it again to the end for a result",
        )),
        _ => Ok(()),
    }
}
