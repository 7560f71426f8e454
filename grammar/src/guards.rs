//! Input guards run before pest: a file too large, expressions nested too
//! deep, too many operands in one expression or too many signs in a row.
//!
//! The scans skip comments and string literals. Past these guards every
//! expression tree is shallow, so no input exhausts the stack — in pest, in
//! building the tree, in cloning or dropping it, or in any later pass.

use crate::ast::Span;
use crate::diagnostic::data::Diagnostic;
use crate::scan::{comment_end, scan_delimiters, string_end};
use crate::source::{MAX_SOURCE_BYTES, too_large};

/// Deepest nesting of parentheses and moduli accepted. Deeper input is
/// rejected before pest sees it, so no input can exhaust the stack.
pub const MAX_NESTING: usize = 64;

/// Most operands (names and numbers) in one expression, a chain of operands
/// joined by `+ - * /` (through parentheses and moduli). Checked before
/// parsing: every later pass may then recurse over an expression, whose tree
/// is at most this deep (plus [`MAX_NESTING`] and [`MAX_SIGNS`] levels).
pub const MAX_OPERANDS: usize = 1000;

/// Most unary signs in a row (`- -u` is two). Checked before parsing.
pub const MAX_SIGNS: usize = 8;

/// Why `source` is refused before parsing, if it is: larger than
/// [`MAX_SOURCE_BYTES`], nested too deep, or an expression too large.
pub(crate) fn refuse(source: &str) -> Option<Diagnostic> {
    if source.len() > MAX_SOURCE_BYTES {
        return Some(too_large(source.len() as u64));
    }
    nesting_guard(source).or_else(|| size_guard(source))
}

/// Rejects input nested deeper than [`MAX_NESTING`].
fn nesting_guard(source: &str) -> Option<Diagnostic> {
    let deepest = scan_delimiters(source, 0, source.len(), MAX_NESTING).err()?;
    Some(
        Diagnostic::error("nesting-too-deep", format!("expression nested more than {MAX_NESTING} levels deep"))
            .with_primary(Span::new(deepest, deepest + 1), "too deep here")
            .with_help("second-order modulus terms never need deep nesting; write the term as a product such as X*u*|v|"),
    )
}

/// A byte of a name or number (`u`, `X_uu`, `water.u`, `1.5e`).
fn is_word_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'.'
}

/// Where the name or number starting at `start` ends. `1e-3`: the
/// exponent's sign belongs to the number.
fn word_end(bytes: &[u8], start: usize) -> usize {
    let number = bytes[start].is_ascii_digit() || bytes[start] == b'.';
    let mut i = start;
    while i < bytes.len() && is_word_byte(bytes[i]) {
        if number
            && matches!(bytes[i], b'e' | b'E')
            && matches!(bytes.get(i + 1), Some(b'+' | b'-'))
        {
            i += 1;
        }
        i += 1;
    }
    i
}

/// What [`size_guard`] keeps while it scans: the chain of operands of the
/// current expression and the current run of unary signs.
#[derive(Default)]
struct Chain {
    /// Operands in the current chain.
    operands: usize,
    /// Where the current chain starts.
    chain_start: usize,
    /// After an operand (name, number, `)` or closing `|`): an operator may follow.
    after_operand: bool,
    /// Moduli open in the current expression.
    modulus_depth: usize,
    /// Unary signs in the current run.
    signs: usize,
    /// Where the current run of signs starts.
    signs_start: usize,
}

impl Chain {
    /// Counts the operand `start..end`; an operand directly after an operand
    /// starts a new chain. Fails past [`MAX_OPERANDS`].
    fn operand(&mut self, start: usize, end: usize) -> Option<Diagnostic> {
        if self.after_operand {
            self.operands = 0;
        }
        if self.operands == 0 {
            self.chain_start = start;
        }
        self.operands += 1;
        if self.operands > MAX_OPERANDS {
            return Some(
                Diagnostic::error("expression-too-large", format!("this expression has more than {MAX_OPERANDS} operands"))
                    .with_primary(Span::new(self.chain_start, end), "too many operands")
                    .with_help("write the terms out; a second-order model has a handful per equation, and a number may be written once (e.g. 2.5e-3)"),
            );
        }
        self.after_operand = true;
        self.signs = 0;
        None
    }

    /// Counts the unary sign at `i`. Fails past [`MAX_SIGNS`] in a row.
    fn sign(&mut self, i: usize) -> Option<Diagnostic> {
        if self.signs == 0 {
            self.signs_start = i;
        }
        self.signs += 1;
        if self.signs > MAX_SIGNS {
            return Some(
                Diagnostic::error(
                    "expression-too-large",
                    format!("more than {MAX_SIGNS} signs in a row"),
                )
                .with_primary(Span::new(self.signs_start, i + 1), "too many signs")
                .with_help("write one sign: `- -u` is `u`, `- - -u` is `-u`"),
            );
        }
        None
    }

    /// `=`, `,`, `;`, braces, brackets, `:` and anything else end an expression.
    fn end_expression(&mut self) {
        self.operands = 0;
        self.after_operand = false;
        self.modulus_depth = 0;
        self.signs = 0;
    }
}

/// Rejects an expression of more than [`MAX_OPERANDS`] operands or a run of
/// more than [`MAX_SIGNS`] unary signs, before pest (or any recursion over
/// the tree) sees it. Skips comments and strings like [`scan_delimiters`].
/// An operand directly after an operand (no operator between) starts a new
/// expression, as do `=`, `,`, `;`, braces and brackets.
fn size_guard(source: &str) -> Option<Diagnostic> {
    let bytes = source.as_bytes();
    let mut chain = Chain::default();
    let mut i = 0;
    while i < bytes.len() {
        if let Some(end) = comment_end(bytes, i, bytes.len()) {
            i = end;
            continue;
        }
        match bytes[i] {
            b'"' => {
                i = string_end(bytes, i, bytes.len());
                chain.operands = 0;
                chain.after_operand = false;
            }
            b if is_word_byte(b) => {
                let start = i;
                i = word_end(bytes, start);
                if let Some(d) = chain.operand(start, i) {
                    return Some(d);
                }
                continue;
            }
            b'(' => chain.after_operand = false,
            b')' => chain.after_operand = true,
            b'|' if chain.after_operand && chain.modulus_depth > 0 => chain.modulus_depth -= 1,
            b'|' => {
                chain.modulus_depth += 1;
                chain.after_operand = false;
            }
            b'+' | b'-' if !chain.after_operand => {
                if let Some(d) = chain.sign(i) {
                    return Some(d);
                }
            }
            b'+' | b'-' | b'*' | b'/' => {
                chain.after_operand = false;
                chain.signs = 0;
            }
            b' ' | b'\t' | b'\r' | b'\n' => {}
            _ => chain.end_expression(),
        }
        i += 1;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::parse;
    use crate::parse::testing::{at, error};

    #[test]
    fn nesting_guard_counts_expressions_only() {
        let deep = format!(
            "model M {{ state u der u = X*{}u{} }}",
            "(".repeat(65),
            ")".repeat(65)
        );
        let d = error(&deep);
        assert_eq!(d.code, "nesting-too-deep");
        assert_eq!(at(&deep, &d), "(");
        let ok = format!(
            "model M {{ state u der u = X*{}u{} }}",
            "(".repeat(64),
            ")".repeat(64)
        );
        assert!(parse(&ok).1.is_empty());
        // Parentheses and bars in comments and strings do not count.
        let quiet = format!(
            "// {}\n/* {} */ model M {{ state u der u = X*u data {{ u = \"{}\" }} }}",
            "(".repeat(100),
            "|".repeat(100),
            "(".repeat(100)
        );
        assert!(parse(&quiet).1.is_empty(), "{:?}", parse(&quiet).1);
    }

    /// Runs `f` on a thread with a small stack, so that recursion proportional
    /// to the input aborts the test instead of passing on a large main stack.
    fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
        let handle = std::thread::Builder::new()
            .stack_size(256 * 1024)
            .spawn(f)
            .unwrap_or_else(|e| panic!("cannot spawn: {e}"));
        handle
            .join()
            .unwrap_or_else(|_| panic!("the parser panicked"))
    }

    #[test]
    fn long_chains_and_sign_runs_are_rejected_before_parsing() {
        // Far past the limits: 7,200 `*1`, `+1`, `/1` after `X*u`, and 7,200 unary `-`.
        for op in ["*1", "+1", "/1", "+X*u"] {
            let src = format!("model M {{ state u der u = X*u{} }}", op.repeat(7200));
            let (model, d) = on_small_stack(move || {
                let (m, d) = parse(&src);
                (m.is_some(), d)
            });
            assert!(!model);
            assert_eq!(d.len(), 1, "{op}");
            assert_eq!(d[0].code, "expression-too-large");
            assert_eq!(d[0].message, "this expression has more than 1000 operands");
        }
        let src = format!("model M {{ state u der u = X*{}u }}", "-".repeat(7200));
        let d = error(&src);
        assert_eq!(d.code, "expression-too-large");
        assert_eq!(d.message, "more than 8 signs in a row");
        assert_eq!(at(&src, &d), "-".repeat(9));
        // At the limits, the model parses (on a small stack: the tree is bounded).
        let ok = format!(
            "model M {{ state u der u = X*u{} + {}u }}",
            "*1".repeat(MAX_OPERANDS - 3),
            "- ".repeat(MAX_SIGNS)
        );
        let diags = on_small_stack(move || parse(&ok).1);
        assert!(diags.is_empty(), "{diags:?}");
        // Exponent signs are part of the number; declarations start new expressions.
        let many = format!(
            "model M {{ state u {} nominal {{ {} }} }}",
            "der u = 1e-3*X*u ".repeat(1200),
            (0..1200)
                .map(|i| format!("P{i} = -1e-3,"))
                .collect::<String>()
        );
        assert!(
            parse(&many)
                .1
                .iter()
                .all(|d| d.code != "expression-too-large")
        );
    }

    #[test]
    fn oversized_input_is_rejected_up_front() {
        let big = " ".repeat(MAX_SOURCE_BYTES + 1);
        let d = error(&big);
        assert_eq!(d.code, "file-too-large");
        assert_eq!(d.primary_span(), Some(Span::new(0, 0)));
    }
}
