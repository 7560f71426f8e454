//! Diagnostics as plain data, and their one renderer.
//!
//! Every pass reports [`Diagnostic`]s; nothing is printed inside the library.
//! [`render`] turns them into rustc-like text (`file:line:col`, the source
//! line, a caret under the span, the help), plain for tests and macros,
//! coloured for terminals.

use crate::ast::Span;
use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term;
use serde::{Deserialize, Serialize};

/// How serious a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// The model is rejected.
    Error,
    /// Accepted, but something is probably wrong.
    Warning,
    /// Information the user should know (e.g. an assumption the data must meet).
    Note,
}

/// A span with a message.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Label {
    /// Where.
    pub span: Span,
    /// What is said there (may be empty).
    pub message: String,
    /// The primary label gets the caret `^`; secondary ones get `-`.
    pub primary: bool,
}

/// One message to the user: a stable kebab-case code, a severity, a message,
/// labelled spans, an optional help line and notes.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Diagnostic {
    /// Stable code, e.g. `order-too-high`.
    pub code: String,
    /// Error, warning or note.
    pub severity: Severity,
    /// One sentence.
    pub message: String,
    /// Where in the source (may be empty for model-wide findings).
    pub labels: Vec<Label>,
    /// How to fix it.
    pub help: Option<String>,
    /// Further facts.
    pub notes: Vec<String>,
}

impl Diagnostic {
    fn new(severity: Severity, code: &str, message: impl Into<String>) -> Self {
        Diagnostic {
            code: code.to_string(),
            severity,
            message: message.into(),
            labels: Vec::new(),
            help: None,
            notes: Vec::new(),
        }
    }
    /// A new error.
    pub fn error(code: &str, message: impl Into<String>) -> Self {
        Self::new(Severity::Error, code, message)
    }
    /// A new warning.
    pub fn warning(code: &str, message: impl Into<String>) -> Self {
        Self::new(Severity::Warning, code, message)
    }
    /// A new note.
    pub fn note(code: &str, message: impl Into<String>) -> Self {
        Self::new(Severity::Note, code, message)
    }
    /// Adds the primary label (the caret).
    pub fn with_primary(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: true,
        });
        self
    }
    /// Adds a secondary label.
    pub fn with_secondary(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: false,
        });
        self
    }
    /// Sets the help line.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
    /// Adds a note.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    /// True for errors.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
    /// The primary span, if any.
    pub fn primary_span(&self) -> Option<Span> {
        self.labels
            .iter()
            .find(|l| l.primary)
            .or(self.labels.first())
            .map(|l| l.span)
    }
}

/// Plain text (tests, `compile_error!`, pipes) or ANSI colour (terminals).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderStyle {
    /// No escape codes.
    Plain,
    /// ANSI colours.
    Color,
}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = floor_char_boundary(source, offset.min(source.len()));
    let before = &source[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = source[line_start..offset].chars().count() + 1;
    (line, col)
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Clamps a span into the source on character boundaries, so a label can
/// always be drawn whatever produced it.
fn clamp(source: &str, span: Span) -> std::ops::Range<usize> {
    let start = floor_char_boundary(source, span.start.min(source.len()));
    let end = floor_char_boundary(source, span.end.min(source.len())).max(start);
    start..end
}

fn to_codespan(d: &Diagnostic, source: &str) -> cs::Diagnostic<()> {
    let severity = match d.severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
        Severity::Note => cs::Severity::Note,
    };
    let labels = d
        .labels
        .iter()
        .map(|l| {
            let style = if l.primary {
                cs::LabelStyle::Primary
            } else {
                cs::LabelStyle::Secondary
            };
            cs::Label::new(style, (), clamp(source, l.span)).with_message(l.message.clone())
        })
        .collect();
    let mut notes: Vec<String> = d.notes.iter().map(|n| format!("note: {n}")).collect();
    if let Some(help) = &d.help {
        notes.push(format!("help: {help}"));
    }
    cs::Diagnostic::new(severity)
        .with_code(d.code.clone())
        .with_message(d.message.clone())
        .with_labels(labels)
        .with_notes(notes)
}

/// Renders diagnostics like a compiler: `error[code]: message`, then
/// `┌─ file:line:col`, the source line with a caret under the span, and the
/// notes and help. A diagnostic without labels renders without a snippet.
pub fn render(
    diagnostics: &[Diagnostic],
    file_name: &str,
    source: &str,
    style: RenderStyle,
) -> String {
    let file = SimpleFile::new(file_name, source);
    let config = term::Config::default();
    let mut out = String::new();
    for d in diagnostics {
        let cd = to_codespan(d, source);
        let mut buffer = match style {
            RenderStyle::Plain => term::termcolor::Buffer::no_color(),
            RenderStyle::Color => term::termcolor::Buffer::ansi(),
        };
        if term::emit(&mut buffer, &config, &file, &cd).is_ok() {
            out.push_str(&String::from_utf8_lossy(buffer.as_slice()));
        } else {
            // The renderer refused (cannot happen for clamped spans); never lose the message.
            out.push_str(&format!("{:?}[{}]: {}\n", d.severity, d.code, d.message).to_lowercase());
        }
    }
    out
}

/// One line per diagnostic: `file:line:col: severity[code]: message`, for logs.
pub fn render_short(diagnostics: &[Diagnostic], file_name: &str, source: &str) -> String {
    let mut out = String::new();
    for d in diagnostics {
        let sev = match d.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Note => "note",
        };
        match d.primary_span() {
            Some(span) => {
                let (l, c) = line_col(source, span.start);
                out.push_str(&format!(
                    "{file_name}:{l}:{c}: {sev}[{}]: {}\n",
                    d.code, d.message
                ));
            }
            None => out.push_str(&format!("{file_name}: {sev}[{}]: {}\n", d.code, d.message)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_characters_from_one() {
        let src = "ab\ncé d\n";
        assert_eq!(line_col(src, 0), (1, 1));
        assert_eq!(line_col(src, 2), (1, 3));
        assert_eq!(line_col(src, 3), (2, 1));
        assert_eq!(line_col(src, 6), (2, 3), "é is one column");
        assert_eq!(line_col(src, 5), (2, 2), "inside é: its start");
        assert_eq!(line_col(src, 999), (3, 1), "past the end: the end");
    }

    #[test]
    fn render_is_like_a_compiler() {
        let src = "model M {\n    der u = X*u*v*r\n}\n";
        let d = Diagnostic::error("order-too-high", "the term `u*v*r` is beyond second order")
            .with_primary(Span::new(22, 29), "3 signals in one term")
            .with_help("second-order modulus terms are a, |a|, a*b and a*|b|");
        let text = render(std::slice::from_ref(&d), "m.som", src, RenderStyle::Plain);
        let expected = "error[order-too-high]: the term `u*v*r` is beyond second order\n  ┌─ m.som:2:13\n  │\n2 │     der u = X*u*v*r\n  │             ^^^^^^^ 3 signals in one term\n  │\n  = help: second-order modulus terms are a, |a|, a*b and a*|b|\n\n";
        assert_eq!(text, expected);
        assert_eq!(
            render_short(&[d], "m.som", src),
            "m.som:2:13: error[order-too-high]: the term `u*v*r` is beyond second order\n"
        );
        let colored = render(
            &[Diagnostic::error("x", "y").with_primary(Span::new(0, 5), "")],
            "m.som",
            src,
            RenderStyle::Color,
        );
        assert!(colored.contains('\u{1b}'));
    }

    #[test]
    fn spans_outside_the_source_are_clamped() {
        let d = Diagnostic::warning("w", "far away").with_primary(Span::new(500, 900), "here");
        let text = render(&[d], "m.som", "é", RenderStyle::Plain);
        assert!(text.starts_with("warning[w]: far away"), "{text}");
        let note = Diagnostic::note("n", "no location");
        assert_eq!(
            render(&[note], "m.som", "", RenderStyle::Plain),
            "note[n]: no location\n\n"
        );
    }
}
