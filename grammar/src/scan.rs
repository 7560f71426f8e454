//! Byte scans of the source before pest sees it: comments and string
//! literals skipped, the `(` and `|` that open expressions tracked.

/// Where the comment starting at `i` ends, or `None` when no comment starts
/// there: a line comment at its newline, a block comment past its `*/`.
/// Scans no further than `to`.
pub(crate) fn comment_end(bytes: &[u8], i: usize, to: usize) -> Option<usize> {
    let next = bytes.get(i + 1).copied();
    match bytes[i] {
        b'/' if next == Some(b'/') => {
            let mut i = i;
            while i < to && bytes[i] != b'\n' {
                i += 1;
            }
            Some(i)
        }
        b'/' if next == Some(b'*') => {
            let mut i = i + 2;
            while i < to && !(bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/')) {
                i += 1;
            }
            Some(i + 2)
        }
        _ => None,
    }
}

/// Where the string literal whose `"` is at `i` ends: its closing `"`, the
/// end of its line, or `to`.
pub(crate) fn string_end(bytes: &[u8], i: usize, to: usize) -> usize {
    let mut i = i + 1;
    while i < to && bytes[i] != b'"' && bytes[i] != b'\n' {
        i += 1;
    }
    i
}

/// Scans `source[from..to]` for the delimiters of expressions, skipping
/// comments and string literals, and returns the byte offsets of the `(` and
/// `|` still open at `to`, innermost last. A `|` opens a modulus where an
/// operand is expected (after an operator, `(`, `|`, `=`, `,`), else closes one.
/// Fails with the offset of the first delimiter nested deeper than `limit`.
pub(crate) fn scan_delimiters(
    source: &str,
    from: usize,
    to: usize,
    limit: usize,
) -> Result<Vec<usize>, usize> {
    let bytes = source.as_bytes();
    let to = to.min(bytes.len());
    let mut open: Vec<usize> = Vec::new();
    let mut operand_expected = true;
    let mut i = from;
    while i < to {
        if let Some(end) = comment_end(bytes, i, to) {
            i = end;
            continue;
        }
        match bytes[i] {
            b'"' => {
                i = string_end(bytes, i, to);
                operand_expected = false;
            }
            b'(' => {
                open.push(i);
                operand_expected = true;
            }
            b')' => {
                open.pop();
                operand_expected = false;
            }
            b'|' if operand_expected => open.push(i),
            b'|' => {
                open.pop();
            }
            b'+' | b'-' | b'*' | b'/' | b'=' | b',' | b'{' | b'[' => operand_expected = true,
            b' ' | b'\t' | b'\r' | b'\n' => {}
            _ => operand_expected = false,
        }
        if open.len() > limit {
            return Err(i);
        }
        i += 1;
    }
    Ok(open)
}

/// The innermost `(` or `|` left open by the expression that ends at `pos`
/// (the text after the last `=` before it), if any.
pub(crate) fn unclosed_delimiter(source: &str, pos: usize) -> Option<usize> {
    let pos = pos.min(source.len());
    let start = source.get(..pos)?.rfind('=').map_or(0, |i| i + 1);
    scan_delimiters(source, start, pos, usize::MAX)
        .ok()?
        .last()
        .copied()
}
