//! Why a call failed, as data, turned into an instance of the matching class
//! of `leeway.errors` (defined in Python, so the hierarchy — `DataError` is
//! also a `ValueError` — is declared once, where users read it).

use leeway_data::DataError;
use leeway_estimate::EstimateError;
use leeway_report::check;
use leeway_structure::Compilation;
use leeway_structure::grammar::Diagnostic;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// One failure: the exception class, the stable code, and what the CLI's
/// JSON says about it.
#[derive(Debug)]
pub struct Failure(Box<Details>);

#[derive(Debug)]
struct Details {
    class: &'static str,
    code: String,
    message: String,
    hint: Option<String>,
    location: Option<String>,
    /// For a model: `check --json` of the failing model (its `errors` are the
    /// located diagnostics).
    report: Option<String>,
}

/// The class each code of the estimator raises: what the data cannot
/// support is an `EstimateError`, what is wrong with the data a `DataError`,
/// what is wrong with the arguments an `OptionError`.
pub fn class_of(code: &str) -> &'static str {
    match code {
        "unidentifiable" => "Unidentifiable",
        "rank-deficient" => "RankDeficient",
        "sign-violation" => "SignViolation",
        "data" | "no-data" | "too-few-samples" | "non-finite-data" => "DataError",
        "invalid-option" | "invalid-params" | "invalid-nominal" | "invalid-start" => "OptionError",
        _ => "EstimateError",
    }
}

impl Failure {
    /// A model that does not compile: every error, located, in the shape of
    /// `check --json`; the first one is the exception's message.
    pub fn model(file: &str, source: &str, c: &Compilation, aggregate: bool) -> Failure {
        let report = check::report(file, source, c, aggregate);
        let first = c.diagnostics.iter().find(|d| d.is_error());
        Failure::model_report(file, source, first, &report)
    }

    /// A model refused before compiling (too large, not UTF-8).
    pub fn diagnostic(file: &str, source: &str, d: Diagnostic, aggregate: bool) -> Failure {
        let report = check::failure(file, d.clone(), aggregate);
        Failure::model_report(file, source, Some(&d), &report)
    }

    fn model_report(
        file: &str,
        source: &str,
        first: Option<&Diagnostic>,
        report: &check::CheckReport,
    ) -> Failure {
        let (code, message, hint, location) = match first {
            Some(d) => {
                let location = d.primary_span().map(|s| {
                    let (l, c) = leeway_structure::grammar::line_col(source, s.start);
                    format!("{file}:{l}:{c}")
                });
                (d.code.clone(), d.message.clone(), d.help.clone(), location)
            }
            None => (
                "model".to_string(),
                format!("`{file}` does not compile"),
                None,
                None,
            ),
        };
        Failure(Box::new(Details {
            class: "ModelError",
            code,
            message,
            hint,
            location,
            report: serde_json::to_string(report).ok(),
        }))
    }

    /// A data problem of leeway-data's loader, located in the frame.
    pub fn data(e: &DataError) -> Failure {
        Failure(Box::new(Details {
            class: "DataError",
            code: "data".to_string(),
            message: e.message.clone(),
            hint: Some(e.hint.clone()),
            location: Some(e.location.clone()),
            report: None,
        }))
    }

    /// A data problem found before the loader runs.
    pub fn data_plain(frame: &str, message: String) -> Failure {
        Failure(Box::new(Details {
            class: "DataError",
            code: "data".to_string(),
            message,
            hint: None,
            location: Some(frame.to_string()),
            report: None,
        }))
    }

    /// An argument out of range or not one of the choices.
    pub fn option(message: String, hint: Option<String>) -> Failure {
        Failure(Box::new(Details {
            class: "OptionError",
            code: "invalid-option".to_string(),
            message,
            hint,
            location: None,
            report: None,
        }))
    }

    /// θ that the model cannot take (the CLI's parameter-file errors).
    pub fn params(message: String) -> Failure {
        Failure(Box::new(Details {
            class: "OptionError",
            code: "invalid-params".to_string(),
            message,
            hint: Some("give every parameter of the model once, as a finite number".into()),
            location: None,
            report: None,
        }))
    }

    /// An estimate that could not be computed.
    pub fn estimate(e: &EstimateError) -> Failure {
        Failure(Box::new(Details {
            class: class_of(e.code),
            code: e.code.to_string(),
            message: e.message.clone(),
            hint: Some(e.hint.clone()),
            location: None,
            report: None,
        }))
    }

    /// A failure of the estimator's shape raised as `class`, at `location`.
    pub fn classed(class: &'static str, e: &EstimateError, location: Option<String>) -> Failure {
        Failure(Box::new(Details {
            class,
            code: e.code.to_string(),
            message: e.message.clone(),
            hint: Some(e.hint.clone()),
            location,
            report: None,
        }))
    }

    /// A design that cannot be made: `class` is `PlanError` (the plan
    /// file, located), `Unidentifiable` or `DesignError`.
    pub fn design(
        class: &'static str,
        code: &str,
        message: &str,
        hint: &str,
        location: Option<String>,
    ) -> Failure {
        Failure(Box::new(Details {
            class,
            code: code.to_string(),
            message: message.to_string(),
            hint: Some(hint.to_string()),
            location,
            report: None,
        }))
    }

    fn exception(&self, py: Python<'_>) -> PyResult<PyErr> {
        let f = &self.0;
        // Ctrl-C stopped the estimate: Python's own exception, as after any
        // interrupted call.
        if f.code == "interrupted" {
            return Ok(pyo3::exceptions::PyKeyboardInterrupt::new_err(
                f.message.clone(),
            ));
        }
        let errors = py.import("leeway.errors")?;
        let class = errors.getattr(f.class)?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("code", &f.code)?;
        kwargs.set_item("hint", &f.hint)?;
        kwargs.set_item("location", &f.location)?;
        if let Some(report) = &f.report {
            kwargs.set_item("report", report)?;
        }
        let instance = class.call((&f.message,), Some(&kwargs))?;
        Ok(PyErr::from_value(instance))
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        // Raising needs the interpreter; if `leeway.errors` itself cannot be
        // imported, that import error is the more useful one to see.
        Python::attach(|py| f.exception(py).unwrap_or_else(|e| e))
    }
}
