//! The protocol of a pass over the data: what the driver asks of every
//! experiment ([`FactsRequest`], [`PassRequest`]), what each experiment
//! answers ([`ExperimentFacts`], [`PassSummary`]), their exact byte form
//! ([`encode`], [`decode`]: CBOR), and the [`Passes`] trait that runs them.
//!
//! This is the map half of estimation: what one experiment contributes to
//! a pass is a small summary (moment sums, long-run sums, sign facts) that
//! serialises exactly; the estimator runs its passes through [`Passes`] —
//! in experiment order on this machine (`LocalPasses`), or mapped over the
//! workers of a distributed engine — and combines the summaries in
//! experiment order whoever computed them, so local and distributed
//! estimates agree bit for bit. A request says everything a pass computes
//! (a warm start's instruments included), so what a runner keeps only
//! changes how soon it answers.

use crate::method::{Instruments, Method};
use crate::moments::CrossMoments;
use leeway_model::signs::ExperimentSigns;
use leeway_structure::ir::PredictorKind;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::options::EstimateOptions;
use crate::outcome::{EstimateError, err};
use crate::plan::{PlanKey, StructuralPlan};
use crate::record::ExperimentInfo;
/// What the facts pass needs of the options.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FactsRequest {
    pub(crate) method: Method,
    pub(crate) heading_spread: f64,
    /// Read only each experiment's head ([`head_samples`] of this fraction):
    /// the passes of a refinement on a subsample. Left out when `None`, so
    /// the passes of every other estimate exchange the same bytes as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) head: Option<f64>,
}

impl FactsRequest {
    /// The facts pass of an estimate with these options.
    pub fn new(options: &EstimateOptions) -> FactsRequest {
        FactsRequest {
            method: options.method,
            heading_spread: options.heading_spread,
            head: None,
        }
    }
}

/// The samples of a record of `len` samples that a subsample of `fraction`
/// reads: its first `⌈fraction·len⌉`, at least [`MIN_SAMPLES`] (all of
/// them when it has fewer). Every runner computes it from the record it
/// holds, so the driver need not know the records' lengths to ask for it.
///
/// [`MIN_SAMPLES`]: leeway_model::experiment::MIN_SAMPLES
pub fn head_samples(len: usize, fraction: f64) -> usize {
    let wanted = (fraction * len as f64).ceil();
    // A fraction in (0, 1] keeps `wanted` within 0..=len; the clamp makes
    // any other value harmless.
    let wanted = if wanted.is_finite() && wanted > 0.0 {
        (wanted as usize).min(len)
    } else {
        len
    };
    wanted.max(leeway_model::experiment::MIN_SAMPLES.min(len))
}

/// One experiment as read once before estimating: its name and length and,
/// when it is long enough to estimate from, its sign pattern (paper A7),
/// measured disturbance means, state bounds and heading spread.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ExperimentFacts {
    /// The experiment's name.
    pub name: String,
    /// Samples the equations see: the record's, less its dead time.
    pub len: usize,
    pub(super) read: Option<(ExperimentSigns, ExperimentInfo)>,
    /// The samples at the record's start that only supply delayed inputs
    /// (the model's longest dead time; left out at 0, so a model without
    /// dead times exchanges the same bytes as before).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub dead_time: usize,
    /// Why the model's dead times are no whole number of this record's
    /// samples, if they are not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) delay_error: Option<String>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One pass over the data as the driver asks it of every experiment: the
/// estimator's plan, the θ to simulate the instruments with, and what each
/// experiment's facts fixed (its signs, means, bounds).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassRequest {
    pub(super) plan: PassPlan,
    pub(super) pass: Pass,
    pub(super) infos: Vec<ExperimentInfo>,
    /// Each experiment's head only, as [`FactsRequest::head`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) head: Option<f64>,
}

/// What a data pass needs of the estimator's plan.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct PassPlan {
    pub(super) kind: PredictorKind,
    /// The instruments of the method (`None`: least squares).
    pub(super) instruments: Option<Instruments>,
    pub(super) delayed_mean: bool,
    pub(super) n_cols: usize,
    /// The block columns of each output.
    pub(super) cols: Vec<Vec<usize>>,
    /// Structurally dropped columns held at nominal.
    pub(super) held: Vec<(usize, f64)>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) enum Pass {
    /// Moment sums per output, the instruments simulated with `theta_sim`
    /// (empty: the delayed bootstrap), compared with a `reference`
    /// simulation; `scan` also looks for non-finite measured values.
    Moments {
        theta_sim: Vec<f64>,
        mu: Vec<f64>,
        reference: Option<(Vec<f64>, Vec<f64>)>,
        scan: bool,
        /// Per experiment (empty: none), the warm start's instruments: the
        /// measured means they take, and the samples they settled on.
        prefix: Vec<Option<PrefixInstruments>>,
    },
    /// Long-run sums of the moment residuals `ζ` (the covariance).
    LongRun(LongRunPass),
    /// The reported θ simulated on the data (unmeasured disturbances at
    /// `means`), fitted: the estimate's own simulation.
    FreeRun { theta: Vec<f64>, means: Vec<f64> },
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct LongRunPass {
    pub(super) theta_sim: Vec<f64>,
    pub(super) mu: Vec<f64>,
    pub(super) lags: usize,
    /// The regressors are their own instruments (least squares).
    pub(super) own: bool,
    /// Every predictor column's value (0 where not estimated).
    pub(super) values: Vec<f64>,
    /// Dimension of `ζ`.
    pub(super) dim: usize,
    /// Per output: `(ζ row, column, the column's index in the output's block)`.
    pub(super) rows: Vec<Vec<(usize, usize, usize)>>,
    /// Per experiment and output: the instruments' centre (by block index)
    /// and the mean residual.
    pub(super) centres: Vec<Vec<Vec<f64>>>,
    pub(super) mean_res: Vec<Vec<f64>>,
    /// The estimate's own simulation, run in the same pass (a streamed
    /// record is then read once for both): `(θ, means)` as
    /// [`Pass::FreeRun`] takes them.
    pub(super) free_run: Option<(Vec<f64>, Vec<f64>)>,
}

/// The instruments a warm start settled on over the first `samples`
/// samples of an experiment (a shorter record this one begins with; see
/// [`crate::Start::instruments`]): simulated instruments take the measured
/// disturbances at `means`, that record's, over the whole experiment.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct PrefixInstruments {
    pub(super) samples: usize,
    pub(super) means: Vec<f64>,
}

/// What one experiment contributed to a pass.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassSummary(pub(super) Summary);

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) enum Summary {
    Moments {
        moments: Vec<CrossMoments>,
        change: SimChange,
        bad: Option<BadValue>,
    },
    /// The instrument simulation left the states' bounds.
    Diverged { bad: Option<BadValue> },
    /// `ζ`'s long-run sum, row-major `dim × dim`; `None` if the simulation
    /// diverged. With the free run's sums when the pass asked for them.
    LongRun {
        dim: usize,
        sums: Option<Vec<f64>>,
        free_run: Option<crate::free_run::FreeRunSums>,
    },
    /// A free run's fit sums.
    FreeRun(crate::free_run::FreeRunSums),
}

/// A non-finite or overflowing measured value: where, and what.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct BadValue {
    pub(super) location: String,
    pub(super) what: String,
}

/// Runs the passes of an estimate over the experiments. Implementations
/// return one result per experiment, in experiment order, each exactly what
/// [`PassRunner::facts`](crate::runner::PassRunner::facts) / [`PassRunner::pass`](crate::runner::PassRunner::pass) compute for it: on this
/// machine ([`LocalPasses`](crate::local::LocalPasses)) or mapped over workers that each read their own
/// experiments.
pub trait Passes {
    /// The facts of every experiment.
    fn facts(&self, request: &FactsRequest) -> Result<Vec<ExperimentFacts>, EstimateError>;
    /// Every experiment's summary of one pass. A moment pass may stop at the
    /// first experiment whose simulation diverged.
    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError>;
    /// The plan the structural analysis fixed for `key` in an earlier
    /// estimate through these passes, if kept (runners that serve several
    /// estimates keep them; none by default).
    fn known_plan(&self, _key: &PlanKey) -> Option<std::sync::Arc<StructuralPlan>> {
        None
    }
    /// Keeps the plan fixed for `key`, for later estimates through these
    /// passes (nothing by default).
    fn keep_plan(&self, _key: PlanKey, _plan: std::sync::Arc<StructuralPlan>) {}
}

/// A pass's request, facts or summaries as bytes (CBOR: every f64 bit for
/// bit, NaN and infinities included), to send to workers and back.
pub fn encode<T: Serialize>(value: &T) -> Vec<u8> {
    let mut out = Vec::new();
    // Writing into a Vec cannot fail, and these types serialise without error.
    if let Err(e) = ciborium::into_writer(value, &mut out) {
        unreachable!("a pass value failed to serialise: {e}");
    }
    out
}

/// Reads what [`encode`] wrote.
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, EstimateError> {
    ciborium::from_reader(bytes).map_err(|e| {
        err(
            "invalid-pass",
            format!("a pass message cannot be read: {e}"),
            "driver and workers must run the same version of leeway",
        )
    })
}

/// How far an instrument simulation moved from a reference one, per output:
/// `‖x − x_ref‖ / ‖x_ref − x̄_ref‖` (0 without a reference).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct SimChange {
    pub(super) diff2: Vec<f64>,
    pub(super) sum: Vec<f64>,
    pub(super) sum2: Vec<f64>,
    pub(super) n: usize,
    /// `Σ (y − x_sim)²`, `Σ y`, `Σ y²` per output: how well the instrument
    /// simulation tracks the measured states (its strength as an instrument).
    pub(super) err2: Vec<f64>,
    pub(super) y_sum: Vec<f64>,
    pub(super) y_sum2: Vec<f64>,
    pub(super) y_n: usize,
}

impl SimChange {
    /// Mean over outputs of the fit `100·(1 − ‖y − x_sim‖/‖y − ȳ‖)`.
    pub(super) fn fit(&self) -> f64 {
        let n = self.y_n.max(1) as f64;
        let fits: Vec<f64> = (0..self.err2.len())
            .map(|o| {
                let var = (self.y_sum2[o] - self.y_sum[o] * self.y_sum[o] / n).max(0.0);
                if var > 0.0 {
                    100.0 * (1.0 - (self.err2[o] / var).sqrt())
                } else {
                    0.0
                }
            })
            .collect();
        fits.iter().sum::<f64>() / fits.len().max(1) as f64
    }

    pub(super) fn relative(&self) -> f64 {
        let n = self.n.max(1) as f64;
        (0..self.diff2.len())
            .map(|o| {
                let mean = self.sum[o] / n;
                let var = (self.sum2[o] / n - mean * mean).max(0.0) * n;
                if var > 0.0 {
                    (self.diff2[o] / var).sqrt()
                } else {
                    0.0
                }
            })
            .fold(0.0, f64::max)
    }
}
