//! Estimation past one machine: the two halves of `leeway_estimate::estimate`
//! as Python sees them. A [`Dataset`] is experiments opened where they are —
//! a data file on a worker (validated once, streamed on every pass), or
//! frames; it answers a pass's request
//! with its experiments' summaries, as bytes. [`estimate_mapped`] is the
//! driver: it runs `leeway_estimate::estimate_with` with passes that call
//! back into Python (`leeway.dask` maps them over the cluster), and writes
//! the same document as `leeway estimate --json`. A distributed estimate is
//! the local one bit for bit, and survives a killed worker
//! (`py/tests/test_dask.py`).

use crate::data::{FrameArg, borrow_frames};
use crate::estimate::estimate_document;
use crate::failure::Failure;
use crate::model::Model;
use crate::options::EstimateOptions;
use leeway_data::FileNotes;
use leeway_data::LoadOptions;
use leeway_estimate::EstimateError;
use leeway_estimate::ExperimentFacts;
use leeway_estimate::FactsRequest;
use leeway_estimate::KeptSimulations;
use leeway_estimate::PassRequest;
use leeway_estimate::PassRunner;
use leeway_estimate::PassSummary;
use leeway_estimate::Passes;
use leeway_estimate::TRAJECTORY_BUDGET;
use leeway_estimate::decode;
use leeway_estimate::encode;
use leeway_estimate::estimate_with;
use leeway_logs::{load_path, open_path};
use leeway_model::Experiment;
use leeway_model::Interpreter;
use leeway_model::Source;
use leeway_report::feedback::closed_loop_alerts;
use leeway_report::heading_warnings;
use leeway_report::unit_warnings_from_peaks;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Bytes the datasets open in this process (a worker) have reserved for
/// their experiments' instrument simulations, at most [`TRAJECTORY_BUDGET`]:
/// a worker holding many files keeps no more than one process of the CLI.
static RESERVED: AtomicUsize = AtomicUsize::new(0);

/// Reserves `bytes` of [`TRAJECTORY_BUDGET`], if they are left.
fn reserve(bytes: usize) -> bool {
    RESERVED
        .fetch_update(Ordering::AcqRel, Ordering::Acquire, |r| {
            r.checked_add(bytes).filter(|&t| t <= TRAJECTORY_BUDGET)
        })
        .is_ok()
}

/// A file's experiments: streamed from a validated copy, or held in memory
/// when resampled (resampling interpolates over a whole experiment), as the
/// CLI opens them.
enum Experiments {
    Streamed(Vec<leeway_data::CsvSource>),
    Held(Vec<Experiment>),
}

impl Experiments {
    fn sources(&self) -> Vec<&dyn Source> {
        match self {
            Experiments::Streamed(v) => v.iter().map(|e| e as &dyn Source).collect(),
            Experiments::Held(v) => v.iter().map(|e| e as &dyn Source).collect(),
        }
    }
}

/// What the driver needs to know of a file beyond the passes: its
/// experiments' names and lengths and the data checks' findings.
#[derive(Serialize, Deserialize)]
struct FileSummary {
    experiments: Vec<(String, usize)>,
    notes: FileNotes,
    heading_gains: Vec<(String, Option<f64>)>,
    input_peaks: Vec<f64>,
    closed_loop: Vec<leeway_estimate::feedback::Feedback>,
}

/// One data file opened on a worker for the passes of an estimate.
#[pyclass(module = "leeway._leeway", frozen)]
pub struct Dataset {
    model: Interpreter,
    experiments: Experiments,
    summary: Vec<u8>,
    /// Each experiment's last instrument simulations, kept between passes
    /// where the process's budget had room (`None`: simulated again).
    kept: Vec<Mutex<Option<KeptSimulations>>>,
    /// What `kept` reserved of the budget, given back when dropped.
    reserved: usize,
}

impl Drop for Dataset {
    fn drop(&mut self) {
        RESERVED.fetch_sub(self.reserved, Ordering::AcqRel);
    }
}

impl Dataset {
    fn open_file(model: &Model, path: &str, options: &LoadOptions) -> Result<Dataset, Failure> {
        let ir = &model.ir;
        let (experiments, notes) = if options.resample.is_some() {
            let f = load_path(Path::new(path), ir, options).map_err(|e| Failure::data(&e))?;
            (Experiments::Held(f.experiments), f.notes)
        } else {
            let f = open_path(Path::new(path), ir, options).map_err(|e| Failure::data(&e))?;
            (Experiments::Streamed(f.sources), f.notes)
        };
        Ok(Dataset::new(ir, experiments, notes))
    }

    fn new(ir: &leeway_structure::ir::Ir, experiments: Experiments, notes: FileNotes) -> Dataset {
        let sources = experiments.sources();
        // The three checks of the data in one visit of each experiment.
        let checks = leeway_report::checks::data_checks(ir, &sources);
        let summary = FileSummary {
            experiments: sources
                .iter()
                .map(|e| (e.name().to_string(), e.len()))
                .collect(),
            notes,
            heading_gains: checks.heading_gains,
            input_peaks: checks.input_peaks,
            closed_loop: checks.closed_loop,
        };
        let summary = encode(&summary);
        let mut reserved = 0;
        let kept = sources
            .iter()
            .map(|e| {
                let bytes = KeptSimulations::bytes(e.len(), ir.states.len());
                let fits = reserve(bytes);
                if fits {
                    reserved += bytes;
                }
                Mutex::new(fits.then(|| KeptSimulations::new(bytes)))
            })
            .collect();
        drop(sources);
        Dataset {
            model: Interpreter::new(ir.clone()),
            experiments,
            summary,
            kept,
            reserved,
        }
    }

    /// A problem met while streaming (the validated copy became unreadable).
    fn failure(&self) -> Option<Failure> {
        match &self.experiments {
            Experiments::Streamed(v) => v
                .iter()
                .find_map(|s| s.failure())
                .map(|e| Failure::data(&e)),
            Experiments::Held(_) => None,
        }
    }
}

fn failed(e: EstimateError) -> PyErr {
    Failure::estimate(&e).into()
}

#[pymethods]
impl Dataset {
    /// Opens (validates) a data file, CSV or Parquet, for `model` with the load options of
    /// `options` (the estimate's options, as `leeway.estimate` takes them).
    #[staticmethod]
    fn open(
        py: Python<'_>,
        model: &Model,
        path: String,
        options: EstimateOptions,
    ) -> PyResult<Dataset> {
        let model = model.for_aggregate(options.aggregate)?;
        let load = options.load_options(&model.ir)?;
        Ok(py.detach(|| Dataset::open_file(&model, &path, &load))?)
    }

    /// The experiments of frames handed over as `leeway.estimate` hands
    /// them (validated as files are), held in memory: for engines that give
    /// each task its data as a DataFrame (Spark's `applyInPandas`).
    #[staticmethod]
    fn from_frames(
        py: Python<'_>,
        model: &Model,
        frames: Vec<FrameArg<'_>>,
        options: EstimateOptions,
    ) -> PyResult<Dataset> {
        let model = model.for_aggregate(options.aggregate)?;
        let load = options.load_options(&model.ir)?;
        let borrowed = borrow_frames(&frames)?;
        let ir = &model.ir;
        let opened = py.detach(|| -> Result<Dataset, Failure> {
            let (experiments, notes) = crate::data::load(ir, &borrowed, &load)?;
            let mut notes = notes.into_iter();
            let notes = match (notes.next(), notes.next()) {
                (Some(only), None) => only,
                // Several frames: one summary of them all, named by the first.
                (first, second) => {
                    let mut all = first.unwrap_or_default();
                    for n in second.into_iter().chain(notes) {
                        all.experiments.extend(n.experiments);
                        all.comment_lines += n.comment_lines;
                        all.blank_lines += n.blank_lines;
                    }
                    all
                }
            };
            Ok(Dataset::new(ir, Experiments::Held(experiments), notes))
        })?;
        Ok(opened)
    }

    /// Its experiments' names and lengths and the data checks' findings (bytes for the driver).
    fn summary<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.summary)
    }

    /// How many experiments the file holds.
    fn __len__(&self) -> usize {
        self.experiments.sources().len()
    }

    /// The facts of each experiment for a facts request.
    fn facts<'py>(&self, py: Python<'py>, request: &[u8]) -> PyResult<Vec<Bound<'py, PyBytes>>> {
        let request: FactsRequest = decode(request).map_err(failed)?;
        self.answer(py, |runner, _, e| encode(&runner.facts(e, &request)))
    }

    /// Each experiment's summary of a pass; `offset` is the index of the
    /// file's first experiment among all experiments of the estimate.
    fn run<'py>(
        &self,
        py: Python<'py>,
        offset: usize,
        request: &[u8],
    ) -> PyResult<Vec<Bound<'py, PyBytes>>> {
        let request: PassRequest = decode(request).map_err(failed)?;
        self.answer(py, |runner, i, e| {
            // A pass that panicked left its experiment's simulations unsure: none kept.
            let mut kept = self.kept[i].lock().unwrap_or_else(|poisoned| {
                let mut slot = poisoned.into_inner();
                *slot = None;
                slot
            });
            encode(&runner.pass_with_kept(e, offset + i, &request, kept.as_mut()))
        })
    }
}

impl Dataset {
    /// `f(runner, i, experiment)` for each experiment, without the GIL; a
    /// file that could no longer be read fails the whole answer.
    fn answer<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn(&PassRunner<'_>, usize, &dyn Source) -> Vec<u8> + Sync,
    ) -> PyResult<Vec<Bound<'py, PyBytes>>> {
        let out: Vec<Vec<u8>> = py.detach(|| {
            let runner = PassRunner::new(&self.model);
            let sources = self.experiments.sources();
            sources
                .iter()
                .enumerate()
                .map(|(i, e)| f(&runner, i, *e))
                .collect()
        });
        if let Some(failure) = self.failure() {
            return Err(failure.into());
        }
        Ok(out.iter().map(|b| PyBytes::new(py, b)).collect())
    }
}

/// Passes that call back into Python: `facts(request) -> [bytes]` and
/// `run(request) -> [bytes]`, one answer per experiment in order. A Python
/// exception (a worker's data error, a lost cluster) is kept and re-raised
/// once the driver has stopped.
struct PythonPasses {
    facts: Py<PyAny>,
    run: Py<PyAny>,
    raised: Mutex<Option<PyErr>>,
}

impl PythonPasses {
    fn call<T: serde::de::DeserializeOwned>(
        &self,
        f: &Py<PyAny>,
        request: Vec<u8>,
    ) -> Result<Vec<T>, EstimateError> {
        let answers: PyResult<Vec<Vec<u8>>> =
            Python::attach(|py| f.call1(py, (PyBytes::new(py, &request),))?.extract(py));
        match answers {
            Ok(answers) => answers.iter().map(|b| decode(b)).collect(),
            Err(e) => {
                let message = e.to_string();
                if let Ok(mut slot) = self.raised.lock() {
                    slot.get_or_insert(e);
                }
                Err(EstimateError {
                    code: "pass-failed",
                    message: format!("a pass over the experiments failed: {message}"),
                    hint: "see the exception raised".to_string(),
                })
            }
        }
    }
}

impl Passes for PythonPasses {
    fn facts(&self, request: &FactsRequest) -> Result<Vec<ExperimentFacts>, EstimateError> {
        self.call(&self.facts, encode(request))
    }
    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        self.call(&self.run, encode(request))
    }
}

/// `leeway estimate --json` of `model` on data files opened on workers:
/// `summaries` are their [`Dataset::summary`] bytes in file order, `files`
/// their names; `facts` and `run` map a request over the files. The GIL is
/// released except while a callback runs.
#[pyfunction]
pub fn estimate_mapped(
    py: Python<'_>,
    model: &Model,
    files: Vec<String>,
    summaries: Vec<Vec<u8>>,
    options: EstimateOptions,
    facts: Py<PyAny>,
    run: Py<PyAny>,
) -> PyResult<String> {
    let runtime_options = options.runtime()?;
    let model = model.for_aggregate(options.aggregate)?;
    let ir = &model.ir;
    let summaries: Vec<FileSummary> = summaries
        .iter()
        .map(|b| decode(b))
        .collect::<Result<_, _>>()
        .map_err(failed)?;
    let passes = PythonPasses {
        facts,
        run,
        raised: Mutex::new(None),
    };
    let interpreter = Interpreter::new(ir.clone());
    let result = py.detach(|| estimate_with(&interpreter, &passes, &runtime_options));
    if let Some(e) = passes.raised.lock().ok().and_then(|mut s| s.take()) {
        return Err(e);
    }
    let mut est = result.map_err(failed)?;
    let mut warnings = model.warnings.clone();
    let mut peaks = vec![0.0f64; ir.inputs.len()];
    for s in &summaries {
        for (p, v) in peaks.iter_mut().zip(&s.input_peaks) {
            *p = p.max(*v);
        }
    }
    warnings.extend(unit_warnings_from_peaks(ir, &peaks));
    let gains: Vec<(String, Option<f64>)> = summaries
        .iter()
        .flat_map(|s| s.heading_gains.iter().cloned())
        .collect();
    warnings.extend(heading_warnings(ir, &gains));
    let stretches: Vec<_> = summaries
        .iter()
        .flat_map(|s| s.closed_loop.iter().cloned())
        .collect();
    let alerts = closed_loop_alerts(&stretches);
    warnings.extend(alerts.iter().map(|w| w.detail.clone()));
    warnings.extend(est.warnings.iter().cloned());
    // The report finds each alert's summary among the estimate's.
    est.warning_summaries.extend(alerts);
    let experiments: Vec<(String, usize)> = summaries
        .iter()
        .flat_map(|s| s.experiments.iter().cloned())
        .collect();
    let notes: Vec<FileNotes> = summaries.into_iter().map(|s| s.notes).collect();
    Ok(estimate_document(
        &model,
        files,
        &est,
        &experiments,
        &gains,
        &notes,
        warnings,
    )?)
}
