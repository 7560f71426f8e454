//! Hovers: on a name, what it is (declaration, unit, frame; for a
//! parameter the terms it multiplies, its nominal value and whether it is
//! identified); on a term, the regressors it brings: its Φ column and the
//! nuisance columns Φρ, Φλ, with the sign factors `s[…]` of the patterns
//! (as `leeway check` prints them).

use crate::analysis::Analysis;
use crate::symbols::{Kind, Occurrence};
use leeway_grammar::{EquationKind, Span};
use leeway_structure::ir::{ColumnKind, Ir};
use leeway_structure::render::column_text;
use std::fmt::Write;

/// Markdown for the hover at byte `at`, and the span it is about.
pub fn hover(text: &str, analysis: &Analysis, at: usize) -> Option<(String, Span)> {
    let ir = analysis.compilation.ir.as_ref();
    let mut md = String::new();
    let mut span = None;
    if let Some(o) = analysis.symbols.at(at) {
        name(&mut md, text, analysis, ir, o);
        span = Some(o.span);
    }
    if let Some(ir) = ir {
        let term = ir
            .terms
            .iter()
            .enumerate()
            .filter(|(_, t)| t.span.start <= at && at < t.span.end)
            .min_by_key(|(_, t)| t.span.end - t.span.start);
        if let Some((t, _)) = term {
            if !md.is_empty() {
                md.push_str("\n---\n\n");
            }
            term_section(&mut md, ir, t);
            span = span.or(Some(ir.terms[t].span));
        }
    }
    span.map(|s| (md, s))
}

/// A declaration as written: its item's text up to the first comment
/// (pest's span of a declaration ending in an optional part reaches over
/// the comments after it), with the keyword of a `state` or `input` list.
fn declaration(text: &str, o: &Occurrence) -> String {
    let item = text.get(o.item.start..o.item.end).unwrap_or("");
    let code = item
        .find("//")
        .into_iter()
        .chain(item.find("/*"))
        .min()
        .map_or(item, |i| &item[..i])
        .trim();
    match o.kind {
        Kind::State if !code.starts_with("state") => format!("state {code}"),
        Kind::Input if !code.starts_with("input") => format!("input {code}"),
        _ => code.to_string(),
    }
}

fn name(md: &mut String, text: &str, analysis: &Analysis, ir: Option<&Ir>, o: &Occurrence) {
    let _ = writeln!(md, "**{}** `{}`\n", o.kind.word(), o.name);
    if o.kind == Kind::Parameter {
        parameter(md, analysis, ir, &o.name);
        return;
    }
    let decls = analysis.symbols.declarations(&o.name, o.kind);
    for d in &decls {
        let _ = writeln!(md, "```som\n{}\n```\n", declaration(text, d));
    }
    let Some(ir) = ir else { return };
    if let Some(column) = ir.data_columns.get(&o.name) {
        let _ = writeln!(md, "data column: `{column}`\n");
    }
    if let Some(unit) = ir.data_units.get(&o.name) {
        let _ = writeln!(md, "logged in: `{unit}`\n");
    }
    let medium = |i: usize| {
        let d = &ir.disturbances[i];
        let components: Vec<&str> = d
            .components
            .iter()
            .map(|&c| ir.components[c].name.as_str())
            .collect();
        format!(
            "`{}`: {}, in the {} frame, components {}",
            d.name,
            if d.measured { "measured" } else { "unmeasured" },
            if d.earth { "earth" } else { "body" },
            components.join(", ")
        )
    };
    match o.kind {
        Kind::Medium => {
            if let Some(i) = ir.disturbances.iter().position(|d| d.name == o.name) {
                let _ = writeln!(md, "{}\n", medium(i));
            }
        }
        Kind::Relative => {
            if let Some(r) = ir.relatives.iter().find(|r| r.name == o.name) {
                let _ = writeln!(md, "the states relative to {}\n", medium(r.disturbance));
            }
        }
        Kind::Component => {
            if let Some(c) = ir.components.iter().find(|c| c.name == o.name) {
                let _ = writeln!(md, "a component of {}\n", medium(c.disturbance));
            }
        }
        _ => {}
    }
}

fn parameter(md: &mut String, analysis: &Analysis, ir: Option<&Ir>, name: &str) {
    let Some(ir) = ir else {
        let uses = analysis.symbols.references(name, Kind::Parameter).len();
        let _ = writeln!(
            md,
            "written {uses} times (the model does not compile: no more is known)"
        );
        return;
    };
    let Some(p) = ir.parameters.iter().position(|q| q.name == name) else {
        return;
    };
    let param = &ir.parameters[p];
    let _ = writeln!(md, "nominal value: {}\n", param.nominal);
    let _ = writeln!(md, "multiplies:\n");
    for t in ir.terms.iter().filter(|t| t.parameter == p) {
        let kind = match ir.equations[t.output].kind {
            EquationKind::Der => "der",
            EquationKind::Next => "next",
        };
        let _ = writeln!(md, "- `{}` in `{kind} {}`", t.text, ir.states[t.output]);
    }
    md.push('\n');
    let combinations: Vec<&str> = ir
        .report
        .unidentifiable
        .iter()
        .filter(|c| c.parameters.contains(&p))
        .map(|c| c.message.as_str())
        .collect();
    if combinations.is_empty() && ir.report.identifiable {
        let _ = writeln!(md, "identified");
    } else if combinations.is_empty() {
        let _ = writeln!(
            md,
            "θ is not identifiable (see the diagnostic on the model's name)"
        );
    } else {
        for c in combinations {
            let _ = writeln!(md, "not identified alone: {c}\n");
        }
    }
}

fn term_section(md: &mut String, ir: &Ir, t: usize) {
    let term = &ir.terms[t];
    let out = term.output;
    let _ = writeln!(
        md,
        "**term** `{}` of `{}` (θ: `{}`)\n",
        term.text, ir.states[out], ir.parameters[term.parameter].name
    );
    let mut rows = String::new();
    for c in &ir.predictors.measured {
        if c.kind.parameter() != term.parameter || !c.outputs().contains(&out) {
            continue;
        }
        let tag = match c.kind {
            ColumnKind::Theta { .. } => "Φ",
            ColumnKind::Rho { .. } => "Φρ",
            ColumnKind::Lambda { .. } => "Φλ",
        };
        let _ = writeln!(rows, "{tag:<3} {:<24} {}", c.name, column_text(ir, c, out));
    }
    let _ = writeln!(md, "regressors in `{}`:\n```\n{rows}```", ir.states[out]);
}
