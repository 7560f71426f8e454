//! The source lines a diagnostic shows, cut to a window around its labels
//! and with control characters escaped, as a codespan [`Files`].

use crate::diagnostic::location::line_col;
use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::{Error as FilesError, Files};

/// Widest source line printed, in characters: a longer line is cut to a
/// window around the labels, marked `…` at the cut ends.
pub const MAX_LINE_COLUMNS: usize = 120;

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
pub(crate) struct View<'a> {
    name: &'a str,
    source: &'a str,
    text: String,
    line_starts: Vec<usize>,
    pieces: Vec<Piece>,
}

/// The lines a diagnostic shows, as the bytes `from..to` of `source`: from
/// the line of its first label to the line after the one of its last.
fn shown_lines(source: &str, first: usize, last: usize) -> (usize, usize) {
    let from = source[..first].rfind('\n').map_or(0, |i| i + 1);
    let mut to = source[last..].find('\n').map_or(source.len(), |i| last + i);
    if to < source.len() {
        to = source[to + 1..]
            .find('\n')
            .map_or(source.len(), |i| to + 1 + i);
    }
    (from, to)
}

/// Whether a line is drawn changed: wider than [`MAX_LINE_COLUMNS`], or
/// holding a character drawn escaped.
fn needs_change(line: &str) -> bool {
    line.chars().nth(MAX_LINE_COLUMNS).is_some() || line.chars().any(escaped)
}

/// The first and the last character (`lo`, `hi`) of a line under the
/// labels `ranges`; the line starts at byte `at` and is `len` bytes long.
fn label_columns(
    chars: &[(usize, char)],
    at: usize,
    len: usize,
    ranges: &[std::ops::Range<usize>],
) -> (usize, usize) {
    let on_line: Vec<&std::ops::Range<usize>> = ranges
        .iter()
        .filter(|r| r.end >= at && r.start <= at + len)
        .collect();
    let char_at = |b: usize| chars.partition_point(|(i, _)| at + *i < b);
    let lo = on_line
        .iter()
        .map(|r| char_at(r.start.max(at)))
        .min()
        .unwrap_or(0);
    let hi = on_line
        .iter()
        .map(|r| char_at(r.end.min(at + len)))
        .max()
        .unwrap_or(0);
    (lo, hi)
}

/// The characters `start..end` drawn of a line of `count` characters: all
/// of them up to [`MAX_LINE_COLUMNS`], else a window around `lo..hi`.
fn window(count: usize, lo: usize, hi: usize) -> (usize, usize) {
    if count <= MAX_LINE_COLUMNS {
        (0, count)
    } else {
        let margin = MAX_LINE_COLUMNS.saturating_sub(hi - lo) / 2;
        let start = lo.saturating_sub(margin.max(MAX_LINE_COLUMNS / 4)).min(lo);
        let start = start.min(count.saturating_sub(MAX_LINE_COLUMNS));
        (start, (start + MAX_LINE_COLUMNS).min(count))
    }
}

/// Draws a changed `line` (starting at source byte `at`) onto `text`: cut to
/// its window with `…` at the cut ends, control characters escaped, and the
/// pieces that map the drawn bytes back to the source.
fn draw_line(
    text: &mut String,
    pieces: &mut Vec<Piece>,
    line: &str,
    at: usize,
    ranges: &[std::ops::Range<usize>],
) {
    let chars: Vec<(usize, char)> = line.char_indices().collect();
    let (lo, hi) = label_columns(&chars, at, line.len(), ranges);
    let (start, end) = window(chars.len(), lo, hi);
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
}

impl<'a> View<'a> {
    /// The view for a diagnostic, or `None` when its lines need no change.
    pub(crate) fn of(name: &'a str, source: &'a str, d: &cs::Diagnostic<()>) -> Option<View<'a>> {
        let ranges: Vec<std::ops::Range<usize>> =
            d.labels.iter().map(|l| l.range.clone()).collect();
        let first = ranges.iter().map(|r| r.start).min()?;
        let last = ranges.iter().map(|r| r.end).max()?;
        let (from, to) = shown_lines(source, first, last);
        if !source[from..to].split('\n').any(needs_change) {
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
            if needs_change(line) {
                draw_line(&mut text, &mut pieces, line, at, &ranges);
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

    pub(crate) fn relabel(&self, mut d: cs::Diagnostic<()>) -> cs::Diagnostic<()> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ast::Span;
    use crate::diagnostic::data::Diagnostic;
    use crate::diagnostic::render::{RenderStyle, render};

    #[test]
    fn long_lines_are_cut_to_a_window_around_the_caret() {
        // A 28 KB line (`state u` 4,000 times) is not reprinted whole for an error on it.
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
