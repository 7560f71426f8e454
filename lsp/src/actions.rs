//! Code actions where the fix is certain: an unused state or input removed
//! from its declaration (`input tau, rudder` → `input tau`).

use crate::analysis::Analysis;
use crate::text::range;
use leeway_grammar::{Ident, Item, Span};
use lsp_types::{CodeAction, CodeActionKind, TextEdit, Uri, WorkspaceEdit};
use std::collections::HashMap;

/// The quick fixes for the diagnostics that touch `within` (byte span).
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
        for item in &model.items {
            let (Item::States(names) | Item::Inputs(names)) = item else {
                continue;
            };
            let Some(i) = names.iter().position(|n| n.span == at) else {
                continue;
            };
            let Some(cut) = removal(text, names, i) else {
                continue;
            };
            let edit = TextEdit::new(range(text, cut), String::new());
            out.push(CodeAction {
                title: format!("remove the unused `{}`", names[i].name),
                kind: Some(CodeActionKind::QUICKFIX),
                diagnostics: None,
                edit: Some(WorkspaceEdit {
                    changes: Some(HashMap::from([(uri.clone(), vec![edit])])),
                    ..Default::default()
                }),
                is_preferred: Some(true),
                ..Default::default()
            });
        }
    }
    out
}

/// The bytes to delete to take name `i` out of its list: with the comma
/// before it (or after it, for the first); the whole line when it is the
/// list's only name and the line holds nothing else.
fn removal(text: &str, names: &[Ident], i: usize) -> Option<Span> {
    let name = &names[i];
    if names.len() > 1 {
        return Some(if i == 0 {
            Span::new(name.span.start, names[1].span.start)
        } else {
            Span::new(names[i - 1].span.end, name.span.end)
        });
    }
    let start = text[..name.span.start].rfind('\n').map_or(0, |n| n + 1);
    let end = text[name.span.end..]
        .find('\n')
        .map_or(text.len(), |n| name.span.end + n + 1);
    let line = text[start..end].trim();
    let alone = line == format!("state {}", name.name) || line == format!("input {}", name.name);
    alone.then(|| Span::new(start, end))
}
