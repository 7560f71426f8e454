//! leeway-format: the one canonical layout of `.som` model files, used by
//! `leeway fmt` and by the language server's formatting request.
//!
//! The layout is printed from the syntax tree ([`leeway_grammar::parse`]),
//! never by editing the text, so it is the same whatever the spacing it was
//! given; the comments, which the tree does not hold, are scanned from the
//! text and put back next to the code they were written beside. The rules:
//!
//! * one declaration per line, indented by four inside `model Name { }`; at
//!   most one blank line kept where the author left blank lines between
//!   declarations or comments;
//! * canonical spacing inside a line: `a*b`, `a + b`, `|water.u|`,
//!   `X_u = -0.2, X_vr = 0.8`, `earth(north, east)`;
//! * the author's line breaks between the terms of an equation and between
//!   the entries of a list (`state`, `input`, `nominal`, `data`, `rotation`)
//!   are kept, and a line that would pass [`WIDTH`] columns is broken there
//!   too; a continued equation aligns its `+` under the `=`, a continued
//!   list aligns under its first entry (or, when the block opens on a line
//!   of its own, is indented by four with `}` on its own line);
//! * comments on the line of some code stay at the end of that line,
//!   aligned with the trailing comments of the lines next to it; comments
//!   on lines of their own stay before the code that follows them.
//!
//! Formatting is idempotent and never changes what the model compiles to
//! (both tested on every model of the repository).

mod comments;
mod expr;
mod layout;
mod print;

use leeway_grammar::Diagnostic;

#[doc(inline)]
pub use layout::WIDTH;

/// The canonical layout of `source`, or the syntax error that keeps it from
/// being formatted (a file that does not parse is left as it is).
pub fn format(source: &str) -> Result<String, Vec<Diagnostic>> {
    let (model, diagnostics) = leeway_grammar::parse(source);
    let Some(model) = model else {
        return Err(diagnostics);
    };
    let comments = comments::scan(source);
    let lines = layout::lines(&model, source, &comments);
    Ok(print::print(source, &lines, &comments))
}
