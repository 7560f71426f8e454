//! leeway-grammar: `.som` text → typed syntax tree with spans, and the
//! diagnostics every later pass reports (plain data with one renderer).
//!
//! The grammar lives in `som.pest`; pest's types never leave this crate.
//! [`parse`] never panics: it returns the tree or one located syntax error.

pub mod ast;
pub mod diagnostic;
mod parse;
pub mod source;

#[doc(inline)]
pub use ast::*;
#[doc(inline)]
pub use diagnostic::{
    Diagnostic, Label, MAX_LINE_COLUMNS, MAX_LISTED, MAX_RENDERED, RenderStyle, Severity, and_list,
    join_capped, line_col, render, render_short,
};
#[doc(inline)]
pub use parse::{MAX_NESTING, MAX_OPERANDS, MAX_SIGNS, MAX_SOURCE_BYTES, parse};
