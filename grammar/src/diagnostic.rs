//! Diagnostics as plain data, and their one renderer.
//!
//! Every pass reports [`Diagnostic`]s; nothing is printed inside the library.
//! [`render`] turns them into rustc-like text (`file:line:col`, the source
//! line, a caret under the span, the help), plain for tests and macros,
//! coloured for terminals.

use crate::ast::Span;
use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::{Error as FilesError, Files, SimpleFile};
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

/// Most items a list inside a message, note or help names: the rest are
/// counted (`… (491 more)`), so no message grows with the model. Structured
/// output (JSON fields) keeps full lists.
pub const MAX_LISTED: usize = 8;

/// At most [`MAX_LISTED`] items joined by `sep`, then `sep… (N more)`:
/// `x0, x1, …, x7, … (9992 more)`.
pub fn join_capped<I>(items: I, sep: &str) -> String
where
    I: IntoIterator,
    I::Item: std::fmt::Display,
{
    let mut out = String::new();
    let mut rest = 0usize;
    for (i, item) in items.into_iter().enumerate() {
        if i < MAX_LISTED {
            if i > 0 {
                out.push_str(sep);
            }
            out.push_str(&item.to_string());
        } else {
            rest += 1;
        }
    }
    if rest > 0 {
        out.push_str(&format!("{sep}… ({rest} more)"));
    }
    out
}

/// `a`, `a and b`, `a, b and c`; beyond [`MAX_LISTED`] items
/// `a, b, …, h and 491 more`.
pub fn and_list<I>(items: I) -> String
where
    I: IntoIterator,
    I::Item: std::fmt::Display,
{
    let mut shown: Vec<String> = Vec::new();
    let mut rest = 0usize;
    for item in items {
        if shown.len() < MAX_LISTED + 1 {
            shown.push(item.to_string());
        } else {
            rest += 1;
        }
    }
    if rest > 0 {
        // Nine kept: the ninth is counted with the rest.
        shown.truncate(MAX_LISTED);
        return format!("{} and {} more", shown.join(", "), rest + 1);
    }
    match shown.len() {
        0 => String::new(),
        1 => shown.remove(0),
        n => format!("{} and {}", shown[..n - 1].join(", "), shown[n - 1]),
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

/// Widest source line printed, in characters: a longer line is cut to a
/// window around the labels, marked `…` at the cut ends.
pub const MAX_LINE_COLUMNS: usize = 120;

/// Renders diagnostics like a compiler: `error[code]: message`, then
/// `┌─ file:line:col`, the source line with a caret under the span, and the
/// notes and help. A diagnostic without labels renders without a snippet.
/// At most [`MAX_RENDERED`] are printed, then one line counts the others;
/// a source line longer than [`MAX_LINE_COLUMNS`] is cut to a window around
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

/// The diagnostics as [`render`] shows them: those of one code and severity
/// whose primary labels lie on one source line form one group (in the order
/// of their first member), so a line is printed once however many errors
/// point at it (`state u` 4,000 times on one line printed the line 4,000
/// times). Each group is a list of indices into `diagnostics`.
fn line_groups(diagnostics: &[Diagnostic], source: &str) -> Vec<Vec<usize>> {
    let line_starts: Vec<usize> = std::iter::once(0)
        .chain(source.match_indices('\n').map(|(i, _)| i + 1))
        .collect();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut by_key: std::collections::BTreeMap<(&str, Severity, usize), usize> =
        std::collections::BTreeMap::new();
    for (i, d) in diagnostics.iter().enumerate() {
        let Some(span) = d.primary_span() else {
            groups.push(vec![i]);
            continue;
        };
        let line = line_starts
            .partition_point(|s| *s <= span.start.min(source.len()))
            .saturating_sub(1);
        match by_key.entry((d.code.as_str(), d.severity, line)) {
            std::collections::btree_map::Entry::Occupied(e) => groups[*e.get()].push(i),
            std::collections::btree_map::Entry::Vacant(e) => {
                e.insert(groups.len());
                groups.push(vec![i]);
            }
        }
    }
    groups
}

/// One diagnostic for a group of [`line_groups`]: the first member's
/// message (with the count), notes and help; the primary label of at most
/// [`MAX_LISTED`] members (each saying its own message when the messages
/// differ) and their other labels once each; a note counting the rest.
fn merge(diagnostics: &[Diagnostic], members: &[usize]) -> Diagnostic {
    let first = &diagnostics[members[0]];
    let same_message = members
        .iter()
        .all(|i| diagnostics[*i].message == first.message);
    let mut d = first.clone();
    d.message = if same_message {
        format!("{} ({} times on this line)", first.message, members.len())
    } else {
        format!(
            "{} (and {} more on this line)",
            first.message,
            members.len() - 1
        )
    };
    d.labels = Vec::new();
    for (k, i) in members.iter().take(MAX_LISTED).enumerate() {
        let m = &diagnostics[*i];
        for l in &m.labels {
            let mut l = l.clone();
            if l.primary && !same_message {
                l.message = m.message.clone();
            } else if l.primary && k > 0 {
                // Said once, at the first caret.
                l.message = String::new();
            }
            if !d
                .labels
                .iter()
                .any(|x| x.span == l.span && x.primary == l.primary)
            {
                d.labels.push(l);
            }
        }
    }
    // Notes and helps of the marked members, each distinct one once.
    let mut helps: Vec<&str> = Vec::new();
    for i in members.iter().take(MAX_LISTED) {
        let m = &diagnostics[*i];
        for n in &m.notes {
            if !d.notes.contains(n) {
                d.notes.push(n.clone());
            }
        }
        if let Some(h) = &m.help
            && !helps.contains(&h.as_str())
        {
            helps.push(h);
        }
    }
    if !helps.is_empty() {
        d.help = Some(helps.join("; "));
    }
    if members.len() > MAX_LISTED {
        d.notes.push(format!(
            "… and {} more on this line, not marked",
            members.len() - MAX_LISTED
        ));
    }
    d
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

/// Whether a character is drawn escaped in a source line.
fn escaped(c: char) -> bool {
    c.is_control() && c != '\t' && c != '\n' && c != '\r'
}

/// A piece of the displayed text: display bytes from `disp` map to source
/// bytes from `orig`, one to one when `verbatim`, else all to `orig`.
#[derive(Clone, Copy, Debug)]
struct Piece {
    disp: usize,
    orig: usize,
    verbatim: bool,
}

/// The source as one diagnostic shows it: the lines its labels touch cut to
/// a window of [`MAX_LINE_COLUMNS`] around the labels, control characters
/// escaped; line numbers and columns still those of the real source.
struct View<'a> {
    name: &'a str,
    source: &'a str,
    text: String,
    line_starts: Vec<usize>,
    pieces: Vec<Piece>,
}

impl<'a> View<'a> {
    /// The view for a diagnostic, or `None` when its lines need no change.
    fn of(name: &'a str, source: &'a str, d: &cs::Diagnostic<()>) -> Option<View<'a>> {
        let ranges: Vec<std::ops::Range<usize>> =
            d.labels.iter().map(|l| l.range.clone()).collect();
        let first = ranges.iter().map(|r| r.start).min()?;
        let last = ranges.iter().map(|r| r.end).max()?;
        // The lines from the first label to the line after the last one.
        let from = source[..first].rfind('\n').map_or(0, |i| i + 1);
        let mut to = source[last..].find('\n').map_or(source.len(), |i| last + i);
        if to < source.len() {
            to = source[to + 1..]
                .find('\n')
                .map_or(source.len(), |i| to + 1 + i);
        }
        let needs =
            |line: &str| line.chars().nth(MAX_LINE_COLUMNS).is_some() || line.chars().any(escaped);
        if !source[from..to].split('\n').any(needs) {
            return None;
        }
        let mut text = String::with_capacity(from + 2 * (to - from).min(4096));
        text.push_str(&source[..from]);
        let mut pieces = vec![Piece {
            disp: 0,
            orig: 0,
            verbatim: true,
        }];
        let mut at = from;
        for line in source[from..to].split('\n') {
            if needs(line) {
                let on_line: Vec<&std::ops::Range<usize>> = ranges
                    .iter()
                    .filter(|r| r.end >= at && r.start <= at + line.len())
                    .collect();
                let chars: Vec<(usize, char)> = line.char_indices().collect();
                let char_at = |b: usize| chars.partition_point(|(i, _)| at + *i < b);
                let lo = on_line
                    .iter()
                    .map(|r| char_at(r.start.max(at)))
                    .min()
                    .unwrap_or(0);
                let hi = on_line
                    .iter()
                    .map(|r| char_at(r.end.min(at + line.len())))
                    .max()
                    .unwrap_or(0);
                let (start, end) = if chars.len() <= MAX_LINE_COLUMNS {
                    (0, chars.len())
                } else {
                    let margin = MAX_LINE_COLUMNS.saturating_sub(hi - lo) / 2;
                    let start = lo.saturating_sub(margin.max(MAX_LINE_COLUMNS / 4)).min(lo);
                    let start = start.min(chars.len().saturating_sub(MAX_LINE_COLUMNS));
                    (start, (start + MAX_LINE_COLUMNS).min(chars.len()))
                };
                if start > 0 {
                    pieces.push(Piece {
                        disp: text.len(),
                        orig: at,
                        verbatim: false,
                    });
                    text.push('…');
                }
                for &(i, c) in &chars[start..end] {
                    let verbatim = !escaped(c);
                    if pieces.last().is_none_or(|p| !(p.verbatim && verbatim)) {
                        pieces.push(Piece {
                            disp: text.len(),
                            orig: at + i,
                            verbatim,
                        });
                    }
                    if verbatim {
                        text.push(c);
                    } else {
                        text.push_str(&format!("\\u{{{:x}}}", u32::from(c)));
                    }
                }
                if end < chars.len() {
                    let cut = chars.get(end).map_or(at + line.len(), |(i, _)| at + i);
                    pieces.push(Piece {
                        disp: text.len(),
                        orig: cut,
                        verbatim: false,
                    });
                    text.push('…');
                }
                pieces.push(Piece {
                    disp: text.len(),
                    orig: at + line.len(),
                    verbatim: true,
                });
            } else {
                text.push_str(line);
            }
            at += line.len();
            if at < to {
                text.push('\n');
                at += 1;
            }
        }
        text.push_str(&source[to..]);
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Some(View {
            name,
            source,
            text,
            line_starts,
            pieces,
        })
    }

    /// The display offset of a source offset (a start: the beginning of an
    /// escape or cut; an end: past it).
    fn to_display(&self, orig: usize, is_end: bool) -> usize {
        let i = self
            .pieces
            .partition_point(|p| p.orig <= orig)
            .saturating_sub(1);
        let p = self.pieces[i];
        if p.verbatim {
            return p.disp + (orig - p.orig);
        }
        match self.pieces.get(i + 1) {
            Some(next) if is_end && orig > p.orig => next.disp,
            _ => p.disp,
        }
    }

    /// The source offset of a display offset.
    fn to_source(&self, disp: usize) -> usize {
        let i = self
            .pieces
            .partition_point(|p| p.disp <= disp)
            .saturating_sub(1);
        let p = self.pieces[i];
        if p.verbatim {
            p.orig + (disp - p.disp)
        } else {
            p.orig
        }
    }

    fn relabel(&self, mut d: cs::Diagnostic<()>) -> cs::Diagnostic<()> {
        for l in &mut d.labels {
            let start = self.to_display(l.range.start, false);
            let end = self.to_display(l.range.end, true).max(start);
            l.range = start..end;
        }
        d
    }
}

impl<'a> Files<'a> for View<'a> {
    type FileId = ();
    type Name = &'a str;
    type Source = &'a str;

    fn name(&'a self, (): ()) -> Result<&'a str, FilesError> {
        Ok(self.name)
    }
    fn source(&'a self, (): ()) -> Result<&'a str, FilesError> {
        Ok(&self.text)
    }
    fn line_index(&'a self, (): (), byte_index: usize) -> Result<usize, FilesError> {
        Ok(self
            .line_starts
            .partition_point(|s| *s <= byte_index)
            .saturating_sub(1))
    }
    fn line_range(
        &'a self,
        (): (),
        line_index: usize,
    ) -> Result<std::ops::Range<usize>, FilesError> {
        let start = *self
            .line_starts
            .get(line_index)
            .ok_or(FilesError::LineTooLarge {
                given: line_index,
                max: self.line_starts.len().saturating_sub(1),
            })?;
        let end = self
            .line_starts
            .get(line_index + 1)
            .copied()
            .unwrap_or(self.text.len());
        Ok(start..end)
    }
    fn column_number(
        &'a self,
        (): (),
        _line: usize,
        byte_index: usize,
    ) -> Result<usize, FilesError> {
        Ok(line_col(self.source, self.to_source(byte_index)).1)
    }
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

    #[test]
    fn at_most_fifty_diagnostics_are_rendered() {
        // Issue 10: 4,097 errors from a 117-byte model filled 1.5 MB of stderr.
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
    fn a_line_is_printed_once_however_many_errors_point_at_it() {
        // Issue 10: `state u` 4,000 times on one line gave 257 MB of stderr,
        // then 50 copies of the line; now one diagnostic marks the first 8.
        let src = format!("model M {{ {}}}\n", "state u ".repeat(4000));
        let first = Span::new(16, 17);
        let ds: Vec<Diagnostic> = (1..4000)
            .map(|k| {
                let at = 10 + 8 * k + 6;
                Diagnostic::error("duplicate-declaration", "`u` is declared twice")
                    .with_primary(Span::new(at, at + 1), "second declaration of a state")
                    .with_secondary(first, "first declared here")
                    .with_help("keep one")
            })
            .collect();
        let text = render(&ds, "m.som", &src, RenderStyle::Plain);
        assert!(text.len() < 3000, "{} bytes:\n{text}", text.len());
        assert_eq!(text.matches("\n1 │").count(), 1, "{text}");
        assert!(text.starts_with(
            "error[duplicate-declaration]: `u` is declared twice (3999 times on this line)\n  ┌─ m.som:1:25\n"
        ), "{text}");
        assert_eq!(text.matches('^').count(), MAX_LISTED, "{text}");
        assert!(
            text.contains("= note: … and 3991 more on this line, not marked"),
            "{text}"
        );
        assert!(!text.contains("not shown"), "{text}");
        // Different messages on one line: each caret says its own.
        let src = "model M { state u state v state u state v }\n";
        let ds = vec![
            Diagnostic::error("duplicate-declaration", "`u` is declared twice")
                .with_primary(Span::new(32, 33), "again"),
            Diagnostic::error("duplicate-declaration", "`v` is declared twice")
                .with_primary(Span::new(40, 41), "again"),
        ];
        let text = render(&ds, "m.som", src, RenderStyle::Plain);
        assert!(
            text.starts_with(
                "error[duplicate-declaration]: `u` is declared twice (and 1 more on this line)"
            ),
            "{text}"
        );
        assert!(text.contains("`v` is declared twice"), "{text}");
        assert_eq!(text.matches("\n1 │").count(), 1, "{text}");
        // Other lines and other codes stay apart.
        let src = "a\nb\n";
        let ds = vec![
            Diagnostic::error("x", "one").with_primary(Span::new(0, 1), ""),
            Diagnostic::error("x", "two").with_primary(Span::new(2, 3), ""),
            Diagnostic::error("y", "three").with_primary(Span::new(0, 1), ""),
        ];
        let text = render(&ds, "m.som", src, RenderStyle::Plain);
        assert_eq!(text.matches("error[").count(), 3, "{text}");
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

    #[test]
    fn lists_are_capped() {
        assert_eq!(join_capped(["a", "b"], ", "), "a, b");
        assert_eq!(
            join_capped((0..10).map(|i| format!("x{i}")), ", "),
            "x0, x1, x2, x3, x4, x5, x6, x7, … (2 more)"
        );
        assert_eq!(and_list(["a"]), "a");
        assert_eq!(and_list(["a", "b", "c"]), "a, b and c");
        assert_eq!(
            and_list((0..9).map(|i| i.to_string())),
            "0, 1, 2, 3, 4, 5, 6, 7 and 8"
        );
        assert_eq!(
            and_list((0..10).map(|i| i.to_string())),
            "0, 1, 2, 3, 4, 5, 6, 7 and 2 more"
        );
        assert_eq!(and_list(Vec::<String>::new()), "");
    }

    #[test]
    fn long_lines_are_cut_to_a_window_around_the_caret() {
        // Issue 10: `state u` 4,000 times on one line reprinted the 28 KB line per error.
        let src = format!("model M {{ {}}}\n", "state u ".repeat(4000));
        let at = 10 + 8 * 3000 + 6;
        let d = Diagnostic::error("duplicate-declaration", "`u` is declared twice")
            .with_primary(Span::new(at, at + 1), "again")
            .with_help("keep one");
        let text = render(std::slice::from_ref(&d), "m.som", &src, RenderStyle::Plain);
        assert!(text.len() < 600, "{}", text.len());
        let expected_col = at + 1;
        assert!(text.contains(&format!("m.som:1:{expected_col}")), "{text}");
        let lines: Vec<&str> = text.lines().collect();
        let code = lines
            .iter()
            .find(|l| l.starts_with("1 │"))
            .copied()
            .unwrap_or_default();
        let caret = lines
            .iter()
            .find(|l| l.contains('^'))
            .copied()
            .unwrap_or_default();
        assert!(code.starts_with("1 │ …") && code.ends_with('…'), "{code}");
        assert_eq!(
            code.chars().count(),
            "1 │ ".chars().count() + MAX_LINE_COLUMNS + 2
        );
        // The caret stands under the `u` it names.
        let col = caret.chars().position(|c| c == '^').unwrap_or(0);
        assert_eq!(code.chars().nth(col), Some('u'), "{code}\n{caret}");
        // Short lines are unchanged (every snapshot stays as it was).
        let short = "model M {\n    der u = X*u*v*r\n}\n";
        let d = Diagnostic::error("o", "m").with_primary(Span::new(22, 29), "");
        assert!(
            render(&[d], "m.som", short, RenderStyle::Plain).contains("2 │     der u = X*u*v*r\n")
        );
    }

    #[test]
    fn control_characters_are_escaped_with_the_caret_on_them() {
        let src = "model M {\n    state u\u{0}v\n}\n";
        let at = src.find('\u{0}').unwrap_or(0);
        let d = Diagnostic::error("syntax", "unexpected `\\u{0}`")
            .with_primary(Span::new(at, at + 1), "here");
        let text = render(&[d], "m.som", src, RenderStyle::Plain);
        assert!(!text.contains('\u{0}'), "{text:?}");
        assert!(text.contains("m.som:2:12"), "{text}");
        assert!(text.contains("2 │     state u\\u{0}v\n"), "{text}");
        assert!(text.contains("  │            ^^^^^ here\n"), "{text}");
    }
}
