//! The paper's Monte Carlo study (`leeway reproduce`) in pieces a cluster
//! can run: [`study_run`] computes one run of one case (a pure function of
//! the configuration and its indices), [`study_summary`] summarises the
//! runs, taken in the order of `leeway_scenarios::study::study_tasks`, into the
//! study's tables and claims — the same figures as `reproduce`'s
//! `results.json`, however the runs were spread.

use crate::failure::Failure;
use crate::model::Model;
use leeway_estimate::decode;
use leeway_estimate::encode;
use leeway_model::Interpreter;
use leeway_scenarios::study;
use leeway_scenarios::study::Outcome;
use leeway_scenarios::study::StudyConfig;
use leeway_scenarios::study::claims;
use leeway_scenarios::study::collect_outcomes;
use leeway_scenarios::study::study_run as run_one;
use leeway_scenarios::study::summarise;
use leeway_scenarios::study::validation_experiment;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// The study's configuration as Python gives it (`reproduce`'s options).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct StudyArgs {
    runs: usize,
    n: Vec<usize>,
    cases: Vec<String>,
    seed: u64,
    paper_iv: bool,
}

/// Bounds of `reproduce`'s options: a record needs some samples per
/// parameter, and a study must finish.
const N_RANGE: (usize, usize) = (100, 1_000_000);
const MAX_RUNS: usize = 100_000;

impl StudyArgs {
    fn config(&self) -> Result<StudyConfig, Failure> {
        if !(1..=MAX_RUNS).contains(&self.runs) {
            return Err(Failure::option(
                format!("runs={} is not in 1..={MAX_RUNS}", self.runs),
                None,
            ));
        }
        if self.n.is_empty() || self.n.iter().any(|n| !(N_RANGE.0..=N_RANGE.1).contains(n)) {
            return Err(Failure::option(
                format!(
                    "n={:?}: every record length must be in {}..={}",
                    self.n, N_RANGE.0, N_RANGE.1
                ),
                None,
            ));
        }
        let mut n = self.n.clone();
        n.sort_unstable();
        n.dedup();
        let known = study::paper_cases();
        let cases = self
            .cases
            .iter()
            .map(|name| {
                known
                    .iter()
                    .find(|c| &c.name == name)
                    .cloned()
                    .ok_or_else(|| {
                        Failure::option(
                            format!("case {name:?} is not one of low, high"),
                            Some("cases is a list of \"low\" and \"high\"".into()),
                        )
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        if cases.is_empty() {
            return Err(Failure::option(
                "no case given".into(),
                Some("cases=[\"low\", \"high\"]".into()),
            ));
        }
        Ok(StudyConfig {
            runs: self.runs,
            n,
            cases,
            seed: self.seed,
            paper_iv: self.paper_iv,
            ..StudyConfig::default()
        })
    }
}

/// The study's `(case, run)` pairs, in the order [`study_summary`] takes them.
#[pyfunction]
pub fn study_tasks(config: StudyArgs) -> PyResult<Vec<(usize, usize)>> {
    Ok(study::study_tasks(&config.config()?))
}

/// One run of the study (every method, every N, validated) as bytes. The
/// GIL is released while it runs.
#[pyfunction]
pub fn study_run<'py>(
    py: Python<'py>,
    model: &Model,
    config: StudyArgs,
    case: usize,
    run: usize,
) -> PyResult<Bound<'py, PyBytes>> {
    let config = config.config()?;
    if case >= config.cases.len() || run >= config.runs {
        return Err(Failure::option(
            format!("run ({case}, {run}) is not a run of this study"),
            None,
        )
        .into());
    }
    let bytes = py.detach(|| {
        let interpreter = Interpreter::new(model.ir.clone());
        let validation = validation_experiment(&interpreter, config.validation_len);
        encode(&run_one(&interpreter, &config, &validation, case, run))
    });
    Ok(PyBytes::new(py, &bytes))
}

/// The study's tables and claims (JSON: `cases`, `claims`) from every run's
/// bytes, in the order of [`study_tasks`].
#[pyfunction]
pub fn study_summary(config: StudyArgs, runs: Vec<Vec<u8>>) -> PyResult<String> {
    let config = config.config()?;
    if runs.len() != config.cases.len() * config.runs {
        return Err(Failure::option(
            format!(
                "{} runs given, the study has {}",
                runs.len(),
                config.cases.len() * config.runs
            ),
            None,
        )
        .into());
    }
    let results: Vec<Vec<Vec<Outcome>>> = runs
        .iter()
        .map(|b| decode(b))
        .collect::<Result<_, _>>()
        .map_err(|e| PyErr::from(Failure::estimate(&e)))?;
    let outcomes = collect_outcomes(&config, results);
    let cases = summarise(&outcomes);
    let claims = claims(&cases);
    serde_json::to_string(&serde_json::json!({ "cases": cases, "claims": claims }))
        .map_err(|e| Failure::option(format!("cannot serialise the study: {e}"), None).into())
}
