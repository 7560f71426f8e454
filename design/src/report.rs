//! The design as an engineer reads it (and as `design --json` writes it,
//! `docs/json.md`): per experiment its pattern, operating point,
//! excitation and margins; the predicted standard errors against run
//! length; which estimators' sign assumptions the design meets; and, where
//! nothing fits, what falls short and what would work.

use crate::plan::{Conditions, Family};
use crate::predict::{Noise, Prediction};
use crate::signs::{Held, held};
use crate::trial::{Base, Fitted, Run, margins, simulate, start_headings, true_system};
use leeway_estimate::Method;
use leeway_model::experiment::Experiment;
use leeway_model::model::Model;
use leeway_scenarios::synth::Truth;
use leeway_structure::identify::{Centring, pattern_text, relevant_signs};
use leeway_structure::ir::{Ir, PredictorKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// A design.
#[derive(Clone, Debug, Serialize)]
pub struct Design {
    /// The model's name.
    pub model: String,
    /// The estimator designed for.
    pub method: String,
    /// The instrument centring the estimate must use.
    pub centring: String,
    /// Whether the estimate must hold θ the trial does not excite at
    /// nominal (`estimate --aggregate`).
    pub aggregate: bool,
    /// Whether every held argument keeps its side in the nominal runs.
    pub feasible: bool,
    /// Sample time, s.
    pub step: f64,
    /// Samples per experiment (the budget's).
    pub samples: usize,
    /// Seconds per experiment.
    pub seconds: f64,
    /// The excitation family chosen.
    pub excitation: Family,
    /// Every family tried.
    pub families: Vec<FamilyScore>,
    /// The runs.
    pub experiments: Vec<PlannedRun>,
    /// Predicted accuracy (absent when no family was feasible).
    pub prediction: Option<PredictionReport>,
    /// Per estimator, whether the design keeps the signs it assumes.
    pub methods: Vec<MethodSigns>,
    /// Held arguments that cross their band in a nominal run.
    pub shortfalls: Vec<Shortfall>,
    /// What would work instead, when something falls short.
    pub proposals: Vec<String>,
    /// Runs whose nominal track leaves the plan's trial area, in words.
    pub sea_room: Vec<String>,
    /// Measurement noise used, per state and heading.
    pub noise: BTreeMap<String, f64>,
    /// What the plan did not say and the design assumed.
    pub assumptions: Vec<String>,
    /// The numbers of runs tried (one per sign pattern; the same pattern
    /// at other speeds with pooled centring) and their worst predicted
    /// relative errors, one marked chosen.
    pub runs_tried: Vec<RunsOption>,
    /// Why the design has the runs it has.
    pub runs_reason: String,
    /// The runs' inputs and initial states (for the input files).
    #[serde(skip)]
    pub runs: Vec<Run>,
    /// The nominal trajectories from heading 0 (for files and the figure).
    #[serde(skip)]
    pub nominal: Vec<Truth>,
    /// The nominal records (the runs' input files).
    #[serde(skip)]
    pub records: Vec<Experiment>,
    /// Per run, the held arguments (for margins over time).
    #[serde(skip)]
    pub held: Vec<Vec<Held>>,
    /// The prediction behind the report.
    #[serde(skip)]
    pub predicted: Option<Prediction>,
    /// The conditions designed for (noise resolved).
    #[serde(skip)]
    pub conditions: Option<Conditions>,
    /// The estimate options the design's method uses.
    #[serde(skip)]
    pub centring_used: Option<Centring>,
    /// The estimator.
    #[serde(skip)]
    pub method_used: Option<Method>,
    /// The noise designed for.
    #[serde(skip)]
    pub noise_used: Option<Noise>,
    /// The held-out run: a manoeuvre over the inputs' ranges from run 1's
    /// operating point (`design::held_out_run`).
    #[serde(skip)]
    pub validation: Option<Run>,
}

/// One family's fate.
#[derive(Clone, Debug, Serialize)]
pub struct FamilyScore {
    /// The family.
    pub family: Family,
    /// Fraction of the inputs' room its amplitude uses.
    pub scale: f64,
    /// Mean `ln(σ/|θ|)` at the budget's run length, from the estimator's asymptotic
    /// covariance on one realisation (lower is better).
    pub score: f64,
    /// `scored`, `chosen`, `infeasible` (signs not kept even unexcited), `failed`.
    pub status: String,
    /// Why it failed.
    pub detail: Option<String>,
}

impl FamilyScore {
    /// A family whose prediction was computed.
    pub fn scored(family: Family, scale: f64, score: f64) -> FamilyScore {
        FamilyScore {
            family,
            scale,
            score,
            status: "scored".into(),
            detail: None,
        }
    }
    /// A family whose runs cannot keep the signs.
    pub fn infeasible(family: Family) -> FamilyScore {
        FamilyScore {
            family,
            scale: 0.0,
            score: f64::INFINITY,
            status: "infeasible".into(),
            detail: None,
        }
    }
    /// A family whose prediction's estimate failed.
    pub fn failed(family: Family, scale: f64, why: String) -> FamilyScore {
        FamilyScore {
            family,
            scale,
            score: f64::INFINITY,
            status: "failed".into(),
            detail: Some(why),
        }
    }
}

/// What sets a design's runs apart from one another.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DifferBy {
    /// One run.
    Nothing,
    /// The same sign pattern at other operating points (speeds).
    Speed,
    /// Different sign patterns (e.g. turns to either side).
    SignPattern,
}

impl DifferBy {
    /// Its name in the report (`None` for one run).
    pub fn name(self) -> Option<&'static str> {
        match self {
            DifferBy::Nothing => None,
            DifferBy::Speed => Some("speed"),
            DifferBy::SignPattern => Some("sign pattern"),
        }
    }

    /// The variant of a report's name.
    pub fn of_name(name: Option<&str>) -> Option<DifferBy> {
        match name {
            None => Some(DifferBy::Nothing),
            Some("speed") => Some(DifferBy::Speed),
            Some("sign pattern") => Some(DifferBy::SignPattern),
            Some(_) => None,
        }
    }

    /// `runs` runs set apart by it, in words.
    pub fn describe(self, runs: usize) -> String {
        let plural = if runs == 1 { "" } else { "s" };
        match self {
            DifferBy::Nothing => format!("{runs} run{plural}"),
            DifferBy::Speed => format!("{runs} runs at different speeds"),
            DifferBy::SignPattern => format!("{runs} runs of different sign patterns"),
        }
    }
}

/// A number of runs and a centring the design tried.
#[derive(Clone, Debug, Serialize)]
pub struct RunsOption {
    /// Runs.
    pub runs: usize,
    /// What sets the runs apart: `speed`, `sign pattern`, or null (one run).
    pub differ_by: Option<String>,
    /// The estimate's centring: `experiment`, `pooled`, `none`.
    pub centring: String,
    /// Seconds per run.
    pub seconds: f64,
    /// The worst `σ/|θ|` at that length, from the estimator's covariance on
    /// one realisation (`None`: no prediction).
    pub worst_relative: Option<f64>,
    /// Its parameter.
    pub worst_parameter: Option<String>,
    /// Whether the design uses it.
    pub chosen: bool,
}

impl RunsOption {
    /// The option of `runs` runs with `centring` and its prediction.
    pub fn of(
        (runs, differ_by): (usize, DifferBy),
        centring: Centring,
        seconds: f64,
        prediction: Option<&Prediction>,
    ) -> RunsOption {
        let worst = prediction.and_then(Prediction::worst);
        RunsOption {
            runs,
            differ_by: differ_by.name().map(str::to_string),
            centring: centring.name().to_string(),
            seconds,
            worst_relative: worst.as_ref().map(|w| w.0),
            worst_parameter: worst.map(|w| w.1),
            chosen: false,
        }
    }

    /// Its runs, centring and what sets the runs apart, as
    /// `DesignOptions::runs` names them.
    pub fn key(&self) -> Option<(usize, Centring, DifferBy)> {
        let centring = match self.centring.as_str() {
            "experiment" => Centring::Experiment,
            "pooled" => Centring::Pooled,
            "none" => Centring::None,
            _ => return None,
        };
        Some((
            self.runs,
            centring,
            DifferBy::of_name(self.differ_by.as_deref())?,
        ))
    }

    /// Its runs in words.
    pub fn describe(&self) -> String {
        DifferBy::of_name(self.differ_by.as_deref())
            .unwrap_or(DifferBy::Nothing)
            .describe(self.runs)
    }
}

/// One input of a run, in the unit the model's data use for it (the run
/// files' unit).
#[derive(Clone, Debug, Serialize)]
pub struct InputPlan {
    /// The static offset.
    pub offset: f64,
    /// The excitation's amplitude about it.
    pub amplitude: f64,
    /// The unit of both: the model's `data { }` unit for the input, or
    /// null for the model's own.
    pub unit: Option<String>,
}

/// A held argument in a run.
#[derive(Clone, Debug, Serialize)]
pub struct HeldReport {
    /// `water.u`.
    pub argument: String,
    /// `+` or `-`.
    pub side: String,
    /// The band it must clear.
    pub band: f64,
    /// Its margin at the operating point's steady state (calm), less the
    /// worst share of the mean disturbance and the band.
    pub steady_margin: f64,
    /// Its smallest margin along the nominal run, from every starting heading.
    pub min_margin: f64,
}

/// A plain state whose modulus is evaluated pointwise.
#[derive(Clone, Debug, Serialize)]
pub struct PointwiseReport {
    /// The state.
    pub state: String,
    /// Fraction of the nominal run's samples below zero (sign changes
    /// separate `x|x|` from `x·x`).
    pub negative_fraction: f64,
}

/// One experiment of the design.
#[derive(Clone, Debug, Serialize)]
pub struct PlannedRun {
    /// `{+water.u -water.v}`.
    pub pattern: String,
    /// Per input.
    pub inputs: BTreeMap<String, InputPlan>,
    /// The nominal steady state at the operating point (calm).
    pub steady: BTreeMap<String, f64>,
    /// The arguments it holds.
    pub held: Vec<HeldReport>,
    /// Plain states evaluated pointwise.
    pub pointwise: Vec<PointwiseReport>,
    /// Range of the nominal heading, degrees (planar craft).
    pub heading_span_deg: Option<f64>,
    /// Whether the offsets had to use the whole ranges (little room left to excite).
    pub full_range: bool,
    /// Where the nominal run goes over ground (planar craft).
    pub track: Option<Track>,
}

/// A run's nominal track over ground from heading 0, the mean media's
/// drift included: the craft's velocity over ground rotated to the earth
/// frame and integrated.
#[derive(Clone, Debug, Serialize)]
pub struct Track {
    /// The farthest it goes from the start, m.
    pub farthest: f64,
    /// Where it ends: north, east of the start, m.
    pub end: [f64; 2],
    /// Positions north, east, m, every sample (for the figure).
    #[serde(skip)]
    pub positions: Vec<[f64; 2]>,
}

/// Where run `e`'s track leaves the plan's area, in words (empty: inside).
fn beyond_area(c: &Conditions, e: usize, t: &Track) -> Vec<String> {
    let m = |x: f64| leeway_model::number::short_number(x.round());
    let mut out = Vec::new();
    if let Some(radius) = c.area_radius.filter(|r| t.farthest > *r) {
        out.push(format!(
            "run {} goes {} m from its start, beyond the area's {} m",
            e + 1,
            m(t.farthest),
            m(radius)
        ));
    }
    let Some(area) = c.area_box else {
        return out;
    };
    let reach = |axis: usize| {
        t.positions.iter().fold((0.0f64, 0.0f64), |(lo, hi), p| {
            (lo.min(p[axis]), hi.max(p[axis]))
        })
    };
    for (axis, [low, high], (below, above)) in [
        (0, area.north, ("south", "north")),
        (1, area.east, ("west", "east")),
    ] {
        let (lo, hi) = reach(axis);
        if hi > high {
            out.push(format!(
                "run {} goes {} m {above} of its start, beyond the area's {} m",
                e + 1,
                m(hi),
                m(high)
            ));
        }
        if lo < low {
            out.push(format!(
                "run {} goes {} m {below} of its start, beyond the area's {} m",
                e + 1,
                m(-lo),
                m(-low)
            ));
        }
    }
    out
}

/// The nominal track of `truth` (`None` for a craft without a planar heading).
pub fn track(ir: &Ir, truth: &Truth, h: f64) -> Option<Track> {
    let leeway_structure::ir::Rotation::Planar { axes, .. } = &ir.rotation else {
        return None;
    };
    let (u, v) = (truth.states.get(axes[0])?, truth.states.get(axes[1])?);
    let mut p = [0.0, 0.0];
    let mut positions = Vec::with_capacity(u.len() + 1);
    positions.push(p);
    let mut farthest: f64 = 0.0;
    for ((u, v), psi) in u.iter().zip(v).zip(&truth.heading) {
        let (s, c) = psi.sin_cos();
        p[0] += h * (u * c - v * s);
        p[1] += h * (u * s + v * c);
        farthest = farthest.max(p[0].hypot(p[1]));
        positions.push(p);
    }
    Some(Track {
        farthest,
        end: p,
        positions,
    })
}

/// One θ's predicted accuracy.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterPrediction {
    /// Its name.
    pub name: String,
    /// The value designed for.
    pub nominal: f64,
    /// Standard error at the budget's run length.
    pub std_error: Option<f64>,
    /// `std_error / |nominal|`.
    pub relative: Option<f64>,
    /// The estimator's own asymptotic standard error on one realisation.
    pub asymptotic: Option<f64>,
}

/// Standard errors at one run length.
#[derive(Clone, Debug, Serialize)]
pub struct CurvePoint {
    /// Samples per experiment.
    pub samples: usize,
    /// Seconds per experiment.
    pub seconds: f64,
    /// The largest relative standard error.
    pub worst_relative: f64,
    /// θ's standard errors.
    pub std_errors: Vec<Option<f64>>,
}

/// The run length a target precision needs.
#[derive(Clone, Debug, Serialize)]
pub struct Target {
    /// The relative standard error asked for.
    pub relative: f64,
    /// Samples per experiment (`None`: more than
    /// [`crate::bounds::SAMPLES`] allows, beyond what leeway plans).
    pub samples: Option<usize>,
    /// Seconds per experiment (`None` as `samples`).
    pub seconds: Option<f64>,
    /// Whether the budget covers it.
    pub within_budget: bool,
}

/// A parameter the design leaves poorly determined.
#[derive(Clone, Debug, Serialize)]
pub struct PoorlyDetermined {
    /// Its name.
    pub name: String,
    /// Relative standard error at the budget.
    pub relative: f64,
    /// Its term in the model.
    pub term: String,
    /// What would help.
    pub help: String,
}

/// The predicted accuracy.
#[derive(Clone, Debug, Serialize)]
pub struct PredictionReport {
    /// Samples per experiment the standard errors were evaluated at.
    pub evaluated_at: usize,
    /// Pilot trials behind the standard errors (half the 95th percentile
    /// of their |error|); 0 when they are the estimator's asymptotic ones.
    pub trials: usize,
    /// At the budget's run length.
    pub parameters: Vec<ParameterPrediction>,
    /// Unmeasured disturbance means and their standard errors at the budget.
    pub disturbances: Vec<DisturbancePrediction>,
    /// Against run length.
    pub curve: Vec<CurvePoint>,
    /// The largest relative standard error at the budget.
    pub worst_relative: f64,
    /// The run a `--target` precision needs.
    pub target: Option<Target>,
    /// Parameters above the target (or 10 %) at the budget.
    pub poorly_determined: Vec<PoorlyDetermined>,
}

/// A disturbance mean's predicted accuracy.
#[derive(Clone, Debug, Serialize)]
pub struct DisturbancePrediction {
    /// `current.north`.
    pub name: String,
    /// The plan's mean.
    pub mean: f64,
    /// Standard error at the budget.
    pub std_error: Option<f64>,
}

/// Whether the design keeps an estimator's sign assumptions.
#[derive(Clone, Debug, Serialize)]
pub struct MethodSigns {
    /// `iv3`.
    pub method: String,
    /// Every argument it holds keeps its side beyond the band in every nominal run.
    pub holds: bool,
    /// Per run and argument, the smallest nominal margin.
    pub arguments: Vec<ArgumentMargin>,
}

/// An argument's smallest margin in one run.
#[derive(Clone, Debug, Serialize)]
pub struct ArgumentMargin {
    /// Experiment, from 1.
    pub experiment: usize,
    /// `air.u`.
    pub argument: String,
    /// `+` or `-`.
    pub side: String,
    /// Smallest margin (negative: short by that much).
    pub min_margin: f64,
}

/// A held argument that crosses its band.
#[derive(Clone, Debug, Serialize)]
pub struct Shortfall {
    /// Experiment, from 1.
    pub experiment: usize,
    /// `air.u`.
    pub argument: String,
    /// How far inside its band it comes.
    pub short_by: f64,
}

/// What [`assemble`] puts together.
pub struct Parts<'a> {
    /// The model.
    pub model: &'a dyn Model,
    /// The conditions (noise resolved).
    pub conditions: &'a Conditions,
    /// The estimator designed for (the caller's option).
    pub method: Method,
    /// The relative standard error wanted for every θ (the caller's option).
    pub target: Option<f64>,
    /// The centring designed for.
    pub centring: Centring,
    /// The experiments' bases.
    pub bases: &'a [Base],
    /// The chosen excitation.
    pub fitted: Fitted,
    /// The runs at the budget's length.
    pub runs: Vec<Run>,
    /// Their nominal trajectories from heading 0.
    pub nominal: Vec<Truth>,
    /// The same as records (what a noise-free logger would write).
    pub records: Vec<Experiment>,
    /// The chosen family's prediction.
    pub prediction: Option<Prediction>,
    /// Every family's fate.
    pub families: Vec<FamilyScore>,
    /// The noise used.
    pub noise: Noise,
    /// Assumptions made.
    pub assumptions: Vec<String>,
    /// The validation run.
    pub validation: Option<Run>,
    /// Whether the estimate holds unexcited θ (`--aggregate`).
    pub aggregate: bool,
    /// The numbers of runs tried.
    pub runs_tried: Vec<RunsOption>,
    /// Why the design has its runs.
    pub runs_reason: String,
}

/// Puts a design's report together.
pub fn assemble(p: Parts) -> Design {
    let ir = p.model.ir();
    let c = p.conditions;
    let n = p.runs.first().map_or(0, |r| r.inputs.len());
    let kind = p.method.predictor();
    let experiments: Vec<PlannedRun> = p
        .bases
        .iter()
        .enumerate()
        .map(|(e, b)| planned_run(p.model, b, &p.fitted, (e, c.h), &p.nominal[e], kind))
        .collect();
    let shortfalls: Vec<Shortfall> = p
        .bases
        .iter()
        .enumerate()
        .flat_map(|(e, b)| {
            b.held
                .iter()
                .zip(&p.fitted.min_margins[e])
                .filter(|(_, m)| **m < 0.0)
                .map(move |(a, m)| Shortfall {
                    experiment: e + 1,
                    argument: a.name.clone(),
                    short_by: -m,
                })
        })
        .collect();
    let mut proposals = proposals(ir, &shortfalls, p.bases);
    // The trial area: a run whose nominal track leaves it is not a plan.
    let sea_room: Vec<String> = experiments
        .iter()
        .enumerate()
        .filter_map(|(e, r): (usize, &PlannedRun)| Some((e, r.track.as_ref()?)))
        .flat_map(|(e, t)| beyond_area(c, e, t))
        .collect();
    if !sea_room.is_empty() {
        proposals.push(format!(
            "the track leaves the trial area ({}): a larger area, a shorter budget per run (more runs), or a calmer current",
            sea_room.join("; ")
        ));
    }
    let mut families = p.families;
    for f in &mut families {
        if f.family == p.fitted.family && f.status == "scored" && p.prediction.is_some() {
            f.status = "chosen".into();
        }
    }
    let mut noise: BTreeMap<String, f64> = ir
        .states
        .iter()
        .cloned()
        .zip(p.noise.states.iter().copied())
        .collect();
    if let leeway_structure::ir::Rotation::Planar { heading, .. } = &ir.rotation {
        noise.insert(heading.clone(), p.noise.heading);
    }
    Design {
        model: ir.name.clone(),
        method: p.method.name().to_string(),
        centring: p.centring.name().to_string(),
        aggregate: p.aggregate,
        feasible: shortfalls.is_empty() && sea_room.is_empty() && p.prediction.is_some(),
        sea_room,
        step: c.h,
        samples: n,
        seconds: n as f64 * c.h,
        excitation: p.fitted.family,
        families,
        experiments,
        prediction: p
            .prediction
            .as_ref()
            .map(|pr| prediction_report(ir, pr, (n, c.h), p.target, p.fitted.scale)),
        methods: method_signs(p.model, c, p.bases, &p.runs, kind),
        shortfalls,
        proposals,
        noise,
        assumptions: p.assumptions,
        held: p.bases.iter().map(|b| b.held.clone()).collect(),
        runs_tried: p.runs_tried,
        runs_reason: p.runs_reason,
        runs: p.runs,
        nominal: p.nominal,
        records: p.records,
        predicted: p.prediction,
        conditions: Some(c.clone()),
        centring_used: Some(p.centring),
        method_used: Some(p.method),
        noise_used: Some(p.noise),
        validation: p.validation,
    }
}

fn planned_run(
    model: &dyn Model,
    b: &Base,
    f: &Fitted,
    (e, h): (usize, f64),
    truth: &Truth,
    kind: PredictorKind,
) -> PlannedRun {
    let ir = model.ir();
    let ex = &f.excitations[e];
    let inputs = ir
        .inputs
        .iter()
        .enumerate()
        .map(|(i, name)| {
            (name.clone(), {
                let factor = leeway_structure::units::factor_of(ir, name);
                InputPlan {
                    offset: ex.offsets[i] / factor,
                    amplitude: ex.amplitudes[i] / factor,
                    unit: ir.data_units.get(name).cloned(),
                }
            })
        })
        .collect();
    let steady = ir
        .states
        .iter()
        .cloned()
        .zip(b.operating.steady.states.iter().copied())
        .collect();
    let held = b
        .held
        .iter()
        .zip(&b.operating.margins)
        .zip(&f.min_margins[e])
        .map(|((a, steady), min)| HeldReport {
            argument: a.name.clone(),
            side: side(a.sign),
            band: a.band,
            steady_margin: *steady,
            min_margin: *min,
        })
        .collect();
    let pointwise = crate::signs::pointwise_states(ir, kind)
        .into_iter()
        .map(|s| {
            let xs = &truth.states[s];
            PointwiseReport {
                state: ir.states[s].clone(),
                negative_fraction: xs.iter().filter(|x| **x < 0.0).count() as f64
                    / xs.len().max(1) as f64,
            }
        })
        .collect();
    let planar = matches!(ir.rotation, leeway_structure::ir::Rotation::Planar { .. });
    let heading_span_deg = (planar && !truth.heading.is_empty()).then(|| {
        let (lo, hi) = truth
            .heading
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                (l.min(*x), h.max(*x))
            });
        (hi - lo).to_degrees()
    });
    PlannedRun {
        track: track(ir, truth, h),
        pattern: pattern_text(ir, &b.pattern, kind),
        inputs,
        steady,
        held,
        pointwise,
        heading_span_deg,
        full_range: b.operating.full_range,
    }
}

fn side(sign: f64) -> String {
    if sign < 0.0 { "-".into() } else { "+".into() }
}

fn prediction_report(
    ir: &Ir,
    p: &Prediction,
    (n, h): (usize, f64),
    target: Option<f64>,
    room_used: f64,
) -> PredictionReport {
    let at_n = p.at(n);
    let f = (p.samples as f64 / n.max(1) as f64).sqrt();
    let rel = |s: &[Option<f64>]| -> f64 {
        s.iter()
            .zip(&p.theta)
            .filter(|(_, t)| **t != 0.0)
            .filter_map(|(s, t)| s.map(|s| s / t.abs()))
            .fold(0.0, f64::max)
    };
    let parameters = p
        .parameters
        .iter()
        .zip(&p.theta)
        .zip(&at_n)
        .zip(&p.asymptotic)
        .map(|(((name, t), s), a)| ParameterPrediction {
            name: name.clone(),
            nominal: *t,
            std_error: *s,
            relative: s.filter(|_| *t != 0.0).map(|s| s / t.abs()),
            asymptotic: a.map(|a| a * f),
        })
        .collect::<Vec<_>>();
    let scale = (p.samples as f64 / n.max(1) as f64).sqrt();
    let disturbances = p
        .disturbances
        .iter()
        .map(|(name, mean, s)| DisturbancePrediction {
            name: name.clone(),
            mean: *mean,
            std_error: s.map(|s| s * scale),
        })
        .collect();
    let mut lengths: Vec<usize> = [n / 4, n / 2, n, 2 * n, 4 * n]
        .into_iter()
        .filter(|l| *l > 0)
        .collect();
    let target = target.and_then(|t| {
        p.samples_for(t).map(|samples| Target {
            relative: t,
            samples,
            seconds: samples.map(|s| s as f64 * h),
            within_budget: samples.is_some_and(|s| s <= n),
        })
    });
    if let Some(s) = target.as_ref().and_then(|t| t.samples) {
        lengths.push(s);
    }
    lengths.sort_unstable();
    lengths.dedup();
    let curve = lengths
        .into_iter()
        .map(|l| {
            let s = p.at(l);
            CurvePoint {
                samples: l,
                seconds: l as f64 * h,
                worst_relative: rel(&s),
                std_errors: s,
            }
        })
        .collect();
    let limit = target.as_ref().map_or(0.1, |t| t.relative);
    let poorly_determined = parameters
        .iter()
        .enumerate()
        .filter_map(|(i, q)| {
            let r = q.relative?;
            (r > limit).then(|| {
                let term = ir
                    .terms
                    .iter()
                    .find(|t| t.parameter == i)
                    .map_or_else(String::new, |t| t.text.clone());
                PoorlyDetermined {
                    name: q.name.clone(),
                    relative: r,
                    help: format!(
                        "run {} per experiment for {:.0} %, or excite {term} more: {}",
                        crate::bounds::needed_words(crate::bounds::needed(
                            n as f64 * (r / limit) * (r / limit)
                        )),
                        limit * 100.0,
                        excite_help(ir, i, room_used)
                    ),
                    term,
                }
            })
        })
        .collect();
    PredictionReport {
        evaluated_at: p.samples,
        trials: p.trials,
        worst_relative: rel(&at_n),
        parameters,
        disturbances,
        curve,
        target,
        poorly_determined,
    }
}

/// Which inputs move parameter `p`'s regressor: those acting directly in
/// the equations of the states its term holds, and how much of their room
/// the excitation already uses.
fn excite_help(ir: &Ir, p: usize, scale: f64) -> String {
    let states: Vec<usize> = ir
        .terms
        .iter()
        .filter(|t| t.parameter == p)
        .flat_map(|t| t.factors.iter())
        .filter_map(|f| match f.arg.signal {
            leeway_structure::ir::Signal::State(s) => Some(s),
            leeway_structure::ir::Signal::Input(_) => None,
        })
        .collect();
    let mut inputs: Vec<&str> = Vec::new();
    for t in ir.terms.iter().filter(|t| states.contains(&t.output)) {
        for f in &t.factors {
            if let leeway_structure::ir::Signal::Input(i) = f.arg.signal
                && !inputs.contains(&ir.inputs[i].as_str())
            {
                inputs.push(&ir.inputs[i]);
            }
        }
    }
    let room = if scale < 0.999 {
        format!(
            " (the excitation uses {:.0} % of their room, limited by the held signs: offsets farther from zero, or wider ranges, leave more)",
            scale * 100.0
        )
    } else {
        " (the excitation already uses their whole room: a wider range would help)".to_string()
    };
    if inputs.is_empty() {
        "a larger amplitude on the inputs that move its states".to_string()
    } else {
        format!("a larger amplitude on {}{room}", inputs.join(", "))
    }
}

/// IV3 (measured media pointwise) and IV2 (every medium held): the signs
/// each holds along the nominal runs. An argument the design's pattern does
/// not fix is held on the side its nominal run mostly takes.
fn method_signs(
    model: &dyn Model,
    c: &Conditions,
    bases: &[Base],
    runs: &[Run],
    designed: PredictorKind,
) -> Vec<MethodSigns> {
    let ir = model.ir();
    let any_measured = ir.disturbances.iter().any(|d| d.measured);
    let methods: &[Method] = if any_measured {
        &[Method::Iv3, Method::Iv2]
    } else {
        &[Method::Iv3]
    };
    methods
        .iter()
        .map(|m| {
            let kind = m.predictor();
            let own = relevant_signs(ir, designed);
            let arguments: Vec<ArgumentMargin> = bases
                .iter()
                .zip(runs)
                .enumerate()
                .flat_map(|(e, (b, run))| {
                    argument_margins(model, c, kind, run, (&b.pattern, &own), e)
                })
                .collect();
            MethodSigns {
                method: m.name().to_string(),
                holds: arguments.iter().all(|a| a.min_margin >= 0.0),
                arguments,
            }
        })
        .collect()
}

/// The smallest nominal margin, over the starting headings, of every
/// argument `kind` holds in run `e`: those in `fixed.1` on the side
/// `fixed.0` gives them, the others on the side their nominal run from
/// heading 0 mostly takes.
pub(crate) fn argument_margins(
    model: &dyn Model,
    c: &Conditions,
    kind: PredictorKind,
    run: &Run,
    fixed: (&[i8], &[usize]),
    e: usize,
) -> Vec<ArgumentMargin> {
    let ir = model.ir();
    let system = true_system(c, &[], 0.0, false);
    let truths: Vec<Truth> = start_headings(model, c)
        .iter()
        .map(|psi| simulate(model, &system, run, "nominal", *psi, 0).1)
        .collect();
    let mut pattern = fixed.0.to_vec();
    for a in held(ir, kind, &pattern, c) {
        if !fixed.1.contains(&a.index) {
            let plain = Held {
                band: 0.0,
                sign: 1.0,
                ..a
            };
            let m = margins(model, &truths[0], &run.inputs, std::slice::from_ref(&plain));
            pattern[plain.index] = if m[0].iter().sum::<f64>() < 0.0 {
                -1
            } else {
                1
            };
        }
    }
    let h = held(ir, kind, &pattern, c);
    let mut worst = vec![f64::INFINITY; h.len()];
    for t in &truths {
        for (w, ms) in worst.iter_mut().zip(margins(model, t, &run.inputs, &h)) {
            *w = ms.into_iter().fold(*w, f64::min);
        }
    }
    h.iter()
        .zip(worst)
        .map(|(a, w)| ArgumentMargin {
            experiment: e + 1,
            argument: a.name.clone(),
            side: side(a.sign),
            min_margin: w,
        })
        .collect()
}

/// What would work when a held argument falls short.
fn proposals(ir: &Ir, shortfalls: &[Shortfall], bases: &[Base]) -> Vec<String> {
    let mut out = Vec::new();
    for s in shortfalls {
        let Some(arg) = ir.sign_args.iter().find(|a| a.name == s.argument) else {
            continue;
        };
        let medium = ir.arg_shares(&arg.arg).first().map(|(_, comp)| {
            ir.disturbances[ir.components[*comp].disturbance]
                .name
                .clone()
        });
        let steady = bases
            .get(s.experiment - 1)
            .and_then(|b| {
                b.held
                    .iter()
                    .zip(&b.operating.margins)
                    .find(|(h, _)| h.name == s.argument)
            })
            .map(|(_, m)| *m);
        let line = match (medium, arg.measured) {
            (Some(m), false) => format!(
                "{}: falls {} short of its band in experiment {}: measure {m} (declare it `measured` and log it) so IV3 evaluates its moduli pointwise (paper A13) and needs no fixed sign; or a larger offset: the best steady margin within the limits is {}",
                s.argument,
                leeway_model::number::short_number(s.short_by),
                s.experiment,
                steady.map_or("unknown".into(), leeway_model::number::short_number),
            ),
            _ => format!(
                "{}: falls {} short in experiment {}: widen the inputs' ranges, or plan for weaker disturbances if the conditions allow",
                s.argument,
                leeway_model::number::short_number(s.short_by),
                s.experiment
            ),
        };
        if !out.contains(&line) {
            out.push(line);
        }
    }
    out
}
