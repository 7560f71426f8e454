//! Why a subcommand stopped: a model that does not compile (rendered like
//! `leeway check` does), or problems found outside the model — a data file, a
//! parameter file, an option, an estimate the data cannot support — each
//! with its place (`file:row:column`) and a hint, and the exit status it maps to.

use crate::output::{Status, headline};
use leeway_data::DataError;
use leeway_estimate::EstimateError;
use leeway_report::check::{JsonDiagnostic, diagnostic};
use leeway_structure::grammar::{self, Diagnostic, RenderStyle};
use serde::Serialize;

/// One problem found outside the model text.
#[derive(Clone, Debug, Serialize)]
pub struct Problem {
    /// Stable kebab-case code: `io`, `data`, `invalid-params`,
    /// `invalid-option`, or the estimator's (`unidentifiable`, ...).
    pub code: String,
    /// Always `error` (warnings are plain strings).
    pub severity: &'static str,
    /// What is wrong.
    pub message: String,
    /// `file`, `file:row` or `file:row:column` (with the column's name for data).
    pub location: Option<String>,
    /// How to fix it.
    pub help: Option<String>,
    /// The exit status it maps to.
    #[serde(skip)]
    pub status: Status,
}

impl Problem {
    /// An error (exit 2) without a place or hint.
    pub fn error(code: &str, message: impl Into<String>) -> Problem {
        Problem {
            code: code.to_string(),
            severity: "error",
            message: message.into(),
            location: None,
            help: None,
            status: Status::Error,
        }
    }

    /// The same, located.
    pub fn at(mut self, location: impl Into<String>) -> Problem {
        self.location = Some(location.into());
        self
    }

    /// The same, with a hint.
    pub fn help(mut self, help: impl Into<String>) -> Problem {
        self.help = Some(help.into());
        self
    }

    /// A data problem found while loading a CSV file (exit 2).
    pub fn data(e: &DataError) -> Problem {
        Problem::error("data", &e.message)
            .at(&e.location)
            .help(&e.hint)
    }

    /// An estimate that could not be computed. Exit 1 when the data cannot
    /// support the model (`unidentifiable`, `rank-deficient`,
    /// `sign-violation`, and under `--strict` an estimate whose own
    /// simulation fails, `own-simulation`); exit 2 for everything the user
    /// must fix in the command (options, nominal values).
    pub fn estimate(e: &EstimateError) -> Problem {
        let mut p = Problem::error(e.code, &e.message).help(&e.hint);
        if matches!(
            e.code,
            "unidentifiable" | "rank-deficient" | "sign-violation" | "own-simulation"
        ) {
            p.status = Status::Unsupported;
        }
        p
    }

    /// `error[code]: location: message` and the hint, for a terminal or a pipe.
    pub fn render(&self, style: RenderStyle) -> String {
        let message = match &self.location {
            Some(at) => format!("{at}: {}", self.message),
            None => self.message.clone(),
        };
        let mut text = headline(style, self.severity, Some(&self.code), &message);
        if let Some(help) = &self.help {
            text.push_str(&format!("  = help: {help}\n"));
        }
        text
    }
}

/// Why a subcommand stopped.
#[derive(Clone, Debug)]
pub enum Failure {
    /// The model does not compile: its diagnostics, rendered with the source.
    Model {
        /// The model file as given.
        file: String,
        /// Its text.
        source: String,
        /// Every diagnostic (errors, and the warnings that came with them).
        diagnostics: Vec<Diagnostic>,
    },
    /// Problems outside the model text, all reported.
    Problems(Vec<Problem>),
}

impl From<Problem> for Failure {
    fn from(p: Problem) -> Failure {
        Failure::Problems(vec![p])
    }
}

/// One entry of a JSON document's `errors`: a model diagnostic in the shape of
/// `leeway check --json`, or a [`Problem`]. Both have `code`, `severity`,
/// `message`, `location` and `help`.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum JsonError {
    /// A diagnostic of the model file.
    Model(JsonDiagnostic),
    /// A problem outside it.
    Problem(Problem),
}

impl Failure {
    /// The exit status: the most severe of the problems.
    pub fn status(&self) -> Status {
        match self {
            Failure::Model { .. } => Status::Error,
            Failure::Problems(ps) => {
                if ps.iter().any(|p| p.status == Status::Error) || ps.is_empty() {
                    Status::Error
                } else {
                    Status::Unsupported
                }
            }
        }
    }

    /// Text for stderr: rendered diagnostics and a closing line, or the problems.
    pub fn render(&self, style: RenderStyle, what: &str) -> String {
        match self {
            Failure::Model {
                file,
                source,
                diagnostics,
            } => {
                let mut text = grammar::render(diagnostics, file, source, style);
                let errors = diagnostics.iter().filter(|d| d.is_error()).count();
                let plural = if errors == 1 { "" } else { "s" };
                text.push_str(&headline(
                    style,
                    "error",
                    None,
                    &format!("`{file}` has {errors} error{plural}: nothing was {what}"),
                ));
                text
            }
            Failure::Problems(ps) => ps.iter().map(|p| p.render(style)).collect(),
        }
    }

    /// The `errors` of a JSON document.
    pub fn json(&self) -> Vec<JsonError> {
        match self {
            Failure::Model {
                file,
                source,
                diagnostics,
            } => diagnostics
                .iter()
                .filter(|d| d.is_error())
                .map(|d| JsonError::Model(diagnostic(file, source, d)))
                .collect(),
            Failure::Problems(ps) => ps.iter().cloned().map(JsonError::Problem).collect(),
        }
    }
}
