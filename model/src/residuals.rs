//! Residual analysis, as MATLAB's `resid`: one-step-ahead predictions of
//! θ on recorded experiments, their residuals, and the tests that a model
//! which describes the data passes — residuals white (uncorrelated with
//! their own past) and independent of the inputs. One implementation for
//! `leeway validate --resid` and `leeway.residuals`.
//!
//! For `der x = f(x, u, θ)` sampled at step `h`, the prediction
//! `x̂(k+1|k)` is one step of the integrator [`simulate`](crate::simulate)
//! uses ([`Model::step`]) from the *measured* state `x(k)`, with the
//! measured inputs, rotation (a planar heading's rotation from the measured
//! heading) and disturbances at `k`; unmeasured disturbance components are
//! held at the given constants, as `validate` holds them. The residual is
//! `e(k+1) = x(k+1) − x̂(k+1|k)`, per state and experiment; the first sample
//! of an experiment has none.

use crate::correlation::{
    autocorrelation, centred, chi_squared_tail, cross_correlation, ljung_box,
};
use crate::delay::delayed;
use crate::experiment::{Experiment, Row, Source};
use crate::model::{Model, Signals, planar_rotation};
use crate::simulate::Disturbances;
use leeway_structure::ir::Rotation;
use serde::Serialize;

/// The default number of lags tested (MATLAB's `resid` uses 25).
pub const DEFAULT_LAGS: usize = 25;

/// The 99 % two-sided normal quantile: the confidence band of a
/// correlation of `N` white samples is `±Z_99/√N`.
pub const Z_99: f64 = 2.575_829_303_549_862;

/// The level at which a verdict fails a model that describes the data: 1 %
/// for the whole family of lags tested, not per lag (a white residual
/// would otherwise cross a 99 % band at one of 25 lags in a fifth of all
/// records).
pub const FAMILY_LEVEL: f64 = 0.01;

/// The two-sided normal quantile `z` with `P(|Z| > z) = alpha`, by bisection
/// on the χ²₁ tail (`Z²` is χ² with one degree of freedom).
pub fn normal_quantile(alpha: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi_squared_tail(mid * mid, 1) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// One experiment's one-step-ahead predictions and residuals.
#[derive(Clone, Debug, PartialEq)]
pub struct OneStep {
    /// `predicted[i][k] = x̂_i(k|k−1)`; `NaN` at `k = 0`.
    pub predicted: Vec<Vec<f64>>,
    /// `residuals[i][k] = x_i(k) − x̂_i(k|k−1)`; `NaN` at `k = 0`.
    pub residuals: Vec<Vec<f64>>,
}

/// The one-step-ahead predictions of `model` with `theta` on `data`,
/// aligned with its samples: with dead times the equations start at sample
/// `d_max` ([`delay`](crate::delay)), so the first `d_max + 1` entries are
/// `NaN` (all of them when a dead time is no whole number of samples).
pub fn one_step(
    model: &dyn Model,
    theta: &[f64],
    data: &Experiment,
    disturbances: Disturbances,
) -> OneStep {
    match delayed(model.ir(), data) {
        Ok(view) => padded(
            one_step_on(model, theta, &view, disturbances),
            view.dropped(),
        ),
        Err(_) => padded(
            OneStep {
                predicted: vec![Vec::new(); model.ir().states.len()],
                residuals: vec![Vec::new(); model.ir().states.len()],
            },
            data.len(),
        ),
    }
}

/// `one` with `n` more `NaN` samples at its start.
fn padded(one: OneStep, n: usize) -> OneStep {
    let pad = |v: Vec<Vec<f64>>| {
        v.into_iter()
            .map(|c| std::iter::repeat_n(f64::NAN, n).chain(c).collect())
            .collect()
    };
    OneStep {
        predicted: pad(one.predicted),
        residuals: pad(one.residuals),
    }
}

/// [`one_step`] on the samples the equations see.
fn one_step_on(
    model: &dyn Model,
    theta: &[f64],
    data: &dyn Source,
    disturbances: Disturbances,
) -> OneStep {
    let ir = model.ir();
    let n_states = ir.states.len();
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let h = data.step();
    let mut predicted = vec![vec![f64::NAN]; n_states];
    let mut residuals = vec![vec![f64::NAN]; n_states];
    let mut f = vec![0.0; n_states];
    let mut next = vec![0.0; n_states];
    let mut dist = vec![0.0; ir.components.len()];
    let mut previous: Option<Vec<f64>> = None;
    data.visit(&mut |row: &Row| {
        if let Some(prediction) = &previous {
            for (i, p) in prediction.iter().enumerate() {
                predicted[i].push(*p);
                residuals[i].push(row.states[i] - p);
            }
        }
        disturbances.fill(ir, row.disturbances, &mut dist);
        let heading_rotation = planar_rotation(row.heading);
        let sig = Signals {
            states: row.states,
            inputs: row.inputs,
            rotation: if planar {
                &heading_rotation
            } else {
                row.rotation
            },
            disturbances: &dist,
        };
        model.step(theta, h, &sig, &mut f, &mut next);
        previous = Some(next.clone());
    });
    OneStep {
        predicted,
        residuals,
    }
}

/// The correlation of one state's residual with one input.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InputTest {
    /// The input.
    pub input: String,
    /// `r_eu(τ)` for τ = −M..=M: `Σ e(t)·u(t−τ) / √(Σe²·Σu²)`, each series
    /// minus its experiment's mean; a positive τ pairs the residual with
    /// past inputs. `null` when undefined (a constant input).
    pub correlation: Vec<Option<f64>>,
    /// The largest `|r_eu(τ)|` (null when none is defined).
    pub max_abs: Option<f64>,
    /// The lags whose correlation lies outside the band.
    pub outside: Vec<i64>,
    /// No lag outside the family band ([`ResidualTests::input_band`]).
    pub independent: bool,
}

/// The tests of one state's residual.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateTest {
    /// The state.
    pub state: String,
    /// The residuals' mean (over every experiment).
    pub mean: Option<f64>,
    /// Their root mean square about each experiment's mean.
    pub std: Option<f64>,
    /// `r_ee(τ)` for τ = 1..=M (each experiment's residual minus its mean).
    pub autocorrelation: Vec<Option<f64>>,
    /// The largest `|r_ee(τ)|`.
    pub max_abs: Option<f64>,
    /// The lags whose autocorrelation lies outside the band.
    pub outside: Vec<usize>,
    /// No lag outside the family band ([`ResidualTests::white_band`]).
    pub white: bool,
    /// The Ljung–Box statistic over lags 1..=M.
    pub ljung_box: Option<f64>,
    /// `P(χ²_M > Q)`: small when the residual is not white.
    pub p_value: Option<f64>,
    /// The correlation with each input.
    pub inputs: Vec<InputTest>,
}

/// Residual tests over every experiment (products never reach across an
/// experiment boundary).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ResidualTests {
    /// M, the largest lag tested.
    pub lags: usize,
    /// The residual samples tested, N (every experiment's but its first).
    pub samples: usize,
    /// The confidence level of the band (0.99).
    pub confidence: f64,
    /// The band's half-width, `Z_99/√N`: each lag's correlation of a
    /// white residual lies within it with 99 % probability (the band
    /// MATLAB's `resid` draws). `outside` lists the lags beyond it.
    pub band: f64,
    /// The band the whiteness verdict reads: `z/√N` with `z` for 1 % over
    /// all M lags together (Bonferroni, [`FAMILY_LEVEL`]`/M` per lag).
    pub white_band: f64,
    /// The band the input-independence verdict reads (the same, over the
    /// 2M+1 lags of a cross-correlation).
    pub input_band: f64,
    /// One entry per state.
    pub states: Vec<StateTest>,
}

/// Residual analysis of θ on experiments: the predictions and the tests.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// Per experiment, in order.
    pub one_step: Vec<OneStep>,
    /// The tests over all of them.
    pub tests: ResidualTests,
}

/// The one-step residuals of `model` with `theta` on every experiment and
/// their tests at lags up to `lags`, with unmeasured disturbances held at
/// `disturbances` (by global component). An error when `lags` is 0 or not
/// below the number of residual samples.
pub fn analyse(
    model: &dyn Model,
    theta: &[f64],
    experiments: &[Experiment],
    disturbances: &[f64],
    lags: usize,
) -> Result<Analysis, String> {
    // The tests run on the samples the equations see (dead times applied);
    // the predictions are handed back aligned with the records.
    let views = experiments
        .iter()
        .map(|e| delayed(model.ir(), e).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, String>>()?;
    let shifted: Vec<&Experiment> = views
        .iter()
        .zip(experiments)
        .map(|(v, e)| v.in_memory().unwrap_or(e))
        .collect();
    let one: Vec<OneStep> = views
        .iter()
        .map(|v| one_step_on(model, theta, v, Disturbances::Constant(disturbances)))
        .collect();
    let experiments = shifted;
    let samples: usize = experiments.iter().map(|e| e.len().saturating_sub(1)).sum();
    if lags == 0 || lags >= samples {
        return Err(format!(
            "{lags} lags cannot be tested on {samples} residual samples (every experiment's but its first)"
        ));
    }
    let root = (samples as f64).sqrt();
    let band = Z_99 / root;
    let bands = Bands {
        band,
        white: normal_quantile(FAMILY_LEVEL / lags as f64) / root,
        input: normal_quantile(FAMILY_LEVEL / (2 * lags + 1) as f64) / root,
    };
    let ir = model.ir();
    let states = ir
        .states
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let segments: Vec<&[f64]> = one.iter().map(|o| &o.residuals[i][1..]).collect();
            let inputs: Vec<(&str, Vec<&[f64]>)> = ir
                .inputs
                .iter()
                .enumerate()
                .map(|(j, u)| {
                    let segments = experiments.iter().map(|e| &e.inputs[j][1..]).collect();
                    (u.as_str(), segments)
                })
                .collect();
            state_test(name, &segments, &inputs, lags, &bands)
        })
        .collect();
    Ok(Analysis {
        one_step: one
            .into_iter()
            .zip(&views)
            .map(|(o, v)| padded(o, v.dropped()))
            .collect(),
        tests: ResidualTests {
            lags,
            samples,
            confidence: 0.99,
            band,
            white_band: bands.white,
            input_band: bands.input,
            states,
        },
    })
}

/// The largest defined `|r|`.
fn max_abs(r: &[Option<f64>]) -> Option<f64> {
    r.iter().flatten().map(|r| r.abs()).reduce(f64::max)
}

/// The per-lag band and the verdicts' family bands.
struct Bands {
    band: f64,
    white: f64,
    input: f64,
}

/// The tests of one state's residual `segments` (one per experiment).
fn state_test(
    name: &str,
    segments: &[&[f64]],
    inputs: &[(&str, Vec<&[f64]>)],
    lags: usize,
    bands: &Bands,
) -> StateTest {
    let band = bands.band;
    let n: usize = segments.iter().map(|s| s.len()).sum();
    let total: f64 = segments.iter().flat_map(|s| s.iter()).sum();
    let e = centred(segments);
    let variance = e.iter().flatten().map(|v| v * v).sum::<f64>() / n as f64;
    let r = autocorrelation(&e, lags);
    let outside: Vec<usize> = (1..=lags)
        .filter(|t| r[t - 1].is_some_and(|r| r.abs() > band))
        .collect();
    let q = ljung_box(&r, n);
    let taus: Vec<i64> = (-(lags as i64)..=lags as i64).collect();
    let inputs = inputs
        .iter()
        .map(|(input, u)| {
            let c = cross_correlation(&e, &centred(u), &taus);
            let outside: Vec<i64> = taus
                .iter()
                .zip(&c)
                .filter(|(_, c)| c.is_some_and(|c| c.abs() > band))
                .map(|(t, _)| *t)
                .collect();
            let max = max_abs(&c);
            InputTest {
                input: input.to_string(),
                max_abs: max,
                // A constant input has no correlation: nothing against it.
                independent: max.is_none_or(|m| m <= bands.input),
                outside,
                correlation: c,
            }
        })
        .collect();
    let finite = |v: f64| v.is_finite().then_some(v);
    StateTest {
        state: name.to_string(),
        mean: finite(total / n as f64),
        std: finite(variance.sqrt()),
        max_abs: max_abs(&r),
        white: r.iter().all(|r| r.is_some_and(|r| r.abs() <= bands.white)),
        outside,
        autocorrelation: r,
        ljung_box: q,
        p_value: q.map(|q| chi_squared_tail(q, lags)),
        inputs,
    }
}
