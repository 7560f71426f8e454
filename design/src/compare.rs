//! An input of the engineer's own (`design --compare IN.csv`), judged like
//! the design: its held signs along the nominal run from every starting
//! heading, and its standard errors from the same pilot trials, set beside
//! the design's per sample (`σ·√N`, so runs of different lengths compare).

use crate::predict::{Prediction, Setting, calibrate, predict};
use crate::report::{ArgumentMargin, Design, argument_margins};

use crate::trial::Run;
use leeway_estimate::EstimateOptions;
use leeway_model::model::Model;
use serde::Serialize;

/// The design beside a given input.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// Samples per experiment of the given input.
    pub samples: usize,
    /// Its held arguments' smallest nominal margins (on the side each
    /// mostly takes).
    pub held: Vec<ArgumentMargin>,
    /// Per θ.
    pub parameters: Vec<ParameterComparison>,
    /// The design's score and the input's (mean `ln(σ/|θ|)` per sample;
    /// lower is better).
    pub scores: (f64, f64),
    /// Why the given input could not be estimated, if it could not.
    pub failure: Option<String>,
}

/// One θ: standard errors per sample of the design and the given input.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterComparison {
    /// Its name.
    pub name: String,
    /// The design's `σ·√N`.
    pub design: Option<f64>,
    /// The given input's `σ·√N`.
    pub given: Option<f64>,
    /// `given / design` (above 1: the design is more accurate per sample).
    pub ratio: Option<f64>,
}

/// Judges `runs` (one per experiment, as read from the files) under the
/// design's conditions and estimator.
pub fn compare(
    model: &dyn Model,
    design: &Design,
    runs: &[Run],
    seed: u64,
    pilot: usize,
) -> Option<Comparison> {
    let c = design.conditions.as_ref()?;
    let noise = design.noise_used.as_ref()?;
    let ir = model.ir();
    let kind = design.method_used?.predictor();
    let unfixed = vec![1i8; ir.sign_args.len()];
    let held_margins: Vec<ArgumentMargin> = runs
        .iter()
        .enumerate()
        .flat_map(|(e, run)| argument_margins(model, c, kind, run, (&unfixed, &[]), e))
        .collect();
    let options = EstimateOptions {
        method: design.method_used?,
        centring: design.centring_used,
        aggregate: design.aggregate,
        ..Default::default()
    };
    let setting = Setting {
        conditions: c,
        runs,
        noise,
        options: &options,
    };
    let samples = runs.first().map_or(0, |r| r.inputs.len());
    let (given, failure) = match predict(model, setting, seed) {
        Ok(mut p) => {
            calibrate(model, setting, seed, pilot, &mut p);
            (Some(p), None)
        }
        Err(e) => (None, Some(e)),
    };
    let mine = design.predicted.as_ref()?;
    let per_sample = |p: &Prediction| -> Vec<Option<f64>> {
        let root = (p.samples as f64).sqrt();
        p.std_errors.iter().map(|s| s.map(|s| s * root)).collect()
    };
    let d = per_sample(mine);
    let g = given.as_ref().map_or(vec![None; d.len()], per_sample);
    let parameters = mine
        .parameters
        .iter()
        .zip(d.iter().zip(&g))
        .map(|(name, (d, g))| ParameterComparison {
            name: name.clone(),
            design: *d,
            given: *g,
            ratio: match (d, g) {
                (Some(d), Some(g)) if *d > 0.0 => Some(g / d),
                _ => None,
            },
        })
        .collect();
    let score = |p: &Prediction| p.score() + 0.5 * (p.samples as f64).ln();
    Some(Comparison {
        samples,
        held: held_margins,
        parameters,
        scores: (score(mine), given.as_ref().map_or(f64::INFINITY, score)),
        failure,
    })
}
