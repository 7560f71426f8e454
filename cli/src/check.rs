//! `leeway check MODEL.som`: compile a model, print its derived structure
//! (regressors, nuisance reduction, required experiments) and diagnostics,
//! or the same as JSON; exit 0 / 1 / 2 (see `main.rs`).

// The document is built in leeway-report, which the Python package shares.
pub use leeway_report::check as json;

use crate::options::choices;
use crate::output::{Status, err, out, print_json, stderr_style};
use leeway_estimate::Centring;
use leeway_structure::grammar::{self, Diagnostic, RenderStyle, Severity};
use leeway_structure::identify::parse_pattern;
use leeway_structure::{Compilation, CompileOptions, compile, compile_with, render};
use std::path::PathBuf;

/// Arguments of `leeway check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// The `.som` model file.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// Print one JSON document on stdout instead of text (the contract is in docs/json.md).
    #[arg(long)]
    pub json: bool,
    /// When θ is not identifiable, estimate its identifiable combinations instead
    /// (the absorbed parameters are held at their nominal values).
    #[arg(long)]
    pub aggregate: bool,
    /// The sign pattern of one experiment, e.g. `water.u:+,air.u:-` (arguments not
    /// named are `+`). Repeat once per experiment. Without it, leeway searches the
    /// smallest set of experiments that identifies θ.
    #[arg(long = "pattern", value_name = "SPEC")]
    pub patterns: Vec<String>,
    /// The instrument centring to analyse (it decides which constants are
    /// annihilated). Default: the model's, as `leeway estimate` would choose it.
    #[arg(long, value_parser = choices::<Centring>())]
    pub centring: Option<Centring>,
}

impl CheckArgs {
    fn options(&self, patterns: Option<Vec<leeway_structure::ir::SignPattern>>) -> CompileOptions {
        CompileOptions {
            aggregate: self.aggregate,
            patterns,
            centring: self.centring,
        }
    }
}

/// Runs `leeway check`.
pub fn run(args: &CheckArgs) -> Status {
    let file = args.model.display().to_string();
    let (source, compilation) = match crate::files::read_model(&args.model) {
        Ok(Ok(source)) => match analyse(args, &source) {
            Ok(c) => (source, c),
            Err(message) => return fail(args, &file, "invalid-pattern", message),
        },
        // Too large or not UTF-8: one located error, reported like the compiler's.
        Ok(Err(refused)) => (
            refused.text,
            Compilation {
                ir: None,
                diagnostics: vec![refused.diagnostic],
            },
        ),
        Err(e) => {
            let message = format!("cannot read `{file}`: {}", crate::files::io_reason(&e));
            return fail(args, &file, "io", message);
        }
    };
    let status = status_of(&compilation);
    if args.json {
        let report = json::report(&file, &source, &compilation, args.aggregate);
        print_json(&report);
    } else {
        if let Some(ir) = &compilation.ir {
            // The notes that are diagnostics are rendered below, in full.
            let shown: Vec<&str> = compilation
                .diagnostics
                .iter()
                .filter(|d| d.severity == Severity::Note)
                .map(|d| d.message.as_str())
                .collect();
            out(&render::render_except(ir, &shown));
            if let Some(candidates) = leeway_select::describe(&source, ir) {
                out(&candidates);
            }
        }
        let style = stderr_style();
        let diagnostics = grammar::render(&compilation.diagnostics, &file, &source, style);
        err(&diagnostics);
        let errors = compilation
            .diagnostics
            .iter()
            .filter(|d| d.is_error())
            .count();
        if status == Status::Error {
            let plural = if errors == 1 { "" } else { "s" };
            err(&headline(
                style,
                &format!("`{file}` was not checked: {errors} error{plural}"),
            ));
        }
    }
    // The process ends right after: freeing the IR of a large model piece by
    // piece (10⁴ states: ~10⁶ allocations) would only add to the wait.
    std::mem::forget(compilation);
    status
}

/// Compiles with the experiments given on the command line, if any: the
/// patterns are read against the sign arguments of the lowered model, before
/// its analysis (one compilation).
fn analyse(args: &CheckArgs, source: &str) -> Result<Compilation, String> {
    if args.patterns.is_empty() {
        return Ok(compile(source, &args.options(None)));
    }
    compile_with(source, &args.options(None), |ir| {
        args.patterns
            .iter()
            .map(|spec| {
                parse_pattern(&ir.sign_args, spec).map_err(|e| format!("--pattern `{spec}`: {e}"))
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    })
}

fn status_of(c: &Compilation) -> Status {
    if c.ir.is_none() {
        Status::Error
    } else if !c.has_errors() {
        Status::Success
    } else if c.only_unidentifiable() {
        Status::NotIdentifiable
    } else {
        Status::Error
    }
}

/// An error found before compiling (unreadable file, bad `--pattern`): exit 2.
fn fail(args: &CheckArgs, file: &str, code: &str, message: String) -> Status {
    if args.json {
        let d = Diagnostic::error(code, message);
        print_json(&json::failure(file, d, args.aggregate));
    } else {
        // Coded like every other command's errors (`error[io]: ...`).
        err(&crate::output::headline(
            stderr_style(),
            "error",
            Some(code),
            &message,
        ));
    }
    Status::Error
}

/// `error: message` and a newline, bold red on a terminal.
fn headline(style: RenderStyle, message: &str) -> String {
    crate::output::headline(style, "error", None, message)
}
