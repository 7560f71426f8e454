//! A compiled model as Python holds it: its source, file and structure, and `check --json`.

use crate::data;
use crate::failure::Failure;
use crate::options::choice;
use leeway_structure::grammar::{self, Diagnostic, Severity};
use leeway_structure::identify::{Centring, parse_pattern};
use leeway_structure::ir::Ir;
use leeway_structure::{Compilation, compile};
use pyo3::prelude::*;

/// A compiled model: its source text (what it pickles by), the file it came
/// from as the user named it, and its structure.
#[pyclass(module = "leeway._leeway", frozen)]
#[derive(Clone)]
pub(crate) struct Model {
    pub(crate) source: String,
    pub(crate) file: String,
    pub(crate) aggregate: bool,
    pub(crate) ir: Ir,
    pub(crate) warnings: Vec<String>,
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

/// The compiler's options for `check`: the sign patterns and the centring.
fn check_options(
    aggregate: bool,
    patterns: Option<Vec<leeway_structure::ir::SignPattern>>,
    centring: Option<&str>,
) -> Result<leeway_structure::CompileOptions, Failure> {
    Ok(leeway_structure::CompileOptions {
        centring: centring.map(choice::<Centring>).transpose()?,
        ..options(aggregate, patterns)
    })
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
    pub(crate) fn for_aggregate(
        &self,
        aggregate: bool,
    ) -> Result<std::borrow::Cow<'_, Model>, Failure> {
        if aggregate == self.aggregate {
            Ok(std::borrow::Cow::Borrowed(self))
        } else {
            Model::compile(self.source.clone(), self.file.clone(), aggregate)
                .map(std::borrow::Cow::Owned)
        }
    }

    /// Model text compiled as `Model.from_str` compiles it (no aggregate).
    pub(crate) fn compile_source(source: String, file: String) -> Result<Model, Failure> {
        Model::compile(source, file, false)
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

    /// Names given for θ matched against the parameters, by the rule the
    /// CLI's parameter files follow (every parameter exactly once): per
    /// name its parameter's index (`None`: unknown), then the unknown names
    /// and the missing parameters.
    #[allow(clippy::type_complexity)]
    fn parameter_names(
        &self,
        names: Vec<String>,
    ) -> (Vec<Option<usize>>, Vec<String>, Vec<String>) {
        let matched =
            leeway_model::given::parameter_names(&self.ir, names.iter().map(String::as_str));
        let unknown = matched.unknown.iter().map(|&i| names[i].clone()).collect();
        let missing = matched
            .missing
            .iter()
            .map(|&p| self.ir.parameters[p].name.clone())
            .collect();
        (matched.slots, unknown, missing)
    }

    /// `leeway check --json` of this model, for the given sign patterns
    /// (`"water.u:+,water.v:-"`, as `--pattern` takes them) or the searched
    /// ones, under `centring` (`experiment`, `pooled`, `none`; default: the
    /// model's).
    #[pyo3(signature = (patterns=None, centring=None))]
    fn check_json(
        &self,
        patterns: Option<Vec<String>>,
        centring: Option<String>,
    ) -> PyResult<String> {
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
        let options = check_options(self.aggregate, patterns, centring.as_deref())?;
        let compilation = compile(&self.source, &options);
        let report =
            leeway_report::check::report(&self.file, &self.source, &compilation, self.aggregate);
        serde_json::to_string(&report)
            .map_err(|e| Failure::option(format!("cannot serialise the report: {e}"), None).into())
    }
}
