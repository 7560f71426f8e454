//! What every subcommand shares: exit statuses and the terminal checks that
//! decide on colour.

use leeway_structure::grammar::RenderStyle;
use std::io::IsTerminal;
use std::process::ExitCode;

/// The outcome of a subcommand, mapped to the documented exit codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Exit 0: the job succeeded (for `check`: θ identifiable, or aggregated).
    Success,
    /// Exit 1: the model is valid but θ is not identifiable.
    NotIdentifiable,
    /// Exit 2: usage, input/output, syntax or semantic error.
    Error,
}

impl Status {
    /// The process exit code.
    pub fn code(self) -> ExitCode {
        match self {
            Status::Success => ExitCode::SUCCESS,
            Status::NotIdentifiable => ExitCode::from(1),
            Status::Error => ExitCode::from(2),
        }
    }
}

/// Colour on a stream only when it is a terminal and `NO_COLOR` is unset
/// (<https://no-color.org>); plain text into pipes, files and tests.
fn style_for(is_terminal: bool) -> RenderStyle {
    let no_color = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
    if is_terminal && !no_color {
        RenderStyle::Color
    } else {
        RenderStyle::Plain
    }
}

/// The render style for text written to standard error.
pub fn stderr_style() -> RenderStyle {
    style_for(std::io::stderr().is_terminal())
}

/// Writes to stdout. A closed pipe (`leeway check m.som | head`) is not an
/// error worth a panic: what cannot be written is dropped.
pub fn out(text: &str) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    let _ = stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush());
}

/// Writes to stderr, ignoring a closed stream like [`out`].
pub fn err(text: &str) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}
