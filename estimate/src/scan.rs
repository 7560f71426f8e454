//! The dead time of an input found by a scan: θ estimated at each
//! candidate dead time on a grid of the sample time, each estimate judged by
//! a criterion ([`ScanBy`]), the best one kept. Several inputs are scanned
//! one after another ([`scan_delays`]), each with the dead times chosen
//! before it. One implementation for `leeway estimate --scan-delay` and
//! Python.

use crate::method::{Choice, Named, choice};
use crate::options::EstimateOptions;
use crate::outcome::{Estimate, EstimateError, err};
use crate::run::estimate;
use leeway_model::delay::delayed;
use leeway_model::experiment::Source;
use leeway_model::interp::Interpreter;
use leeway_model::model::{HeadingRotation, Model, Signals};
use leeway_model::number::short_number;
use leeway_model::simulate::Disturbances;
use leeway_structure::ir::{Delay, Ir, Lag, MAX_DELAY_SAMPLES, Rotation, samples_in};
use serde::Serialize;

/// The most candidates a scan estimates at.
pub const MAX_SCAN_CANDIDATES: usize = 200;

/// A bound of a scanned range, as given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// Samples.
    Samples(usize),
    /// Seconds (a whole number of the sample time).
    Seconds(f64),
}

/// The dead times to try for one input: `lo..=hi`, every sample between.
#[derive(Clone, Debug, PartialEq)]
pub struct DelayRange {
    /// The input.
    pub input: String,
    /// The shortest dead time tried.
    pub lo: Bound,
    /// The longest.
    pub hi: Bound,
}

impl DelayRange {
    /// `INPUT=LO..HI` (samples) or `INPUT=LO..HIs` (seconds, both bounds),
    /// or one sentence saying what is wrong.
    pub fn parse(text: &str) -> Result<DelayRange, String> {
        let shape =
            || format!("`{text}` is not `INPUT=LO..HI` (samples) or `INPUT=LO..HIs` (seconds)");
        let (input, range) = text.split_once('=').ok_or_else(shape)?;
        let (lo, hi) = range.split_once("..").ok_or_else(shape)?;
        let input = input.trim();
        if input.is_empty() {
            return Err(shape());
        }
        let (hi, seconds) = match hi.trim().strip_suffix('s') {
            Some(h) => (h, true),
            None => (hi, false),
        };
        let bound = |t: &str| -> Result<Bound, String> {
            let t = t.trim();
            if seconds {
                match t.parse::<f64>() {
                    Ok(v) if v.is_finite() && v >= 0.0 => Ok(Bound::Seconds(v)),
                    _ => Err(format!("`{t}` is not a dead time in seconds (0 or more)")),
                }
            } else {
                match t.parse::<usize>() {
                    Ok(v) if v <= MAX_DELAY_SAMPLES => Ok(Bound::Samples(v)),
                    _ => Err(format!(
                        "`{t}` is not a dead time in samples (a whole number from 0 to {MAX_DELAY_SAMPLES}; end the range with `s` for seconds)"
                    )),
                }
            }
        };
        Ok(DelayRange {
            input: input.to_string(),
            lo: bound(lo)?,
            hi: bound(hi)?,
        })
    }

    /// A comma-separated list of ranges (`tau_x=0..2s,tau_y=0..2s`), each
    /// input at most once.
    pub fn parse_list(text: &str) -> Result<Vec<DelayRange>, String> {
        let mut out: Vec<DelayRange> = Vec::new();
        for part in text.split(',') {
            let range = DelayRange::parse(part)?;
            if out.iter().any(|r| r.input == range.input) {
                return Err(format!("`{}` is scanned twice", range.input));
            }
            out.push(range);
        }
        Ok(out)
    }

    /// The candidate dead times in samples at the sample time `h`, checked:
    /// `lo ≤ hi`, whole numbers of samples, at most
    /// [`MAX_SCAN_CANDIDATES`], on an input of `ir`.
    pub fn candidates(&self, ir: &Ir, h: f64) -> Result<Vec<usize>, String> {
        if !ir.inputs.contains(&self.input) {
            return Err(format!(
                "`{}` is not an input of the model (inputs: {})",
                self.input,
                if ir.inputs.is_empty() {
                    "none".to_string()
                } else {
                    ir.inputs.join(", ")
                }
            ));
        }
        let samples = |b: Bound| match b {
            Bound::Samples(n) => Ok(n),
            Bound::Seconds(s) => samples_in(s, h).map_err(|_| {
                format!(
                    "{} s is no whole number of sample times of {} s (at most {MAX_DELAY_SAMPLES})",
                    short_number(s),
                    short_number(h)
                )
            }),
        };
        let (lo, hi) = (samples(self.lo)?, samples(self.hi)?);
        if lo > hi {
            return Err(format!("the range runs backwards: {lo} to {hi} samples"));
        }
        if hi - lo + 1 > MAX_SCAN_CANDIDATES {
            return Err(format!(
                "{} candidate dead times ({lo} to {hi} samples); a scan tries at most {MAX_SCAN_CANDIDATES}",
                hi - lo + 1
            ));
        }
        Ok((lo..=hi).collect())
    }
}

/// What a scan judges each candidate's estimate by (larger is better).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ScanBy {
    /// The estimate's simulation on its data, fitted as `validate` fits
    /// (the mean of the states' fits, %).
    #[default]
    Fit,
    /// The one-step-ahead prediction of the estimate on its data, fitted the
    /// same way (%): the equation error the estimator's regression leaves.
    Residual,
}

impl Named for ScanBy {
    const OPTION: &'static str = "scan-by";
    const CHOICES: &'static [Choice<ScanBy>] = &[
        choice(
            "fit",
            ScanBy::Fit,
            "the estimate's simulation on its data, fitted as `validate` fits",
        ),
        choice(
            "residual",
            ScanBy::Residual,
            "the estimate's one-step-ahead prediction on its data, fitted the same way",
        ),
    ];
}

/// One candidate of a scan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScanPoint {
    /// The dead time in samples.
    pub samples: usize,
    /// In seconds.
    pub seconds: f64,
    /// The criterion (%); `None` when undefined (a simulation diverged).
    pub criterion: Option<f64>,
    /// Why there is no estimate at this dead time, if there is none.
    pub error: Option<String>,
}

/// A scan's curve, its choice and the estimate there.
#[derive(Clone, Debug)]
pub struct DelayScan {
    /// The input scanned.
    pub input: String,
    /// The criterion.
    pub by: ScanBy,
    /// Every candidate in order.
    pub points: Vec<ScanPoint>,
    /// The index of the chosen one in `points`.
    pub chosen: usize,
    /// The model with the chosen dead time.
    pub ir: Ir,
    /// The estimate at the chosen dead time.
    pub estimate: Estimate,
}

/// Scans the inputs of `ranges` one after another: each scan starts from
/// the dead times the ones before it chose (the others as the model
/// declares them). The last scan's estimate is at every chosen dead time.
/// A coordinate search, not a joint grid: its cost is the sum of the
/// ranges, not their product, and it finds the joint best when the inputs'
/// dead times act on the fit apart (as distinct actuators do).
pub fn scan_delays(
    ir: &Ir,
    experiments: &[&dyn Source],
    options: &EstimateOptions,
    ranges: &[DelayRange],
    by: ScanBy,
) -> Result<Vec<DelayScan>, EstimateError> {
    let mut scans: Vec<DelayScan> = Vec::with_capacity(ranges.len());
    for range in ranges {
        let current = scans.last().map_or(ir, |s| &s.ir);
        let scan = scan_delay(current, experiments, options, range, by)?;
        scans.push(scan);
    }
    Ok(scans)
}

/// `ir` with `input`'s dead time set to `samples` (any declared one replaced).
pub fn with_dead_time(ir: &Ir, input: usize, samples: usize) -> Ir {
    let mut out = ir.clone();
    out.delays.retain(|d| d.input != input);
    if samples > 0 {
        out.delays.push(Delay {
            input,
            lag: Lag::Samples(samples),
        });
    }
    out
}

/// The sample time every experiment shares (the model's `step` when
/// declared), or an error naming the first that differs.
fn common_step(ir: &Ir, experiments: &[&dyn Source]) -> Result<f64, EstimateError> {
    if let Some(h) = ir.step {
        return Ok(h);
    }
    let h = experiments.first().map_or(1.0, |e| e.step());
    match experiments
        .iter()
        .find(|e| e.step().to_bits() != h.to_bits())
    {
        None => Ok(h),
        Some(e) => Err(err(
            "invalid-scan",
            format!(
                "experiment `{}` is sampled at {} s, the first at {h} s: a scan's grid is one sample time",
                e.name(),
                e.step()
            ),
            "scan experiments of one sample time, or declare `step` in the model",
        )),
    }
}

/// Estimates θ at every candidate dead time of `range` and keeps the one
/// with the best criterion (the shortest dead time among equals). Fails
/// only when the range is invalid or no candidate gives an estimate (then
/// with the error of the last).
pub fn scan_delay(
    ir: &Ir,
    experiments: &[&dyn Source],
    options: &EstimateOptions,
    range: &DelayRange,
    by: ScanBy,
) -> Result<DelayScan, EstimateError> {
    let h = common_step(ir, experiments)?;
    let candidates = range.candidates(ir, h).map_err(|m| {
        err(
            "invalid-scan",
            m,
            "scan an input of the model over at most 200 samples, e.g. tau=0..20 or tau=0..2s",
        )
    })?;
    let input = ir
        .inputs
        .iter()
        .position(|i| *i == range.input)
        .unwrap_or_default();
    let mut options = options.clone();
    options.own_simulation = options.own_simulation || by == ScanBy::Fit;
    let mut points = Vec::with_capacity(candidates.len());
    let mut best: Option<(usize, f64, Ir, Estimate)> = None;
    let mut last_error = None;
    for d in candidates {
        crate::estimator::stop_if_interrupted(&options)?;
        let ir_d = with_dead_time(ir, input, d);
        let model = Interpreter::new(ir_d.clone());
        let (criterion, error) = match estimate(&model, experiments, &options) {
            Ok(e) => {
                let c = match by {
                    ScanBy::Fit => e
                        .diagnostics
                        .own_simulation
                        .as_ref()
                        .and_then(|o| o.mean_fit),
                    ScanBy::Residual => one_step_fit(&model, &e, experiments),
                };
                let score = c.unwrap_or(f64::NEG_INFINITY);
                if best.as_ref().is_none_or(|b| score > b.1) {
                    best = Some((points.len(), score, ir_d, e));
                }
                (c, None)
            }
            Err(e) => {
                let message = e.message.clone();
                last_error = Some(e);
                (None, Some(message))
            }
        };
        points.push(ScanPoint {
            samples: d,
            seconds: d as f64 * h,
            criterion,
            error,
        });
    }
    let Some((chosen, _, ir, estimate)) = best else {
        return Err(last_error.unwrap_or_else(|| {
            err(
                "invalid-scan",
                "no candidate dead time",
                "give a range of dead times",
            )
        }));
    };
    Ok(DelayScan {
        input: range.input.clone(),
        by,
        points,
        chosen,
        ir,
        estimate,
    })
}

/// The mean over states of the one-step-ahead prediction's fit on the
/// experiments (pooled), `None` when undefined.
fn one_step_fit(model: &dyn Model, e: &Estimate, experiments: &[&dyn Source]) -> Option<f64> {
    let ir = model.ir();
    let n = ir.states.len();
    let means: Vec<f64> = ir
        .components
        .iter()
        .map(|c| {
            e.disturbances
                .iter()
                .find(|m| m.component == c.name)
                .map_or(0.0, |m| m.mean)
        })
        .collect();
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let (mut err2, mut sum, mut sum2, mut count) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], 0.0);
    let (mut f, mut next, mut dist) = (vec![0.0; n], vec![0.0; n], vec![0.0; ir.components.len()]);
    for source in experiments {
        let view = delayed(ir, *source).ok()?;
        let mut previous: Option<Vec<f64>> = None;
        let mut headings = HeadingRotation::default();
        view.visit(&mut |row| {
            if let Some(p) = &previous {
                for o in 0..n {
                    let d = row.states[o] - p[o];
                    err2[o] += d * d;
                    sum[o] += row.states[o];
                    sum2[o] += row.states[o] * row.states[o];
                }
                count += 1.0;
            }
            Disturbances::Constant(&means).fill(ir, row.disturbances, &mut dist);
            let rot = headings.next(row.heading);
            let sig = Signals {
                states: row.states,
                inputs: row.inputs,
                rotation: if planar { &rot } else { row.rotation },
                disturbances: &dist,
            };
            model.step(&e.theta, view.step(), &sig, &mut f, &mut next);
            previous = Some(next.clone());
        });
    }
    let fits: Vec<f64> = (0..n)
        .filter_map(|o| {
            let spread = sum2[o] - sum[o] * sum[o] / count;
            (spread > 0.0 && err2[o].is_finite()).then(|| 100.0 * (1.0 - (err2[o] / spread).sqrt()))
        })
        .collect();
    (!fits.is_empty()).then(|| fits.iter().sum::<f64>() / fits.len() as f64)
}
