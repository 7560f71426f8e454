//! The one renderer: diagnostics as compiler-like text through
//! codespan-reporting, and one short line per diagnostic for logs.

use crate::diagnostic::data::{Diagnostic, Severity};
use crate::diagnostic::group::{line_groups, merge};
use crate::diagnostic::lists::MAX_LISTED;
use crate::diagnostic::location::{clamp, line_col};
use crate::diagnostic::view::View;
use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term;

/// Plain text (tests, `compile_error!`, pipes) or ANSI colour (terminals).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderStyle {
    /// No escape codes.
    Plain,
    /// ANSI colours.
    Color,
}

/// Most notes [`render`] prints per diagnostic; the rest are counted.
pub const MAX_NOTES: usize = 3 * MAX_LISTED;

/// Longest message, note, help or label text [`render`] prints, in
/// characters: a longer one (a name of 10⁵ characters quoted twice) is cut
/// with `… (N characters)`.
pub const MAX_TEXT_CHARS: usize = 1000;

/// `text`, cut to [`MAX_TEXT_CHARS`] characters.
fn cut_text(text: &str) -> String {
    match text.char_indices().nth(MAX_TEXT_CHARS) {
        None => text.to_string(),
        Some((at, _)) => format!("{}… ({} characters)", &text[..at], text.chars().count()),
    }
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
            cs::Label::new(style, (), clamp(source, l.span)).with_message(cut_text(&l.message))
        })
        .collect();
    let mut notes: Vec<String> = d
        .notes
        .iter()
        .take(MAX_NOTES)
        .map(|n| format!("note: {}", cut_text(n)))
        .collect();
    if d.notes.len() > MAX_NOTES {
        notes.push(format!(
            "note: … and {} more notes, not shown",
            d.notes.len() - MAX_NOTES
        ));
    }
    if let Some(help) = &d.help {
        notes.push(format!("help: {}", cut_text(help)));
    }
    cs::Diagnostic::new(severity)
        .with_code(d.code.clone())
        .with_message(cut_text(&d.message))
        .with_labels(labels)
        .with_notes(notes)
}

/// Most diagnostics [`render`] and [`render_short`] print; the rest are
/// counted in one closing line, so no input floods the terminal.
pub const MAX_RENDERED: usize = 50;

/// Renders diagnostics like a compiler: `error[code]: message`, then
/// `┌─ file:line:col`, the source line with a caret under the span, and the
/// notes and help. A diagnostic without labels renders without a snippet.
/// At most [`MAX_RENDERED`] are printed, then one line counts the others;
/// a source line longer than [`MAX_LINE_COLUMNS`](crate::MAX_LINE_COLUMNS) is cut to a window around
/// the labels, and control characters are shown escaped (`\u{0}`).
pub fn render(
    diagnostics: &[Diagnostic],
    file_name: &str,
    source: &str,
    style: RenderStyle,
) -> String {
    let file = SimpleFile::new(file_name, source);
    let config = term::Config::default();
    let mut out = String::new();
    let groups = line_groups(diagnostics, source);
    for group in groups.iter().take(MAX_RENDERED) {
        let merged;
        let d = match group.as_slice() {
            [one] => &diagnostics[*one],
            many => {
                merged = merge(diagnostics, many);
                &merged
            }
        };
        let cd = to_codespan(d, source);
        let mut buffer = match style {
            RenderStyle::Plain => term::termcolor::Buffer::no_color(),
            RenderStyle::Color => term::termcolor::Buffer::ansi(),
        };
        let emitted = match View::of(file_name, source, &cd) {
            Some(view) => {
                let cd = view.relabel(cd);
                term::emit(&mut buffer, &config, &view, &cd)
            }
            None => term::emit(&mut buffer, &config, &file, &cd),
        };
        if emitted.is_ok() {
            out.push_str(&String::from_utf8_lossy(buffer.as_slice()));
        } else {
            // The renderer refused (cannot happen for clamped spans); never lose the message.
            out.push_str(
                &format!("{:?}[{}]: {}\n", d.severity, d.code, cut_text(&d.message)).to_lowercase(),
            );
        }
    }
    let rest = groups.get(MAX_RENDERED..).unwrap_or_default();
    out.push_str(&omitted_line(
        rest.iter().flatten().map(|i| &diagnostics[*i]),
    ));
    out
}

/// `… and N more errors (M warnings) not shown`, or nothing.
fn omitted_line<'a>(rest: impl Iterator<Item = &'a Diagnostic>) -> String {
    let (mut errors, mut others) = (0usize, 0usize);
    for d in rest {
        if d.is_error() {
            errors += 1;
        } else {
            others += 1;
        }
    }
    if errors + others == 0 {
        return String::new();
    }
    let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    let what = match (errors, others) {
        (0, o) => plural(o, "warning or note"),
        (e, 0) => plural(e, "error"),
        (e, o) => format!(
            "{} and {}",
            plural(e, "error"),
            plural(o, "warning or note")
        ),
    };
    format!("… and {what} more, not shown (the first {MAX_RENDERED} are above)\n")
}

/// One line per diagnostic: `file:line:col: severity[code]: message`, for logs.
pub fn render_short(diagnostics: &[Diagnostic], file_name: &str, source: &str) -> String {
    let mut out = String::new();
    for d in diagnostics.iter().take(MAX_RENDERED) {
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
                    d.code,
                    cut_text(&d.message)
                ));
            }
            None => out.push_str(&format!(
                "{file_name}: {sev}[{}]: {}\n",
                d.code,
                cut_text(&d.message)
            )),
        }
    }
    out.push_str(&omitted_line(
        diagnostics.get(MAX_RENDERED..).unwrap_or_default().iter(),
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ast::Span;

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

    #[test]
    fn at_most_fifty_diagnostics_are_rendered() {
        // No flood: 4,097 errors from a 117-byte model must not fill 1.5 MB of stderr.
        // One error per line (errors on one line are merged, see below).
        let src = "x\n".repeat(5000);
        let src = src.as_str();
        let mut ds: Vec<Diagnostic> = (0..4097)
            .map(|i| {
                Diagnostic::error("e", format!("error {i}"))
                    .with_primary(Span::new(2 * i, 2 * i + 1), "")
            })
            .collect();
        ds.push(Diagnostic::warning("w", "a warning"));
        let text = render(&ds, "m.som", src, RenderStyle::Plain);
        assert_eq!(text.matches("error[e]").count(), MAX_RENDERED);
        assert!(
            text.ends_with(
                "… and 4047 errors and 1 warning or note more, not shown (the first 50 are above)\n"
            ),
            "{}",
            &text[text.len() - 200..]
        );
        let short = render_short(&ds, "m.som", src);
        assert_eq!(short.lines().count(), MAX_RENDERED + 1);
        assert!(render(&ds[..50], "m.som", src, RenderStyle::Plain).ends_with("\n\n"));
    }

    #[test]
    fn long_texts_and_many_notes_are_cut() {
        let name = "a".repeat(100_000);
        let mut d = Diagnostic::error("e", format!("`{name}` is declared twice"))
            .with_primary(Span::new(0, 1), name.clone());
        for i in 0..100 {
            d = d.with_note(format!("note {i}"));
        }
        let text = render(&[d], "m.som", "x\n", RenderStyle::Plain);
        assert!(text.len() < 6000, "{}", text.len());
        assert!(text.contains("… (100020 characters)"), "{text}");
        assert!(text.contains("… (100000 characters)"), "{text}");
        assert_eq!(text.matches("= note: note").count(), MAX_NOTES);
        assert!(
            text.contains("= note: … and 76 more notes, not shown"),
            "{text}"
        );
    }
}
