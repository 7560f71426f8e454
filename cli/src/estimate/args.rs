//! The arguments of `leeway estimate` and the estimator options they give.

use crate::options::{TimeArgs, choices, fraction, positive, refinements};
use leeway_estimate::{
    Centring, Combine, DelayRange, EstimateOptions, Initial, Instruments, Method, ScanBy,
};
use std::path::PathBuf;

/// Arguments of `leeway estimate`.
#[derive(Debug, clap::Args)]
pub struct EstimateArgs {
    /// The `.som` model file.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// A CSV or Parquet file of experiments (one, or several with an `experiment` column).
    /// Repeat for more files.
    #[arg(long = "data", value_name = "FILE", required = true)]
    pub data: Vec<PathBuf>,
    /// The estimator: least squares, or instrumental variables on the basic (iv1),
    /// augmented (iv2) or augmented-plus-measured-medium (iv3) predictor.
    #[arg(long, default_value = "iv3", value_parser = choices::<Method>())]
    pub method: Method,
    /// Nominal θ for the instruments' first simulation (an `estimate --json`
    /// output or `{"name": value}`), instead of the model's `nominal { }`.
    #[arg(long, value_name = "FILE.json")]
    pub nominal: Option<PathBuf>,
    /// Print one JSON document on stdout instead of text (the contract is in docs/json.md).
    #[arg(long)]
    pub json: bool,
    /// Instruments: simulated (the nominal model, refined) or delayed (measurements one sample earlier).
    #[arg(long, default_value = "simulated", value_parser = choices::<Instruments>())]
    pub instruments: Instruments,
    /// θ of the first instrument simulation: a delayed-instrument estimate, or the nominal model.
    #[arg(long, default_value = "delayed", value_parser = choices::<Initial>())]
    pub initial: Initial,
    /// Centre the instruments per experiment (consistent under a disturbance mean), pooled,
    /// or not at all. Default: per experiment when the model has a disturbance the method
    /// does not take from data, none otherwise (the output says which and why).
    #[arg(long, value_parser = choices::<Centring>())]
    pub centring: Option<Centring>,
    /// Combine the experiments' moment equations summed (the pooled IV estimator) or
    /// stacked and solved by least squares (the paper's eq. IV_problem as written).
    #[arg(long, default_value = "summed", value_parser = choices::<Combine>())]
    pub combine: Combine,
    /// When θ is not identifiable from these data, estimate its identifiable combinations
    /// (absorbed parameters held at their nominal values).
    #[arg(long)]
    pub aggregate: bool,
    /// Fail (exit 1) instead of warning when something can bias the estimate: a sign
    /// assumption violated in the data (paper A7), a parameter held for lack of
    /// excitation, an angle or heading in the wrong unit, an estimate that does not
    /// reproduce its own data.
    #[arg(long)]
    pub strict: bool,
    /// Print every warning in full (exact combinations, figures) under its two lines.
    #[arg(long)]
    pub verbose: bool,
    /// Lags of the robust (long-run) covariance; at least 1 (the Euler residual is MA(1)).
    #[arg(long, value_name = "L", default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=leeway_estimate::MAX_LAGS as i64))]
    pub lags: u16,
    /// Most re-simulations of the refined IV.
    #[arg(long, value_name = "N", default_value_t = 8, value_parser = refinements)]
    pub max_refinements: usize,
    /// Refine on a subsample first: the bootstrap and the refinement run on the first
    /// FRACTION of every experiment (e.g. 0.1), and the refinement over all samples goes
    /// on from their settled estimate — for long records, one pass over all samples
    /// instead of three; the same fixed point within the tolerance, not the same bits
    /// (docs/estimation.md).
    #[arg(long, value_name = "FRACTION", value_parser = fraction)]
    pub refine_subsample: Option<f64>,
    /// Run the plain refined IV: do not stop a refinement whose simulation tracks
    /// the data markedly worse than an earlier iterate (docs/estimation.md).
    #[arg(long)]
    pub no_runaway_guard: bool,
    /// Find an input's dead time: estimate at every dead time from LO to HI (in
    /// samples, or in seconds with a trailing `s`: `tau_x=0..2s`, at most 200
    /// candidates) and keep the best by --scan-by; the curve is printed, then
    /// the estimate at the chosen dead time. Several inputs (repeat the option,
    /// or separate with commas) are scanned one after another, each with the
    /// dead times chosen before it.
    #[arg(long, value_name = "INPUT=LO..HI[s]", value_parser = DelayRange::parse, value_delimiter = ',', action = clap::ArgAction::Append)]
    pub scan_delay: Vec<DelayRange>,
    /// What --scan-delay judges each dead time by: the estimate's simulation on
    /// the data (fit, as `validate` computes it) or its one-step prediction (residual).
    #[arg(long, default_value = "fit", value_parser = choices::<ScanBy>(), requires = "scan_delay")]
    pub scan_by: ScanBy,
    /// Sample time for data without a time column when the model declares no `step`.
    #[arg(long, value_name = "H", value_parser = positive)]
    pub step: Option<f64>,
    /// Time stamps: jitter tolerance and resampling.
    #[command(flatten)]
    pub time: TimeArgs,
}

impl EstimateArgs {
    pub fn options(&self, nominal: Option<Vec<f64>>) -> EstimateOptions {
        EstimateOptions {
            method: self.method,
            instruments: self.instruments,
            initial: self.initial,
            centring: self.centring,
            combine: self.combine,
            nominal,
            max_refinements: self.max_refinements,
            aggregate: self.aggregate,
            strict: self.strict,
            lags: usize::from(self.lags),
            runaway_guard: !self.no_runaway_guard,
            refine_subsample: self.refine_subsample,
            ..EstimateOptions::default()
        }
    }
}
