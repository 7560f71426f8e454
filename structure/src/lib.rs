//! leeway-structure: a parsed `.som` model → its regressor structure and an
//! exact identifiability report.
//!
//! The passes run in order from [`compile`]: resolve (names), terms (the
//! second-order modulus class), signs and expand (`Φ`, `Φ_ρ`, `Φ_λ`, `Φ2`),
//! lower (the [`ir::Ir`]), identify (exact rank over sign patterns). Every
//! pass collects diagnostics; nothing here does IO or panics.

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

#[doc(inline)]
pub use identify::CompileOptions;
#[doc(inline)]
pub use ir::Ir;
#[doc(inline)]
pub use leeway_grammar as grammar;
use leeway_grammar::{Diagnostic, Label, Severity};

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
    let (model, mut diagnostics) = leeway_grammar::parse(source);
    let Some(model) = model else {
        return Compilation {
            ir: None,
            diagnostics,
        };
    };
    let resolved = resolve::resolve(&model, &mut diagnostics);
    let (params, terms) = terms::lower_terms(&resolved, &mut diagnostics);
    merge_repeats(&mut diagnostics);
    if diagnostics.iter().any(Diagnostic::is_error) {
        return Compilation {
            ir: None,
            diagnostics,
        };
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
        return Compilation {
            ir: None,
            diagnostics,
        };
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
        return Compilation {
            ir: None,
            diagnostics,
        };
    }
    ir.report = identify::report(&ir, options);
    identifiability_diagnostics(&ir, options, &mut diagnostics);
    let mut notes: Vec<String> = diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Note)
        .map(|d| d.message.clone())
        .collect();
    notes.append(&mut ir.report.notes);
    ir.report.notes = notes;
    Compilation {
        ir: Some(ir),
        diagnostics,
    }
}

fn unused_declarations(
    r: &resolve::Resolved,
    terms: &[terms::TermDecl],
    diags: &mut Vec<Diagnostic>,
) {
    use ir::Signal;
    // One pass over the terms (a model may have 10⁴ inputs and terms).
    let mut used_inputs = std::collections::BTreeSet::new();
    let mut used_relatives = std::collections::BTreeSet::new();
    for f in terms.iter().flat_map(|t| t.factors.iter()) {
        if let Signal::Input(i) = f.arg.signal {
            used_inputs.insert(i);
        }
        if let Some(ri) = f.arg.relative {
            used_relatives.insert(ri);
        }
    }
    for (i, input) in r.inputs.iter().enumerate() {
        if !used_inputs.contains(&i) {
            diags.push(
                Diagnostic::warning(
                    "unused-declaration",
                    format!("input `{}` appears in no equation", input.name),
                )
                .with_primary(input.span, "unused")
                .with_help("remove it, or add the term it drives"),
            );
        }
    }
    for (ri, (name, _)) in r.relatives.iter().enumerate() {
        if !used_relatives.contains(&ri) {
            diags.push(
                Diagnostic::warning(
                    "unused-declaration",
                    format!("relative velocity `{}` appears in no equation", name.name),
                )
                .with_primary(name.span, "unused")
                .with_help(
                    "write terms such as `X*{0}.u`, or remove it".replace("{0}", &name.name),
                ),
            );
        }
    }
    for (di, d) in r.disturbances.iter().enumerate() {
        if !r.relatives.iter().any(|(_, dd)| *dd == di) {
            diags.push(
                Diagnostic::warning(
                    "unused-declaration",
                    format!("disturbance `{}` has no relative velocity", d.name.name),
                )
                .with_primary(d.name.span, "never acts on the craft")
                .with_help(format!(
                    "declare `rel = relative({})` and use it in the equations",
                    d.name.name
                )),
            );
        }
    }
}

fn identifiability_diagnostics(ir: &Ir, options: &CompileOptions, diags: &mut Vec<Diagnostic>) {
    let r = &ir.report;
    // The first term of each parameter, once (a model may have 10⁴ groups).
    let mut first_term: std::collections::BTreeMap<usize, &ir::Term> = Default::default();
    for t in ir.terms.iter().rev() {
        first_term.insert(t.parameter, t);
    }
    // At most MAX_LISTED labels: the message names the group (capped too), and
    // each label would print a source line.
    let labels_for = |params: &[usize]| -> Vec<Label> {
        params
            .iter()
            .filter_map(|p| first_term.get(p).copied())
            .take(leeway_grammar::MAX_LISTED)
            .enumerate()
            .map(|(i, t)| Label {
                span: t.span,
                message: format!("`{}`", ir.parameters[t.parameter].name),
                primary: i == 0,
            })
            .collect()
    };
    if !r.identifiable {
        let constants: std::collections::BTreeSet<usize> =
            identify::constant_parameters(ir).into_iter().collect();
        for (c, s) in r.unidentifiable.iter().zip(&r.separations) {
            let mut d = if options.aggregate {
                Diagnostic::warning(
                    "aggregated-combination",
                    format!("{}; estimating the aggregate", c.message),
                )
            } else {
                Diagnostic::error(
                    "unidentifiable-combination",
                    format!("θ is not identifiable: {}", c.message),
                )
            };
            d.labels = labels_for(&c.parameters);
            d = d.with_note(s.message.clone());
            d = if options.aggregate {
                d.with_help("the absorbed parameters are held at their nominal values; the kept ones estimate the combinations above")
            } else if c.parameters.iter().all(|p| constants.contains(p)) {
                d.with_help("estimate with the centring named in the note (`leeway check --centring`, `leeway estimate --centring`), or remove the constant term")
            } else if s.patterns.is_some() {
                d.with_help("run the experiments named in the note, or estimate the identifiable combinations with --aggregate")
            } else {
                d.with_help("merge the parameters into one, measure the medium (IV3), or estimate the identifiable combinations with --aggregate")
            };
            diags.push(d);
        }
    } else if let Some(cut) = &r.search_cut {
        let mut d = Diagnostic::warning(
            "search-cut",
            format!(
                "θ is identifiable from {} experiment{} with sign pattern{} {}; whether fewer suffice is undecided",
                r.required_patterns.len(),
                if r.required_patterns.len() == 1 { "" } else { "s" },
                if r.required_patterns.len() == 1 { "" } else { "s" },
                identify::patterns_text(ir, &r.required_patterns, ir::PredictorKind::Measured)
            ),
        )
        .with_note(cut.clone());
        if let Some(first) = r.unidentifiable.first() {
            d.labels = labels_for(&first.parameters);
        }
        diags.push(d.with_help(
            "the verdict is exact: these experiments identify θ; name the experiments you plan with --pattern to check them exactly",
        ));
    } else if r.required_patterns.len() > 1 {
        let mut d = Diagnostic::note(
            "required-experiments",
            format!(
                "θ is identifiable from {} experiments with sign patterns {}, not from one",
                r.required_patterns.len(),
                identify::patterns_text(ir, &r.required_patterns, ir::PredictorKind::Measured)
            ),
        );
        // One pair of notes per group, at most MAX_LISTED groups (a model
        // may have 10⁴ of them; `check --json` lists every one).
        let groups = r.unidentifiable.len().min(r.separations.len());
        for (c, s) in r
            .unidentifiable
            .iter()
            .zip(&r.separations)
            .take(leeway_grammar::MAX_LISTED)
        {
            d = d
                .with_note(format!("from one experiment: {}", c.message))
                .with_note(s.message.clone());
        }
        if groups > leeway_grammar::MAX_LISTED {
            d = d.with_note(format!(
                "… and {} more groups like these, not shown (`leeway check --json` lists every one in `unidentifiable` and `separations`)",
                groups - leeway_grammar::MAX_LISTED
            ));
        }
        if let Some(first) = r.unidentifiable.first() {
            d.labels = labels_for(&first.parameters);
        }
        diags.push(d);
    }
}

/// Keeps one diagnostic per code and place (the start of its primary span):
/// the products of one multiplied-out term start where it does, and 4,096 of
/// them must not report the same problem 4,096 times. The kept one counts the others in a note.
fn merge_repeats(diagnostics: &mut Vec<Diagnostic>) {
    let mut seen: std::collections::BTreeMap<(String, Option<usize>), (usize, usize)> =
        std::collections::BTreeMap::new();
    let mut keep = vec![true; diagnostics.len()];
    for (i, d) in diagnostics.iter().enumerate() {
        let key = (d.code.clone(), d.primary_span().map(|s| s.start));
        if d.labels.is_empty() {
            continue;
        }
        match seen.get_mut(&key) {
            Some((_, n)) => {
                *n += 1;
                keep[i] = false;
            }
            None => {
                seen.insert(key, (i, 0));
            }
        }
    }
    for (first, n) in seen.into_values() {
        if n > 0 {
            let more = if n == 1 { "term" } else { "terms" };
            diagnostics[first].notes.push(format!(
                "{n} more {more} of this expression have the same problem"
            ));
        }
    }
    let mut i = 0;
    diagnostics.retain(|_| {
        i += 1;
        keep[i - 1]
    });
}
