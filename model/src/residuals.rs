//! Residual analysis, as MATLAB's `resid` reads an output-error model: the
//! errors of θ's simulation on recorded experiments and the tests that a
//! model which describes the data passes. One implementation for `leeway
//! validate --resid` and `leeway.residuals`.
//!
//! The errors tested are those of the *free run* ([`simulate`], from each
//! experiment's first measured state, driven by its measured inputs),
//! `e(k) = x(k) − x̂(k)`, not one-step prediction errors: with white
//! measurement noise the one-step error of the *true* model is MA(1)
//! (`v(k+1) − v(k)`, lag-1 correlation −½), so a whiteness test on it
//! rejects every model. The free-run error of the true model is the
//! measurement noise plus the response to the disturbances' variation
//! about the values held; whatever its colour, it is independent of the
//! inputs in open loop. So the **verdict is independence of the inputs**:
//! each cross-correlation `r_eu(τ)` is read against a band widened by
//! `√P`, `P = Σ_τ r_ee(τ)·r_uu(τ)` (Ljung, *System Identification*, 2nd
//! ed., §16.6), which is the variance of `√N·r_eu` when `e` is independent
//! of `u` whatever either's colour. Whiteness is reported too, as
//! information: it holds for the true model when the disturbances are
//! constant, and fails for any model when they vary.
//!
//! One-step-ahead predictions ([`one_step`]) are kept for
//! `leeway.predict`: `x̂(k+1|k)` is one step of the integrator
//! [`simulate`] uses ([`Model::step`]) from the *measured* state `x(k)`,
//! with the measured inputs, rotation (a planar heading's rotation from the
//! measured heading) and disturbances at `k`; unmeasured disturbance
//! components are held at the given constants, as `validate` holds them.

use crate::correlation::{
    autocorrelation, centred, chi_squared_tail, cross_correlation, ljung_box,
};
use crate::delay::delayed;
use crate::experiment::{Experiment, Row, Source};
use crate::model::{Model, Signals, planar_rotation};
use crate::simulate::{Disturbances, simulate};
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

/// The correlation of one state's error with one input.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InputTest {
    /// The input.
    pub input: String,
    /// `r_eu(τ)` for τ = −M..=M: `Σ e(t)·u(t−τ) / √(Σe²·Σu²)`, each series
    /// minus its experiment's mean; a positive τ pairs the error with
    /// past inputs. `null` when undefined (a constant input).
    pub correlation: Vec<Option<f64>>,
    /// The largest `|r_eu(τ)|` (null when none is defined).
    pub max_abs: Option<f64>,
    /// `P = Σ_{|τ|≤M} r_ee(τ)·r_uu(τ)` (at least 1): the variance of
    /// `√N·r_eu(τ)` when the error is independent of the input; 1 when
    /// the error is white.
    pub variance_factor: Option<f64>,
    /// The band this input's verdict reads: the family band for a white
    /// error ([`ResidualTests::input_band`]) times `√P`.
    pub band: Option<f64>,
    /// The lags whose correlation lies outside the per-lag 99 % band
    /// ([`ResidualTests::band`] times `√P`).
    pub outside: Vec<i64>,
    /// No lag outside `band`: nothing of this input is left in the error.
    pub independent: bool,
}

/// The tests of one state's error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateTest {
    /// The state.
    pub state: String,
    /// The errors' mean (over every experiment).
    pub mean: Option<f64>,
    /// Their root mean square about each experiment's mean.
    pub std: Option<f64>,
    /// `r_ee(τ)` for τ = 1..=M (each experiment's error minus its mean).
    pub autocorrelation: Vec<Option<f64>>,
    /// The largest `|r_ee(τ)|`.
    pub max_abs: Option<f64>,
    /// The lags whose autocorrelation lies outside the per-lag band.
    pub outside: Vec<usize>,
    /// No lag outside the family band ([`ResidualTests::white_band`]).
    /// Information, not the verdict: the free-run error of the true model
    /// is white only when the disturbances are constant.
    pub white: bool,
    /// The Ljung–Box statistic over lags 1..=M.
    pub ljung_box: Option<f64>,
    /// `P(χ²_M > Q)`: small when the error is not white.
    pub p_value: Option<f64>,
    /// The correlation with each input.
    pub inputs: Vec<InputTest>,
    /// The verdict: the simulation stayed finite and the error is
    /// independent of every input.
    pub independent: bool,
}

/// Residual tests over every experiment (products never reach across an
/// experiment boundary).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ResidualTests {
    /// The errors tested: `"simulation"`, `x(k) − x̂(k)` of the free run.
    pub errors: &'static str,
    /// M, the largest lag tested.
    pub lags: usize,
    /// The error samples tested, N (every experiment's but its first).
    pub samples: usize,
    /// The confidence level of the band (0.99).
    pub confidence: f64,
    /// The band's half-width, `Z_99/√N`: each lag's correlation of a
    /// white error lies within it with 99 % probability (the band
    /// MATLAB's `resid` draws). `outside` lists the lags beyond it.
    pub band: f64,
    /// The band the whiteness test reads: `z/√N` with `z` for 1 % over
    /// all M lags together (Bonferroni, [`FAMILY_LEVEL`]`/M` per lag).
    pub white_band: f64,
    /// The band the input-independence verdict reads for a white error
    /// (the same, over the 2M+1 lags of a cross-correlation); each input's
    /// own band is this times `√P` ([`InputTest::band`]).
    pub input_band: f64,
    /// The experiments whose simulation left the finite numbers.
    pub diverged: Vec<String>,
    /// One entry per state.
    pub states: Vec<StateTest>,
}

/// One experiment's free-run simulation and its errors.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulated {
    /// `simulated[i][k] = x̂_i(k)`, aligned with the record's samples
    /// (`NaN` before the equations start, with dead times).
    pub simulated: Vec<Vec<f64>>,
    /// `residuals[i][k] = x_i(k) − x̂_i(k)`; `NaN` at the first sample the
    /// equations see (the simulation starts there from the measurement).
    pub residuals: Vec<Vec<f64>>,
}

/// Residual analysis of θ on experiments: the simulations and the tests.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// Per experiment, in order.
    pub simulated: Vec<Simulated>,
    /// The tests over all of them.
    pub tests: ResidualTests,
}

/// The free-run errors of `model` with `theta` on every experiment and
/// their tests at lags up to `lags`, with unmeasured disturbances held at
/// `disturbances` (by global component). An error when `lags` is 0 or not
/// below the number of error samples.
pub fn analyse(
    model: &dyn Model,
    theta: &[f64],
    experiments: &[Experiment],
    disturbances: &[f64],
    lags: usize,
) -> Result<Analysis, String> {
    // The tests run on the samples the equations see (dead times applied);
    // the simulations are handed back aligned with the records.
    let views = experiments
        .iter()
        .map(|e| delayed(model.ir(), e).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, String>>()?;
    let shifted: Vec<&Experiment> = views
        .iter()
        .zip(experiments)
        .map(|(v, e)| v.in_memory().unwrap_or(e))
        .collect();
    let runs: Vec<(Simulated, bool)> = shifted
        .iter()
        .map(|e| free_run(model, theta, e, disturbances))
        .collect();
    let samples: usize = shifted.iter().map(|e| e.len().saturating_sub(1)).sum();
    if lags == 0 || lags >= samples {
        return Err(format!(
            "{lags} lags cannot be tested on {samples} residual samples (every experiment's but its first)"
        ));
    }
    let root = (samples as f64).sqrt();
    let bands = Bands {
        band: Z_99 / root,
        white: normal_quantile(FAMILY_LEVEL / lags as f64) / root,
        input: normal_quantile(FAMILY_LEVEL / (2 * lags + 1) as f64) / root,
    };
    let ir = model.ir();
    let states = ir
        .states
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let segments: Vec<&[f64]> = runs.iter().map(|(r, _)| &r.residuals[i][1..]).collect();
            let inputs: Vec<(&str, Vec<&[f64]>)> = ir
                .inputs
                .iter()
                .enumerate()
                .map(|(j, u)| {
                    let segments = shifted.iter().map(|e| &e.inputs[j][1..]).collect();
                    (u.as_str(), segments)
                })
                .collect();
            state_test(name, &segments, &inputs, lags, &bands)
        })
        .collect();
    let diverged = runs
        .iter()
        .zip(&shifted)
        .filter(|((_, diverged), _)| *diverged)
        .map(|(_, e)| e.name.clone())
        .collect();
    Ok(Analysis {
        simulated: runs
            .into_iter()
            .zip(&views)
            .map(|((r, _), v)| Simulated {
                simulated: pad(r.simulated, v.dropped()),
                residuals: pad(r.residuals, v.dropped()),
            })
            .collect(),
        tests: ResidualTests {
            errors: "simulation",
            lags,
            samples,
            confidence: 0.99,
            band: bands.band,
            white_band: bands.white,
            input_band: bands.input,
            diverged,
            states,
        },
    })
}

/// The free run of `theta` on `e` (the samples the equations see) and its
/// errors, and whether it diverged.
fn free_run(
    model: &dyn Model,
    theta: &[f64],
    e: &Experiment,
    disturbances: &[f64],
) -> (Simulated, bool) {
    let run = simulate(model, theta, e, Disturbances::Constant(disturbances));
    let residuals = e
        .states
        .iter()
        .zip(&run.states)
        .map(|(x, xhat)| {
            let mut r: Vec<f64> = x.iter().zip(xhat).map(|(x, xhat)| x - xhat).collect();
            if let Some(first) = r.first_mut() {
                *first = f64::NAN;
            }
            r
        })
        .collect();
    let simulated = Simulated {
        simulated: run.states,
        residuals,
    };
    (simulated, run.diverged)
}

/// Columns with `n` more `NaN` samples at their start.
fn pad(columns: Vec<Vec<f64>>, n: usize) -> Vec<Vec<f64>> {
    columns
        .into_iter()
        .map(|c| std::iter::repeat_n(f64::NAN, n).chain(c).collect())
        .collect()
}

/// The largest defined `|r|`.
fn max_abs(r: &[Option<f64>]) -> Option<f64> {
    r.iter().flatten().map(|r| r.abs()).reduce(f64::max)
}

/// The per-lag band and the tests' family bands, for a white error.
struct Bands {
    band: f64,
    white: f64,
    input: f64,
}

/// The tests of one state's error `segments` (one per experiment).
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
    let inputs: Vec<InputTest> = inputs
        .iter()
        .map(|(input, u)| input_test(input, &e, &r, &centred(u), lags, bands))
        .collect();
    let finite = |v: f64| v.is_finite().then_some(v);
    StateTest {
        state: name.to_string(),
        mean: finite(total / n as f64),
        std: finite(variance.sqrt()),
        max_abs: max_abs(&r),
        white: r.iter().all(|r| r.is_some_and(|r| r.abs() <= bands.white)),
        outside,
        ljung_box: q,
        p_value: q.map(|q| chi_squared_tail(q, lags)),
        independent: variance.is_finite() && inputs.iter().all(|i| i.independent),
        autocorrelation: r,
        inputs,
    }
}

/// The cross-correlation of the centred error `e` (autocorrelation
/// `r_ee`) with the centred input `u`, read against bands widened by
/// `√P` for the colour of both.
fn input_test(
    input: &str,
    e: &[Vec<f64>],
    r_ee: &[Option<f64>],
    u: &[Vec<f64>],
    lags: usize,
    bands: &Bands,
) -> InputTest {
    let taus: Vec<i64> = (-(lags as i64)..=lags as i64).collect();
    let c = cross_correlation(e, u, &taus);
    let r_uu = autocorrelation(u, lags);
    // P = 1 + 2·Σ_{τ≥1} r_ee(τ)·r_uu(τ), floored at 1: an estimate below
    // the white value would only narrow the band by sampling noise.
    let factor = r_ee
        .iter()
        .zip(&r_uu)
        .map(|(a, b)| Some(a.as_ref()? * b.as_ref()?))
        .sum::<Option<f64>>()
        .map(|s| (1.0 + 2.0 * s).max(1.0));
    let widen = factor.map(f64::sqrt);
    let outside: Vec<i64> = match widen {
        Some(w) => taus
            .iter()
            .zip(&c)
            .filter(|(_, c)| c.is_some_and(|c| c.abs() > bands.band * w))
            .map(|(t, _)| *t)
            .collect(),
        None => Vec::new(),
    };
    let max = max_abs(&c);
    let band = widen.map(|w| bands.input * w);
    InputTest {
        input: input.to_string(),
        max_abs: max,
        // A constant input has no correlation: nothing against it. An
        // error that is not finite (a diverged run) has none either, and
        // fails the verdict.
        // A constant input has no correlation: nothing against it (a
        // diverged run fails the state's verdict, not each input's).
        independent: max.is_none_or(|m| band.is_none_or(|b| m <= b)),
        variance_factor: factor,
        band,
        outside,
        correlation: c,
    }
}
