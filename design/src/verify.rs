//! `--verify M`: the Monte Carlo study of a design, for any model. Each run
//! realises every experiment of the design (the plan's random disturbances
//! and noise, seeded by the run's index), estimates with every method, and
//! validates each estimate on a held-out manoeuvre; the summary sets the
//! spread of the estimates against the predicted standard errors (coverage
//! of ±2σ), the signs actually kept, rank deficiencies and fits. Runs go
//! through the study engine `leeway_scenarios::engine::campaign`, as
//! `leeway reproduce` does.

use crate::predict::Noise;
use crate::report::Design;
use crate::signs::Held;
use crate::trial::{Run, draw_theta, kept, simulate, true_system};
use leeway_estimate::{Estimate, EstimateOptions, Method, estimate};
use leeway_model::experiment::{Experiment, Source};
use leeway_model::model::Model;
use leeway_model::simulate::{Disturbances, fits};
use leeway_scenarios::engine::{campaign, keyed_seed};
use leeway_scenarios::synth::TrueSystem;
use leeway_structure::identify::Centring;
use serde::{Deserialize, Serialize};

/// The verification of a design.
#[derive(Clone, Debug, Serialize)]
pub struct Verification {
    /// Monte Carlo runs.
    pub runs: usize,
    /// Master seed.
    pub seed: u64,
    /// Samples per experiment.
    pub samples: usize,
    /// Per experiment and held argument: the fraction of samples on its side.
    pub signs: Vec<SignKept>,
    /// Per method.
    pub methods: Vec<MethodVerification>,
    /// The true model's fit per state on the held-out run (θ of the plan,
    /// the plan's mean disturbances): what an estimated model is measured
    /// against.
    pub true_fits: Vec<(String, f64)>,
    /// The seconds of the held-out run's first part ([`EARLY`] of it)
    /// whose fits are measured as well: how the fit falls with the length
    /// of the free run.
    pub early_seconds: f64,
    /// The true model's fit per state over that first part.
    pub true_early_fits: Vec<(String, f64)>,
    /// Whether the designed method's models are what the user needs.
    pub verdict: Verdict,
    /// With the other runs the design tried verified after a failing
    /// verdict ([`crate::verified`]): each option verified, in order, the
    /// design's first (empty when only the design was verified).
    pub runs_verified: Vec<RunsVerified>,
}

/// One runs option of a design, verified.
#[derive(Clone, Debug, Serialize)]
pub struct RunsVerified {
    /// Runs.
    pub runs: usize,
    /// What sets the runs apart: `speed`, `sign pattern`, or null (one run).
    pub differ_by: Option<String>,
    /// The estimate's centring: `experiment`, `pooled`, `none`.
    pub centring: String,
    /// Seconds per run.
    pub seconds: f64,
    /// Whether its verified models passed the verdict (`None`: not
    /// verified, the design did not keep its signs or its area).
    pub passed: Option<bool>,
    /// What failed, one line each.
    pub failures: Vec<String>,
    /// Whether it is the design reported.
    pub taken: bool,
}

impl RunsVerified {
    /// The runs of `design` with their verification.
    pub fn of(design: &Design, v: Option<&Verification>) -> RunsVerified {
        let chosen = design.runs_tried.iter().find(|o| o.chosen);
        RunsVerified {
            runs: chosen.map_or(design.runs.len(), |o| o.runs),
            differ_by: chosen.and_then(|o| o.differ_by.clone()),
            centring: chosen.map_or_else(
                || design.centring_used.map_or("-", |c| c.name()).to_string(),
                |o| o.centring.clone(),
            ),
            seconds: design.seconds,
            passed: v.map(|v| v.verdict.passed),
            failures: v.map_or(Vec::new(), |v| v.verdict.failures.clone()),
            taken: false,
        }
    }
}

/// The outcome judged: the designed method's held-out fit within
/// [`FIT_POINTS`] of the true model's in every state, and (with at least
/// [`COVERAGE_TRIALS`] trials) every parameter's ±2σ coverage within
/// [`COVERAGE`].
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    /// Every criterion met.
    pub passed: bool,
    /// What fails, one line each.
    pub failures: Vec<String>,
    /// What would help.
    pub help: Vec<String>,
}

/// Points of fit an estimated model may lose against the true model's on
/// the held-out run.
pub const FIT_POINTS: f64 = 10.0;
/// The band ±2σ_predicted must cover (a calibrated σ covers 95 %).
pub const COVERAGE: (f64, f64) = (0.90, 0.98);
/// Trials below which coverage is reported but not judged: its sampling
/// error (±2.2 points at 100 trials) would exceed the band.
pub const COVERAGE_TRIALS: usize = 100;
/// The chance, were the true coverage at the band's nearer edge, below
/// which a measured coverage fails ([`coverage_outside`]).
pub const COVERAGE_TEST: f64 = 0.05;

/// Whether a coverage measured on `n` trials lies outside [`COVERAGE`]
/// beyond its sampling error: as few covered (or as many) would happen
/// with a chance below [`COVERAGE_TEST`] were the true coverage at the
/// band's nearer edge (a one-sided binomial test). At 100 trials: below
/// 85 % fails; no count above the band does (100 of 100 happens 13 % of
/// the time at 98 %).
pub fn coverage_outside(coverage: f64, n: usize) -> bool {
    let (low, high) = covered_limits(n);
    coverage < low - 1e-12 || coverage > high + 1e-12
}

/// The smallest and largest coverage on `n` trials that pass
/// [`coverage_outside`].
pub fn covered_limits(n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    // Smallest k with P(X ≤ k | p = low) ≥ the test's level.
    let low = (0..=n)
        .find(|k| binomial_cdf(*k, n, COVERAGE.0) >= COVERAGE_TEST)
        .unwrap_or(0);
    // Largest k with P(X ≥ k | p = high) ≥ the level.
    let high = (0..=n)
        .rev()
        .find(|k| *k == 0 || 1.0 - binomial_cdf(k - 1, n, COVERAGE.1) >= COVERAGE_TEST)
        .unwrap_or(n);
    (low as f64 / n as f64, high as f64 / n as f64)
}

/// P(X ≤ k) for X binomial with `n` trials of chance `p` (0 < p < 1),
/// summed in logs.
fn binomial_cdf(k: usize, n: usize, p: f64) -> f64 {
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    let mut ln_choose = 0.0;
    let mut sum = 0.0;
    for i in 0..=k.min(n) {
        if i > 0 {
            ln_choose += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        sum += (ln_choose + i as f64 * lp + (n - i) as f64 * lq).exp();
    }
    sum.min(1.0)
}
/// The share of trials whose model may diverge on the held-out run.
pub const DIVERGED: f64 = 0.05;
/// The share of the held-out run, from its start, over which the fits are
/// also measured.
pub const EARLY: f64 = 0.1;

/// How often a held argument kept its side.
#[derive(Clone, Debug, Serialize)]
pub struct SignKept {
    /// Experiment, from 1.
    pub experiment: usize,
    /// `water.u`.
    pub argument: String,
    /// Mean over runs of the fraction of samples on its side.
    pub mean: f64,
    /// The smallest such fraction of any run.
    pub min: f64,
}

/// One method's figures over the runs.
#[derive(Clone, Debug, Serialize)]
pub struct MethodVerification {
    /// `iv3`.
    pub method: String,
    /// The method the design was made for.
    pub designed_for: bool,
    /// Runs whose estimate failed.
    pub failed: usize,
    /// The first failure's message.
    pub failure: Option<String>,
    /// Runs whose data left a column unexcited or the system rank deficient.
    pub rank_deficient: usize,
    /// Per θ.
    pub parameters: Vec<ParameterVerification>,
    /// Mean validation fit per state (%), over runs whose model did not diverge.
    pub fits: Vec<(String, f64)>,
    /// The same over the held-out run's first part ([`EARLY`]).
    pub early_fits: Vec<(String, f64)>,
    /// Runs whose model diverged on the validation run.
    pub diverged: usize,
    /// Runs whose refinement did not settle (the runaway guard stopped it
    /// and reported an earlier iterate): their estimates are the tails of
    /// the spread.
    pub unconverged: usize,
}

/// One θ over the runs.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterVerification {
    /// Its name.
    pub name: String,
    /// The true value (the plan's nominal).
    pub truth: f64,
    /// Mean of the estimates.
    pub mean: f64,
    /// Their standard deviation (the verified standard error).
    pub std: f64,
    /// The design's predicted standard error.
    pub predicted: Option<f64>,
    /// Fraction of runs with `|θ̂ − θ0| ≤ 2σ_predicted`.
    pub coverage: Option<f64>,
    /// The estimator's own standard error, averaged over the runs (the
    /// designed method only).
    pub reported: Option<f64>,
}

/// One method's estimate in a run as the summary reads it, or why it
/// failed.
pub type Outcome = Result<Estimated, String>;

/// What the summary reads of one estimate: plain data, so that a run can
/// be made on another machine ([`crate::distributed`]) and summarised here.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Estimated {
    /// θ̂.
    pub theta: Vec<f64>,
    /// The estimator's own standard errors.
    pub std_errors: Vec<Option<f64>>,
    /// The data left the system rank deficient, or a θ not excited that
    /// the design did not plan to hold.
    pub rank_deficient: bool,
    /// The refinement settled (not stopped by the runaway guard).
    pub converged: bool,
    /// Validation fits per state (`None`: the model diverged).
    pub fits: Option<Vec<f64>>,
    /// The same over the held-out run's first part ([`EARLY`]).
    #[serde(default)]
    pub early_fits: Option<Vec<f64>>,
}

/// One run's results: per method the estimate (or its error), per
/// experiment and held argument the fraction kept.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunResult {
    /// The run's true θ (drawn from the plan's prior; the nominal without one).
    #[serde(default)]
    pub truth: Vec<f64>,
    /// With a prior: the true model's fit per state on the run's own
    /// held-out run (realised with its θ); without one, the bench's.
    #[serde(default)]
    pub true_fits: Option<Vec<f64>>,
    /// The same over the held-out run's first part ([`EARLY`]).
    #[serde(default)]
    pub true_early_fits: Option<Vec<f64>>,
    /// Per method, in the order of `Method::ALL`.
    pub estimates: Vec<Outcome>,
    /// Per experiment and held argument, the fraction of samples on its side.
    pub kept: Vec<Vec<f64>>,
}

/// What every run of a verification shares: the noise designed for, the
/// validation run, the methods and the one designed for.
pub struct Bench<'a> {
    noise: &'a Noise,
    validation: Experiment,
    true_fits: (Vec<f64>, Vec<f64>),
    methods: &'static [Method],
    designed: Method,
}

impl<'a> Bench<'a> {
    /// The bench of `design`; `None` when the design has nothing to verify
    /// (no noise resolved, no validation run or no method).
    pub fn new(model: &dyn Model, design: &'a Design) -> Option<Bench<'a>> {
        let noise = design.noise_used.as_ref()?;
        let validation = validation_experiment(model, design, noise)?;
        let true_fits = true_fits(model, design, &validation)?;
        Some(Bench {
            noise,
            validation,
            true_fits,
            methods: &Method::ALL,
            designed: design.method_used?,
        })
    }

    /// Run `r` of a verification seeded by `seed`.
    pub fn run(&self, model: &dyn Model, design: &Design, seed: u64, r: usize) -> RunResult {
        one_run(
            model,
            design,
            self.noise,
            &self.validation,
            self.methods,
            self.designed,
            keyed_seed(seed, "verify", r),
        )
    }

    /// The verification from every run's results, in run order.
    pub fn summarise(
        &self,
        model: &dyn Model,
        design: &Design,
        seed: u64,
        results: &[RunResult],
    ) -> Verification {
        summarise(
            model,
            design,
            (self.methods, self.designed),
            (&self.true_fits.0, &self.true_fits.1),
            seed,
            results,
        )
    }
}

/// Verifies `design` by `runs` Monte Carlo runs, seeded by `seed`;
/// `progress` is called after each run.
pub fn verify(
    model: &dyn Model,
    design: &Design,
    runs: usize,
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Option<Verification> {
    let bench = Bench::new(model, design)?;
    let results = campaign(runs, progress, &|r| bench.run(model, design, seed, r));
    Some(bench.summarise(model, design, seed, &results))
}

fn one_run(
    model: &dyn Model,
    design: &Design,
    noise: &Noise,
    validation: &Experiment,
    methods: &[Method],
    designed: Method,
    seed: u64,
) -> RunResult {
    let Some(c) = design.conditions.as_ref() else {
        return RunResult {
            truth: Vec::new(),
            true_fits: None,
            true_early_fits: None,
            estimates: Vec::new(),
            kept: Vec::new(),
        };
    };
    let truth = draw_theta(c, keyed_seed(seed, "theta", 0));
    let system = TrueSystem {
        theta: truth.clone(),
        ..true_system(c, &noise.states, noise.heading, true)
    };
    // With a prior the held-out run is the run's own, realised with its θ.
    let own = (c.prior > 0.0)
        .then_some(design.validation.as_ref())
        .flatten()
        .map(|run| {
            let held_out = simulate(
                model,
                &system,
                run,
                "validation",
                0.0,
                keyed_seed(seed, "held-out", 0),
            )
            .0;
            let sim = leeway_model::simulate::simulate(
                model,
                &truth,
                &held_out,
                Disturbances::Constant(&c.mean),
            );
            let f = window_fits(&held_out, &sim);
            (held_out, f)
        });
    let validation = own.as_ref().map_or(validation, |(v, _)| v);
    let mut experiments = Vec::new();
    let mut kept_fractions = Vec::new();
    for (e, (run, held)) in design.runs.iter().zip(&design.held).enumerate() {
        let (exp, truth) = simulate(
            model,
            &system,
            run,
            &format!("run{}", e + 1),
            0.0,
            keyed_seed(seed, "experiment", e),
        );
        kept_fractions.push(kept(model, &truth, &run.inputs, held));
        experiments.push(exp);
    }
    let sources: Vec<&dyn Source> = experiments.iter().map(|e| e as &dyn Source).collect();
    let estimates = methods
        .iter()
        .map(|m| {
            let options = EstimateOptions {
                method: *m,
                centring: centring_for(design, *m),
                aggregate: design.aggregate,
                // The designed method's own standard errors, averaged over
                // the runs, say whether the estimator's σ is calibrated.
                covariance: *m == designed,
                own_simulation: false,
                ..Default::default()
            };
            let est = estimate(model, &sources, &options)
                .map_err(|e| format!("{}: {}", e.code, e.message))?;
            let (fits, early_fits) = validate(model, &est, validation).unzip();
            Ok(Estimated {
                rank_deficient: deficient(&est, &held_by_design(design)),
                converged: est.diagnostics.converged,
                theta: est.theta,
                std_errors: est.std_errors,
                fits,
                early_fits,
            })
        })
        .collect();
    RunResult {
        truth,
        true_fits: own.as_ref().map(|(_, f)| f.0.clone()),
        true_early_fits: own.map(|(_, f)| f.1),
        estimates,
        kept: kept_fractions,
    }
}

/// The held-out run: the design's manoeuvre over the inputs' ranges,
/// realised as a trial would log it (the plan's random disturbances and
/// noise, from its own seed).
fn validation_experiment(model: &dyn Model, design: &Design, noise: &Noise) -> Option<Experiment> {
    let c = design.conditions.as_ref()?;
    let run: &Run = design.validation.as_ref()?;
    let system = true_system(c, &noise.states, noise.heading, true);
    let seed = keyed_seed(0, "held-out", 0);
    Some(simulate(model, &system, run, "validation", 0.0, seed).0)
}

/// The true model's fit per state on the held-out run: θ of the plan with
/// the plan's mean disturbances (what no estimate can beat: the rest is
/// the random disturbance and the noise).
fn true_fits(
    model: &dyn Model,
    design: &Design,
    validation: &Experiment,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let c = design.conditions.as_ref()?;
    let sim = leeway_model::simulate::simulate(
        model,
        &c.theta,
        validation,
        Disturbances::Constant(&c.mean),
    );
    Some(window_fits(validation, &sim))
}

/// Fits per state over the whole run and over its first [`EARLY`].
fn window_fits(
    data: &Experiment,
    sim: &leeway_model::simulate::Trajectory,
) -> (Vec<f64>, Vec<f64>) {
    let whole = fits(data, sim);
    let early = data
        .states
        .iter()
        .zip(&sim.states)
        .map(|(y, s)| {
            let n = y.len().min(s.len());
            let k = early_samples(n);
            leeway_model::simulate::fit(&y[..k], &s[..k])
        })
        .collect();
    (whole, early)
}

/// Samples in the first [`EARLY`] of `n` (at least 2, at most `n`).
fn early_samples(n: usize) -> usize {
    ((EARLY * n as f64).round() as usize).clamp(2.min(n), n)
}

/// Fits per state of `est` simulated on `validation` with its disturbance
/// means held; `None` when it diverged.
fn validate(
    model: &dyn Model,
    est: &Estimate,
    validation: &Experiment,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let ir = model.ir();
    let means: Vec<f64> = ir
        .components
        .iter()
        .map(|comp| {
            let medium = &ir.disturbances[comp.disturbance].name;
            est.disturbances
                .iter()
                .find(|d| &d.disturbance == medium && d.component == comp.name)
                .map_or(0.0, |d| d.mean)
        })
        .collect();
    let sim = leeway_model::simulate::simulate(
        model,
        &est.theta,
        validation,
        Disturbances::Constant(&means),
    );
    let f = window_fits(validation, &sim);
    (!sim.diverged && f.0.iter().all(|v| v.is_finite())).then_some(f)
}

fn summarise(
    model: &dyn Model,
    design: &Design,
    (methods, designed): (&[Method], Method),
    (true_fits, true_early): (&[f64], &[f64]),
    seed: u64,
    results: &[RunResult],
) -> Verification {
    let ir = model.ir();
    let runs = results.len();
    let signs = design
        .held
        .iter()
        .enumerate()
        .flat_map(|(e, held): (usize, &Vec<Held>)| {
            held.iter().enumerate().map(move |(a, h)| {
                let fr: Vec<f64> = results
                    .iter()
                    .filter_map(|r| r.kept.get(e).and_then(|k| k.get(a)).copied())
                    .collect();
                SignKept {
                    experiment: e + 1,
                    argument: h.name.clone(),
                    mean: fr.iter().sum::<f64>() / fr.len().max(1) as f64,
                    min: fr.iter().copied().fold(f64::INFINITY, f64::min),
                }
            })
        })
        .collect();
    let predicted = design.predicted.as_ref().map(|p| p.at(design.samples));
    let methods: Vec<MethodVerification> = methods
        .iter()
        .enumerate()
        .map(|(mi, m)| {
            let outcomes: Vec<&Outcome> =
                results.iter().filter_map(|r| r.estimates.get(mi)).collect();
            let ok: Vec<(&Estimated, &[f64])> = results
                .iter()
                .filter_map(|r| match r.estimates.get(mi) {
                    Some(Ok(e)) => Some((e, r.truth.as_slice())),
                    _ => None,
                })
                .collect();
            let failure = outcomes.iter().find_map(|o| o.as_ref().err().cloned());
            let rank_deficient = ok.iter().filter(|e| e.0.rank_deficient).count();
            let parameters = ir
                .parameters
                .iter()
                .enumerate()
                .map(|(p, param)| {
                    let truth = design.conditions.as_ref().map_or(f64::NAN, |c| c.theta[p]);
                    // Each estimate's error against its run's own θ, set
                    // about the nominal (the same values without a prior).
                    let values: Vec<f64> = ok
                        .iter()
                        .map(|(e, own)| match own.get(p) {
                            Some(t) if *t != truth => truth + (e.theta[p] - t),
                            _ => e.theta[p],
                        })
                        .collect();
                    let (mean, std) = mean_std(&values);
                    let sigma = if *m == designed {
                        predicted.as_ref().and_then(|s| s[p])
                    } else {
                        None
                    };
                    let coverage = sigma.filter(|_| !values.is_empty()).map(|s| {
                        values
                            .iter()
                            .filter(|v| (*v - truth).abs() <= 2.0 * s)
                            .count() as f64
                            / values.len() as f64
                    });
                    let own: Vec<f64> = ok.iter().filter_map(|e| e.0.std_errors[p]).collect();
                    let reported = (!own.is_empty()).then(|| mean_std(&own).0);
                    ParameterVerification {
                        name: param.name.clone(),
                        truth,
                        mean,
                        std,
                        predicted: sigma,
                        coverage,
                        reported,
                    }
                })
                .collect();
            let fitted: Vec<&Vec<f64>> = ok.iter().filter_map(|e| e.0.fits.as_ref()).collect();
            let early: Vec<&Vec<f64>> = ok.iter().filter_map(|e| e.0.early_fits.as_ref()).collect();
            let fits = per_state(ir, &fitted);
            let early_fits = per_state(ir, &early);
            MethodVerification {
                method: m.name().to_string(),
                designed_for: *m == designed,
                failed: outcomes.len() - ok.len(),
                failure,
                rank_deficient,
                parameters,
                fits,
                early_fits,
                diverged: ok.len() - fitted.len(),
                unconverged: ok.iter().filter(|e| !e.0.converged).count(),
            }
        })
        .collect();
    // With a prior each run has its own true model: their mean fit.
    let truths = |own: Vec<&Vec<f64>>, bench: &[f64]| -> Vec<(String, f64)> {
        if own.is_empty() {
            ir.states
                .iter()
                .enumerate()
                .map(|(s, name)| (name.clone(), bench.get(s).copied().unwrap_or(f64::NAN)))
                .collect()
        } else {
            per_state(ir, &own)
        }
    };
    let true_fits = truths(
        results
            .iter()
            .filter_map(|r| r.true_fits.as_ref())
            .collect(),
        true_fits,
    );
    let true_early_fits = truths(
        results
            .iter()
            .filter_map(|r| r.true_early_fits.as_ref())
            .collect(),
        true_early,
    );
    let early_seconds = design.step * early_samples(design.samples) as f64;
    let verdict = judge(
        design,
        &methods,
        (&true_fits, &true_early_fits, early_seconds),
        runs,
    );
    Verification {
        runs,
        seed,
        samples: design.samples,
        signs,
        methods,
        true_fits,
        early_seconds,
        true_early_fits,
        verdict,
        runs_verified: Vec::new(),
    }
}

/// The outcome of the designed method against [`FIT_POINTS`],
/// [`DIVERGED`] and [`COVERAGE`], with what would help.
fn judge(
    design: &Design,
    methods: &[MethodVerification],
    (true_fits, true_early, early_seconds): (&[StateFit], &[StateFit], f64),
    runs: usize,
) -> Verdict {
    let pct = |x: f64| leeway_model::number::short_number(100.0 * x);
    let mut failures = Vec::new();
    let mut help = Vec::new();
    let Some(m) = methods.iter().find(|m| m.designed_for) else {
        return Verdict {
            passed: false,
            failures: vec!["the designed method was not verified".into()],
            help,
        };
    };
    let estimated = runs - m.failed;
    if m.failed > 0 {
        failures.push(format!("{} of {runs} estimates failed", m.failed));
    }
    let short: Vec<String> = m
        .fits
        .iter()
        .zip(true_fits)
        // A NaN fit (no model simulated the run) falls short too.
        .filter(|((_, f), (_, t))| f.is_nan() || *f < t - FIT_POINTS)
        .map(|((name, f), (_, t))| {
            format!(
                "{name} {} % against {} %",
                leeway_model::number::short_number(*f),
                leeway_model::number::short_number(*t)
            )
        })
        .collect();
    if !short.is_empty() {
        failures.push(format!(
            "held-out fit more than {} points below the true model's: {}",
            FIT_POINTS,
            short.join(", ")
        ));
    }
    if m.diverged as f64 > DIVERGED * estimated.max(1) as f64 {
        failures.push(format!(
            "{} of {estimated} models diverge on the held-out run (at most {} % may)",
            m.diverged,
            pct(DIVERGED)
        ));
    }
    if runs >= COVERAGE_TRIALS {
        // Outside the band beyond the sampling error of the trials: the
        // count covered is improbable (one-sided binomial, < 5 %) were the
        // true coverage at the band's nearer edge.
        let outside: Vec<String> = m
            .parameters
            .iter()
            .filter_map(|p| p.coverage.map(|c| (p, c)))
            .filter(|(_, c)| coverage_outside(*c, estimated))
            .map(|(p, c)| format!("{} {} %", p.name, pct(c)))
            .collect();
        if !outside.is_empty() {
            let n = estimated;
            failures.push(format!(
                "±2σ coverage outside {}–{} % beyond the sampling error of {n} trials (below {} % or above {} %): {}",
                pct(COVERAGE.0),
                pct(COVERAGE.1),
                pct(covered_limits(n).0),
                pct(covered_limits(n).1),
                outside.join(", ")
            ));
            help.push(
                "coverage below the band: the spread exceeds the predicted σ (more pilot trials or a longer run); above it: σ is conservative".into(),
            );
        }
    }
    if m.unconverged > 0 && !failures.is_empty() {
        help.push(format!(
            "{} of {estimated} refinements stopped at an earlier iterate (unsettled): their models are the tails; a longer run or a calmer medium settles them",
            m.unconverged
        ));
    }
    if !failures.is_empty() {
        let poor: Vec<&str> = design
            .prediction
            .as_ref()
            .map(|p| {
                p.poorly_determined
                    .iter()
                    .map(|q| q.name.as_str())
                    .collect()
            })
            .unwrap_or_default();
        if !poor.is_empty() {
            help.push(format!(
                "poorly determined at this budget: {} — a longer budget (the predicted curve gives the run it needs) or wider input ranges",
                poor.join(", ")
            ));
        }
        let tried: Vec<String> = design
            .runs_tried
            .iter()
            .map(|o| format!("{} with {} centring", o.describe(), o.centring))
            .collect();
        if tried.len() > 1 {
            help.push(format!(
                "the design tried {} within this budget",
                tried.join(", ")
            ));
        }
        if m.fits
            .iter()
            .zip(true_fits)
            .any(|((_, f), (_, t))| *f < t - FIT_POINTS)
        {
            let pair = |f: &[(String, f64)]| {
                f.iter()
                    .map(|(_, x)| leeway_model::number::short_number(*x))
                    .collect::<Vec<_>>()
                    .join("/")
            };
            let short_early = m
                .early_fits
                .iter()
                .zip(true_early)
                .any(|((_, f), (_, t))| *f < t - FIT_POINTS);
            let why = if short_early {
                "short from the start: the parameters' errors, not the free run's length (a longer budget, wider input ranges, or a narrower prior)"
            } else {
                "the errors add up along the free run (a small error in a rate integrates into the heading, and an earth-fixed medium's direction with it): measure the medium, or runs at more operating points"
            };
            help.push(format!(
                "a held-out fit far below the true model's: over the held-out run's first {} s the models fit {} % (the true model {} %) — {why}",
                leeway_model::number::short_number(early_seconds),
                pair(&m.early_fits),
                pair(true_early)
            ));
        }
    }
    Verdict {
        passed: failures.is_empty(),
        failures,
        help,
    }
}

/// The θ the design holds at nominal (`--aggregate`): not excited apart
/// from others by any excitation within the limits.
fn held_by_design(design: &Design) -> Vec<String> {
    design
        .predicted
        .as_ref()
        .map_or(Vec::new(), |p| p.undetermined())
}

/// A rank deficiency beyond what the design holds: a numerically
/// dependent system, or a θ not excited that the design did not plan to
/// hold (`--aggregate`). Nuisance columns held at 0 are the estimator's
/// business.
fn deficient(e: &Estimate, held_by_design: &[String]) -> bool {
    e.diagnostics.rank < e.diagnostics.estimated
        || e.parameters.iter().any(|name| {
            !held_by_design.contains(name)
                && e.diagnostics
                    .unexcited
                    .iter()
                    .any(|u| u.starts_with(&format!("{name} ")))
        })
}

/// A state's name and a fit (%).
type StateFit = (String, f64);

/// Per state, the mean over runs of their fits.
fn per_state(ir: &leeway_structure::ir::Ir, fits: &[&Vec<f64>]) -> Vec<(String, f64)> {
    ir.states
        .iter()
        .enumerate()
        .map(|(s, name)| {
            let v: Vec<f64> = fits.iter().filter_map(|f| f.get(s).copied()).collect();
            (name.clone(), mean_std(&v).0)
        })
        .collect()
}

/// Mean and standard deviation (n − 1) of the finite values: the study's.
fn mean_std(v: &[f64]) -> (f64, f64) {
    let (mean, std, _) = leeway_scenarios::study::mean_std(v.iter().copied());
    (mean, std)
}

/// The centring a method's estimate uses in a verification: the design's
/// for the method it was made for, the method's default for the others.
fn centring_for(design: &Design, method: Method) -> Option<Centring> {
    (Some(method) == design.method_used)
        .then_some(design.centring_used)
        .flatten()
}

#[cfg(test)]
mod tests {
    use super::{binomial_cdf, covered_limits};

    #[test]
    fn the_binomial_tail_sums_to_one_and_matches_a_hand_count() {
        assert!((binomial_cdf(100, 100, 0.9) - 1.0).abs() < 1e-12);
        // P(X ≤ 1 | 3, 0.5) = (1 + 3)/8.
        assert!((binomial_cdf(1, 3, 0.5) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn coverage_at_100_trials_fails_below_85_and_never_above() {
        // P(X ≤ 84 | 100, 0.9) = 0.040 < 5 % ≤ P(X ≤ 85) = 0.073.
        assert_eq!(covered_limits(100), (0.85, 1.0));
        // 1000 trials narrow the band's allowance to about a point.
        let (low, high) = covered_limits(1000);
        assert!((0.88..0.89).contains(&low) && (0.985..0.99).contains(&high));
    }
}
