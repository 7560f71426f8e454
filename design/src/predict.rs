//! Predicted accuracy: the estimator's own asymptotic covariance evaluated
//! on a realisation of the design (the plan's disturbances and noise,
//! seeded) — which scores the excitation families — then calibrated on the
//! chosen design by pilot trials ([`calibrate`]); scaled with run length
//! as `1/√N`.

use crate::plan::Conditions;
use crate::trial::{Run, draw_theta, simulate, true_system};
use leeway_estimate::{EstimateOptions, estimate};
use leeway_model::experiment::Experiment;
use leeway_model::experiment::Source;
use leeway_model::model::Model;
use leeway_scenarios::engine::{campaign, keyed_seed};
use leeway_scenarios::synth::TrueSystem;

/// Standard errors at one run length, and how to scale them.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Prediction {
    /// Samples per experiment the covariance was evaluated at.
    pub samples: usize,
    /// θ's names.
    pub parameters: Vec<String>,
    /// θ designed for.
    pub theta: Vec<f64>,
    /// θ's predicted standard errors at `samples` (`None`: held or not
    /// determined): half the 95th percentile of |error| over the pilot
    /// trials when they ran, else the estimator's asymptotic ones.
    pub std_errors: Vec<Option<f64>>,
    /// The estimator's own asymptotic standard errors on one realisation.
    pub asymptotic: Vec<Option<f64>>,
    /// Pilot trials behind `std_errors` (0: asymptotic only).
    pub trials: usize,
    /// Each unmeasured disturbance component: the plan's mean and the
    /// predicted standard error of its estimate.
    pub disturbances: Vec<(String, f64, Option<f64>)>,
    /// Nuisance columns' estimates and standard errors.
    pub nuisance: Vec<(String, Option<f64>, Option<f64>)>,
    /// Columns the realisation did not excite (the estimator's verdict).
    pub unexcited: Vec<String>,
    /// Whether the estimate held unexcited θ at nominal (`--aggregate`).
    pub aggregated: bool,
}

impl Prediction {
    /// θ's standard errors at `n` samples per experiment.
    pub fn at(&self, n: usize) -> Vec<Option<f64>> {
        let f = (self.samples as f64 / n.max(1) as f64).sqrt();
        self.std_errors.iter().map(|s| s.map(|s| s * f)).collect()
    }

    /// `σ/|θ|` at `samples` (`None` where θ is 0 or σ unknown).
    pub fn relative(&self) -> Vec<Option<f64>> {
        self.std_errors
            .iter()
            .zip(&self.theta)
            .map(|(s, t)| s.filter(|_| *t != 0.0).map(|s| s / t.abs()))
            .collect()
    }

    /// The shortest run (samples per experiment) at which every θ with a
    /// nominal value is known to `target` relative standard error: `None`
    /// when no θ has one; `Some(None)` when it is more than
    /// [`crate::bounds::SAMPLES`] allows (beyond what leeway plans).
    pub fn samples_for(&self, target: f64) -> Option<Option<usize>> {
        let worst = self.relative().into_iter().flatten().fold(0.0, f64::max);
        (worst > 0.0 && target > 0.0).then(|| {
            crate::bounds::needed(self.samples as f64 * (worst / target) * (worst / target))
        })
    }

    /// The largest `σ/|θ|` and its parameter.
    pub fn worst(&self) -> Option<(f64, String)> {
        self.relative()
            .into_iter()
            .zip(&self.parameters)
            .filter_map(|(r, name)| r.map(|r| (r, name.clone())))
            .max_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// θ with a nominal value the realisation left without a standard
    /// error (held at nominal: not excited apart from others).
    pub fn undetermined(&self) -> Vec<String> {
        self.parameters
            .iter()
            .zip(&self.std_errors)
            .zip(&self.theta)
            .filter(|((_, s), t)| **t != 0.0 && s.is_none())
            .map(|((name, _), _)| name.clone())
            .collect()
    }

    /// The design score: the mean of `ln(σ/|θ|)` over θ with a nominal
    /// value (information per parameter, unit-free); `+∞` when a parameter
    /// went undetermined.
    pub fn score(&self) -> f64 {
        let rel: Vec<f64> = self.relative().into_iter().flatten().collect();
        if rel.is_empty() || (!self.aggregated && !self.undetermined().is_empty()) {
            return f64::INFINITY;
        }
        rel.iter().map(|r| r.ln()).sum::<f64>() / rel.len() as f64
    }
}

/// The noises of a prediction: per state, and the heading's.
#[derive(Clone, Debug, PartialEq)]
pub struct Noise {
    /// Per state.
    pub states: Vec<f64>,
    /// Heading, rad.
    pub heading: f64,
}

/// A design's runs in the plan's conditions, and how they are estimated.
#[derive(Clone, Copy)]
pub struct Setting<'a> {
    /// The conditions.
    pub conditions: &'a Conditions,
    /// The runs.
    pub runs: &'a [Run],
    /// The measurement noise.
    pub noise: &'a Noise,
    /// The estimate's options.
    pub options: &'a EstimateOptions,
}

/// Realises the runs (the plan's random disturbances and noise, seed
/// `seed`) and estimates with the options and its covariance.
pub fn predict(model: &dyn Model, setting: Setting, seed: u64) -> Result<Prediction, String> {
    let Setting {
        conditions: c,
        runs,
        noise,
        options,
    } = setting;
    let system = true_system(c, &noise.states, noise.heading, true);
    let experiments = realise(model, &system, runs, keyed_seed(seed, "predict", 0));
    let sources: Vec<&dyn Source> = experiments.iter().map(|e| e as &dyn Source).collect();
    let options = EstimateOptions {
        covariance: true,
        own_simulation: false,
        ..options.clone()
    };
    let est = estimate(model, &sources, &options).map_err(|e| failure(e.code, &e.message))?;
    Ok(Prediction {
        samples: runs.first().map_or(0, |r| r.inputs.len()),
        parameters: est.parameters.clone(),
        theta: c.theta.clone(),
        std_errors: est.std_errors.clone(),
        asymptotic: est.std_errors.clone(),
        trials: 0,
        disturbances: est
            .disturbances
            .iter()
            .map(|d| {
                let name = format!("{}.{}", d.disturbance, d.component);
                (
                    name,
                    plan_mean(model, c, &d.disturbance, &d.component),
                    d.std_error,
                )
            })
            .collect(),
        nuisance: est
            .columns
            .iter()
            .filter(|col| col.kind != "theta")
            .map(|col| (col.name.clone(), col.value, col.std_error))
            .collect(),
        unexcited: est.diagnostics.unexcited.clone(),
        aggregated: options.aggregate,
    })
}

/// The runs realised on `system`, run `e` from `keyed_seed(seed,
/// "experiment", e)` and heading 0: what a trial's logger records.
pub fn realise(model: &dyn Model, system: &TrueSystem, runs: &[Run], seed: u64) -> Vec<Experiment> {
    runs.iter()
        .enumerate()
        .map(|(e, run)| {
            let name = format!("run{}", e + 1);
            simulate(
                model,
                system,
                run,
                &name,
                0.0,
                keyed_seed(seed, "experiment", e),
            )
            .0
        })
        .collect()
}

/// The plan's mean of a component named by medium and component.
fn plan_mean(model: &dyn Model, c: &Conditions, medium: &str, component: &str) -> f64 {
    let ir = model.ir();
    ir.components
        .iter()
        .position(|comp| comp.name == component && ir.disturbances[comp.disturbance].name == medium)
        .map_or(f64::NAN, |i| c.mean[i])
}

/// Replaces the asymptotic standard errors by the spread of the errors of
/// `trials` pilot realisations (`interval_sigma`) of the design (seeded, on the study
/// engine): the estimator's own covariance can be off by a factor when the
/// residuals are correlated beyond its lags or dominated by measurement
/// noise, and a design is judged by the spread the trial will see. Keeps
/// the asymptotic ones when fewer than half the trials estimate.
pub fn calibrate(
    model: &dyn Model,
    setting: Setting,
    seed: u64,
    trials: usize,
    prediction: &mut Prediction,
) {
    let Setting {
        conditions: c,
        runs,
        noise,
        options,
    } = setting;
    let system = true_system(c, &noise.states, noise.heading, true);
    let options = EstimateOptions {
        covariance: false,
        own_simulation: false,
        ..options.clone()
    };
    // Each trial's θ drawn from the plan's prior (the nominal when it is
    // 0): its error is taken against its own truth.
    let outcomes: Vec<Option<(Vec<f64>, Vec<f64>)>> = campaign(trials, &|| (), &|t| {
        let trial = keyed_seed(seed, "pilot", t);
        let truth = draw_theta(c, keyed_seed(trial, "theta", 0));
        let system = TrueSystem {
            theta: truth.clone(),
            ..system.clone()
        };
        let experiments = realise(model, &system, runs, trial);
        let sources: Vec<&dyn Source> = experiments.iter().map(|e| e as &dyn Source).collect();
        let est = estimate(model, &sources, &options).ok()?;
        let errors = est.theta.iter().zip(&truth).map(|(e, t)| e - t).collect();
        Some((errors, est.disturbances.iter().map(|d| d.mean).collect()))
    });
    let ok: Vec<&(Vec<f64>, Vec<f64>)> = outcomes.iter().flatten().collect();
    if ok.len() * 2 < trials.max(1) {
        return;
    }
    let rms = |errors: &mut dyn Iterator<Item = f64>| interval_sigma(errors.collect());
    prediction.std_errors = (0..prediction.theta.len())
        .map(|p| {
            prediction.asymptotic[p]?;
            Some(rms(&mut ok.iter().map(|(errors, _)| errors[p])))
        })
        .collect();
    for (i, d) in prediction.disturbances.iter_mut().enumerate() {
        let mean = d.1;
        d.2 = Some(rms(&mut ok
            .iter()
            .filter_map(|(_, m)| m.get(i))
            .map(|m| m - mean)));
    }
    prediction.trials = ok.len();
}

/// Half the 95th percentile of |error| (linearly interpolated): the σ
/// whose ±2σ interval covers 95 % of the pilot's errors whatever the
/// shape of their distribution. A Gaussian spread gives its standard
/// deviation (1.96/2 of it); a heavy tail (a refinement that did not
/// settle) widens it, where a root-mean-square of the bulk would leave the
/// interval covering less than it says.
fn interval_sigma(errors: Vec<f64>) -> f64 {
    let mut abs: Vec<f64> = errors.iter().map(|e| e.abs()).collect();
    if abs.is_empty() {
        return f64::NAN;
    }
    abs.sort_by(f64::total_cmp);
    let at = COVERED * (abs.len() - 1) as f64;
    let (lo, frac) = (at.floor() as usize, at - at.floor());
    let hi = (lo + 1).min(abs.len() - 1);
    0.5 * (abs[lo] + frac * (abs[hi] - abs[lo]))
}

/// The share of the pilot's errors a ±2σ interval covers.
const COVERED: f64 = 0.95;

/// An estimate's failure in a line: its code and, for a rank deficiency,
/// the parameters not separately excited (not the combinations).
fn failure(code: &str, message: &str) -> String {
    let names: Vec<&str> = message
        .split("; ")
        .flat_map(|part| part.split(": "))
        .filter_map(|part| part.strip_suffix(" is not separately excited"))
        .map(|name| name.rsplit(' ').next().unwrap_or(name))
        .collect();
    if names.is_empty() {
        format!("{code}: {}", message.split(": ").next().unwrap_or(message))
    } else {
        format!(
            "{code}: {} not separately excited by these runs (a condition on the data, not the structure)",
            names.join(", ")
        )
    }
}
