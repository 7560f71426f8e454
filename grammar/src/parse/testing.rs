//! Helpers of the parser's unit tests: the one error a source gives, and the
//! text its primary label covers.

#![cfg(test)]

use crate::diagnostic::data::Diagnostic;
use crate::parse::parse;

/// The one diagnostic of a source that must not parse.
pub(crate) fn error(src: &str) -> Diagnostic {
    let (model, diags) = parse(src);
    assert!(model.is_none(), "{src:?} should not parse");
    assert_eq!(diags.len(), 1, "{diags:?}");
    diags
        .into_iter()
        .next()
        .unwrap_or_else(|| Diagnostic::error("none", ""))
}

/// The source text under a diagnostic's primary label.
pub(crate) fn at(src: &str, d: &Diagnostic) -> String {
    let span = d.primary_span().unwrap_or_default();
    src.get(span.start..span.end)
        .unwrap_or("<bad span>")
        .to_string()
}
