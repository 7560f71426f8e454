//! `DIR/results.json`, the contract scripts rely on (docs/json.md): `{"runs", "seed", "cases": {"low"|"high": {"wind", "N",
//! "estimators": {"LS"|"IV1"|"IV2"|"IV3": {"fit_mean": {"surge", "sway",
//! "yaw"}, "fit_std", "param_error", "diverged"}}}}, "seconds"}` with arrays
//! aligned with `N`, plus fields that may grow (never renamed or removed):
//! per estimator `fit_median`, `param_error_median`, `estimated`,
//! `param_error_median_all`; at the top `threads`, `claims`, `config`,
//! `input_design`. Non-finite numbers (a mean over runs that all diverged) are
//! written as `null`: serde_json serialises NaN and ±∞ that way, and the
//! tests hold it to that.

use crate::output::Ordered;
use crate::reproduce::margins::{CaseCheck, DesignCheck};
use crate::reproduce::report::Report;
use leeway_scenarios::design::Range;
use leeway_scenarios::study;
use leeway_scenarios::study::CaseSummary;
use leeway_scenarios::study::Claim;
use leeway_scenarios::study::EstimatorSummary;
use leeway_scenarios::study::InputDesign;
use serde::Serialize;
use std::collections::BTreeMap;

/// The document.
#[derive(Debug, Serialize)]
pub struct Document<'a> {
    /// Monte Carlo runs per case.
    pub runs: usize,
    /// Master seed.
    pub seed: u64,
    /// Per case (`low`, `high`): the summaries.
    pub cases: BTreeMap<String, CaseOut<'a>>,
    /// Wall time of the study (simulation, estimation, validation and the
    /// design check), seconds; plotting and writing excluded.
    pub seconds: f64,
    /// Worker threads used (the figures do not depend on it).
    pub threads: usize,
    /// The paper's four claims with their verdicts (`holds`: true, false, or
    /// null when a needed case was not run).
    pub claims: &'a [Claim],
    /// Claim (a) investigated: per case, the N at which LS's median
    /// parameter error over every estimate is below IV3's.
    pub ls_parameter_error_below_iv3: BTreeMap<String, Vec<usize>>,
    /// What was run.
    pub config: Config,
    /// The estimation input and its check on the true trajectories.
    pub input_design: Design,
}

/// One case: the study's summary with two figures per estimator added.
#[derive(Debug, Serialize)]
pub struct CaseOut<'a> {
    /// Mean wind, m/s.
    pub wind: f64,
    /// Record lengths.
    #[serde(rename = "N")]
    pub n: &'a [usize],
    /// By estimator name.
    pub estimators: BTreeMap<String, EstimatorOut<'a>>,
}

/// One estimator's figures: the contract's, `fit_median`,
/// `param_error_median`, and over every estimate returned (diverged models
/// included) their count and median parameter error.
#[derive(Debug, Serialize)]
pub struct EstimatorOut<'a> {
    /// The study's summary (fit_mean, fit_std, fit_median, param_error,
    /// param_error_median, diverged).
    #[serde(flatten)]
    pub summary: &'a EstimatorSummary,
    /// Runs that returned an estimate.
    pub estimated: &'a [usize],
    /// Median parameter error over every estimate returned.
    pub param_error_median_all: &'a [f64],
}

/// What was run.
#[derive(Debug, Serialize)]
pub struct Config {
    /// The model file compiled into the binary.
    pub model: &'static str,
    /// Record lengths.
    #[serde(rename = "N")]
    pub n: Vec<usize>,
    /// Cases and their mean wind (m/s, north and east).
    pub cases: Vec<study::Case>,
    /// Length of the undisturbed validation record.
    pub validation_len: usize,
    /// Most refinements of the refined IV.
    pub max_refinements: usize,
    /// `leeway` (delayed-instrument start, runaway guard) or `paper`
    /// (nominal-model start, plain refinement).
    pub refined_iv: &'static str,
    /// θ0 of the paper's table, by parameter.
    pub theta0: Ordered<f64>,
    /// The noise levels (standard deviations) and the current's mean.
    pub true_system: TrueSystem,
}

/// The true system's disturbances and noises (standard deviations).
#[derive(Debug, Serialize)]
pub struct TrueSystem {
    /// Mean of the current, north and east, m/s.
    pub current_mean: [f64; 2],
    /// Std of each current and wind component (i.i.d., earth frame).
    pub disturbance_std: f64,
    /// Std of the velocity measurement noise.
    pub velocity_noise_std: f64,
    /// Std of the heading measurement noise.
    pub heading_noise_std: f64,
    /// Std of the anemometer noise.
    pub aux_noise_std: f64,
}

/// The input design and the margins measured.
#[derive(Debug, Serialize)]
pub struct Design {
    /// Static offset τ̄ per thruster.
    pub offset: [f64; 3],
    /// Pulse amplitude (half range) per thruster.
    pub pulse: [f64; 3],
    /// Pulse widths drawn from this range (samples).
    pub width: [usize; 2],
    /// First-order smoothing factor per sample.
    pub smoothing: f64,
    /// Initial state (the steady turn).
    pub x0: [f64; 3],
    /// Sway thrust added per unit of yaw pulse.
    pub sway_from_yaw: f64,
    /// The check.
    pub check: Check,
}

/// The design check (ranges over the true trajectories).
#[derive(Debug, Serialize)]
pub struct Check {
    /// Experiments per case over which the ranges are taken (all the runs).
    pub experiments: usize,
    /// Samples per experiment (the largest N).
    pub samples: usize,
    /// Per case.
    pub cases: BTreeMap<String, CaseMargins>,
    /// Std of the yaw rate's measurement noise.
    pub yaw_rate_noise_std: f64,
    /// Std of each output over the validation record (the fit's normaliser).
    pub validation_std: Ordered<f64>,
}

/// One case's margins.
#[derive(Debug, Serialize)]
pub struct CaseMargins {
    /// Mean wind, m/s.
    pub wind: f64,
    /// Per relative velocity under a modulus: its range.
    pub arguments: Ordered<Stats>,
    /// Every water-relative velocity stays positive (paper A7 for the current).
    pub water_positive: bool,
    /// Every wind-relative velocity stays positive (IV2's sign assumption).
    pub air_positive: bool,
    /// The yaw rate's range.
    pub yaw_rate: Stats,
    /// The range of the yaw rate averaged over each minute (60 samples).
    pub yaw_rate_minute_means: Stats,
    /// The range of each run's mean yaw rate.
    pub yaw_rate_run_means: Stats,
}

/// A signal's range.
#[derive(Debug, Serialize)]
pub struct Stats {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Mean.
    pub mean: f64,
    /// Standard deviation.
    pub std: f64,
    /// Fraction of samples below zero.
    pub negative_fraction: f64,
}

impl From<&Range> for Stats {
    fn from(r: &Range) -> Stats {
        Stats {
            min: r.min,
            max: r.max,
            mean: r.mean(),
            std: r.std(),
            negative_fraction: r.negative_fraction(),
        }
    }
}

fn case_margins(c: &CaseCheck) -> CaseMargins {
    CaseMargins {
        wind: c.wind,
        arguments: Ordered(
            c.arguments
                .iter()
                .map(|(n, r)| (n.clone(), Stats::from(r)))
                .collect(),
        ),
        water_positive: c.min_of("water") > 0.0,
        air_positive: c.min_of("air") > 0.0,
        yaw_rate: Stats::from(&c.yaw_rate),
        yaw_rate_minute_means: Stats::from(&c.yaw_rate_blocks),
        yaw_rate_run_means: Stats::from(&c.yaw_rate_runs),
    }
}

fn check(d: &DesignCheck) -> Check {
    Check {
        experiments: d.experiments,
        samples: d.samples,
        cases: d
            .cases
            .iter()
            .map(|c| (c.case.clone(), case_margins(c)))
            .collect(),
        yaw_rate_noise_std: d.yaw_noise_std,
        validation_std: Ordered(d.validation_std.clone()),
    }
}

fn case_out<'a>(report: &'a Report, name: &str, case: &'a CaseSummary) -> CaseOut<'a> {
    let all = report.all_estimates.get(name);
    CaseOut {
        wind: case.wind,
        n: &case.n,
        estimators: case
            .estimators
            .iter()
            .map(|(est, summary)| {
                let extra = all.and_then(|a| a.get(est));
                (
                    est.clone(),
                    EstimatorOut {
                        summary,
                        estimated: extra.map_or(&[][..], |x| &x.estimated),
                        param_error_median_all: extra.map_or(&[][..], |x| &x.median),
                    },
                )
            })
            .collect(),
    }
}

/// The document of a report.
pub fn document(report: &Report) -> Document<'_> {
    let cfg = &report.outcomes.config;
    let InputDesign {
        offset,
        pulse,
        width,
        smoothing,
        x0,
        sway_from_yaw,
    } = cfg.design.clone();
    let system = study::true_system(0.0);
    let first = |v: &[f64]| v.first().copied().unwrap_or(f64::NAN);
    Document {
        runs: cfg.runs,
        seed: cfg.seed,
        cases: report
            .summaries
            .iter()
            .map(|(name, case)| (name.clone(), case_out(report, name, case)))
            .collect(),
        seconds: report.seconds,
        threads: report.threads,
        claims: &report.claims,
        ls_parameter_error_below_iv3: crate::reproduce::report::ls_ahead(report),
        config: Config {
            model: crate::reproduce::ship::MODEL_FILE,
            n: cfg.n.clone(),
            cases: cfg.cases.clone(),
            validation_len: cfg.validation_len,
            max_refinements: cfg.max_refinements,
            refined_iv: if cfg.paper_iv { "paper" } else { "leeway" },
            theta0: Ordered(
                crate::reproduce::ship::ShipParams::NAMES
                    .iter()
                    .zip(study::THETA0)
                    .map(|(n, v)| (n.to_string(), v))
                    .collect(),
            ),
            true_system: TrueSystem {
                current_mean: study::CURRENT_MEAN,
                disturbance_std: first(&system.disturbance_std),
                velocity_noise_std: first(&system.state_noise),
                heading_noise_std: system.heading_noise,
                aux_noise_std: first(&system.aux_noise),
            },
        },
        input_design: Design {
            offset,
            pulse,
            width: [width.0, width.1],
            smoothing,
            x0,
            sway_from_yaw,
            check: check(&report.margins),
        },
    }
}

#[cfg(test)]
mod tests {
    use leeway_scenarios::study::CaseSummary;
    use leeway_scenarios::study::EstimatorSummary;

    #[test]
    fn non_finite_numbers_are_written_as_null() {
        let mut s = EstimatorSummary::default();
        s.fit_mean
            .insert("surge".into(), vec![f64::NAN, 1.5, f64::INFINITY]);
        s.param_error = vec![f64::NEG_INFINITY];
        let mut case = CaseSummary::default();
        case.estimators.insert("IV1".into(), s);
        let text = serde_json::to_string(&case).unwrap_or_default();
        assert!(text.contains(r#""surge":[null,1.5,null]"#), "{text}");
        assert!(text.contains(r#""param_error":[null]"#), "{text}");
        let back: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
        assert!(back["estimators"]["IV1"]["fit_mean"]["surge"][0].is_null());
    }
}
