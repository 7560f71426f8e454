//! `leeway lsp`: the language server (leeway-lsp) over stdin and stdout,
//! for the editors set up in docs/editor.md.

use crate::output::{Status, err, headline, stderr_style};

/// Arguments of `leeway lsp`.
#[derive(Debug, clap::Args)]
pub struct LspArgs {
    /// Accepted for clients that name the transport (the server only speaks stdio).
    #[arg(long)]
    pub stdio: bool,
}

/// Runs the server until the client leaves (`shutdown` and `exit`, or its
/// end of the stream closed): exit 0; 2 when the handshake or the output
/// fails.
pub fn run(_args: &LspArgs) -> Status {
    match leeway_lsp::run_stdio() {
        Ok(()) => Status::Success,
        Err(_) => {
            let message =
                "the connection to the editor failed (the `initialize` handshake or a write)";
            err(&headline(stderr_style(), "error", None, message));
            Status::Error
        }
    }
}
