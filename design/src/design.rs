//! `design`: from the exact analysis's smallest set of sign patterns to runs
//! an engineer can take to sea. Per pattern an operating point
//! ([`operating_point`]); one excitation family for all runs, the largest
//! amplitude (a fraction of each input's room) whose nominal trajectories
//! keep every held argument beyond its band from every starting heading,
//! chosen among the families by predicted information ([`predict`]); the
//! standard errors against run length; what falls short and what would
//! work when nothing fits.

use crate::error::DesignError;
use crate::excitation::Excitation;
use crate::operating::{operating_point, other_points};
use crate::plan::{Conditions, Family};
use crate::predict::{Noise, Prediction, Setting, calibrate, predict};
use crate::report::{self, Design, DifferBy, FamilyScore, RunsOption};
use crate::signs::{held, pointwise_states};
use crate::trial::{Base, Fitted, Run, draw_theta, margins, simulate, start_headings, true_system};
use leeway_estimate::{EstimateOptions, Method};
use leeway_model::experiment::Experiment;
use leeway_model::model::Model;
use leeway_scenarios::synth::{TrueSystem, Truth};
use leeway_structure::identify::{Analysis, Centring, centring_remedies, relevant_signs};
use leeway_structure::ir::{PredictorKind, SignPattern};

/// What the caller asks of a design.
#[derive(Clone, Debug)]
pub struct DesignOptions {
    /// The estimator to design for (default IV3: measured media pointwise).
    pub method: Method,
    /// Relative standard error wanted for every θ (e.g. 0.05).
    pub target: Option<f64>,
    /// Seed of the excitation and of the prediction's realisation.
    pub seed: u64,
    /// Pilot trials calibrating the predicted standard errors (0: the
    /// estimator's asymptotic ones).
    pub pilot: usize,
    /// The runs to take, as `Design::runs_tried` names them (their number,
    /// the centring, what sets them apart): that option whatever its score
    /// (`None`: the search chooses). What `--verify` uses to try the others.
    pub runs: Option<(usize, Centring, DifferBy)>,
}

impl Default for DesignOptions {
    fn default() -> DesignOptions {
        DesignOptions {
            method: Method::Iv3,
            target: None,
            seed: 0,
            pilot: 100,
            runs: None,
        }
    }
}

/// Designs the trial for `model` under conditions `c`.
pub fn design(
    model: &dyn Model,
    c: &Conditions,
    options: &DesignOptions,
) -> Result<Design, DesignError> {
    let ir = model.ir();
    crate::bounds::pilot(options.pilot).map_err(|why| {
        DesignError::option(
            why,
            "fewer pilot trials: each is a simulated trial and its estimate",
        )
    })?;
    let kind = options.method.predictor();
    let (centring, patterns, choose_one, mut assumptions) = experiments(model, kind)?;
    assumptions.extend(c.assumptions.iter().cloned());
    let runs_needed = if choose_one { 1 } else { patterns.len() };
    // Every run length below is at most this one: bounded before anything
    // is allocated for it.
    let n = c.budget.samples(runs_needed, c.h)?;
    let pointwise = pointwise_states(ir, kind);
    let (mut bases, mut partners) = bases(model, c, kind, &patterns, &pointwise, choose_one)?;
    let time_scale = bases
        .iter()
        .map(|b| b.operating.steady.time_constant)
        .max()
        .unwrap_or(1)
        .clamp(2, (n / 10).max(2));
    // The noise the plan leaves out is 1 % of the planned excursion.
    let first = fit(
        model,
        c,
        &bases,
        first_family(c),
        time_scale,
        n,
        options.seed,
    );
    let noise = noise(model, c, &first.runs(&bases, n, c), &mut assumptions);
    let c = Conditions {
        state_noise: noise.states.iter().map(|s| Some(*s)).collect(),
        heading_noise: Some(noise.heading),
        ..c.clone()
    };
    for b in bases.iter_mut().chain(&mut partners) {
        b.held = held(ir, kind, &b.pattern, &c);
    }
    let mut estimate = EstimateOptions {
        method: options.method,
        centring: Some(centring),
        ..Default::default()
    };
    let mut chosen = choose_family(
        model,
        &c,
        &bases,
        &noise,
        &estimate,
        (time_scale, n),
        options.seed,
    );
    if chosen.1.is_none() && chosen.2.iter().all(|f| f.status == "failed") {
        // Every feasible excitation leaves some θ not excited apart from
        // others (e.g. two media moving alike, paper A12): design for the
        // estimate that holds those at nominal.
        estimate.aggregate = true;
        chosen = choose_family(
            model,
            &c,
            &bases,
            &noise,
            &estimate,
            (time_scale, n),
            options.seed,
        );
        if let Some(p) = &chosen.1 {
            assumptions.push(format!(
                "no excitation within the limits determines {} apart from the other parameters: the estimate holds {} at nominal and reports the identifiable combinations (--aggregate)",
                p.undetermined().join(", "),
                if p.undetermined().len() == 1 { "it" } else { "them" }
            ));
        }
    }
    let (mut fitted, mut prediction, mut scores) = chosen;
    let (mut centring, mut n) = (centring, n);
    let mut differ = if bases.len() == 1 {
        DifferBy::Nothing
    } else {
        DifferBy::SignPattern
    };
    let mut runs_tried = vec![RunsOption::of(
        (bases.len(), differ),
        centring,
        n as f64 * c.h,
        prediction.as_ref(),
    )];
    let wanted = options.target.unwrap_or(POORLY);
    let forced = options.runs;
    let baseline = forced == Some((bases.len(), centring, differ));
    if let Some(worst) = prediction
        .as_ref()
        .and_then(Prediction::worst)
        .filter(|w| !baseline && (forced.is_some() || w.0 > wanted))
    {
        let plan = Alternatives {
            model,
            c: &c,
            noise: &noise,
            estimate: &estimate,
            time_scale,
            seed: options.seed,
        };
        let mut best: Option<Alternative> = None;
        let mut best_worst = worst.0;
        for (alt_bases, alt_n, alt_differ) in
            plan.candidates(&bases, &partners, centring, choose_one, n)
        {
            let alt = plan.try_runs(&alt_bases, alt_n, fitted.family);
            let option = RunsOption::of(
                (alt_bases.len(), alt_differ),
                Centring::Pooled,
                alt_n as f64 * c.h,
                alt.1.as_ref(),
            );
            let alt_worst = option.worst_relative.unwrap_or(f64::INFINITY);
            runs_tried.push(option);
            // A clear gain only: each is scored on one realisation.
            let take = match forced {
                Some(runs) => runs == (alt_bases.len(), Centring::Pooled, alt_differ),
                None => alt_worst < 0.8 * best_worst,
            };
            if alt.0.feasible() && take {
                best_worst = alt_worst;
                best = Some((alt_bases, alt_n, alt_differ, alt));
            }
        }
        if let Some((alt_bases, alt_n, alt_differ, (f, p, s))) = best {
            for score in &mut scores {
                if let Some(new) = s.iter().find(|x| x.family == score.family) {
                    *score = new.clone();
                }
            }
            bases = alt_bases;
            n = alt_n;
            differ = alt_differ;
            centring = Centring::Pooled;
            estimate.centring = Some(centring);
            fitted = f;
            prediction = p;
        }
    }
    let chosen_runs = (bases.len(), centring, differ);
    for o in &mut runs_tried {
        o.chosen = o.key() == Some(chosen_runs);
    }
    let runs_reason = runs_reason(&runs_tried, wanted);
    let runs = fitted.runs(&bases, n, &c);
    if let Some(p) = prediction.as_mut() {
        let setting = Setting {
            conditions: &c,
            runs: &runs,
            noise: &noise,
            options: &estimate,
        };
        calibrate(model, setting, options.seed, options.pilot, p);
    }
    let (records, nominal) = nominal_truths(model, &c, &runs, &noise).into_iter().unzip();
    let validation = bases
        .first()
        .map(|b| held_out_run(&c, b, time_scale, n, options.seed));
    Ok(report::assemble(report::Parts {
        model,
        conditions: &c,
        method: options.method,
        target: options.target,
        centring,
        bases: &bases,
        fitted,
        runs,
        nominal,
        records,
        prediction,
        families: scores,
        noise,
        assumptions,
        validation,
        aggregate: estimate.aggregate,
        runs_tried,
        runs_reason,
    }))
}

/// The held-out run the verification judges models by: a manoeuvre over
/// the inputs' whole ranges (random levels across 90 % of each range, held
/// one to four time constants, smoothed), from the first run's operating
/// point, as long as a run. Not a run of the design re-realised: those
/// keep the held signs with small excursions around one steady point,
/// where a steady offset of a few per cent of θ is most of the variation
/// and the fit measures the offset rather than the model; a manoeuvre
/// over the envelope asks what the engineer will ask of the model.
fn held_out_run(c: &Conditions, base: &Base, time_scale: usize, n: usize, seed: u64) -> Run {
    let middle = c.limits.iter().map(|l| 0.5 * (l.low + l.high)).collect();
    let half = c.limits.iter().map(|l| 0.45 * l.span()).collect();
    Run {
        x0: base.operating.steady.states.clone(),
        inputs: Excitation {
            family: Family::Pulses,
            offsets: middle,
            amplitudes: half,
            time_scale,
            seed: leeway_scenarios::engine::keyed_seed(seed, "validation", 0),
        }
        .generate(n, &c.limits),
    }
}

/// θ drawn from the prior whose nominal runs must keep the signs too.
const PRIOR_DRAWS: usize = 4;

/// The worst relative standard error a design is judged by when no
/// `--target` is given (the report's "poorly determined" threshold).
const POORLY: f64 = 0.10;

/// An alternative's bases, samples per run, what sets its runs apart and
/// its fitted design.
type Alternative = (
    Vec<Base>,
    usize,
    DifferBy,
    (Fitted, Option<Prediction>, Vec<FamilyScore>),
);

/// What trying other numbers of runs shares.
struct Alternatives<'a> {
    model: &'a dyn Model,
    c: &'a Conditions,
    noise: &'a Noise,
    estimate: &'a EstimateOptions,
    time_scale: usize,
    seed: u64,
}

impl Alternatives<'_> {
    /// Designs of several runs with pooled centring, within the budget of
    /// the one-run-per-pattern design: when one pattern suffices, the same
    /// pattern at two and at three operating points (other speeds), and
    /// the pattern beside the next one by margin (`partners`: a turn to
    /// either side), the budget shared; else the same runs with pooled
    /// centring when the design centred per experiment. Under
    /// per-experiment centring a run's mean is annihilated with the
    /// medium's, so a drag level at one steady speed is confounded with
    /// the medium's mean; pooled centring over runs at different speeds
    /// keeps the difference between them. One steady turn also leaves its
    /// states near one point, each term's regressor nearly a multiple of
    /// the others'; the mirrored turn puts the odd terms (`v`, `v|v|`,
    /// `r`, the rudder's) on both sides of zero.
    fn candidates(
        &self,
        bases: &[Base],
        partners: &[Base],
        centring: Centring,
        choose_one: bool,
        n: usize,
    ) -> Vec<(Vec<Base>, usize, DifferBy)> {
        if centring != Centring::Experiment {
            return Vec::new();
        }
        let ir = self.model.ir();
        let kind = self.estimate.method.predictor();
        if !choose_one {
            return vec![(bases.to_vec(), n, DifferBy::SignPattern)];
        }
        let Some(first) = bases.first() else {
            return Vec::new();
        };
        if Analysis::with_centring(ir, kind, Centring::Pooled)
            .required()
            .is_none()
        {
            return Vec::new();
        }
        let enough = |k: usize| n / k >= crate::bounds::SAMPLES.0;
        let others = other_points(self.model, self.c, &first.held, &first.operating, 2);
        let mut out: Vec<(Vec<Base>, usize, DifferBy)> = (1..=others.len())
            .filter(|more| enough(more + 1))
            .map(|more| {
                let mut b = vec![first.clone()];
                b.extend(others[..more].iter().map(|op| Base {
                    operating: op.clone(),
                    ..first.clone()
                }));
                (b, n / (more + 1), DifferBy::Speed)
            })
            .collect();
        if let Some(partner) = partners.first().filter(|_| enough(2)) {
            out.push((
                vec![first.clone(), partner.clone()],
                n / 2,
                DifferBy::SignPattern,
            ));
        }
        out
    }

    /// The runs of `bases` at `n` samples each, excited by `family`,
    /// estimated with pooled centring.
    fn try_runs(
        &self,
        bases: &[Base],
        n: usize,
        family: Family,
    ) -> (Fitted, Option<Prediction>, Vec<FamilyScore>) {
        let c = Conditions {
            family: Some(family),
            ..self.c.clone()
        };
        let estimate = EstimateOptions {
            centring: Some(Centring::Pooled),
            ..self.estimate.clone()
        };
        choose_family(
            self.model,
            &c,
            bases,
            self.noise,
            &estimate,
            (self.time_scale, n),
            self.seed,
        )
    }
}

/// Why the design has the runs it has.
fn runs_reason(tried: &[RunsOption], wanted: f64) -> String {
    let pct = |r: Option<f64>| {
        r.map_or("-".to_string(), |r| {
            format!("{} %", leeway_model::number::short_number(100.0 * r))
        })
    };
    let Some(chosen) = tried.iter().find(|o| o.chosen) else {
        return String::new();
    };
    let first = &tried[0];
    if tried.len() == 1 {
        let runs = first.describe();
        return match first.worst_relative {
            Some(w) if w <= wanted => format!(
                "{runs} (one per sign pattern needed): every θ within {} at the budget by the estimator's covariance on one realisation",
                pct(Some(wanted))
            ),
            Some(_) => format!(
                "{runs} with {} centring: no other runs tried (they are tried with per-experiment centring, whose means pooled centring would keep)",
                first.centring
            ),
            None => format!("{runs} (one per sign pattern needed)"),
        };
    }
    if std::ptr::eq(chosen, first) {
        let others: Vec<String> = tried[1..].iter().map(RunsOption::describe).collect();
        return format!(
            "{} with {} centring: {} with pooled centring did not improve the worst relative error ({}) clearly",
            first.describe(),
            first.centring,
            if tried[1..].iter().all(|o| o.runs == first.runs) {
                "the same runs".to_string()
            } else {
                others.join(", ")
            },
            pct(first.worst_relative)
        );
    }
    format!(
        "{} with pooled centring (estimate with `--centring pooled`): the worst relative error {} ({}) with {} and {} centring falls to {} ({}); {}",
        if chosen.runs == first.runs {
            format!("the same {}", first.describe())
        } else {
            chosen.describe()
        },
        pct(first.worst_relative),
        first.worst_parameter.as_deref().unwrap_or("-"),
        first.describe(),
        first.centring,
        pct(chosen.worst_relative),
        chosen.worst_parameter.as_deref().unwrap_or("-"),
        if chosen.differ_by.as_deref() == Some("speed") {
            "per-experiment centring annihilates each run's mean with the medium's, leaving a drag level or constant at one steady speed confounded with the medium's mean"
        } else {
            "one steady operating point leaves each term's regressor near a multiple of the others'; runs of other sign patterns put the odd terms on both sides of zero"
        }
    )
}

/// Fits every family the plan allows (or its one), scores the feasible
/// ones by the estimator's asymptotic covariance on one realisation, and
/// keeps the best (or, when none is feasible, the first, to report what
/// falls short). `(time_scale, n)`: the craft's time constant and the run
/// length, samples.
fn choose_family(
    model: &dyn Model,
    c: &Conditions,
    bases: &[Base],
    noise: &Noise,
    estimate: &EstimateOptions,
    (time_scale, n): (usize, usize),
    seed: u64,
) -> (Fitted, Option<Prediction>, Vec<FamilyScore>) {
    let families: Vec<Family> = c.family.map_or(Family::ALL.to_vec(), |f| vec![f]);
    let mut tried: Vec<(Fitted, Option<Prediction>, FamilyScore)> = Vec::new();
    for family in families {
        let fitted = fit(model, c, bases, family, time_scale, n, seed);
        let (prediction, score) = if fitted.feasible() {
            let runs = fitted.runs(bases, n, c);
            let setting = Setting {
                conditions: c,
                runs: &runs,
                noise,
                options: estimate,
            };
            match predict(model, setting, seed) {
                Ok(p) if p.score().is_finite() => {
                    let s = p.score();
                    (Some(p), FamilyScore::scored(family, fitted.scale, s))
                }
                Ok(p) => {
                    let why = format!("leaves {} undetermined", p.undetermined().join(", "));
                    (None, FamilyScore::failed(family, fitted.scale, why))
                }
                Err(e) => (None, FamilyScore::failed(family, fitted.scale, e)),
            }
        } else {
            (None, FamilyScore::infeasible(family))
        };
        tried.push((fitted, prediction, score));
    }
    let scores: Vec<FamilyScore> = tried.iter().map(|t| t.2.clone()).collect();
    let best = tried
        .iter()
        .enumerate()
        .filter(|(_, t)| t.1.as_ref().is_some_and(|p| p.score().is_finite()))
        .min_by(|a, b| a.1.2.score.total_cmp(&b.1.2.score))
        .map_or(0, |(i, _)| i);
    let (fitted, prediction, _) = tried.swap_remove(best);
    let prediction = prediction.filter(|p| p.score().is_finite());
    (fitted, prediction, scores)
}

/// The centring and sign patterns to design for: the model's centring if
/// θ is identifiable under it, else the first centring that identifies θ
/// (said in the assumptions: the estimate must use it too).
fn experiments(
    model: &dyn Model,
    kind: PredictorKind,
) -> Result<(Centring, Vec<SignPattern>, bool, Vec<String>), DesignError> {
    let ir = model.ir();
    let centring = Centring::for_model(ir, kind);
    let analysis = Analysis::with_centring(ir, kind, centring);
    if let Some(found) = analysis.required() {
        if found.patterns.len() == 1 && analysis.any_single_pattern() == Some(true) {
            return Ok((centring, single_candidates(ir, kind), true, Vec::new()));
        }
        return Ok((centring, found.patterns, false, Vec::new()));
    }
    let remedy = centring_remedies(ir, kind, centring).into_iter().next().ok_or_else(|| {
        DesignError {
            code: "not-identifiable",
            ..DesignError::cannot(
                "θ is not identifiable from any set of experiments, so no trial can identify it",
                "`leeway check MODEL` names the parameters that enter together: merge them, measure the medium (IV3), or estimate the identifiable combinations with --aggregate",
            )
        }
    })?;
    let note = format!(
        "θ is not identifiable with {} centring (it annihilates a constant term); designed for `--centring {}`: estimate with it",
        centring.name(),
        remedy.centring.name()
    );
    Ok((remedy.centring, remedy.patterns, false, vec![note]))
}

/// When any one pattern identifies θ, every pattern over the held signs is
/// a candidate for the single experiment (at most 16); [`bases`] keeps the
/// one with the largest margin.
fn single_candidates(ir: &leeway_structure::ir::Ir, kind: PredictorKind) -> Vec<SignPattern> {
    let relevant = relevant_signs(ir, kind);
    if relevant.is_empty() || relevant.len() > 4 {
        return vec![vec![1; ir.sign_args.len()]];
    }
    (0..1usize << relevant.len())
        .map(|bits| {
            let mut p = vec![1i8; ir.sign_args.len()];
            for (j, a) in relevant.iter().enumerate() {
                if bits >> j & 1 == 1 {
                    p[*a] = -1;
                }
            }
            p
        })
        .collect()
}

/// The operating point of each pattern; of the single-experiment
/// candidates, the best one, and the others whose margins are positive
/// (best first: the partners of a run of another sign pattern).
fn bases(
    model: &dyn Model,
    c: &Conditions,
    kind: PredictorKind,
    patterns: &[SignPattern],
    pointwise: &[usize],
    choose_one: bool,
) -> Result<(Vec<Base>, Vec<Base>), DesignError> {
    let ir = model.ir();
    let mut out = Vec::new();
    for p in patterns {
        let h = held(ir, kind, p, c);
        let op = operating_point(model, c, &h, pointwise).ok_or_else(|| {
            DesignError::cannot(
                "no input within the limits brings the nominal craft to a steady state",
                "check the nominal θ (a stable craft: damping terms negative) and the inputs' ranges",
            )
        })?;
        out.push(Base {
            pattern: p.clone(),
            held: h,
            operating: op,
        });
    }
    if choose_one {
        // Best margin first; on ties the last pattern (as `max_by` took it).
        out.reverse();
        out.sort_by(|a, b| {
            b.operating
                .min_margin()
                .total_cmp(&a.operating.min_margin())
        });
        let partners = out
            .split_off(1.min(out.len()))
            .into_iter()
            .filter(|b| b.operating.min_margin() > 0.0)
            .collect();
        return Ok((out, partners));
    }
    Ok((out, Vec::new()))
}

fn first_family(c: &Conditions) -> Family {
    c.family.unwrap_or(Family::ALL[0])
}

/// The largest fraction of each input's room (bisected) whose nominal
/// trajectories keep every held argument beyond its band.
pub fn fit(
    model: &dyn Model,
    c: &Conditions,
    bases: &[Base],
    family: Family,
    time_scale: usize,
    n: usize,
    seed: u64,
) -> Fitted {
    let excite = |scale: f64| -> Vec<Excitation> {
        bases
            .iter()
            .enumerate()
            .map(|(e, b)| Excitation {
                family,
                offsets: b.operating.offsets.clone(),
                amplitudes: b
                    .operating
                    .offsets
                    .iter()
                    .zip(&c.limits)
                    .map(|(u, l)| scale * (u - l.low).min(l.high - u))
                    .collect(),
                time_scale,
                seed: leeway_scenarios::engine::keyed_seed(seed, "excitation", e),
            })
            .collect()
    };
    let evaluate = |scale: f64| {
        let fitted = Fitted {
            family,
            excitations: excite(scale),
            scale,
            min_margins: Vec::new(),
        };
        let runs = fitted.runs(bases, n, c);
        let min_margins = nominal_margins(model, c, bases, &runs);
        Fitted {
            min_margins,
            ..fitted
        }
    };
    let full = evaluate(1.0);
    if full.feasible() {
        return full;
    }
    let none = evaluate(0.0);
    if !none.feasible() {
        return none;
    }
    let (mut lo, mut hi) = (none, 1.0);
    for _ in 0..10 {
        let mid = 0.5 * (lo.scale + hi);
        let f = evaluate(mid);
        if f.feasible() {
            lo = f;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Per run, per held argument: the smallest margin along the nominal
/// trajectory from every starting heading (a diverging simulation counts
/// as −∞).
fn nominal_margins(
    model: &dyn Model,
    c: &Conditions,
    bases: &[Base],
    runs: &[Run],
) -> Vec<Vec<f64>> {
    // With a prior on θ, the signs must hold for θ drawn from it as well.
    let systems: Vec<_> = std::iter::once(c.theta.clone())
        .chain((0..if c.prior > 0.0 { PRIOR_DRAWS } else { 0 }).map(|i| {
            draw_theta(
                c,
                leeway_scenarios::engine::keyed_seed(0, "prior-margins", i),
            )
        }))
        .map(|theta| TrueSystem {
            theta,
            ..true_system(c, &[], 0.0, false)
        })
        .collect();
    let headings = start_headings(model, c);
    bases
        .iter()
        .zip(runs)
        .map(|(b, run)| {
            let mut worst = vec![f64::INFINITY; b.held.len()];
            for (system, psi0) in systems
                .iter()
                .flat_map(|s| headings.iter().map(move |h| (s, h)))
            {
                let (_, truth) = simulate(model, system, run, "nominal", *psi0, 0);
                if truth.states.iter().flatten().any(|x| !x.is_finite()) {
                    return vec![f64::NEG_INFINITY; b.held.len().max(1)];
                }
                for (w, m) in worst
                    .iter_mut()
                    .zip(margins(model, &truth, &run.inputs, &b.held))
                {
                    *w = m.into_iter().fold(*w, f64::min);
                }
            }
            worst
        })
        .collect()
}

/// The measurement noise: the plan's, else 1 % of each state's standard
/// deviation along the nominal runs (stated), and 0.005 rad for a heading.
fn noise(model: &dyn Model, c: &Conditions, runs: &[Run], assumptions: &mut Vec<String>) -> Noise {
    let ir = model.ir();
    let system = true_system(c, &[], 0.0, false);
    let truths: Vec<Truth> = runs
        .iter()
        .map(|r| simulate(model, &system, r, "nominal", 0.0, 0).1)
        .collect();
    let mut defaulted: Vec<String> = Vec::new();
    let states = (0..ir.states.len())
        .map(|s| {
            c.state_noise[s].unwrap_or_else(|| {
                let (mut n, mut sum, mut sq) = (0.0, 0.0, 0.0);
                for x in truths.iter().flat_map(|t| &t.states[s]) {
                    n += 1.0;
                    sum += x;
                    sq += x * x;
                }
                let mean = sum / f64::max(n, 1.0);
                let std = (sq / f64::max(n, 1.0) - mean * mean).max(0.0).sqrt();
                let sigma = 0.01 * std.max(1e-6 * (1.0 + mean.abs()));
                defaulted.push(format!(
                    "{} {}",
                    ir.states[s],
                    leeway_model::number::short_number(sigma)
                ));
                sigma
            })
        })
        .collect();
    if !defaulted.is_empty() {
        assumptions.push(format!(
            "measurement noise {} (1 % of each state's planned excursion; the plan gives none)",
            defaulted.join(", ")
        ));
    }
    let heading = match (&ir.rotation, c.heading_noise) {
        (leeway_structure::ir::Rotation::Planar { heading, .. }, None) => {
            assumptions.push(format!(
                "noise on {heading}: 0.005 rad (a gyro compass; the plan gives none)"
            ));
            0.005
        }
        (_, h) => h.unwrap_or(0.0),
    };
    Noise { states, heading }
}

/// The nominal record and trajectory of each run from heading 0 (what the
/// files and the figure show).
fn nominal_truths(
    model: &dyn Model,
    c: &Conditions,
    runs: &[Run],
    noise: &Noise,
) -> Vec<(Experiment, Truth)> {
    let system = true_system(c, &noise.states, noise.heading, false);
    runs.iter()
        .enumerate()
        .map(|(e, r)| simulate(model, &system, r, &format!("run-{}", e + 1), 0.0, 0))
        .collect()
}
