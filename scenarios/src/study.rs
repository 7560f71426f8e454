//! The paper's simulation study (§V): the true ship, its disturbances and
//! noises, the input designs, the Monte Carlo loop, its summaries and the
//! paper's claims checked against them. Tables and plots live in the CLI
//! (`leeway reproduce`).
//!
//! One run estimates every method on longer and longer prefixes of one
//! record, through passes continued along them ([`evaluate_continuing`]),
//! on the study engine ([`campaign`]);
//! [`run_study_inspecting`] hands each run's true trajectory to a caller
//! that measures it, as the design check does. Every run has its own seed
//! and results are merged in run order, so they do not depend on the thread
//! count.
//!
//! Input design (estimation): a static offset `τ̄` that holds the ship in a
//! steady turn with surge ≈ 5 m/s, sway ≈ 3.3 m/s and yaw rate ≈ 0.15 rad/s,
//! plus smoothed pulses of random width (20–80 s) and amplitude on each
//! thruster; the sway thrust follows the yaw pulse so a harder turn does not
//! pull sway towards zero. The ship circles (radius ≈ 39 m) with zigzags; a
//! strong yaw pulse occasionally stops or reverses the turn for a minute
//! (the yaw rate is below zero in ≈ 3.5 % of the samples), giving short
//! straight runs. Surge and sway stay well above the current (0.28 m/s) and,
//! at 1 m/s wind, above the wind (1.41 m/s), so IV2's sign assumption holds at
//! low wind and fails at 10 m/s, as in the paper; the yaw-rate excitation is
//! ≈ 7 times its measurement noise, which a 10 m/s wind's yaw moment does not
//! change. Validation: undisturbed, a zigzag-forward input whose thrust is
//! stepped too (else the surge fit would divide by ~0).

use crate::engine::{campaign, keyed_seed};
use crate::synth::{TrueSystem, Truth, experiment};
use leeway_model::experiment::Experiment;
use leeway_model::model::Model;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// θ0 of the paper's table, in `ship.som` order
/// (X_u, X_vr, X_uu, W_uu, X_tau, Y_v, Y_ur, Y_vv, Y_vr, W_vv, Y_tau, N_r, N_uv, N_vv, N_vr, W_uv, N_tau).
pub const THETA0: [f64; 17] = [
    -0.05, 1.0, -0.05, -0.0005, 0.02, -0.2, -0.65, -0.2, -0.1, -0.0015, 0.02, -0.1, -0.0015,
    -0.001, -0.04, -0.00003, 0.0003,
];

/// Mean of the current (north, east), m/s.
pub const CURRENT_MEAN: [f64; 2] = [0.2, 0.2];

/// The estimation input: a static offset plus smoothed pulses.
#[derive(Clone, Debug, PartialEq)]
pub struct InputDesign {
    /// Static offset `τ̄` (holds the steady turn).
    pub offset: [f64; 3],
    /// Pulse amplitude (half range) per thruster.
    pub pulse: [f64; 3],
    /// Pulse widths are drawn uniformly from this range (samples).
    pub width: (usize, usize),
    /// First-order smoothing factor per sample (1 = no smoothing).
    pub smoothing: f64,
    /// Initial state (the steady turn).
    pub x0: [f64; 3],
    /// Sway thrust added per unit of yaw pulse: a turn harder than the mean
    /// pulls sway down through `−Y_ur·u·r`; this keeps sway positive.
    pub sway_from_yaw: f64,
}

impl Default for InputDesign {
    fn default() -> InputDesign {
        InputDesign {
            offset: [50.0, 169.0, 235.0],
            pulse: [30.0, 40.0, 150.0],
            width: (20, 80),
            smoothing: 0.15,
            x0: [5.0, 3.3, 0.15],
            sway_from_yaw: 0.25,
        }
    }
}

/// The paper's true system with mean wind `wind` m/s in both north and east.
/// Current `N([0.2, 0.2], 1e-3·I)`, wind `N([w̄, w̄], 1e-3·I)`, i.i.d. in the
/// earth frame; `e_ν ~ N(0, 2e-4·I)`, `e_ψ ~ N(0, 1e-4)`, `e_aux ~ N(0, 1e-3·I)`.
pub fn true_system(wind: f64) -> TrueSystem {
    TrueSystem {
        theta: THETA0.to_vec(),
        h: 1.0,
        disturbance_mean: vec![CURRENT_MEAN[0], CURRENT_MEAN[1], wind, wind],
        disturbance_std: vec![1e-3f64.sqrt(); 4],
        disturbance_time: Vec::new(),
        state_noise: vec![2e-4f64.sqrt(); 3],
        heading_noise: 1e-4f64.sqrt(),
        aux_noise: vec![1e-3f64.sqrt(); 4],
        process_noise: vec![0.0; 3],
    }
}

/// The estimation input: offset plus smoothed pulses of varying width.
pub fn estimation_input(design: &InputDesign, n: usize, seed: u64) -> Vec<Vec<f64>> {
    Pulses::new(design, seed).take(n).collect()
}

/// The estimation input as an endless stream (offset plus smoothed pulses),
/// for experiments too long to hold.
#[derive(Clone, Debug)]
pub struct Pulses {
    design: InputDesign,
    rng: ChaCha8Rng,
    current: [f64; 3],
    target: [f64; 3],
    left: [usize; 3],
}

impl Pulses {
    /// The pulse stream of a design and seed.
    pub fn new(design: &InputDesign, seed: u64) -> Pulses {
        Pulses {
            design: design.clone(),
            rng: ChaCha8Rng::seed_from_u64(seed),
            current: [0.0; 3],
            target: [0.0; 3],
            left: [0; 3],
        }
    }
}

impl Iterator for Pulses {
    type Item = Vec<f64>;
    fn next(&mut self) -> Option<Vec<f64>> {
        let d = &self.design;
        for i in 0..3 {
            if self.left[i] == 0 {
                self.left[i] = self
                    .rng
                    .random_range(d.width.0..d.width.1.max(d.width.0 + 1));
                self.target[i] = d.pulse[i] * self.rng.random_range(-1.0..1.0);
            }
            self.left[i] -= 1;
            // First-order smoothing.
            self.current[i] += d.smoothing * (self.target[i] - self.current[i]);
        }
        Some(vec![
            d.offset[0] + self.current[0],
            d.offset[1] + self.current[1] + d.sway_from_yaw * self.current[2],
            d.offset[2] + self.current[2],
        ])
    }
}

/// The validation input: zigzag forward (rudder-like sway/yaw steps every
/// 50 s), with the thrust stepped between two levels every 120 s.
pub fn validation_input(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|k| {
            let zig = if (k / 50) % 2 == 0 { 1.0 } else { -1.0 };
            let thrust = if (k / 120) % 2 == 0 { 70.0 } else { 45.0 };
            vec![thrust, 40.0 * zig, 150.0 * zig]
        })
        .collect()
}

/// One estimation experiment of the study.
pub fn estimation_experiment(
    model: &dyn Model,
    design: &InputDesign,
    wind: f64,
    n: usize,
    seed: u64,
) -> (Experiment, Truth) {
    let input = estimation_input(design, n, seed ^ 0x5eed_1e57);
    experiment(
        model,
        &true_system(wind),
        &format!("run{seed}"),
        &design.x0,
        0.0,
        &input,
        seed,
    )
}

/// The undisturbed, noise-free validation experiment.
pub fn validation_experiment(model: &dyn Model, n: usize) -> Experiment {
    let mut sys = true_system(0.0);
    sys.disturbance_mean = vec![0.0; 4];
    sys.disturbance_std = vec![0.0; 4];
    sys.state_noise = vec![0.0; 3];
    sys.heading_noise = 0.0;
    sys.aux_noise = vec![0.0; 4];
    experiment(
        model,
        &sys,
        "validation",
        &[4.0, 0.0, 0.0],
        0.0,
        &validation_input(n),
        0,
    )
    .0
}

/// The identifiable aggregates of the ship's θ (in order): every parameter
/// except the wind ones, with the confounded pairs summed —
/// `X_uu + W_uu`, `Y_vv + W_vv`, `N_uv + W_uv` — which every estimator can
/// estimate whatever the wind, so all four compare on the same footing.
pub fn aggregates(theta: &[f64]) -> Vec<f64> {
    // Indices in ship.som order: W_uu = 3 pairs with X_uu = 2, W_vv = 9 with
    // Y_vv = 7, W_uv = 15 with N_uv = 12.
    let mut v = theta.to_vec();
    v[2] += theta[3];
    v[7] += theta[9];
    v[12] += theta[15];
    [0, 1, 2, 4, 5, 6, 7, 8, 10, 11, 12, 13, 14, 16]
        .iter()
        .map(|i| v[*i])
        .collect()
}

/// Mean relative error of the identifiable aggregates against θ0.
pub fn aggregate_error(theta: &[f64]) -> f64 {
    let est = aggregates(theta);
    let truth = aggregates(&THETA0);
    est.iter()
        .zip(&truth)
        .map(|(a, b)| ((a - b) / b).abs())
        .sum::<f64>()
        / truth.len() as f64
}

/// A wind case of the study.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Case {
    /// `low` or `high`.
    pub name: String,
    /// Mean wind speed in each of north and east, m/s.
    pub wind: f64,
}

/// The paper's two cases: `w̄ = 1` (low) and `w̄ = 10` m/s (high).
pub fn paper_cases() -> Vec<Case> {
    vec![
        Case {
            name: "low".into(),
            wind: 1.0,
        },
        Case {
            name: "high".into(),
            wind: 10.0,
        },
    ]
}

/// Configuration of the Monte Carlo study.
#[derive(Clone, Debug)]
pub struct StudyConfig {
    /// Monte Carlo runs per case.
    pub runs: usize,
    /// Estimation record lengths; each run's record is simulated once at the
    /// largest N and every smaller N uses its beginning, so N is "more data".
    pub n: Vec<usize>,
    /// Cases.
    pub cases: Vec<Case>,
    /// Master seed: run `r` of case `c` uses seed `(seed, c, r)`.
    pub seed: u64,
    /// The estimation input.
    pub design: InputDesign,
    /// Length of the validation record.
    pub validation_len: usize,
    /// Most refinements of the refined IV.
    pub max_refinements: usize,
    /// The refined IV as leeway runs it (delayed-instrument start, runaway
    /// guard) or as the paper describes it (nominal start, plain refinement).
    pub paper_iv: bool,
}

impl Default for StudyConfig {
    fn default() -> StudyConfig {
        StudyConfig {
            runs: 100,
            n: vec![1000, 2000, 3000, 4000, 5000],
            cases: paper_cases(),
            seed: 2024,
            design: InputDesign::default(),
            validation_len: 1000,
            max_refinements: 8,
            paper_iv: false,
        }
    }
}

/// One estimate of the study.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Outcome {
    /// θ (held parameters at nominal), if the estimator returned one.
    pub theta: Option<Vec<f64>>,
    /// Validation fit per output (surge, sway, yaw); NaN where the simulation diverged.
    pub fit: [f64; 3],
    /// The estimator failed or its model's simulation diverged on the validation input.
    pub diverged: bool,
    /// Mean relative error on the identifiable aggregates.
    pub param_error: f64,
}

/// All outcomes: `outcomes[case][run][n_index][method]` (methods in `Method::ALL` order).
#[derive(Clone, Debug)]
pub struct StudyOutcomes {
    /// The configuration.
    pub config: StudyConfig,
    /// The outcomes.
    pub outcomes: Vec<Vec<Vec<Vec<Outcome>>>>,
}

/// The seed of run `run` of a case. Keyed by the case's name (not its place
/// in the list), so a study of one case draws the same experiments as that
/// case of a study of both.
pub fn run_seed(seed: u64, case: &Case, run: usize) -> u64 {
    keyed_seed(seed, &case.name, run)
}

/// The estimator options the study uses for a method: the refined IV as in
/// [`leeway_estimate::EstimateOptions::default`], aggregated where the structure
/// requires it (IV1, IV2; IV3 at low wind holds the unexcited wind
/// parameters), no standard errors and no own simulation (only fits are
/// compared, each estimate validated on its own validation record).
pub fn study_options(
    method: leeway_estimate::Method,
    max_refinements: usize,
    paper_iv: bool,
) -> leeway_estimate::EstimateOptions {
    leeway_estimate::EstimateOptions {
        method,
        aggregate: true,
        covariance: false,
        max_refinements,
        initial: if paper_iv {
            leeway_estimate::Initial::Nominal
        } else {
            leeway_estimate::Initial::Delayed
        },
        runaway_guard: !paper_iv,
        own_simulation: false,
        ..Default::default()
    }
}

/// Estimates with every method on one record and validates each model.
///
/// `starts[m]` is method `m`'s warm start: the converged estimate of the
/// same record's shorter prefix (the refinement then starts next to its fixed
/// point rather than from the delayed bootstrap; `--paper-iv` starts every
/// estimate from the nominal model, as the paper does). It is updated with
/// this record's converged estimates.
pub fn evaluate(
    model: &dyn Model,
    data: &Experiment,
    validation: &Experiment,
    config: &StudyConfig,
    starts: &mut [Option<leeway_estimate::Start>],
) -> Vec<Outcome> {
    evaluate_continuing(model, data, validation, config, starts, &mut None, 0)
}

/// [`evaluate`] on a record that begins with the one `rows` were kept over
/// (the study's shorter prefix of the same record): the regressors of its
/// first samples are not evaluated again. `rows` is replaced by what this
/// record's passes kept, with room for a record of `longest` samples. The
/// same outcomes.
pub fn evaluate_continuing(
    model: &dyn Model,
    data: &Experiment,
    validation: &Experiment,
    config: &StudyConfig,
    starts: &mut [Option<leeway_estimate::Start>],
    rows: &mut Option<leeway_estimate::PrefixRows>,
    longest: usize,
) -> Vec<Outcome> {
    use leeway_estimate::{LocalPasses, Method, Start, estimate_with};
    use leeway_model::simulate::{Disturbances, fits, simulate};
    // One set of passes for the four methods: what one method's passes
    // compute that another's need (facts, regressor rows, headings) is kept.
    let experiments = [data as &dyn leeway_model::experiment::Source];
    let mut passes = LocalPasses::new(model, &experiments).for_several_estimates();
    if let Some(prefix) = rows.take() {
        passes = passes.continuing(prefix);
    }
    let passes = passes.reserving(longest);
    let outcomes = Method::ALL
        .iter()
        .zip(starts.iter_mut())
        .map(|(m, start)| {
            let options = leeway_estimate::EstimateOptions {
                start: if config.paper_iv { None } else { start.take() },
                ..study_options(*m, config.max_refinements, config.paper_iv)
            };
            match estimate_with(model, &passes, &options) {
                Ok(est) => {
                    if est.diagnostics.converged {
                        *start = Some(Start::from_estimate(model.ir(), &est));
                    }
                    let sim = simulate(model, &est.theta, validation, Disturbances::None);
                    let f = fits(validation, &sim);
                    let fit = [f[0], f[1], f[2]];
                    Outcome {
                        diverged: sim.diverged || fit.iter().any(|v| !v.is_finite()),
                        param_error: aggregate_error(&est.theta),
                        theta: Some(est.theta),
                        fit,
                    }
                }
                Err(_) => Outcome {
                    theta: None,
                    fit: [f64::NAN; 3],
                    diverged: true,
                    param_error: f64::NAN,
                },
            }
        })
        .collect();
    *rows = Some(passes.into_prefix_rows());
    outcomes
}

/// Runs the Monte Carlo study, in parallel over runs (rayon); `progress` is
/// called once per finished run. Results do not depend on the thread count.
pub fn run_study(
    model: &dyn Model,
    config: &StudyConfig,
    progress: &(dyn Fn() + Sync),
) -> StudyOutcomes {
    run_study_inspecting(model, config, progress, &|_, _, _| ()).0
}

/// [`run_study`], and `inspect(case, run, truth)` of each run's true
/// trajectory (the estimation record before noise), in the order of
/// [`study_tasks`]: what is measured on the records the estimators saw,
/// without simulating them again.
pub fn run_study_inspecting<T: Send>(
    model: &dyn Model,
    config: &StudyConfig,
    progress: &(dyn Fn() + Sync),
    inspect: &(dyn Fn(usize, usize, &Truth) -> T + Sync),
) -> (StudyOutcomes, Vec<T>) {
    let validation = validation_experiment(model, config.validation_len);
    let tasks = study_tasks(config);
    let (results, inspected): (Vec<Vec<Vec<Outcome>>>, Vec<T>) =
        campaign(tasks.len(), progress, &|t| {
            let (c, r) = tasks[t];
            study_run_inspecting(model, config, &validation, c, r, |truth| {
                inspect(c, r, truth)
            })
        })
        .into_iter()
        .unzip();
    (collect_outcomes(config, results), inspected)
}

/// The study's runs as `(case, run)`, cases first: the order in which
/// [`collect_outcomes`] takes their outcomes.
pub fn study_tasks(config: &StudyConfig) -> Vec<(usize, usize)> {
    (0..config.cases.len())
        .flat_map(|c| (0..config.runs).map(move |r| (c, r)))
        .collect()
}

/// One run of the study, `outcomes[n_index][method]`: run `run` of case
/// `case` simulated once at the largest N, every method estimated on each
/// prefix and validated on `validation`. A function of its arguments only,
/// so runs can be computed anywhere (threads, processes, machines).
pub fn study_run(
    model: &dyn Model,
    config: &StudyConfig,
    validation: &Experiment,
    case: usize,
    run: usize,
) -> Vec<Vec<Outcome>> {
    study_run_inspecting(model, config, validation, case, run, |_| ()).0
}

/// [`study_run`], and `inspect` of the run's true trajectory.
pub fn study_run_inspecting<T>(
    model: &dyn Model,
    config: &StudyConfig,
    validation: &Experiment,
    case: usize,
    run: usize,
    inspect: impl FnOnce(&Truth) -> T,
) -> (Vec<Vec<Outcome>>, T) {
    let n_max = config.n.iter().copied().max().unwrap_or(0);
    let (data, truth) = estimation_experiment(
        model,
        &config.design,
        config.cases[case].wind,
        n_max,
        run_seed(config.seed, &config.cases[case], run),
    );
    let inspected = inspect(&truth);
    drop(truth);
    // Record lengths in increasing order: each warm-starts the next, and
    // its regressor rows are the next one's first rows.
    let mut starts = vec![None; leeway_estimate::Method::ALL.len()];
    let mut rows = None;
    let outcomes = config
        .n
        .iter()
        .map(|&n| {
            let prefix = data.truncated(n);
            evaluate_continuing(
                model,
                &prefix,
                validation,
                config,
                &mut starts,
                &mut rows,
                n_max,
            )
        })
        .collect();
    (outcomes, inspected)
}

/// The outcomes of the runs of [`study_tasks`], in that order.
pub fn collect_outcomes(config: &StudyConfig, results: Vec<Vec<Vec<Outcome>>>) -> StudyOutcomes {
    let mut outcomes = vec![Vec::with_capacity(config.runs); config.cases.len()];
    for ((c, _), res) in study_tasks(config).iter().zip(results) {
        outcomes[*c].push(res);
    }
    StudyOutcomes {
        config: config.clone(),
        outcomes,
    }
}

/// Mean and standard deviation of the finite values.
pub fn mean_std(values: impl Iterator<Item = f64>) -> (f64, f64, usize) {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN, 0);
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 {
        v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, var.sqrt(), v.len())
}

/// Output names in the study's tables and JSON.
pub const OUTPUTS: [&str; 3] = ["surge", "sway", "yaw"];

/// Estimator names in the study's tables and JSON, in `Method::ALL` order.
pub const ESTIMATORS: [&str; 4] = ["LS", "IV1", "IV2", "IV3"];

/// One estimator's figures in one case, arrays aligned with `N`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct EstimatorSummary {
    /// Mean validation fit per output (over runs whose model did not diverge).
    pub fit_mean: std::collections::BTreeMap<String, Vec<f64>>,
    /// Standard deviation of the fit per output.
    pub fit_std: std::collections::BTreeMap<String, Vec<f64>>,
    /// Median fit per output (robust to the occasional wild run).
    pub fit_median: std::collections::BTreeMap<String, Vec<f64>>,
    /// Mean relative error on the identifiable aggregates.
    pub param_error: Vec<f64>,
    /// Median of that error.
    pub param_error_median: Vec<f64>,
    /// Runs whose estimate failed or whose model diverged on the validation input.
    pub diverged: Vec<usize>,
}

/// One case's figures.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CaseSummary {
    /// Mean wind, m/s.
    pub wind: f64,
    /// Record lengths.
    #[serde(rename = "N")]
    pub n: Vec<usize>,
    /// By estimator name (`LS`, `IV1`, `IV2`, `IV3`).
    pub estimators: std::collections::BTreeMap<String, EstimatorSummary>,
}

/// The median of the finite values (NaN when there are none).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Summarises the outcomes per case (in a fixed order: bit-identical for the
/// same outcomes).
pub fn summarise(out: &StudyOutcomes) -> std::collections::BTreeMap<String, CaseSummary> {
    let cfg = &out.config;
    let mut cases = std::collections::BTreeMap::new();
    for (c, case) in cfg.cases.iter().enumerate() {
        let mut estimators = std::collections::BTreeMap::new();
        for (mi, name) in ESTIMATORS.iter().enumerate() {
            let mut s = EstimatorSummary::default();
            for (k, output) in OUTPUTS.iter().enumerate() {
                let (mut means, mut stds, mut medians) = (Vec::new(), Vec::new(), Vec::new());
                for ni in 0..cfg.n.len() {
                    let fits = out.outcomes[c]
                        .iter()
                        .map(|r| &r[ni][mi])
                        .filter(|o| !o.diverged)
                        .map(|o| o.fit[k]);
                    let (m, sd, _) = mean_std(fits.clone());
                    means.push(m);
                    stds.push(sd);
                    medians.push(median(fits.collect()));
                }
                s.fit_mean.insert(output.to_string(), means);
                s.fit_std.insert(output.to_string(), stds);
                s.fit_median.insert(output.to_string(), medians);
            }
            for ni in 0..cfg.n.len() {
                let runs: Vec<&Outcome> = out.outcomes[c].iter().map(|r| &r[ni][mi]).collect();
                s.param_error
                    .push(mean_std(runs.iter().filter(|o| !o.diverged).map(|o| o.param_error)).0);
                s.param_error_median.push(median(
                    runs.iter()
                        .filter(|o| !o.diverged)
                        .map(|o| o.param_error)
                        .collect(),
                ));
                s.diverged.push(runs.iter().filter(|o| o.diverged).count());
            }
            estimators.insert(name.to_string(), s);
        }
        cases.insert(
            case.name.clone(),
            CaseSummary {
                wind: case.wind,
                n: cfg.n.clone(),
                estimators,
            },
        );
    }
    cases
}

/// One of the paper's claims, checked against the study's figures.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Claim {
    /// `a`, `b`, `c`, `d`.
    pub id: String,
    /// The paper's statement.
    pub statement: String,
    /// How it is checked.
    pub criterion: String,
    /// Whether the figures bear it out (`None` when a needed case was not run).
    pub holds: Option<bool>,
    /// The figures behind the verdict.
    pub evidence: String,
}

fn mean_fit(s: &EstimatorSummary, ni: usize) -> f64 {
    OUTPUTS.iter().map(|o| s.fit_mean[*o][ni]).sum::<f64>() / OUTPUTS.len() as f64
}

fn fits_text(s: &EstimatorSummary, ni: usize) -> String {
    OUTPUTS
        .iter()
        .map(|o| format!("{:.1}", s.fit_mean[*o][ni]))
        .collect::<Vec<_>>()
        .join("/")
}

/// Checks the paper's four claims (§V) against the summaries. Criteria:
/// (a) at the smallest N, LS's mean fit (averaged over the outputs) is at
///     least IV2's and IV3's, and at the largest N both exceed LS;
/// (b) at low wind and the largest N, IV2 and IV3 are within 2 fit points in
///     every output;
/// (c) at high wind and the largest N, IV3 beats IV2 by more than 2 points in
///     surge, surge is where IV2 loses most, and IV3 stays within 5 points of
///     its low-wind fit in every output;
/// (d) IV1's mean fit is below IV2's and IV3's by more than 10 points in
///     surge or sway at every N of every case.
pub fn claims(cases: &std::collections::BTreeMap<String, CaseSummary>) -> Vec<Claim> {
    vec![
        claim_a(cases),
        claim_b(cases),
        claim_c(cases),
        claim_d(cases),
    ]
}

/// An estimator's summary in a case (empty when it was not run).
fn est(case: &CaseSummary, name: &str) -> EstimatorSummary {
    case.estimators.get(name).cloned().unwrap_or_default()
}

/// Claim (a): LS fits best at the smallest N; IV2 and IV3 overtake it.
fn claim_a(cases: &std::collections::BTreeMap<String, CaseSummary>) -> Claim {
    let mut holds_a = None;
    let mut ev_a = Vec::new();
    for (name, case) in cases {
        let (ls, iv2, iv3) = (est(case, "LS"), est(case, "IV2"), est(case, "IV3"));
        let last = case.n.len().saturating_sub(1);
        if case.n.is_empty() {
            continue;
        }
        let small = mean_fit(&ls, 0) >= mean_fit(&iv2, 0).max(mean_fit(&iv3, 0));
        let large = mean_fit(&iv2, last).min(mean_fit(&iv3, last)) > mean_fit(&ls, last);
        let breakpoint = (0..case.n.len())
            .find(|&i| mean_fit(&iv2, i).min(mean_fit(&iv3, i)) > mean_fit(&ls, i))
            .map(|i| case.n[i]);
        holds_a = Some(holds_a.unwrap_or(true) && small && large);
        ev_a.push(format!(
            "{name}: N = {} LS {} vs IV2 {} IV3 {}; N = {} LS {} vs IV2 {} IV3 {}; IV2 and IV3 both above LS from N = {}",
            case.n[0],
            fits_text(&ls, 0),
            fits_text(&iv2, 0),
            fits_text(&iv3, 0),
            case.n[last],
            fits_text(&ls, last),
            fits_text(&iv2, last),
            fits_text(&iv3, last),
            breakpoint.map_or("no N run".to_string(), |n| n.to_string())
        ));
    }
    Claim {
        id: "a".into(),
        statement: "LS fits best at the smallest N; IV2 and IV3 overtake it beyond a breakpoint".into(),
        criterion: "mean fit over outputs: LS ≥ IV2, IV3 at the smallest N, and IV2, IV3 > LS at the largest N, in every case".into(),
        holds: holds_a,
        evidence: ev_a.join("; "),
    }
}

/// Claim (b): At low wind IV2 and IV3 perform equally well.
fn claim_b(cases: &std::collections::BTreeMap<String, CaseSummary>) -> Claim {
    let (holds_b, ev_b) = match cases.get("low") {
        Some(case) if !case.n.is_empty() => {
            let last = case.n.len() - 1;
            let (iv2, iv3) = (est(case, "IV2"), est(case, "IV3"));
            let gaps: Vec<f64> = OUTPUTS
                .iter()
                .map(|o| (iv2.fit_mean[*o][last] - iv3.fit_mean[*o][last]).abs())
                .collect();
            (
                Some(gaps.iter().all(|g| *g <= 2.0)),
                format!(
                    "low wind, N = {}: IV2 {} vs IV3 {} (largest gap {:.1})",
                    case.n[last],
                    fits_text(&iv2, last),
                    fits_text(&iv3, last),
                    gaps.iter().copied().fold(0.0, f64::max)
                ),
            )
        }
        _ => (None, "the low-wind case was not run".to_string()),
    };
    Claim {
        id: "b".into(),
        statement: "at low wind IV2 and IV3 perform equally well".into(),
        criterion: "low wind, largest N: |IV2 − IV3| ≤ 2 fit points in every output".into(),
        holds: holds_b,
        evidence: ev_b,
    }
}

/// Claim (c): At high wind IV2 degrades, in surge most, while IV3 stays good.
fn claim_c(cases: &std::collections::BTreeMap<String, CaseSummary>) -> Claim {
    let (holds_c, ev_c) = match (cases.get("high"), cases.get("low")) {
        (Some(high), Some(low)) if !high.n.is_empty() && !low.n.is_empty() => {
            let (lh, ll) = (high.n.len() - 1, low.n.len() - 1);
            let (iv2, iv3, iv3_low) = (est(high, "IV2"), est(high, "IV3"), est(low, "IV3"));
            let loss: Vec<f64> = OUTPUTS
                .iter()
                .map(|o| iv3.fit_mean[*o][lh] - iv2.fit_mean[*o][lh])
                .collect();
            let stays = OUTPUTS
                .iter()
                .all(|o| iv3.fit_mean[*o][lh] >= iv3_low.fit_mean[*o][ll] - 5.0);
            let surge_most = loss[0] >= loss[1] && loss[0] >= loss[2];
            (
                Some(loss[0] > 2.0 && surge_most && stays),
                format!(
                    "high wind, N = {}: IV2 {} vs IV3 {} (IV2 loses {:.1}/{:.1}/{:.1}); IV3 at low wind {}",
                    high.n[lh],
                    fits_text(&iv2, lh),
                    fits_text(&iv3, lh),
                    loss[0],
                    loss[1],
                    loss[2],
                    fits_text(&iv3_low, ll)
                ),
            )
        }
        _ => (
            None,
            "needs both the low- and the high-wind case".to_string(),
        ),
    };
    Claim {
        id: "c".into(),
        statement: "at high wind IV2 degrades, in surge most, while IV3 stays good".into(),
        criterion: "high wind, largest N: IV3 − IV2 > 2 points in surge, largest in surge, and IV3 within 5 points of its low-wind fit".into(),
        holds: holds_c,
        evidence: ev_c,
    }
}

/// Claim (d): IV1 fits poorly.
fn claim_d(cases: &std::collections::BTreeMap<String, CaseSummary>) -> Claim {
    let mut holds_d = None;
    let mut ev_d = Vec::new();
    for (name, case) in cases {
        let (iv1, iv2, iv3) = (est(case, "IV1"), est(case, "IV2"), est(case, "IV3"));
        let poor = (0..case.n.len()).all(|i| {
            ["surge", "sway"]
                .iter()
                .any(|o| iv1.fit_mean[*o][i] < iv2.fit_mean[*o][i].min(iv3.fit_mean[*o][i]) - 10.0)
        });
        holds_d = Some(holds_d.unwrap_or(true) && poor);
        let last = case.n.len().saturating_sub(1);
        if !case.n.is_empty() {
            ev_d.push(format!(
                "{name}, N = {}: IV1 {} (diverged {}) vs IV3 {}",
                case.n[last],
                fits_text(&iv1, last),
                iv1.diverged[last],
                fits_text(&iv3, last)
            ));
        }
    }
    Claim {
        id: "d".into(),
        statement: "IV1 fits poorly".into(),
        criterion: "IV1 more than 10 points below IV2 and IV3 in surge or sway at every N".into(),
        holds: holds_d,
        evidence: ev_d.join("; "),
    }
}
