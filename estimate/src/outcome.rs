//! What an estimate returns: θ, the nuisance columns, disturbance moments, diagnostics, errors.

use crate::method::Method;
use leeway_model::signs::ExperimentSigns;

use serde::Serialize;

/// One column's estimate (θ or nuisance).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ColumnEstimate {
    /// Column name.
    pub name: String,
    /// `theta`, `rho` or `lambda`.
    pub kind: &'static str,
    /// The estimate (held value for held columns, `None` when dropped).
    pub value: Option<f64>,
    /// Standard error (estimated columns only).
    pub std_error: Option<f64>,
    /// `estimated`; `aggregate` (a θ that estimates the sum in
    /// `estimates`, with parameters held beside it); `held at nominal`,
    /// `held at 0`, `dropped` (each with its reason in parentheses).
    pub status: String,
    /// What the value estimates, in moments and parameter names.
    pub estimates: String,
}

/// The mean of an unmeasured disturbance component (paper Corollary 1).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DisturbanceMoment {
    /// The disturbance.
    pub disturbance: String,
    /// The component.
    pub component: String,
    /// Estimated mean.
    pub mean: f64,
    /// Its standard error (delta method).
    pub std_error: Option<f64>,
}

/// How the estimate was computed and how well the data support it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Diagnostics {
    /// `basic`, `augmented`, `measured`.
    pub predictor: String,
    /// Experiments.
    pub experiments: usize,
    /// Equations used (samples − 2 per experiment).
    pub equations: usize,
    /// Columns of the predictor (unreduced).
    pub columns: usize,
    /// Columns estimated after structural and numeric reduction.
    pub estimated: usize,
    /// Numerical rank of the stacked moment matrix over the structurally kept columns.
    pub rank: usize,
    /// Condition number of the column-equilibrated stacked matrix (largest block).
    pub condition_number: f64,
    /// Refinements (re-simulations with an estimate).
    pub refinements: usize,
    /// The refined estimate settled within the tolerance.
    pub converged: bool,
    /// Instruments used.
    pub instruments: String,
    /// Centring used, and why it is valid.
    pub centring: String,
    /// `summed` or `stacked`: how the experiments' equations were combined.
    pub combine: String,
    /// Lags of the long-run covariance.
    pub lags: usize,
    /// Combinations the data did not excite, in the model's names.
    pub unexcited: Vec<String>,
    /// What kept parameters estimate when others were held.
    pub aggregates: Vec<String>,
    /// The estimate's own simulation on its data (`None` when not asked:
    /// [`EstimateOptions::own_simulation`](crate::EstimateOptions::own_simulation)).
    pub own_simulation: Option<OwnSimulation>,
    /// Per experiment, the equations left out at its start, when the model
    /// declares dead times (empty, and left out of the JSON, otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dropped_at_start: Vec<DroppedAtStart>,
    /// The refinement on a subsample that began this one, when asked for
    /// ([`EstimateOptions::refine_subsample`](crate::EstimateOptions::refine_subsample));
    /// left out of the JSON otherwise. `refinements` and `converged` above
    /// are those over all samples.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub subsample: Option<SubsampleRefinement>,
}

/// A refinement on a subsample: the bootstrap and the refinement ran on the
/// first samples of every experiment, and once they settled, the refinement
/// over all samples went on from their estimate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SubsampleRefinement {
    /// The fraction of every experiment's samples refined on.
    pub fraction: f64,
    /// The samples the subsample has (over all experiments).
    pub samples: usize,
    /// Refinements on the subsample.
    pub refinements: usize,
    /// Its estimate began the refinement over all samples. When `false`,
    /// the refinement over all samples began from the bootstrap, as without
    /// a subsample, and `why_not` says why.
    pub used: bool,
    /// Why the subsample's estimate was not used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why_not: Option<String>,
}

/// The equations one experiment loses at its start: the method's, then the
/// dead time's.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DroppedAtStart {
    /// The experiment.
    pub experiment: String,
    /// Samples that only supply delayed inputs (the longest dead time).
    pub dead_time: usize,
    /// Equations every method leaves out after those (the first, so that
    /// no instrument uses a same-sample measurement).
    pub method: usize,
    /// Their sum.
    pub equations: usize,
}

/// The reported θ simulated on its own data (a free run from each
/// experiment's first sample, with its inputs and measured disturbances,
/// the unmeasured ones at the means the estimate implies), fitted as
/// `validate` fits: the check that the estimate describes the data.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OwnSimulation {
    /// Per state, the mean over experiments of its fit (%), `None` where
    /// undefined or when a simulation diverged.
    pub fits: Vec<StateFit>,
    /// The mean of the states' fits.
    pub mean_fit: Option<f64>,
    /// The experiments on which the simulation diverged (the model is
    /// unstable on their inputs).
    pub diverged: Vec<String>,
}

/// One state's fit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateFit {
    /// The state.
    pub state: String,
    /// Its fit (%).
    pub fit: Option<f64>,
}

/// The result of an estimation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// The method.
    pub method: Method,
    /// θ names.
    pub parameters: Vec<String>,
    /// θ (held parameters at their nominal values).
    pub theta: Vec<f64>,
    /// Standard errors of θ (`None` for held parameters).
    pub std_errors: Vec<Option<f64>>,
    /// The covariance of θ, the robust sandwich the standard errors come
    /// from: `covariance[i][j]` for parameters `i` and `j` in the order of
    /// `parameters` (square; symmetric, off-diagonal entries the mean of the
    /// sandwich's two round-off-different triangles). An entry is `None` when `i` or `j`
    /// was not estimated (held, or an aggregate's absorbed parameter), and
    /// every entry is `None` when the covariance could not be computed (then
    /// `std_errors` are all `None` too). A diagonal entry `v` gives the
    /// standard error `√max(v, 0)` bit for bit.
    pub covariance: Vec<Vec<Option<f64>>>,
    /// Every column of the predictor.
    pub columns: Vec<ColumnEstimate>,
    /// Means of the unmeasured disturbances.
    pub disturbances: Vec<DisturbanceMoment>,
    /// Sign pattern per experiment.
    pub sign_patterns: Vec<ExperimentSigns>,
    /// Diagnostics.
    pub diagnostics: Diagnostics,
    /// Warnings, each in full (the `detail` of the same entry of
    /// `warning_summaries`).
    pub warnings: Vec<String>,
    /// The warnings with their one-line summary, help line and whether they
    /// can bias the estimate, in the order of `warnings`.
    pub warning_summaries: Vec<leeway_model::warning::Warning>,
    /// Notes: facts about the data worth knowing that need no action (e.g.
    /// where a pointwise modulus of a noisy state crosses zero).
    pub notes: Vec<String>,
    /// The simulation whose instruments gave a refined IV estimate that
    /// settled (`None` otherwise): what a warm start on longer records that
    /// begin with these experiments continues ([`crate::Start::from_estimate`]).
    #[serde(skip)]
    pub instrument_simulation: Option<InstrumentSimulation>,
    /// The reported solve's moment equations and the long-run covariance of
    /// its moment residuals, per block and experiment (`None` without a
    /// covariance): what a sub-model's IV estimate is solved from without
    /// another pass over the data (`leeway select`).
    #[serde(skip)]
    pub moment_system: Option<MomentSystem>,
}

/// The IV moment equations of an estimate, kept for solving sub-models:
/// per block of outputs, the summed moment sums of each experiment over the
/// block's predictor columns (the same columns index the instruments' rows
/// and the regressors' columns).
#[derive(Clone, Debug, PartialEq)]
pub struct MomentSystem {
    /// The blocks, in the estimate's order.
    pub blocks: Vec<MomentBlock>,
}

/// One block of a [`MomentSystem`].
#[derive(Clone, Debug, PartialEq)]
pub struct MomentBlock {
    /// Predictor columns of the block (indices into the predictor's columns).
    pub cols: Vec<usize>,
    /// Columns the estimate kept (estimated); the others it held.
    pub kept: Vec<usize>,
    /// Per experiment, `H_i = Σ_k z̃ φᵀ` (`cols × cols`, centred as the
    /// estimate centred its instruments).
    pub h: Vec<nalgebra::DMatrix<f64>>,
    /// Per experiment, `g_i = Σ_k z̃ t`.
    pub g: Vec<nalgebra::DVector<f64>>,
    /// Per experiment, the long-run covariance of `ζ_k = z̃_k ε_k` over the
    /// rows `cols`, at the estimate's residuals.
    pub long_run: Vec<nalgebra::DMatrix<f64>>,
}

/// The instrument simulation of a settled refined IV estimate: the θ and
/// disturbance means simulated, and per experiment its samples and the
/// measured disturbance means its instruments took. A warm start that
/// carries it begins on a longer record with these very instruments over
/// the first samples (the simulation continued over the new ones), so a
/// pass over that record can go on from the sums of the shorter one's.
#[derive(Clone, Debug, PartialEq)]
pub struct InstrumentSimulation {
    /// θ simulated.
    pub theta: Vec<f64>,
    /// Disturbance-component means simulated (by global index).
    pub means: Vec<f64>,
    /// Per experiment: `(samples, measured disturbance means)`.
    pub experiments: Vec<(usize, Vec<f64>)>,
}

impl Estimate {
    /// θ by name.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.parameters
            .iter()
            .position(|p| p == name)
            .map(|i| self.theta[i])
    }
}

/// Why an estimate could not be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct EstimateError {
    /// Stable kebab-case code (`unidentifiable`, `rank-deficient`, `sign-violation`, ...).
    pub code: &'static str,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: String,
}

pub(super) fn err(
    code: &'static str,
    message: impl Into<String>,
    hint: impl Into<String>,
) -> EstimateError {
    EstimateError {
        code,
        message: message.into(),
        hint: hint.into(),
    }
}
