//! Diagnostics drawn from the passes' results: unused declarations, the
//! identifiability verdict as errors, warnings and notes, and repeats merged.

use crate::identify::pattern::patterns_text;
use crate::identify::report::{CompileOptions, constant_parameters};
use crate::ir::{Combination, Ir, PredictorKind, Separation, Signal, Term};
use crate::resolve::decl::Resolved;
use crate::terms::TermDecl;
use leeway_grammar::{Diagnostic, Label, MAX_LISTED};
use std::collections::{BTreeMap, BTreeSet};

/// Warns of inputs, relative velocities and disturbances no equation uses.
pub(crate) fn unused_declarations(r: &Resolved, terms: &[TermDecl], diags: &mut Vec<Diagnostic>) {
    // One pass over the terms (a model may have 10⁴ inputs and terms).
    let mut used_inputs = BTreeSet::new();
    let mut used_relatives = BTreeSet::new();
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

/// The identifiability verdict of the report as diagnostics: an error (or,
/// aggregating, a warning) per unidentifiable group; a warning when the
/// search for the fewest experiments was cut; a note when θ needs several.
pub(crate) fn identifiability_diagnostics(
    ir: &Ir,
    options: &CompileOptions,
    diags: &mut Vec<Diagnostic>,
) {
    let r = &ir.report;
    let first_term = first_terms(ir);
    let labels_for = |params: &[usize]| labels_for(ir, &first_term, params);
    if !r.identifiable {
        unidentifiable_diagnostics(ir, options, &labels_for, diags);
    } else if let Some(cut) = &r.search_cut {
        let mut d = Diagnostic::warning(
            "search-cut",
            format!(
                "θ is identifiable from {} experiment{} with sign pattern{} {}; whether fewer suffice is undecided",
                r.required_patterns.len(),
                if r.required_patterns.len() == 1 { "" } else { "s" },
                if r.required_patterns.len() == 1 { "" } else { "s" },
                patterns_text(ir, &r.required_patterns, PredictorKind::Measured)
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
        diags.push(required_experiments(ir, &labels_for));
    }
}

/// The first term of each parameter, once (a model may have 10⁴ groups).
fn first_terms(ir: &Ir) -> BTreeMap<usize, &Term> {
    let mut first_term: BTreeMap<usize, &Term> = Default::default();
    for t in ir.terms.iter().rev() {
        first_term.insert(t.parameter, t);
    }
    first_term
}

/// At most MAX_LISTED labels: the message names the group (capped too), and
/// each label would print a source line.
fn labels_for(ir: &Ir, first_term: &BTreeMap<usize, &Term>, params: &[usize]) -> Vec<Label> {
    params
        .iter()
        .filter_map(|p| first_term.get(p).copied())
        .take(MAX_LISTED)
        .enumerate()
        .map(|(i, t)| Label {
            span: t.span,
            message: format!("`{}`", ir.parameters[t.parameter].name),
            primary: i == 0,
        })
        .collect()
}

/// One diagnostic per unidentifiable group, with what separates it.
fn unidentifiable_diagnostics(
    ir: &Ir,
    options: &CompileOptions,
    labels_for: &dyn Fn(&[usize]) -> Vec<Label>,
    diags: &mut Vec<Diagnostic>,
) {
    let r = &ir.report;
    let constants: BTreeSet<usize> = constant_parameters(ir).into_iter().collect();
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
        d = d.with_help(unidentifiable_help(options, &constants, c, s));
        diags.push(d);
    }
}

/// What to do about one unidentifiable group.
fn unidentifiable_help(
    options: &CompileOptions,
    constants: &BTreeSet<usize>,
    c: &Combination,
    s: &Separation,
) -> &'static str {
    if options.aggregate {
        "the absorbed parameters are held at their nominal values; the kept ones estimate the combinations above"
    } else if c.parameters.iter().all(|p| constants.contains(p)) && s.patterns.is_some() {
        "estimate with the centring and from the experiments named in the note (`leeway check --centring` shows that analysis), or remove the constant term"
    } else if c.parameters.iter().all(|p| constants.contains(p)) {
        "remove the constant term, or estimate the identifiable combinations with --aggregate"
    } else if s.patterns.is_some() {
        "run the experiments named in the note, or estimate the identifiable combinations with --aggregate"
    } else {
        "merge the parameters into one, measure the medium (IV3), or estimate the identifiable combinations with --aggregate"
    }
}

/// The note that θ needs several experiments, with what one experiment leaves
/// unidentified.
fn required_experiments(ir: &Ir, labels_for: &dyn Fn(&[usize]) -> Vec<Label>) -> Diagnostic {
    let r = &ir.report;
    let mut d = Diagnostic::note(
        "required-experiments",
        format!(
            "θ is identifiable from {} experiments with sign patterns {}, not from one",
            r.required_patterns.len(),
            patterns_text(ir, &r.required_patterns, PredictorKind::Measured)
        ),
    );
    // One pair of notes per group, at most MAX_LISTED groups (a model
    // may have 10⁴ of them; `check --json` lists every one).
    let groups = r.unidentifiable.len().min(r.separations.len());
    for (c, s) in r.unidentifiable.iter().zip(&r.separations).take(MAX_LISTED) {
        d = d
            .with_note(format!("from one experiment: {}", c.message))
            .with_note(s.message.clone());
    }
    if groups > MAX_LISTED {
        d = d.with_note(format!(
            "… and {} more groups like these, not shown (`leeway check --json` lists every one in `unidentifiable` and `separations`)",
            groups - MAX_LISTED
        ));
    }
    if let Some(first) = r.unidentifiable.first() {
        d.labels = labels_for(&first.parameters);
    }
    d
}

/// Keeps one diagnostic per code and place (the start of its primary span):
/// the products of one multiplied-out term start where it does, and 4,096 of
/// them must not report the same problem 4,096 times. The kept one counts the others in a note.
pub(crate) fn merge_repeats(diagnostics: &mut Vec<Diagnostic>) {
    let mut seen: BTreeMap<(String, Option<usize>), (usize, usize)> = BTreeMap::new();
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
