//! leeway-structure: a parsed `.som` model → its regressor structure and an
//! exact identifiability report.
//!
//! The passes run in order from [`compile`]: resolve (names), terms (the
//! second-order modulus class), signs and expand (`Φ`, `Φ_ρ`, `Φ_λ`, `Φ2`),
//! lower (the [`ir::Ir`]), identify (exact rank over sign patterns). Every
//! pass collects diagnostics; nothing here does IO or panics.
//!
//! [`compile`] returns an IR only with no error or with
//! `unidentifiable-combination` alone, so a valid model whose θ is not
//! identifiable is still reported. Diagnostics of one code at one place are
//! merged into one with a count, so a multiplied-out product reports a
//! problem once. Every diagnostic code has a broken model in
//! `examples/models/broken/` and a section in `docs/language.md`
//! (`structure/tests/structure/broken.rs` holds both to it). Nothing is quadratic in
//! the size of the model: columns are grouped by output in one pass
//! ([`ir::columns_by_output`]), and the experiment search and its report
//! grow with the model (10⁴ states, 100 media: well under a second).

mod diagnostics;
pub mod exact;
pub mod expand;
pub mod identify;
pub mod ir;
pub mod lower;
pub mod poly;
pub mod render;
pub mod resolve;
pub mod terms;
pub mod units;

use diagnostics::{identifiability_diagnostics, merge_repeats, unused_declarations};
#[doc(inline)]
pub use identify::report::CompileOptions;
#[doc(inline)]
pub use ir::Ir;
#[doc(inline)]
pub use leeway_grammar as grammar;
use leeway_grammar::{Diagnostic, Severity};

/// The result of compiling a model: the IR when the model is valid (also when
/// θ is not identifiable, so the report can be shown), and every diagnostic.
#[derive(Clone, Debug)]
pub struct Compilation {
    /// The IR, if the model is well formed.
    pub ir: Option<Ir>,
    /// Errors, warnings and notes, in pass order.
    pub diagnostics: Vec<Diagnostic>,
}

impl Compilation {
    /// True when some diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
    /// True when the only errors say that θ is not identifiable (valid model).
    pub fn only_unidentifiable(&self) -> bool {
        self.ir.is_some()
            && self
                .diagnostics
                .iter()
                .filter(|d| d.is_error())
                .all(|d| d.code == "unidentifiable-combination")
    }
}

/// Parses and compiles a `.som` source.
pub fn compile(source: &str, options: &CompileOptions) -> Compilation {
    let analysed = |_: &Ir| Ok::<_, std::convert::Infallible>(options.patterns.clone());
    match compile_with(source, options, analysed) {
        Ok(c) => c,
        Err(never) => match never {},
    }
}

/// Compiles as [`compile`] does, the experiments to analyse decided by
/// `patterns` from the lowered IR, before the analysis: a sign pattern the
/// user wrote (`water.u:+`) names sign arguments that only the compiled
/// model knows. An `Err` from `patterns` ends the compilation with it.
pub fn compile_with<E>(
    source: &str,
    options: &CompileOptions,
    patterns: impl FnOnce(&Ir) -> Result<Option<Vec<ir::SignPattern>>, E>,
) -> Result<Compilation, E> {
    let (model, mut diagnostics) = leeway_grammar::parse(source);
    let Some(model) = model else {
        return Ok(Compilation {
            ir: None,
            diagnostics,
        });
    };
    let resolved = resolve::resolve(&model, &mut diagnostics);
    let (params, terms) = terms::lower_terms(&resolved, &mut diagnostics);
    merge_repeats(&mut diagnostics);
    if diagnostics.iter().any(Diagnostic::is_error) {
        return Ok(Compilation {
            ir: None,
            diagnostics,
        });
    }
    if params.is_empty() {
        diagnostics.push(
            Diagnostic::error(
                "no-parameters",
                format!(
                    "model `{}` has no parameter to estimate",
                    resolved.name.name
                ),
            )
            .with_primary(resolved.name.span, "")
            .with_help("write each equation as a sum of `parameter * regressor` terms"),
        );
        return Ok(Compilation {
            ir: None,
            diagnostics,
        });
    }
    unused_declarations(&resolved, &terms, &mut diagnostics);
    let signs = expand::sign_args(&resolved, &terms);
    let (basic, augmented, measured) = expand::expand(&resolved, &params, &terms, &signs);
    let predictors = ir::Predictors {
        basic,
        augmented,
        measured,
    };
    let mut ir = lower::lower(
        &resolved,
        &params,
        &terms,
        signs,
        predictors,
        &mut diagnostics,
    );
    if diagnostics.iter().any(Diagnostic::is_error) {
        return Ok(Compilation {
            ir: None,
            diagnostics,
        });
    }
    let options = CompileOptions {
        patterns: patterns(&ir)?,
        ..options.clone()
    };
    ir.report = identify::report::report(&ir, &options);
    identifiability_diagnostics(&ir, &options, &mut diagnostics);
    let mut notes: Vec<String> = diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Note)
        .map(|d| d.message.clone())
        .collect();
    notes.append(&mut ir.report.notes);
    ir.report.notes = notes;
    Ok(Compilation {
        ir: Some(ir),
        diagnostics,
    })
}
