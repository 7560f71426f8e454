//! Byte offsets ↔ the protocol's positions (line, UTF-16 code unit), and
//! the edits of `didChange`. Positions past a line's end or inside a
//! character are clamped, never trusted.

use leeway_grammar::Span;
use lsp_types::{Position, Range};

/// The protocol position of byte `offset` in `text`.
pub fn position(text: &str, offset: usize) -> Position {
    let mut offset = offset.min(text.len());
    while offset > 0 && !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count();
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    let character: usize = text[start..offset].chars().map(char::len_utf16).sum();
    Position::new(to_u32(line), to_u32(character))
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// The range of a byte span.
pub fn range(text: &str, span: Span) -> Range {
    Range::new(position(text, span.start), position(text, span.end))
}

/// The byte offset of a protocol position: the end of the line when the
/// column is past it, the end of the text when the line is; a column inside
/// a surrogate pair lands before its character.
pub fn offset(text: &str, at: Position) -> usize {
    let mut start = 0;
    for _ in 0..at.line {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => return text.len(),
        }
    }
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let mut units = 0usize;
    for (i, c) in text[start..line_end].char_indices() {
        units += c.len_utf16();
        if units > at.character as usize {
            return start + i;
        }
    }
    line_end
}

/// Applies one content change of `didChange`: a range replaced, or the
/// whole text when no range is given.
pub fn apply(text: &mut String, range: Option<Range>, new_text: &str) {
    match range {
        Some(r) => {
            let a = offset(text, r.start);
            let b = offset(text, r.end).max(a);
            text.replace_range(a..b, new_text);
        }
        None => *text = new_text.to_string(),
    }
}
