//! The centring policy: which centring a predictor of a model needs by
//! default, and why a centring is valid for it.

use crate::ir::{Centring, Ir, PredictorKind};
use leeway_grammar::and_list;

impl Centring {
    /// The default for a predictor of a model: per experiment when the model
    /// has a disturbance the predictor does not take from data (its mean must
    /// be annihilated), none when it has none (uncentred instruments are then
    /// consistent and keep the between-experiment information).
    pub fn for_model(ir: &Ir, kind: PredictorKind) -> Centring {
        if unmeasured_media(ir, kind).is_empty() {
            Centring::None
        } else {
            Centring::Experiment
        }
    }

    /// Why this centring is valid for the model, one sentence.
    pub fn reason(self, ir: &Ir, kind: PredictorKind) -> String {
        let media = unmeasured_media(ir, kind);
        let list = and_list(&media);
        let (is, its) = if media.len() == 1 {
            ("is", "its mean")
        } else {
            ("are", "their means")
        };
        match (self, media.is_empty()) {
            (Centring::Experiment, false) => format!(
                "the {list} {is} not taken from data by this predictor: zero-mean instruments per experiment annihilate {its} and every constant (paper A9)"
            ),
            (Centring::Experiment, true) => "zero-mean instruments per experiment annihilate every constant within an experiment (and any mean of the process disturbance)".to_string(),
            (Centring::Pooled, false) => format!(
                "valid when the means of the {list} and of the process disturbance are the same in every experiment: pooled centring keeps the between-experiment information"
            ),
            (Centring::Pooled, true) => "valid when the process disturbance has the same mean in every experiment: pooled centring keeps the between-experiment information".to_string(),
            (Centring::None, false) => format!(
                "valid only when the {list} and the process disturbance have zero mean, or their means are modelled (constant terms, nuisance columns)"
            ),
            (Centring::None, true) => "the model has no disturbance this predictor does not take from data, so uncentred instruments are consistent and keep the between-experiment information".to_string(),
        }
    }
}

/// Names of the media a predictor does not evaluate from data.
fn unmeasured_media(ir: &Ir, kind: PredictorKind) -> Vec<String> {
    ir.disturbances
        .iter()
        .filter(|d| !(d.measured && kind == PredictorKind::Measured))
        .map(|d| d.name.clone())
        .collect()
}
