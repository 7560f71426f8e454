//! What the caller chooses: the method, its instruments, centring and combination.

use crate::method::{Combine, Initial, Instruments, Method};
use leeway_structure::identify::Centring;

/// Options of [`estimate`](crate::run::estimate): the method, its instruments, how
/// experiments combine, the refinement and what is reported.
#[derive(Clone, Debug)]
pub struct EstimateOptions {
    /// The estimator.
    pub method: Method,
    /// Instrument kind.
    pub instruments: Instruments,
    /// The θ the first instrument simulation uses (simulated instruments).
    pub initial: Initial,
    /// Instrument centring (`None`: the model's default,
    /// [`Centring::for_model`]: per experiment when the model has a
    /// disturbance the predictor does not take from data, none otherwise).
    pub centring: Option<Centring>,
    /// How the experiments' moment equations are combined.
    pub combine: Combine,
    /// θ of the nominal model (default: the model's `nominal { }`).
    pub nominal: Option<Vec<f64>>,
    /// Most re-simulations of the refined IV.
    pub max_refinements: usize,
    /// The refinement has settled when a new instrument simulation moves less
    /// than this fraction of the simulated states' variation (RMS), or when
    /// the refinement contracts (each move less than half the previous) and
    /// the next move, predicted geometrically, would.
    pub tolerance: f64,
    /// Estimate identifiable combinations when θ is not identifiable.
    pub aggregate: bool,
    /// A7 violations (wrong signs) are errors instead of warnings.
    pub strict: bool,
    /// Lags of the long-run covariance (≥ 1: the Euler residual is MA(1)).
    pub lags: usize,
    /// Relative residual below which a column is numerically dependent.
    pub rank_tolerance: f64,
    /// Heading spread (circular std, rad) below which `R` counts as constant.
    pub heading_spread: f64,
    /// Compute standard errors and disturbance moments (one more pass).
    pub covariance: bool,
    /// Stop a refinement whose simulation tracks the data markedly worse than
    /// an earlier iterate, and report the best iterate (small-sample runaway
    /// guard). `false` gives the plain refined IV of the paper.
    pub runaway_guard: bool,
    /// A warm start: the first instrument simulation uses this θ and these
    /// disturbance means instead of `initial` (e.g. the estimate from a
    /// shorter record of the same experiment).
    pub start: Option<Start>,
    /// Simulate the reported estimate on its own data (one more pass) and
    /// report its fit; an estimate whose simulation diverges or fits worse
    /// than the data's mean is then never reported as converged (a warning,
    /// or an error under `strict`). The Monte Carlo study, which validates
    /// its estimates itself, turns it off.
    pub own_simulation: bool,
    /// Asked before and after every pass over the data, and by the
    /// estimate's own passes ([`estimate`](crate::run::estimate)'s, not
    /// those given to [`estimate_with`](crate::run::estimate_with)) every
    /// 32768 samples of a data walk or facts visit, whose rest is then
    /// skipped: `true` stops the estimate with the error `interrupted`
    /// (Ctrl-C in Python, whose handler runs only when asked while native
    /// code runs).
    pub interrupt: Option<Interrupt>,
    /// Refine on a subsample first (`Some(fraction)`, in (0, 1]): the
    /// bootstrap and the refinement run on the first `⌈fraction·n⌉` samples
    /// of every experiment, and once they settle, the refinement over all
    /// samples goes on from their estimate. Its first pass over all samples
    /// compares the subsample's last two instrument simulations there, and
    /// stops when they moved less than `tolerance` — the test every
    /// refinement settles by. At scale that saves the bootstrap pass and a
    /// refinement pass over all samples; the estimate is the same fixed
    /// point within the tolerance, not the same bits (docs/estimation.md).
    /// Only for a refined IV from the delayed bootstrap (no `start`).
    pub refine_subsample: Option<f64>,
}

pub use leeway_model::interrupt::Interrupt;

/// The θ and disturbance-component means of a first instrument simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct Start {
    /// θ, one value per parameter.
    pub theta: Vec<f64>,
    /// Means of the disturbance components (by global index) in the
    /// simulation; measured components are simulated as recorded.
    pub means: Vec<f64>,
    /// The simulation that gave the start's own instruments (a settled
    /// refined IV estimate on records the new ones begin with): the first
    /// instruments are then that simulation's, continued over the new
    /// samples, instead of a simulation of `theta` — the same fixed point
    /// within the refinement's tolerance, and the sums over the shorter
    /// records need not be made again.
    pub instruments: Option<crate::outcome::InstrumentSimulation>,
}

impl Start {
    /// The warm start an estimate gives: its θ and the unmeasured
    /// disturbance means it implies (0 where it implies none).
    pub fn from_estimate(
        ir: &leeway_structure::ir::Ir,
        estimate: &crate::outcome::Estimate,
    ) -> Start {
        let means = ir
            .components
            .iter()
            .map(|c| {
                estimate
                    .disturbances
                    .iter()
                    .find(|d| d.component == c.name)
                    .map_or(0.0, |d| d.mean)
            })
            .collect();
        Start {
            theta: estimate.theta.clone(),
            means,
            instruments: estimate.instrument_simulation.clone(),
        }
    }
}

/// Most lags of the robust covariance ([`EstimateOptions::lags`]): each
/// costs one pass of O(n_ϑ²) work; an MA(1) residual needs one.
pub const MAX_LAGS: usize = 1000;

/// Most re-simulations of the refined IV
/// ([`EstimateOptions::max_refinements`]): each re-reads the data; one or two
/// give most of the gain.
pub const MAX_REFINEMENTS: usize = 100;

/// A count option outside the range the estimator accepts.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{option}={value} is not in {min}..={max}")]
pub struct OutOfRange {
    /// The option (`lags`, `max_refinements`).
    pub option: &'static str,
    /// The value given.
    pub value: usize,
    /// The smallest value accepted.
    pub min: usize,
    /// The largest value accepted.
    pub max: usize,
}

impl EstimateOptions {
    /// The options' counts within what the estimator accepts: `lags` in
    /// 1..=[`MAX_LAGS`], `max_refinements` in 0..=[`MAX_REFINEMENTS`].
    pub fn validate(&self) -> Result<(), OutOfRange> {
        let within = |option, value, min, max| {
            if (min..=max).contains(&value) {
                Ok(())
            } else {
                Err(OutOfRange {
                    option,
                    value,
                    min,
                    max,
                })
            }
        };
        within("lags", self.lags, 1, MAX_LAGS)?;
        within("max_refinements", self.max_refinements, 0, MAX_REFINEMENTS)
    }
}

impl Default for EstimateOptions {
    fn default() -> EstimateOptions {
        EstimateOptions {
            method: Method::Iv3,
            instruments: Instruments::Simulated,
            initial: Initial::Delayed,
            centring: None,
            combine: Combine::Summed,
            nominal: None,
            max_refinements: 8,
            tolerance: 1e-3,
            aggregate: false,
            strict: false,
            lags: 1,
            rank_tolerance: 1e-9,
            heading_spread: 0.05,
            covariance: true,
            runaway_guard: true,
            start: None,
            own_simulation: true,
            interrupt: None,
            refine_subsample: None,
        }
    }
}
