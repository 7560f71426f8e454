//! leeway-lsp: the language server of `.som` models (`leeway lsp`).
//!
//! Built on rust-analyzer's `lsp-server` (the transport: stdio, messages
//! handled one at a time in the order they came, so an edit is never
//! reordered past a request) and `lsp-types`. Every answer comes from the
//! compiler `leeway check` runs: the same diagnostics (codes, texts, help
//! and notes; related locations for the other labels), the
//! identifiability verdict as an information on the model's name, hovers
//! from the IR (a term's regressors and nuisance columns, a parameter's
//! terms and whether it is identified, a signal's declaration and unit),
//! definitions and references from the syntax tree, completion, document
//! symbols, semantic tokens (parameters apart from signals), formatting by
//! leeway-format, and the code actions that are certain (an unused input,
//! relative velocity or medium removed; a parameter listed in `nominal`).
//! While a text does not parse, hover, definition and references answer
//! from the last version that parsed where the text is unchanged ([`last`]).
//!
//! A document is analysed at most once per version, and only when the
//! queue of messages is empty or a request needs it. Positions are the
//! protocol's: lines and UTF-16 code units ([`text`]).

pub mod actions;
pub mod analysis;
pub mod diagnostics;
pub mod hover;
pub mod last;
pub mod server;
pub mod symbols;
pub mod text;
pub mod tokens;

use lsp_server::Connection;

/// Serves one client over standard input and output until it exits.
pub fn run_stdio() -> Result<(), server::Disconnected> {
    let (connection, io_threads) = Connection::stdio();
    let served = server::serve(&connection);
    drop(connection);
    io_threads.join().map_err(|_| server::Disconnected)?;
    served
}
