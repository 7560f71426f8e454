//! The input design checked on the true trajectories (reporting
//! the margin): over every estimation experiment of the study —
//! measured as the study simulates them, so these are exactly the records
//! the estimators saw, at the largest N — the range of each relative velocity
//! under a modulus (`water.u`, `water.v`: the current; `air.u`, `air.v`: the
//! wind) and of the yaw rate, from the true states, heading and disturbances.

use leeway_model::Model;
use leeway_scenarios::design::Range;
use leeway_scenarios::design::block_mean_range;
use leeway_scenarios::design::sign_argument_ranges;
use leeway_scenarios::design::state_range;
use leeway_scenarios::study;
use leeway_scenarios::study::StudyConfig;
use leeway_scenarios::synth::Truth;
use leeway_structure::ir::Rotation;

/// Samples per block of the yaw rate's block means (one minute at 1 Hz).
pub const BLOCK: usize = 60;

/// One case's ranges.
#[derive(Clone, Debug)]
pub struct CaseCheck {
    /// `low` or `high`.
    pub case: String,
    /// Mean wind, m/s (north and east).
    pub wind: f64,
    /// Each sign argument's range over every sample of every run, in the
    /// model's order (`water.u`, `water.v`, `air.u`, `air.v` for the ship).
    pub arguments: Vec<(String, Range)>,
    /// The yaw rate's range.
    pub yaw_rate: Range,
    /// The range of the yaw rate averaged over each block of [`BLOCK`] samples.
    pub yaw_rate_blocks: Range,
    /// The range of each run's mean yaw rate.
    pub yaw_rate_runs: Range,
    /// The true trajectory of run 0 (for the track figure).
    pub first: Truth,
}

/// The design check of the whole study.
#[derive(Clone, Debug)]
pub struct DesignCheck {
    /// Experiments per case (the runs).
    pub experiments: usize,
    /// Samples per experiment (the largest N).
    pub samples: usize,
    /// Per case, in the study's order.
    pub cases: Vec<CaseCheck>,
    /// The name of the integrated yaw rate (`r`).
    pub yaw_name: String,
    /// Standard deviation of the yaw rate's measurement noise.
    pub yaw_noise_std: f64,
    /// Standard deviation of each output over the validation record (the
    /// fit's normaliser `‖y − ȳ‖/√n`), in the model's output order.
    pub validation_std: Vec<(String, f64)>,
}

impl CaseCheck {
    /// The smallest value of the arguments relative to `medium` (`water`, `air`).
    pub fn min_of(&self, medium: &str) -> f64 {
        self.arguments
            .iter()
            .filter(|(name, _)| medium_of(name) == medium)
            .map(|(_, r)| r.min)
            .fold(f64::INFINITY, f64::min)
    }
}

/// `water` of `water.u`.
pub fn medium_of(argument: &str) -> &str {
    argument.split('.').next().unwrap_or(argument)
}

/// What one run's true trajectory shows: the ranges of the sign arguments,
/// of the yaw rate, of its block means and of its mean, and the trajectory
/// itself for the first run.
pub type Measured = (Vec<(String, Range)>, [Range; 3], Option<Truth>);

/// The yaw-rate state: the one a planar heading integrates, else the last.
fn yaw_state(model: &dyn Model) -> usize {
    let ir = model.ir();
    match &ir.rotation {
        Rotation::Planar { integrates, .. } => *integrates,
        _ => ir.states.len().saturating_sub(1),
    }
}

/// Measures run `run`'s true trajectory (the study's estimation record at
/// the largest N, handed over by `study::run_study_inspecting`: exactly the
/// record the estimators saw, not simulated again).
pub fn measure(model: &dyn Model, config: &StudyConfig, run: usize, truth: &Truth) -> Measured {
    let yaw = yaw_state(model);
    let samples = config.n.iter().copied().max().unwrap_or(0);
    let arguments = sign_argument_ranges(model, truth);
    let yaw_rate = [
        state_range(truth, yaw),
        block_mean_range(truth, yaw, BLOCK),
        block_mean_range(truth, yaw, samples.max(1)),
    ];
    (arguments, yaw_rate, (run == 0).then(|| truth.clone()))
}

/// The design check from every run's measurements ([`measure`]), in the
/// order of `study::study_tasks`: merged in run order, so the figures do
/// not depend on the thread count.
pub fn collect(model: &dyn Model, config: &StudyConfig, measured: Vec<Measured>) -> DesignCheck {
    let ir = model.ir();
    let yaw = yaw_state(model);
    let samples = config.n.iter().copied().max().unwrap_or(0);
    let tasks = study::study_tasks(config);
    let mut cases: Vec<CaseCheck> = config
        .cases
        .iter()
        .map(|c| CaseCheck {
            case: c.name.clone(),
            wind: c.wind,
            arguments: ir
                .sign_args
                .iter()
                .map(|a| (a.name.clone(), Range::default()))
                .collect(),
            yaw_rate: Range::default(),
            yaw_rate_blocks: Range::default(),
            yaw_rate_runs: Range::default(),
            first: Truth::default(),
        })
        .collect();
    for ((c, _), (arguments, yaw_rate, first)) in tasks.iter().zip(measured) {
        let case = &mut cases[*c];
        for ((_, total), (_, part)) in case.arguments.iter_mut().zip(&arguments) {
            total.merge(part);
        }
        case.yaw_rate.merge(&yaw_rate[0]);
        case.yaw_rate_blocks.merge(&yaw_rate[1]);
        case.yaw_rate_runs.merge(&yaw_rate[2]);
        if let Some(truth) = first {
            case.first = truth;
        }
    }
    let system = study::true_system(0.0);
    let validation = study::validation_experiment(model, config.validation_len);
    let validation_std = ir
        .states
        .iter()
        .enumerate()
        .map(|(o, name)| {
            let mut r = Range::default();
            validation.states[o].iter().for_each(|x| r.push(*x));
            (name.clone(), r.std())
        })
        .collect();
    DesignCheck {
        experiments: config.runs,
        samples,
        cases,
        yaw_name: ir.states.get(yaw).cloned().unwrap_or_default(),
        yaw_noise_std: system.state_noise.get(yaw).copied().unwrap_or(f64::NAN),
        validation_std,
    }
}
