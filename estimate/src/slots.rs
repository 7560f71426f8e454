//! The slots of the regressor buffers a pass reads, and the model's
//! evaluators of just those ([`Model::regressor_slots`]). A pass reads a
//! predictor's estimated columns (and the measured regressors' held ones,
//! which move the target); the interpreter's plans of those slots alone
//! skip the rest of the buffer — the structurally nonzero columns no
//! block estimates — with the same bits in the slots read.

use crate::protocol::PassPlan;
use leeway_model::model::{Model, SlotRegressors};
use leeway_structure::ir::PredictorKind;
use std::sync::{Arc, Mutex};

/// An evaluator, with the predictor and the slots it evaluates.
type SlotPlan = (PredictorKind, Vec<bool>, Arc<dyn SlotRegressors>);

/// One evaluator per predictor and set of slots, made on first use.
#[derive(Default)]
pub(super) struct SlotPlans(Mutex<Vec<SlotPlan>>);

impl SlotPlans {
    /// `model`'s evaluator of the `wanted` slots of `kind` (`None` where it
    /// has none: it evaluates every slot).
    pub(super) fn get(
        &self,
        model: &dyn Model,
        kind: PredictorKind,
        wanted: Vec<bool>,
    ) -> Option<Arc<dyn SlotRegressors>> {
        // A poisoned lock only means another pass panicked: evaluate every slot.
        let mut plans = self.0.lock().ok()?;
        if let Some((_, _, s)) = plans.iter().find(|(k, w, _)| *k == kind && *w == wanted) {
            return Some(Arc::clone(s));
        }
        let made: Arc<dyn SlotRegressors> = Arc::from(model.regressor_slots(kind, &wanted)?);
        plans.push((kind, wanted, Arc::clone(&made)));
        Some(made)
    }
}

/// The slots (`n_out × n_cols`) a pass with `plan` reads: each output's
/// estimated columns, and (`measured`) the held ones.
pub(super) fn read_slots(plan: &PassPlan, n_out: usize, measured: bool) -> Vec<bool> {
    let n = plan.n_cols;
    let mut wanted = vec![false; n_out * n];
    for (o, cols) in plan.cols.iter().enumerate().take(n_out) {
        for &c in cols {
            if let Some(w) = wanted.get_mut(o * n + c) {
                *w = true;
            }
        }
    }
    if measured {
        for &(c, _) in &plan.held {
            for o in 0..n_out {
                if let Some(w) = wanted.get_mut(o * n + c) {
                    *w = true;
                }
            }
        }
    }
    wanted
}
