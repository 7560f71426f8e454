//! leeway-grammar: `.som` text → typed syntax tree with spans, and the
//! diagnostics every later pass reports (plain data with one renderer).
//!
//! The grammar lives in `som.pest`; pest's types never leave this crate.
//! [`parse`] never panics: it returns the tree or one located syntax error.

pub mod ast;
pub mod diagnostic;
mod guards;
mod parse;
mod scan;
pub mod source;

#[doc(inline)]
pub use ast::*;
#[doc(inline)]
pub use diagnostic::data::{Diagnostic, Label, Severity};
#[doc(inline)]
pub use diagnostic::lists::{MAX_LISTED, and_list, join_capped};
#[doc(inline)]
pub use diagnostic::location::line_col;
#[doc(inline)]
pub use diagnostic::render::{MAX_RENDERED, RenderStyle, render, render_short};
#[doc(inline)]
pub use diagnostic::view::MAX_LINE_COLUMNS;
#[doc(inline)]
pub use guards::{MAX_NESTING, MAX_OPERANDS, MAX_SIGNS};
#[doc(inline)]
pub use parse::parse;
#[doc(inline)]
pub use source::MAX_SOURCE_BYTES;
