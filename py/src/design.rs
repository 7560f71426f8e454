//! `leeway.design` and `leeway.dask.verify_design`: the trial design of
//! `leeway design` (leeway-design) on a compiled model and a plan's text.
//! [`Designed`] holds one design, made by the code the CLI runs; it answers
//! with the CLI's JSON document (`leeway_design::document::json`), the
//! runs' nominal records as the columns `design --out` writes to
//! `run-N.csv`, and, for a cluster, each Monte Carlo run of the
//! verification as bytes and the verification from every run's bytes
//! (`leeway_design::distributed`) — the same as the local verification,
//! bit for bit.

use crate::failure::Failure;
use crate::model::Model;
use crate::options::choice;
use leeway_data::write;
use leeway_design::bounds::{PILOT, TRIALS, pilot};
use leeway_design::design::DesignOptions;
use leeway_design::distributed::{summarise, trial, verifiable};
use leeway_design::document::json;
use leeway_design::plan::{locate, parse};
use leeway_design::report::Design;
use leeway_design::verified::design_verified;
use leeway_design::verify::Verification;
use leeway_estimate::Method;
use leeway_model::Interpreter;
use leeway_model::model::Model as _;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// The options as Python gives them (`leeway design`'s flags).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct DesignArgs {
    method: String,
    target: Option<f64>,
    seed: u64,
    pilot: usize,
    /// Monte Carlo trials verifying the design, and the other runs it
    /// tried when its verdict fails (`None`: not verified here).
    verify: Option<usize>,
}

/// The CLI's bounds (`leeway_design::bounds`), checked here too so that a
/// caller past the Python half meets the same limits.
const MAX_RUNS: usize = TRIALS;

impl DesignArgs {
    fn options(&self) -> Result<DesignOptions, Failure> {
        let method = choice::<Method>(&self.method)?;
        if !matches!(method, Method::Iv3 | Method::Iv2) {
            return Err(Failure::option(
                format!("method={:?}: a design is made for iv3 or iv2", self.method),
                Some("method=\"iv3\" (measured media pointwise) or method=\"iv2\"".into()),
            ));
        }
        if let Some(t) = self
            .target
            .filter(|t| !(t.is_finite() && *t > 0.0 && *t < 1.0))
        {
            return Err(Failure::option(
                format!("target={t}: a relative precision is between 0 and 1"),
                Some("target=0.05 or target=\"5%\"".into()),
            ));
        }
        if pilot(self.pilot).is_err() {
            return Err(Failure::option(
                format!("pilot={} is not in 0..={PILOT}", self.pilot),
                None,
            ));
        }
        Ok(DesignOptions {
            method,
            target: self.target,
            seed: self.seed,
            pilot: self.pilot,
            runs: None,
        })
    }
}

/// A design's error as the exception of its class: the plan file at its
/// line and column (`location`), a model no trial can identify
/// (`Unidentifiable`), or a model and plan no design can serve.
fn failure(e: &leeway_design::error::DesignError, plan: &str, located: bool) -> Failure {
    let class = match e.code {
        "plan" => "PlanError",
        "invalid-option" => "OptionError",
        "not-identifiable" => "Unidentifiable",
        _ => "DesignError",
    };
    let location = match (e.code, e.line, e.column) {
        ("plan", Some(l), Some(c)) if located => Some(format!("{plan}:{l}:{c}")),
        ("plan", _, _) => Some(plan.to_string()),
        _ => None,
    };
    Failure::design(class, e.code, &e.message, &e.hint, location)
}

/// One design: the model it was made for, the design, its seed and, when
/// made with `verify`, its verification (the design then the first of the
/// runs it tried whose verified models pass, as the CLI's).
#[pyclass(module = "leeway._leeway", frozen)]
pub struct Designed {
    interpreter: Interpreter,
    design: Design,
    seed: u64,
    verification: Option<Verification>,
}

#[pymethods]
impl Designed {
    /// Designs the trial for `model` from the plan's text (JSON when `json`
    /// or when it starts with `{`, TOML otherwise); `plan_name` locates the
    /// plan's errors, at their line and column when `located`. The GIL is
    /// released while it designs.
    #[staticmethod]
    fn make(
        py: Python<'_>,
        model: &Model,
        plan: &str,
        json: bool,
        plan_name: &str,
        located: bool,
        options: DesignArgs,
    ) -> PyResult<Designed> {
        let trials = checked_runs(options.verify)?;
        let options = options.options()?;
        let ir = model.ir.clone();
        let made = py.detach(|| {
            let interpreter = Interpreter::new(ir);
            let conditions = parse(plan, json)?.conditions(interpreter.ir())?;
            let verified = design_verified(&interpreter, &conditions, &options, trials, &|| ())?;
            Ok((interpreter, verified))
        });
        // A plan error at its value's line and column, as the CLI's.
        let (interpreter, verified) =
            made.map_err(|e| failure(&locate(e, plan, json), plan_name, located))?;
        Ok(Designed {
            interpreter,
            design: verified.design,
            seed: options.seed,
            verification: verified.verification,
        })
    }

    /// The model's parameters, in its order.
    #[getter]
    fn parameters(&self) -> Vec<String> {
        let ir = self.interpreter.ir();
        ir.parameters.iter().map(|p| p.name.clone()).collect()
    }

    /// θ the design was made for (the plan's nominal values), in the
    /// model's order.
    #[getter]
    fn theta(&self) -> Vec<f64> {
        self.design
            .conditions
            .as_ref()
            .map(|c| c.theta.clone())
            .unwrap_or_default()
    }

    /// Whether the design keeps every held sign and can be verified.
    #[getter]
    fn verifiable(&self) -> bool {
        verifiable(&self.interpreter, &self.design)
    }

    /// The JSON document of `leeway design --json [--verify M]`: with the
    /// verification the design was made with, if any (`make`'s `verify`).
    fn document(&self) -> String {
        json(&self.design, self.verification.as_ref())
    }

    /// Run `index` (from 0) of the design's verification, as bytes. The
    /// GIL is released while it runs.
    fn trial<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyBytes>> {
        if index >= MAX_RUNS {
            return Err(Failure::option(
                format!("run {index} is not a run of a verification (0..{MAX_RUNS})"),
                None,
            )
            .into());
        }
        let bytes = py
            .detach(|| trial(&self.interpreter, &self.design, self.seed, index))
            .ok_or_else(nothing_to_verify)?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// The JSON document of `leeway design --json --verify M` from the bytes
    /// of the verification's runs 0..M, in order.
    fn summarise(&self, py: Python<'_>, trials: Vec<Vec<u8>>) -> PyResult<String> {
        checked_runs(Some(trials.len()))?;
        let verification = py
            .detach(|| summarise(&self.interpreter, &self.design, self.seed, &trials))
            .map_err(|e| Failure::estimate(&e))?
            .ok_or_else(nothing_to_verify)?;
        Ok(json(&self.design, Some(&verification)))
    }

    /// Per experiment, its nominal record as the columns `design --out`
    /// writes to `run-N.csv` (`leeway_data::write`): the model's data
    /// columns, the nominal trajectory beside the inputs.
    fn runs<'py>(&self, py: Python<'py>) -> Vec<Vec<(String, Bound<'py, PyArray1<f64>>)>> {
        let ir = self.interpreter.ir();
        self.design
            .records
            .iter()
            .map(|record| {
                write::header(ir, 1)
                    .into_iter()
                    .zip(write::columns(ir, record, 0.0))
                    .map(|(name, c)| (name, PyArray1::from_vec(py, c)))
                    .collect()
            })
            .collect()
    }
}

fn checked_runs(runs: Option<usize>) -> Result<Option<usize>, Failure> {
    match runs {
        Some(m) if !(1..=MAX_RUNS).contains(&m) => Err(Failure::option(
            format!("verify={m} is not in 1..={MAX_RUNS}"),
            Some("give the number of Monte Carlo runs, e.g. verify=100".into()),
        )),
        _ => Ok(runs),
    }
}

fn nothing_to_verify() -> Failure {
    Failure::option(
        "the design cannot be verified: it does not keep every held sign".into(),
        Some(
            "verify a feasible design (Design.feasible); its proposals say what would work".into(),
        ),
    )
}
