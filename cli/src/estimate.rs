//! `leeway estimate MODEL --data A.csv [--data B.csv]... --method iv3`:
//! load and validate the experiments, estimate θ and the nuisance parameters,
//! and print the table, disturbance means, sign patterns, diagnostics and
//! warnings — or one JSON document (README, "Estimating"). Exit 0 on success
//! (warnings allowed), 1 when the data cannot support the model, 2 on any
//! model, data or option error.

mod json;
mod text;

use crate::model::{
    DataSet, TimeArgs, heading_gains, heading_warnings, load, load_options, open_data,
    unit_warnings,
};
use crate::output::{Status, err, headline, out, print_json, stderr_style};
use crate::problem::{Failure, Problem};
use leeway_estimate::Centring;
use leeway_estimate::Combine;
use leeway_estimate::Estimate;
use leeway_estimate::EstimateOptions;
use leeway_estimate::Initial;
use leeway_estimate::Instruments;
use leeway_estimate::Method;
use leeway_estimate::estimate;
use leeway_model::Interpreter;
use std::path::PathBuf;

/// Arguments of `leeway estimate`.
#[derive(Debug, clap::Args)]
pub struct EstimateArgs {
    /// The `.som` model file.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// A CSV file of experiments (one, or several with an `experiment` column). Repeat for more files.
    #[arg(long = "data", value_name = "FILE.csv", required = true)]
    pub data: Vec<PathBuf>,
    /// The estimator: least squares, or instrumental variables on the basic (iv1),
    /// augmented (iv2) or augmented-plus-measured-medium (iv3) predictor.
    #[arg(long, value_enum, default_value_t = MethodArg::Iv3)]
    pub method: MethodArg,
    /// Nominal θ for the instruments' first simulation (an `estimate --json`
    /// output or `{"name": value}`), instead of the model's `nominal { }`.
    #[arg(long, value_name = "FILE.json")]
    pub nominal: Option<PathBuf>,
    /// Print one JSON document on stdout instead of text (the contract is in the README).
    #[arg(long)]
    pub json: bool,
    /// Instruments: simulated (the nominal model, refined) or delayed (measurements one sample earlier).
    #[arg(long, value_enum, default_value_t = InstrumentsArg::Simulated)]
    pub instruments: InstrumentsArg,
    /// θ of the first instrument simulation: a delayed-instrument estimate, or the nominal model.
    #[arg(long, value_enum, default_value_t = InitialArg::Delayed)]
    pub initial: InitialArg,
    /// Centre the instruments per experiment (consistent under a disturbance mean), pooled,
    /// or not at all. Default: per experiment when the model has a disturbance the method
    /// does not take from data, none otherwise (the output says which and why).
    #[arg(long, value_enum)]
    pub centring: Option<CentringArg>,
    /// Combine the experiments' moment equations summed (the pooled IV estimator) or
    /// stacked and solved by least squares (the paper's eq. IV_problem as written).
    #[arg(long, value_enum, default_value_t = CombineArg::Summed)]
    pub combine: CombineArg,
    /// When θ is not identifiable from these data, estimate its identifiable combinations
    /// (absorbed parameters held at their nominal values).
    #[arg(long)]
    pub aggregate: bool,
    /// A sign assumption violated in the data (paper A7) is an error, not a warning.
    #[arg(long)]
    pub strict: bool,
    /// Lags of the robust (long-run) covariance; at least 1 (the Euler residual is MA(1)).
    #[arg(long, value_name = "L", default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=MAX_LAGS as i64))]
    pub lags: u16,
    /// Most re-simulations of the refined IV.
    #[arg(long, value_name = "N", default_value_t = 8, value_parser = refinements)]
    pub max_refinements: usize,
    /// Run the plain refined IV: do not stop a refinement whose simulation tracks
    /// the data markedly worse than an earlier iterate (docs/estimation.md).
    #[arg(long)]
    pub no_runaway_guard: bool,
    /// Sample time for data without a time column when the model declares no `step`.
    #[arg(long, value_name = "H", value_parser = positive)]
    pub step: Option<f64>,
    /// Time stamps: jitter tolerance and resampling.
    #[command(flatten)]
    pub time: TimeArgs,
}

/// `--method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Least squares (biased under noise and disturbances; a baseline).
    Ls,
    /// IV on the basic predictor (consistent only for zero-mean disturbances).
    Iv1,
    /// IV on the augmented predictor, every medium unmeasured.
    Iv2,
    /// IV on the augmented predictor plus measured media pointwise.
    Iv3,
}

/// `--instruments`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum InstrumentsArg {
    /// Noise-free regressors of a simulated nominal model, refined.
    Simulated,
    /// Regressors of the measurements one sample earlier.
    Delayed,
}

/// `--initial`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum InitialArg {
    /// A delayed-instrument estimate.
    Delayed,
    /// The nominal model.
    Nominal,
}

/// `--centring`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CentringArg {
    /// Zero-mean instruments per experiment.
    Experiment,
    /// Zero mean over all experiments pooled.
    Pooled,
    /// No centring.
    None,
}

impl CentringArg {
    /// The runtime's centring.
    pub fn centring(self) -> Centring {
        match self {
            CentringArg::Experiment => Centring::Experiment,
            CentringArg::Pooled => Centring::Pooled,
            CentringArg::None => Centring::None,
        }
    }
}

/// `--combine`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CombineArg {
    /// `(Σ H_i) ϑ = Σ g_i`: one system over all experiments.
    Summed,
    /// `[H_1/n_1; …] ϑ = [g_1/n_1; …]` by least squares.
    Stacked,
}

/// Most lags of the robust covariance (`--lags`): each costs one pass of
/// O(n_ϑ²) work; an MA(1) residual needs one.
pub const MAX_LAGS: u16 = 1000;
/// Most re-simulations of the refined IV (`--max-refinements`): each re-reads
/// the data; one or two give most of the gain.
pub const MAX_REFINEMENTS: usize = 100;
/// Sample times (`--step`, `--resample`) in seconds: from a microsecond to a
/// day (11.6 days at most).
pub const STEP_RANGE: (f64, f64) = (1e-6, 1e6);

fn refinements(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(v) if v <= MAX_REFINEMENTS => Ok(v),
        Ok(_) => Err(format!("`{s}` is not in 0..={MAX_REFINEMENTS}")),
        Err(_) => Err(format!("`{s}` is not a whole number")),
    }
}

/// A sample time in seconds within [`STEP_RANGE`] (`--step`, `--resample`).
pub fn positive(s: &str) -> Result<f64, String> {
    let (lo, hi) = STEP_RANGE;
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (lo..=hi).contains(&v) => Ok(v),
        Ok(v) if v.is_finite() && v > 0.0 => Err(format!(
            "`{s}` s is outside {lo:e}..={hi:e} seconds, the sample times leeway accepts"
        )),
        _ => Err(format!("`{s}` is not a positive number of seconds")),
    }
}

impl EstimateArgs {
    fn options(&self, nominal: Option<Vec<f64>>) -> EstimateOptions {
        EstimateOptions {
            method: match self.method {
                MethodArg::Ls => Method::Ls,
                MethodArg::Iv1 => Method::Iv1,
                MethodArg::Iv2 => Method::Iv2,
                MethodArg::Iv3 => Method::Iv3,
            },
            instruments: match self.instruments {
                InstrumentsArg::Simulated => Instruments::Simulated,
                InstrumentsArg::Delayed => Instruments::Delayed,
            },
            initial: match self.initial {
                InitialArg::Delayed => Initial::Delayed,
                InitialArg::Nominal => Initial::Nominal,
            },
            centring: self.centring.map(CentringArg::centring),
            combine: match self.combine {
                CombineArg::Summed => Combine::Summed,
                CombineArg::Stacked => Combine::Stacked,
            },
            nominal,
            max_refinements: self.max_refinements,
            aggregate: self.aggregate,
            strict: self.strict,
            lags: usize::from(self.lags),
            runaway_guard: !self.no_runaway_guard,
            ..EstimateOptions::default()
        }
    }
}

/// What a successful run produced.
pub struct Outcome {
    /// The model's name.
    pub model: String,
    /// The estimate.
    pub estimate: Estimate,
    /// Experiment names with their sample counts.
    pub experiments: Vec<(String, usize)>,
    /// The heading's unit check per experiment (planar heading only).
    pub heading_gains: Vec<(String, Option<f64>)>,
    /// What reading each data file noted (comment lines, jitter, resampling).
    pub data_notes: Vec<leeway_data::FileNotes>,
    /// The declared units, one line each (`delta: column rudder in deg, converted to rad`).
    pub units: Vec<String>,
    /// The declared units by signal, as written.
    pub data_units: std::collections::BTreeMap<String, String>,
}

/// Runs `leeway estimate`.
pub fn run(args: &EstimateArgs) -> Status {
    let mut warnings = Vec::new();
    let mut model = None;
    let result = execute(args, &mut warnings, &mut model);
    if args.json {
        print_json(&json::report(args, model, &result, warnings));
    } else {
        let style = stderr_style();
        if let Ok(o) = &result {
            out(&text::render(o));
        }
        for w in &warnings {
            err(&headline(style, "warning", None, w));
        }
        if let Ok(o) = &result {
            for n in &o.estimate.notes {
                err(&headline(style, "note", None, n));
            }
        }
        if let Err(f) = &result {
            err(&f.render(style, "estimated"));
        }
    }
    match &result {
        Ok(_) => Status::Success,
        Err(f) => f.status(),
    }
}

/// Warnings of the model, the data checks and the estimator go to `warnings`,
/// in that order, also when a later step fails; the model's name goes to
/// `model` as soon as it compiles (the JSON names it also on a data error).
fn execute(
    args: &EstimateArgs,
    warnings: &mut Vec<String>,
    model_name: &mut Option<String>,
) -> Result<Outcome, Failure> {
    let loaded = load(&args.model, args.aggregate)?;
    let ir = loaded.ir;
    *model_name = Some(ir.name.clone());
    let load_options = load_options(&ir, args.step, Some(&args.time))?;
    let nominal = match &args.nominal {
        Some(path) => Some(crate::params::read(path, &ir, "--nominal")?),
        None => None,
    };
    let (data, data_notes) = open_data(&ir, &args.data, &load_options)?;
    let sources = data.sources();
    warnings.extend(loaded.warnings);
    warnings.extend(unit_warnings(&ir, &sources));
    let gains = heading_gains(&ir, &sources);
    warnings.extend(heading_warnings(&ir, &gains));
    let model = Interpreter::new(ir.clone());
    let result = estimate(&model, &sources, &args.options(nominal));
    // A file that changed between passes voids whatever was computed.
    if let Some(p) = data.failure() {
        return Err(Failure::from(p));
    }
    let est = result.map_err(|e| Failure::from(Problem::estimate(&located(e, &data))))?;
    warnings.extend(est.warnings.iter().cloned());
    Ok(Outcome {
        model: ir.name.clone(),
        experiments: sources
            .iter()
            .map(|e| (e.name().to_string(), e.len()))
            .collect(),
        heading_gains: gains,
        estimate: est,
        data_notes,
        units: crate::model::unit_lines(&ir),
        data_units: ir.data_units.clone(),
    })
}

/// An estimator's error with the data's places: `too-few-samples` names every
/// experiment with its file and sample count.
fn located(
    mut e: leeway_estimate::EstimateError,
    data: &DataSet,
) -> leeway_estimate::EstimateError {
    if e.code == "too-few-samples" {
        let list: Vec<String> = data
            .sources()
            .iter()
            .zip(data.files())
            .map(|(s, f)| format!("`{}` in {f}: {} samples", s.name(), s.len()))
            .collect();
        e.message = format!("{} (experiments: {})", e.message, list.join("; "));
    }
    e
}
