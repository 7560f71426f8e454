//! `leeway.residuals`: the residual analysis of `leeway validate --resid`
//! (`leeway_model::residuals`) on frames loaded as `leeway.validate` loads
//! them — the free run's errors and their input-independence (the
//! verdict) and whiteness tests; one-step-ahead predictions for
//! `leeway.predict`.

use crate::data::{self, FrameArg, borrow_frames};
use crate::failure::Failure;
use crate::model::Model;
use crate::options::load_options;
use crate::simulate::{check_theta, held};
use leeway_model::Interpreter;
use leeway_model::residuals::{analyse, one_step as predict};
use leeway_model::simulate::Disturbances;
use numpy::PyArray1;
use pyo3::prelude::*;

/// One experiment: its name, step, and per state the measurement, the
/// model's value (the free run, or the one-step prediction) and the error
/// (NaN where there is none).
type Columns<'py> = (
    String,
    f64,
    Vec<Bound<'py, PyArray1<f64>>>,
    Vec<Bound<'py, PyArray1<f64>>>,
    Vec<Bound<'py, PyArray1<f64>>>,
);

/// One experiment's model values and errors, per state.
type Run = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// The experiments' columns, the tests as JSON (the `residuals` object of
/// `leeway validate --json --resid`; `null` for one-step predictions) and
/// the warnings (a disturbance zero by default).
type Analysed<'py> = (Vec<Columns<'py>>, String, Vec<String>);

/// The residual analysis of `model` with `theta` on the frames'
/// experiments — the free run's errors and their tests at lags up to
/// `lags` — or, with `one_step`, the one-step-ahead predictions and their
/// errors (no tests). Unmeasured disturbances are held as `leeway.simulate`
/// holds them (`disturbances`, `zero`, the estimate's `means`). The GIL is
/// released while loading and computing.
#[pyfunction]
#[pyo3(signature = (model, frames, theta, disturbances, lags, zero=false, means=None, step=None, time_tolerance=0.05, resample=None, one_step=false))]
#[allow(clippy::too_many_arguments)]
pub fn residual_analysis<'py>(
    py: Python<'py>,
    model: &Model,
    frames: Vec<FrameArg<'py>>,
    theta: Vec<f64>,
    disturbances: Vec<(String, f64)>,
    lags: usize,
    zero: bool,
    means: Option<Vec<(String, f64)>>,
    step: Option<f64>,
    time_tolerance: f64,
    resample: Option<f64>,
    one_step: bool,
) -> PyResult<Analysed<'py>> {
    let ir = &model.ir;
    check_theta(ir, &theta)?;
    let options = load_options(ir, step, Some(time_tolerance), resample)?;
    let (dist, _, warning) = held(ir, &disturbances, zero, means.as_deref(), "theta")?;
    let frames = borrow_frames(&frames)?;
    let (experiments, runs, tests) = py.detach(|| -> Result<(_, Vec<Run>, _), Failure> {
        let (experiments, _notes) = data::load(ir, &frames, &options)?;
        let interpreter = Interpreter::new(ir.clone());
        if one_step {
            let runs = experiments
                .iter()
                .map(|e| {
                    let o = predict(&interpreter, &theta, e, Disturbances::Constant(&dist));
                    (o.predicted, o.residuals)
                })
                .collect();
            return Ok((experiments, runs, "null".to_string()));
        }
        let analysis = analyse(&interpreter, &theta, &experiments, &dist, lags).map_err(|m| {
            Failure::option(
                format!("lags={lags}: {m}"),
                Some("give fewer lags, e.g. lags=25, or more samples".into()),
            )
        })?;
        let tests = serde_json::to_string(&analysis.tests)
            .map_err(|e| Failure::option(format!("the tests could not be written: {e}"), None))?;
        let runs = analysis
            .simulated
            .into_iter()
            .map(|r| (r.simulated, r.residuals))
            .collect();
        Ok((experiments, runs, tests))
    })?;
    let arrays = |columns: &[Vec<f64>]| -> Vec<Bound<'py, PyArray1<f64>>> {
        columns
            .iter()
            .map(|c| PyArray1::from_slice(py, c))
            .collect()
    };
    let columns = experiments
        .iter()
        .zip(&runs)
        .map(|(e, (model_values, errors))| {
            (
                e.name.clone(),
                e.h,
                arrays(&e.states),
                arrays(model_values),
                arrays(errors),
            )
        })
        .collect();
    Ok((columns, tests, warning.into_iter().collect()))
}
