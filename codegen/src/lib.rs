//! leeway-codegen: a `.som` model → the Rust tokens of `include_model!` and
//! `inline_model!`, as a normal library (the proc-macro crate is a shell over
//! it). It runs the structure compiler and emits, for a model `Ship`, a unit
//! struct `Ship` implementing `leeway::Model` with straight-line regressor
//! code (the evaluation order of `leeway_structure::ir::Entry`, shared with
//! the run-time interpreter, so both agree bit for bit), the typed parameter
//! struct `ShipParams`, typed constants, and the IR embedded as JSON data.
//!
//! Nothing here returns `Err` or panics: every problem becomes a
//! `compile_error!` on the macro's string literal, carrying the rendered
//! diagnostic (`path:line:col`, source line, caret, help), emitted beside a
//! fallback expansion so the user sees the model's errors and nothing else.
//! The only IO is reading the model file of `include_model!`.

mod emit;
mod entry;
mod eval;
mod expand;
mod fallback;
mod input;
mod message;
mod tokens;

pub use entry::{include_model, inline_model, resolve_path};
pub use expand::expand;
pub use input::{Invocation, MacroInput, Source};
pub use message::error_message;
