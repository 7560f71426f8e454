//! The compiler's diagnostics as the protocol's: the same codes and texts
//! as `leeway check` prints; the primary label is the range, the other
//! labels related locations; help and notes follow the message. The
//! identifiability verdict is one more, an information on the model's name.

use crate::analysis::Analysis;
use crate::text::range;
use leeway_grammar::{Diagnostic, Severity, Span};
use lsp_types::{DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString, Uri};

/// The code of the verdict's information diagnostic.
pub const VERDICT: &str = "identifiability";

/// The protocol diagnostics of a document.
pub fn of(uri: &Uri, text: &str, analysis: &Analysis) -> Vec<lsp_types::Diagnostic> {
    let model_name = analysis.model.as_ref().map(|m| m.name.span);
    let mut out: Vec<lsp_types::Diagnostic> = analysis
        .compilation
        .diagnostics
        .iter()
        .map(|d| convert(uri, text, d, model_name))
        .collect();
    if let (Some(ir), Some(at)) = (&analysis.compilation.ir, model_name) {
        out.push(lsp_types::Diagnostic {
            range: range(text, at),
            severity: Some(DiagnosticSeverity::INFORMATION),
            code: Some(NumberOrString::String(VERDICT.into())),
            source: Some("leeway".into()),
            message: verdict_message(&leeway_structure::render::verdict(ir)),
            ..Default::default()
        });
    }
    out
}

/// The report's verdict section as one message: the verdict first (an
/// editor shows the first line beside the code), the centring it was
/// analysed under after it, without the section's title.
pub fn verdict_message(section: &str) -> String {
    let lines: Vec<&str> = section
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("Identifiability of"))
        .collect();
    let (centring, verdict): (Vec<&str>, Vec<&str>) = lines
        .iter()
        .partition(|l| l.starts_with("instrument centring"));
    verdict
        .into_iter()
        .chain(centring)
        .collect::<Vec<_>>()
        .join("\n")
}

/// The text shown for a diagnostic: its message, the primary label's text,
/// `help:` and `note:` lines, as `check` renders them.
pub fn message(d: &Diagnostic) -> String {
    let mut m = d.message.clone();
    if let Some(l) = d.labels.iter().find(|l| l.primary && !l.message.is_empty()) {
        m.push_str(&format!("\n{}", l.message));
    }
    if let Some(h) = &d.help {
        m.push_str(&format!("\nhelp: {h}"));
    }
    for n in &d.notes {
        m.push_str(&format!("\nnote: {n}"));
    }
    m
}

fn convert(
    uri: &Uri,
    text: &str,
    d: &Diagnostic,
    model_name: Option<Span>,
) -> lsp_types::Diagnostic {
    // A finding about the whole model (no label) is shown on its name.
    let at = d.primary_span().or(model_name).unwrap_or_default();
    let related: Vec<DiagnosticRelatedInformation> = d
        .labels
        .iter()
        .filter(|l| !(l.primary && l.span == at))
        .map(|l| DiagnosticRelatedInformation {
            location: Location::new(uri.clone(), range(text, l.span)),
            message: if l.message.is_empty() {
                d.message.clone()
            } else {
                l.message.clone()
            },
        })
        .collect();
    lsp_types::Diagnostic {
        range: range(text, at),
        severity: Some(match d.severity {
            Severity::Error => DiagnosticSeverity::ERROR,
            Severity::Warning => DiagnosticSeverity::WARNING,
            Severity::Note => DiagnosticSeverity::INFORMATION,
        }),
        code: Some(NumberOrString::String(d.code.clone())),
        source: Some("leeway".into()),
        message: message(d),
        related_information: (!related.is_empty()).then_some(related),
        ..Default::default()
    }
}
