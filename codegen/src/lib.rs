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
//! The rendering names the path as the user wrote it, so ui snapshots are the
//! same on every machine. Warnings and notes never fail a build: they go into
//! the struct's documentation. The only IO is reading the model file of
//! `include_model!`.
//!
//! Generated code names the facade as `::leeway::__private` and compiles
//! without warnings under strict lint sets (`missing_docs`, clippy pedantic)
//! in user crates. `tests/expand.rs` snapshots the pretty-printed expansion
//! of the example models, fixtures and a broken model, without a compiler in
//! the loop; the facade's `tests/bit_exact.rs` holds generated and
//! interpreted results to `f64::to_bits` equality on every example model.

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
