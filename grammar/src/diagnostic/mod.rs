//! Diagnostics as plain data, and their one renderer.
//!
//! Every pass reports [`Diagnostic`]s; nothing is printed inside the library.
//! [`render()`] turns them into rustc-like text (`file:line:col`, the source
//! line, a caret under the span, the help), plain for tests and macros,
//! coloured for terminals.

pub(crate) mod data;
pub(crate) mod group;
pub(crate) mod lists;
pub(crate) mod location;
pub(crate) mod render;
pub(crate) mod view;

pub use data::{Diagnostic, Label, Severity};
pub use lists::{MAX_LISTED, and_list, join_capped};
pub use location::line_col;
pub use render::{MAX_NOTES, MAX_RENDERED, MAX_TEXT_CHARS, RenderStyle, render, render_short};
pub use view::MAX_LINE_COLUMNS;
