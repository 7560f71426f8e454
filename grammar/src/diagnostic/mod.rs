//! Diagnostics as plain data, and their one renderer.
//!
//! Every pass reports [`Diagnostic`]s; nothing is printed inside the library.
//! [`render()`] turns them into rustc-like text (`file:line:col`, the source
//! line, a caret under the span, the help), plain for tests and macros,
//! coloured for terminals.
//!
//! No input floods a terminal: the renderer prints at most [`MAX_RENDERED`]
//! diagnostics and then one count line, merges those of one code on one
//! source line into one (the first [`MAX_LISTED`] marked, the rest counted),
//! cuts a source line to a [`MAX_LINE_COLUMNS`] window around its labels,
//! escapes control characters, prints at most [`MAX_NOTES`] notes per
//! diagnostic and cuts any text beyond [`MAX_TEXT_CHARS`] characters; every
//! list inside a message goes through [`join_capped`] or [`and_list`]. Every
//! label is drawn inside the source, on character boundaries.

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
