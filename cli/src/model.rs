//! What `estimate`, `simulate` and `validate` share: reading and compiling
//! the model, with every problem located (data files are `data.rs`,
//! parameter files `params.rs`).

use crate::files::io_reason;
use crate::files::read_model;
use crate::problem::{Failure, Problem};
use leeway_structure::grammar::{self, Diagnostic, Severity};
use leeway_structure::ir::Ir;
use leeway_structure::{CompileOptions, compile};
use std::path::Path;

/// A compiled model.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The model's IR.
    pub ir: Ir,
    /// The compiler's warnings, one line each (`file:line:col: warning[code]: …`).
    pub warnings: Vec<String>,
}

/// Reads and compiles a model. A model that does not compile is a failure
/// with its rendered diagnostics; one whose θ is not identifiable from any
/// experiment still compiles (the estimator then says why, with the data).
pub fn load(path: &Path, aggregate: bool) -> Result<Loaded, Failure> {
    let file = path.display().to_string();
    let source = match read_model(path) {
        Ok(Ok(source)) => source,
        Ok(Err(refused)) => {
            return Err(Failure::Model {
                file,
                source: refused.text,
                diagnostics: vec![refused.diagnostic],
            });
        }
        Err(e) => {
            return Err(Problem::error(
                "io",
                format!("cannot read the model `{file}`: {}", io_reason(&e)),
            )
            .at(&file)
            .into());
        }
    };
    compiled(file, source, aggregate)
}

/// Compiles a model's text read from `file` (the name its diagnostics carry).
pub fn compiled(file: String, source: String, aggregate: bool) -> Result<Loaded, Failure> {
    let compilation = compile(
        &source,
        &CompileOptions {
            aggregate,
            patterns: None,
            centring: None,
        },
    );
    let Some(ir) = compilation.ir else {
        return Err(Failure::Model {
            file,
            source,
            diagnostics: compilation.diagnostics,
        });
    };
    let warnings: Vec<Diagnostic> = compilation
        .diagnostics
        .into_iter()
        .filter(|d| d.severity == Severity::Warning)
        .collect();
    let warnings = grammar::render_short(&warnings, &file, &source)
        .lines()
        .map(str::to_string)
        .collect();
    Ok(Loaded { ir, warnings })
}
