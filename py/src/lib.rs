//! `leeway._leeway`: the native half of the Python package. It compiles
//! models, checks them and estimates from columns handed over by
//! `python/leeway` (numpy float64 arrays, read in place), and answers with the
//! same JSON documents as `leeway check --json` and `leeway estimate --json`,
//! built by the same code ([`leeway_report`]); it simulates and
//! validates with the runtime functions `leeway simulate` and `leeway
//! validate` call (`simulate.rs`), answering with columns and fits. The Python half turns
//! those documents into dataclasses and DataFrames and raises the exception
//! classes of `leeway.errors`, so the error hierarchy lives in one place.

// As in the CLI: estimates allocate and free record-sized buffers many
// times a second, and mimalloc reuses freed pages rather than faulting
// fresh ones in (Python's own objects keep Python's allocator).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod data;
mod distributed;
mod failure;
mod simulate;
mod study;

use failure::Failure;
use leeway_data::LoadOptions;
use leeway_estimate::Centring;
use leeway_estimate::Combine;
use leeway_estimate::Initial;
use leeway_estimate::Instruments;
use leeway_estimate::Method;
use leeway_estimate::estimate;
use leeway_model::Interpreter;
use leeway_report::Estimated;
use leeway_report::estimate_report;
use leeway_report::heading_gains;
use leeway_report::heading_warnings;
use leeway_structure::grammar::{self, Diagnostic, Severity};
use leeway_structure::identify::parse_pattern;
use leeway_structure::ir::Ir;
use leeway_structure::{Compilation, compile};
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;

/// A compiled model: its source text (what it pickles by), the file it came
/// from as the user named it, and its structure.
#[pyclass(module = "leeway._leeway", frozen)]
#[derive(Clone)]
struct Model {
    source: String,
    file: String,
    aggregate: bool,
    ir: Ir,
    warnings: Vec<String>,
}

fn options(
    aggregate: bool,
    patterns: Option<Vec<leeway_structure::ir::SignPattern>>,
) -> leeway_structure::CompileOptions {
    leeway_structure::CompileOptions {
        aggregate,
        patterns,
        centring: None,
    }
}

/// The compiler's warnings, one line each, as the CLI lists them.
fn warning_lines(c: &Compilation, file: &str, source: &str) -> Vec<String> {
    let warnings: Vec<Diagnostic> = c
        .diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Warning)
        .cloned()
        .collect();
    grammar::render_short(&warnings, file, source)
        .lines()
        .map(str::to_string)
        .collect()
}

impl Model {
    /// The model as compiled with `aggregate` (which changes the predictor's
    /// columns), recompiled only when it differs.
    fn for_aggregate(&self, aggregate: bool) -> Result<std::borrow::Cow<'_, Model>, Failure> {
        if aggregate == self.aggregate {
            Ok(std::borrow::Cow::Borrowed(self))
        } else {
            Model::compile(self.source.clone(), self.file.clone(), aggregate)
                .map(std::borrow::Cow::Owned)
        }
    }

    fn compile(source: String, file: String, aggregate: bool) -> Result<Model, Failure> {
        let compilation = compile(&source, &options(aggregate, None));
        let Some(ir) = compilation.ir.clone() else {
            return Err(Failure::model(&file, &source, &compilation, aggregate));
        };
        let warnings = warning_lines(&compilation, &file, &source);
        Ok(Model {
            source,
            file,
            aggregate,
            ir,
            warnings,
        })
    }
}

#[pymethods]
impl Model {
    /// Compiles model text; `file` names it in diagnostics.
    #[staticmethod]
    #[pyo3(signature = (source, file, aggregate=false))]
    fn compile_text(source: String, file: String, aggregate: bool) -> PyResult<Model> {
        Ok(Model::compile(source, file, aggregate)?)
    }

    /// Compiles a model file's bytes: too large or not UTF-8 is a located
    /// model error, as in `leeway check`.
    #[staticmethod]
    #[pyo3(signature = (data, file, aggregate=false))]
    fn compile_bytes(data: Vec<u8>, file: String, aggregate: bool) -> PyResult<Model> {
        let limit = grammar::MAX_SOURCE_BYTES;
        if data.len() > limit {
            let d = grammar::source::too_large(data.len() as u64);
            return Err(Failure::diagnostic(&file, "", d, aggregate).into());
        }
        match grammar::source::decode(data) {
            Ok(source) => Ok(Model::compile(source, file, aggregate)?),
            Err(refused) => {
                Err(Failure::diagnostic(&file, &refused.text, refused.diagnostic, aggregate).into())
            }
        }
    }

    #[getter]
    fn source(&self) -> &str {
        &self.source
    }
    #[getter]
    fn file(&self) -> &str {
        &self.file
    }
    #[getter]
    fn aggregate(&self) -> bool {
        self.aggregate
    }
    #[getter]
    fn name(&self) -> &str {
        &self.ir.name
    }
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.ir.parameters.iter().map(|p| p.name.clone()).collect()
    }
    #[getter]
    fn nominal(&self) -> Vec<f64> {
        self.ir.parameters.iter().map(|p| p.nominal).collect()
    }
    #[getter]
    fn states(&self) -> Vec<String> {
        self.ir.states.clone()
    }
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.ir.inputs.clone()
    }
    /// The data columns the model reads (after `data { }` mapping), time first.
    #[getter]
    fn columns(&self) -> Vec<String> {
        data::model_columns(&self.ir)
    }
    /// The unit the model's `data { }` declares for the time column, if any.
    #[getter]
    fn time_unit(&self) -> Option<String> {
        self.ir.data_units.get("time").cloned()
    }
    /// The column that splits a frame into experiments.
    #[getter]
    fn experiment_column(&self) -> String {
        leeway_model::experiment::column_name(&self.ir, "experiment")
    }
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// `leeway check --json` of this model, for the given sign patterns
    /// (`"water.u:+,water.v:-"`, as `--pattern` takes them) or the searched ones.
    #[pyo3(signature = (patterns=None))]
    fn check_json(&self, patterns: Option<Vec<String>>) -> PyResult<String> {
        let patterns = match patterns {
            None => None,
            Some(specs) => {
                let parsed = specs
                    .iter()
                    .map(|spec| {
                        parse_pattern(&self.ir.sign_args, spec)
                            .map_err(|e| Failure::option(format!("pattern `{spec}`: {e}"), None))
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Some(parsed)
            }
        };
        let compilation = compile(&self.source, &options(self.aggregate, patterns));
        let report =
            leeway_report::check::report(&self.file, &self.source, &compilation, self.aggregate);
        serde_json::to_string(&report)
            .map_err(|e| Failure::option(format!("cannot serialise the report: {e}"), None).into())
    }
}

/// The estimator's options as `leeway.estimate` takes them (keyword names
/// of the CLI's flags, values as their strings).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct EstimateOptions {
    method: String,
    instruments: String,
    initial: String,
    centring: Option<String>,
    combine: String,
    nominal: Option<Vec<f64>>,
    aggregate: bool,
    strict: bool,
    lags: usize,
    max_refinements: usize,
    runaway_guard: bool,
    step: Option<f64>,
    time_tolerance: f64,
    resample: Option<f64>,
}

fn choice<T: Copy>(what: &str, given: &str, table: &[(&str, T)]) -> Result<T, Failure> {
    table
        .iter()
        .find(|(name, _)| *name == given)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = table.iter().map(|(n, _)| *n).collect();
            Failure::option(
                format!("{what}={given:?} is not one of {}", names.join(", ")),
                Some(format!("{what} is one of {}", names.join(", "))),
            )
        })
}

/// Ctrl-C during an estimate: Python runs its SIGINT handler only when
/// asked while native code holds the thread, so the estimator asks between
/// passes (from the calling thread, the main one for an interactive user);
/// the handler's `KeyboardInterrupt` is raised when the estimate has stopped
/// (`interrupted`, see `failure.rs`).
fn python_interrupt() -> leeway_estimate::Interrupt {
    leeway_estimate::Interrupt::new(|| Python::attach(|py| py.check_signals().is_err()))
}

/// The CLI's bounds on the options (cli/src/estimate.rs), so a script and a
/// notebook accept the same values.
const MAX_LAGS: usize = 1000;
const MAX_REFINEMENTS: usize = 100;
const STEP_RANGE: (f64, f64) = (1e-6, 1e6);

impl EstimateOptions {
    /// The load options these options give, checked against the model.
    fn load_options(&self, ir: &Ir) -> Result<LoadOptions, Failure> {
        load_options(ir, self.step, Some(self.time_tolerance), self.resample)
    }

    fn runtime(&self) -> Result<leeway_estimate::EstimateOptions, Failure> {
        if !(1..=MAX_LAGS).contains(&self.lags) {
            return Err(Failure::option(
                format!("lags={} is not in 1..={MAX_LAGS}", self.lags),
                None,
            ));
        }
        if self.max_refinements > MAX_REFINEMENTS {
            return Err(Failure::option(
                format!(
                    "max_refinements={} is not in 0..={MAX_REFINEMENTS}",
                    self.max_refinements
                ),
                None,
            ));
        }
        Ok(leeway_estimate::EstimateOptions {
            method: choice(
                "method",
                &self.method,
                &[
                    ("ls", Method::Ls),
                    ("iv1", Method::Iv1),
                    ("iv2", Method::Iv2),
                    ("iv3", Method::Iv3),
                ],
            )?,
            instruments: choice(
                "instruments",
                &self.instruments,
                &[
                    ("simulated", Instruments::Simulated),
                    ("delayed", Instruments::Delayed),
                ],
            )?,
            initial: choice(
                "initial",
                &self.initial,
                &[("delayed", Initial::Delayed), ("nominal", Initial::Nominal)],
            )?,
            centring: match &self.centring {
                None => None,
                Some(c) => Some(choice(
                    "centring",
                    c,
                    &[
                        ("experiment", Centring::Experiment),
                        ("pooled", Centring::Pooled),
                        ("none", Centring::None),
                    ],
                )?),
            },
            combine: choice(
                "combine",
                &self.combine,
                &[("summed", Combine::Summed), ("stacked", Combine::Stacked)],
            )?,
            nominal: self.nominal.clone(),
            max_refinements: self.max_refinements,
            aggregate: self.aggregate,
            strict: self.strict,
            lags: self.lags,
            runaway_guard: self.runaway_guard,
            interrupt: Some(python_interrupt()),
            ..leeway_estimate::EstimateOptions::default()
        })
    }
}

/// How data are read: `step`, `time_tolerance` (`None`: the default) and
/// `resample` within the CLI's bounds, `step` against the model's own
/// `step`, and `resample` against both: a conflict is an error, never
/// silently resolved (as in the CLI).
fn load_options(
    ir: &Ir,
    step: Option<f64>,
    time_tolerance: Option<f64>,
    resample: Option<f64>,
) -> Result<LoadOptions, Failure> {
    for (what, v) in [("step", step), ("resample", resample)] {
        if let Some(v) = v
            && !(v.is_finite() && (STEP_RANGE.0..=STEP_RANGE.1).contains(&v))
        {
            return Err(Failure::option(
                format!(
                    "{what}={v} is outside 1e-6..=1e6 seconds, the sample times leeway accepts"
                ),
                None,
            ));
        }
    }
    let time_tolerance = time_tolerance.unwrap_or(LoadOptions::default().time_tolerance);
    if !(time_tolerance > 0.0 && time_tolerance < 0.5) {
        return Err(Failure::option(
            format!("time_tolerance={time_tolerance} is not a fraction in (0, 0.5)"),
            Some("write 0.05 for 5 %; 0.5 or more would accept a dropped sample".into()),
        ));
    }
    if let (Some(declared), Some(given)) = (ir.step, step)
        && (declared - given).abs() > 1e-9 * declared.abs()
    {
        return Err(Failure::option(
            format!("step={given} conflicts with the model's `step {declared}`"),
            Some("drop step= (the model's step is used), or change `step` in the model".into()),
        ));
    }
    if let (Some(declared), Some(given)) = (ir.step.or(step), resample)
        && (declared - given).abs() > 1e-9 * declared.abs()
    {
        return Err(Failure::option(
            format!(
                "resample={given} conflicts with the sample time {declared} (the model's `step` or step=)"
            ),
            Some(format!("resample at the model's step: resample={declared}")),
        ));
    }
    Ok(LoadOptions {
        step,
        time_tolerance,
        resample,
    })
}

/// A frame as `leeway` hands it over: name, float64 columns, and the
/// experiment labels coded (`pandas.factorize`: a code per row, the names).
type FrameArg<'py> = (
    String,
    Vec<(String, PyReadonlyArray1<'py, f64>)>,
    Option<(PyReadonlyArray1<'py, i64>, Vec<String>)>,
);

/// The frames' columns borrowed in place (`leeway` hands over contiguous
/// float64 arrays).
fn borrow_frames<'a>(frames: &'a [FrameArg<'_>]) -> Result<Vec<data::Frame<'a>>, Failure> {
    frames
        .iter()
        .map(|(name, columns, experiment)| {
            let columns = columns
                .iter()
                .map(|(c, a)| {
                    a.as_slice().map(|s| (c.as_str(), s)).map_err(|_| {
                        Failure::data_plain(
                            name,
                            format!("column `{c}` is not a contiguous float64 array"),
                        )
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            let experiment = match experiment {
                Some((codes, names)) => Some(leeway_data::Labels::Coded {
                    codes: codes.as_slice().map_err(|_| {
                        Failure::data_plain(
                            name,
                            "the experiment codes are not a contiguous int64 array".into(),
                        )
                    })?,
                    names,
                }),
                None => None,
            };
            Ok(data::Frame {
                name,
                columns,
                experiment,
            })
        })
        .collect()
}

/// `leeway estimate --json` of `model` on the frames: each frame is
/// `(name, [(column, float64 array)], experiment labels or None)`. The GIL is
/// released from the moment the columns are borrowed until the document is
/// written.
#[pyfunction]
fn estimate_json(
    py: Python<'_>,
    model: &Model,
    frames: Vec<FrameArg<'_>>,
    options: EstimateOptions,
) -> PyResult<String> {
    let runtime_options = options.runtime()?;
    // `aggregate` changes what the structure compiler keeps: the CLI compiles
    // with it, so does this.
    let model = &*model.for_aggregate(options.aggregate)?;
    let load_options = load_options(
        &model.ir,
        options.step,
        Some(options.time_tolerance),
        options.resample,
    )?;
    let borrowed = borrow_frames(&frames)?;
    let document = py.detach(|| run_estimate(model, &borrowed, &load_options, &runtime_options))?;
    Ok(document)
}

fn run_estimate(
    model: &Model,
    frames: &[data::Frame<'_>],
    load_options: &LoadOptions,
    options: &leeway_estimate::EstimateOptions,
) -> Result<String, Failure> {
    let ir = &model.ir;
    let (loaded, notes) =
        data::load_for_estimate(ir, frames, load_options, options.interrupt.as_ref())?;
    let sources = loaded.sources();
    let mut warnings = model.warnings.clone();
    warnings.extend(leeway_report::unit_warnings(ir, &sources));
    let gains = heading_gains(ir, &sources);
    warnings.extend(heading_warnings(ir, &gains));
    let interpreter = Interpreter::new(ir.clone());
    let result = estimate(&interpreter, &sources, options);
    // A spill file that could not be read back voids whatever was computed.
    if let Some(f) = loaded.failure() {
        return Err(f);
    }
    let est = result.map_err(|mut e| {
        if e.code == "too-few-samples" {
            let list: Vec<String> = sources
                .iter()
                .map(|s| format!("`{}`: {} samples", s.name(), s.len()))
                .collect();
            e.message = format!("{} (experiments: {})", e.message, list.join("; "));
        }
        Failure::estimate(&e)
    })?;
    warnings.extend(est.warnings.iter().cloned());
    let experiments: Vec<(String, usize)> = sources
        .iter()
        .map(|e| (e.name().to_string(), e.len()))
        .collect();
    estimate_document(
        model,
        frames.iter().map(|f| f.name.to_string()).collect(),
        &est,
        &experiments,
        &gains,
        &notes,
        warnings,
    )
}

/// `leeway estimate --json`'s document of an estimate of `model` from the
/// named data (frames or files), with what loading and the data checks found.
fn estimate_document(
    model: &Model,
    data: Vec<String>,
    est: &leeway_estimate::Estimate,
    experiments: &[(String, usize)],
    gains: &[(String, Option<f64>)],
    notes: &[leeway_data::FileNotes],
    warnings: Vec<String>,
) -> Result<String, Failure> {
    let ir = &model.ir;
    let report = estimate_report::<serde_json::Value>(
        model.file.clone(),
        data,
        est.method,
        Some(ir.name.clone()),
        Ok(Estimated {
            model: &ir.name,
            estimate: est,
            experiments,
            heading_gains: gains,
            data_notes: notes,
            data_units: &ir.data_units,
        }),
        warnings,
    );
    report
        .to_json()
        .map_err(|e| Failure::option(format!("cannot serialise the report: {e}"), None))
}

/// The native module.
#[pymodule]
fn _leeway(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_function(wrap_pyfunction!(estimate_json, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate_columns, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::validate_fits, m)?)?;
    m.add_class::<distributed::Dataset>()?;
    m.add_function(wrap_pyfunction!(distributed::estimate_mapped, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_run, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_summary, m)?)?;
    Ok(())
}
