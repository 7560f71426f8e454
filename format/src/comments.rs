//! The comments of a source, which the syntax tree does not keep.

use leeway_grammar::Span;

/// A comment as written (`// ...` without its newline, or `/* ... */`).
#[derive(Clone, Debug)]
pub(crate) struct Comment {
    /// Where it is.
    pub span: Span,
    /// Its text, trailing blanks of a line comment removed.
    pub text: String,
}

/// Every comment of `source`, in order, skipping string literals (a data
/// column may be named `"a//b"`).
pub(crate) fn scan(source: &str) -> Vec<Comment> {
    let bytes = source.as_bytes();
    let mut found = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match (bytes[i], bytes.get(i + 1)) {
            (b'"', _) => {
                // A string ends at its quote or at the end of its line.
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                    i += 1;
                }
                i += 1;
            }
            (b'/', Some(b'/')) => {
                let end = source[i..].find('\n').map_or(bytes.len(), |n| i + n);
                found.push(Comment {
                    span: Span::new(i, end),
                    text: source[i..end].trim_end().to_string(),
                });
                i = end;
            }
            (b'/', Some(b'*')) => {
                let end = source[i + 2..]
                    .find("*/")
                    .map_or(bytes.len(), |n| i + 2 + n + 2);
                found.push(Comment {
                    span: Span::new(i, end),
                    text: source[i..end].to_string(),
                });
                i = end;
            }
            _ => i += 1,
        }
    }
    found
}

/// Where the first `{` at or after `from` is, outside comments.
pub(crate) fn brace_after(source: &str, from: usize) -> Option<usize> {
    let bytes = source.as_bytes();
    let mut i = from;
    while i < bytes.len() {
        match (bytes[i], bytes.get(i + 1)) {
            (b'{', _) => return Some(i),
            (b'/', Some(b'/')) => i = source[i..].find('\n').map_or(bytes.len(), |n| i + n),
            (b'/', Some(b'*')) => {
                i = source[i + 2..]
                    .find("*/")
                    .map_or(bytes.len(), |n| i + 2 + n + 2)
            }
            _ => i += 1,
        }
    }
    None
}
