//! Code actions where the fix is certain.
//!
//! - Quick fixes for `check`'s `unused-declaration` warnings: an unused input
//!   taken out of its declaration (`input tau, rudder` → `input tau`), an
//!   unused relative velocity or a disturbance no relative velocity sees
//!   removed with its line.
//! - A refactor on a parameter without a `nominal` entry: list it with the
//!   value it has when unlisted (0), so the meaning does not change and the
//!   number is there to edit. `check` does not warn of such a parameter (0
//!   is a valid nominal value), so this is no quick fix.
//!
//! Every edit is compiled before it is offered: an action whose result would
//! hold an error (an input still named by a `delay` or a `data` entry, a
//! disturbance whose components are mapped to columns) or would keep the
//! diagnostic it fixes is not offered.

use crate::analysis::Analysis;
use crate::symbols::Kind;
use crate::text::range;
use leeway_grammar::{Diagnostic, Ident, Item, ModelSyntax, Span};
use leeway_structure::{CompileOptions, compile};
use lsp_types::{CodeAction, CodeActionKind, TextEdit, Uri, WorkspaceEdit};
use std::collections::{BTreeSet, HashMap};

/// The code actions for the range `within` (byte span): quick fixes for the
/// diagnostics that touch it, the `nominal` refactor on a parameter in it.
pub fn actions(uri: &Uri, text: &str, analysis: &Analysis, within: Span) -> Vec<CodeAction> {
    let Some(model) = &analysis.model else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for d in &analysis.compilation.diagnostics {
        let Some(at) = d.primary_span() else { continue };
        if d.code != "unused-declaration" || at.end < within.start || at.start > within.end {
            continue;
        }
        let Some((name, cut)) = unused_removal(text, model, at) else {
            continue;
        };
        let edit = TextEdit::new(range(text, cut), String::new());
        if certain(text, &edit_of(cut, ""), Some(d)) {
            out.push(action(
                uri,
                format!("remove the unused `{name}`"),
                CodeActionKind::QUICKFIX,
                edit,
            ));
        }
    }
    out.extend(nominal_actions(uri, text, analysis, model, within));
    out
}

fn action(uri: &Uri, title: String, kind: CodeActionKind, edit: TextEdit) -> CodeAction {
    let quick = kind == CodeActionKind::QUICKFIX;
    CodeAction {
        title,
        kind: Some(kind),
        diagnostics: None,
        edit: Some(WorkspaceEdit {
            changes: Some(HashMap::from([(uri.clone(), vec![edit])])),
            ..Default::default()
        }),
        is_preferred: quick.then_some(true),
        ..Default::default()
    }
}

/// One replacement of bytes.
struct Splice {
    span: Span,
    with: String,
}

fn edit_of(span: Span, with: &str) -> Splice {
    Splice {
        span,
        with: with.to_string(),
    }
}

/// Whether `text` with `splice` applied compiles without error and, when
/// `fixes` is given, without that diagnostic (same code and message).
fn certain(text: &str, splice: &Splice, fixes: Option<&Diagnostic>) -> bool {
    let mut edited = text.to_string();
    edited.replace_range(splice.span.start..splice.span.end, &splice.with);
    let c = compile(&edited, &CompileOptions::default());
    c.ir.is_some()
        && !c.diagnostics.iter().any(Diagnostic::is_error)
        && fixes.is_none_or(|f| {
            !c.diagnostics
                .iter()
                .any(|d| d.code == f.code && d.message == f.message)
        })
}

/// The name declared at `at` and the bytes that remove its declaration.
fn unused_removal(text: &str, model: &ModelSyntax, at: Span) -> Option<(String, Span)> {
    for item in &model.items {
        match item {
            Item::States(names) | Item::Inputs(names) => {
                if let Some(i) = names.iter().position(|n| n.span == at) {
                    return Some((names[i].name.clone(), list_removal(text, names, i)?));
                }
            }
            Item::Relative { name, span, .. } | Item::Disturbance { name, span, .. }
                if name.span == at =>
            {
                return Some((name.name.clone(), line_removal(text, *span)?));
            }
            _ => {}
        }
    }
    None
}

/// The bytes to delete to take name `i` out of its list: with the comma
/// before it (or after it, for the first); the whole line when it is the
/// list's only name.
fn list_removal(text: &str, names: &[Ident], i: usize) -> Option<Span> {
    let name = &names[i];
    if names.len() > 1 {
        return Some(if i == 0 {
            Span::new(name.span.start, names[1].span.start)
        } else {
            Span::new(names[i - 1].span.end, name.span.end)
        });
    }
    let start = text[..name.span.start].rfind('\n').map_or(0, |n| n + 1);
    let keyword = text[start..name.span.start].trim();
    if keyword != "state" && keyword != "input" {
        return None;
    }
    let keyword_start = name.span.start - text[start..name.span.start].trim_start().len();
    let whole = Span::new(keyword_start, name.span.end);
    line_removal(text, whole).filter(|cut| *cut != whole)
}

/// The whole lines of a declaration, when nothing but blanks precedes it on
/// its first line and nothing but blanks, a `;` or a comment follows it on
/// its last (the comment went with the declaration); else the declaration
/// alone.
fn line_removal(text: &str, span: Span) -> Option<Span> {
    let start = text[..span.start].rfind('\n').map_or(0, |n| n + 1);
    let end = text[span.end..]
        .find('\n')
        .map_or(text.len(), |n| span.end + n + 1);
    let before = &text[start..span.start];
    let after = text[span.end..end].trim();
    let after = after.strip_prefix(';').unwrap_or(after).trim_start();
    if before.trim().is_empty() && (after.is_empty() || after.starts_with("//")) {
        Some(Span::new(start, end))
    } else {
        Some(span)
    }
}

/// On a parameter without a `nominal` entry: list it (and, when several
/// lack one, all of them) with the value 0 it has unlisted.
fn nominal_actions(
    uri: &Uri,
    text: &str,
    analysis: &Analysis,
    model: &ModelSyntax,
    within: Span,
) -> Vec<CodeAction> {
    // Only on a model that compiles: there a name in an equation that is no
    // signal is certainly a parameter (not a misspelt signal).
    let Some(ir) = &analysis.compilation.ir else {
        return Vec::new();
    };
    let symbols = &analysis.symbols;
    let Some(here) = symbols.at(within.start) else {
        return Vec::new();
    };
    let listed: BTreeSet<&str> = symbols
        .occurrences
        .iter()
        .filter(|o| o.kind == Kind::Parameter && o.declaration)
        .map(|o| o.name.as_str())
        .collect();
    if here.kind != Kind::Parameter || listed.contains(here.name.as_str()) {
        return Vec::new();
    }
    if !ir.parameters.iter().any(|p| p.name == here.name) {
        return Vec::new();
    }
    let unlisted: Vec<&str> = ir
        .parameters
        .iter()
        .map(|p| p.name.as_str())
        .filter(|n| !listed.contains(n))
        .collect();
    let mut out = Vec::new();
    let mut offer = |names: &[&str], title: String| {
        let Some(splice) = nominal_insertion(text, model, names) else {
            return;
        };
        if certain(text, &splice, None) {
            let edit = TextEdit::new(range(text, splice.span), splice.with);
            out.push(action(uri, title, CodeActionKind::REFACTOR_REWRITE, edit));
        }
    };
    offer(
        &[here.name.as_str()],
        format!(
            "list `{}` in `nominal {{ }}` (0, its value unlisted)",
            here.name
        ),
    );
    if unlisted.len() > 1 {
        offer(
            &unlisted,
            format!(
                "list the {} parameters without a nominal value in `nominal {{ }}` (0)",
                unlisted.len()
            ),
        );
    }
    out
}

/// The insertion of `name = 0` entries: after the last entry of the
/// `nominal` block, inside an empty one, or a new block before the model's
/// closing brace.
fn nominal_insertion(text: &str, model: &ModelSyntax, names: &[&str]) -> Option<Splice> {
    let entries = names
        .iter()
        .map(|n| format!("{n} = 0"))
        .collect::<Vec<_>>()
        .join(", ");
    let block = model.items.iter().find_map(|i| match i {
        Item::Nominal { entries, span } => Some((entries, *span)),
        _ => None,
    });
    if let Some((written, span)) = block {
        return Some(match written.last() {
            Some((_, value)) => edit_of(
                Span::new(value.span.end, value.span.end),
                &format!(", {entries}"),
            ),
            None => {
                let brace = span.start + text[span.start..span.end].find('{')? + 1;
                edit_of(Span::new(brace, brace), &format!(" {entries}"))
            }
        });
    }
    let close = model.span.end.checked_sub(1)?;
    if text.as_bytes().get(close) != Some(&b'}') {
        return None;
    }
    let line = text[..close].rfind('\n').map_or(0, |n| n + 1);
    if !text[line..close].trim().is_empty() {
        return Some(edit_of(
            Span::new(close, close),
            &format!(" nominal {{ {entries} }} "),
        ));
    }
    // Indented as the nearest line above that holds something.
    let indent = text[..line]
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .map_or("", |l| &l[..l.len() - l.trim_start().len()]);
    Some(edit_of(
        Span::new(line, line),
        &format!("{indent}nominal {{ {entries} }}\n"),
    ))
}
