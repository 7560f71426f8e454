//! What every subcommand shares: exit statuses, the terminal checks that
//! decide on colour (ANSI only on a terminal and without `NO_COLOR`),
//! the one writer of stdout (checked: a failed write decides the exit code,
//! [`finish`]), tables and number formatting.

use leeway_model::warning::Warning;
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
    /// Exit 1: model, data and options are valid, but the data cannot support
    /// the result: θ not identifiable or not excited by these experiments, a
    /// sign assumption violated under `--strict`, a simulation that diverges.
    Unsupported,
    /// Exit 2: usage, input/output, syntax or semantic error.
    Error,
}

impl Status {
    /// The process exit code.
    pub fn code(self) -> ExitCode {
        match self {
            Status::Success => ExitCode::SUCCESS,
            Status::NotIdentifiable | Status::Unsupported => ExitCode::from(1),
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

/// The first write to stdout that failed; nothing more is written after it.
static STDOUT_FAILED: std::sync::OnceLock<std::io::Error> = std::sync::OnceLock::new();

/// Writes to stdout and flushes: the only place that does. A failed write
/// (a full disk, a closed pipe) is kept, later text is dropped, and
/// [`finish`] turns it into the exit code: never a panic, never a silent 0.
pub fn out(text: &str) {
    use std::io::Write;
    if STDOUT_FAILED.get().is_some() {
        return;
    }
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        let _ = STDOUT_FAILED.set(e);
    }
}

/// The exit code: the command's `status`, unless a write to stdout failed.
/// A closed pipe (`leeway check m.som | head -1`) exits quietly with 141
/// (what a shell reports for a process ended by SIGPIPE); any other failure
/// (`> /dev/full`) says `error[io]: cannot write the output to stdout: …`
/// and exits 2.
pub fn finish(status: Status) -> ExitCode {
    match STDOUT_FAILED.get() {
        None => status.code(),
        Some(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::from(141),
        Some(e) => {
            err(&headline(
                stderr_style(),
                "error",
                Some("io"),
                &format!("cannot write the output to stdout: {}", io_reason(e)),
            ));
            Status::Error.code()
        }
    }
}

/// An IO error as a reason, without the `(os error N)` its display ends with.
pub fn io_reason(e: &std::io::Error) -> String {
    let text = e.to_string();
    match text.rfind(" (os error ") {
        Some(i) if text.ends_with(')') => text[..i].to_string(),
        _ => text,
    }
}

/// Writes to stderr, ignoring a closed stream like [`out`].
pub fn err(text: &str) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// `severity[code]: message` (or `severity: message` without a code) and a
/// newline, bold and coloured on a terminal.
pub fn headline(style: RenderStyle, severity: &str, code: Option<&str>, message: &str) -> String {
    let tag = match code {
        Some(c) => format!("{severity}[{c}]"),
        None => severity.to_string(),
    };
    match style {
        RenderStyle::Color => {
            let colour = if severity == "error" { "31" } else { "33" };
            format!("\x1b[1;{colour}m{tag}\x1b[0m\x1b[1m: {message}\x1b[0m\n")
        }
        RenderStyle::Plain => format!("{tag}: {message}\n"),
    }
}

/// A warning as text: its summary as the headline and its help line (two
/// lines at most), and with `verbose` its full detail under them.
pub fn warning_text(style: RenderStyle, w: &Warning, verbose: bool) -> String {
    let mut text = headline(style, "warning", None, &w.summary);
    if !w.help.is_empty() {
        text.push_str(&format!("  = help: {}\n", w.help));
    }
    if verbose && w.detail != w.summary {
        text.push_str(&format!("  = detail: {}\n", w.detail));
    }
    text
}

/// Messages that are short already (one line each), as warnings.
pub fn plain(code: &'static str, messages: Vec<String>) -> impl Iterator<Item = Warning> {
    messages.into_iter().map(move |m| Warning::plain(code, m))
}

/// Writes a document as pretty JSON and a newline on stdout.
pub fn print_json<T: serde::Serialize>(document: &T) {
    match serde_json::to_string_pretty(document) {
        Ok(text) => out(&format!("{text}\n")),
        // Serialising plain structs of strings and numbers cannot fail; say so if it ever does.
        Err(e) => err(&format!("error: cannot serialise the report: {e}\n")),
    }
}

/// A number for a table: five significant digits, in positional notation
/// between 10⁻³ and 10⁵ and with an exponent outside.
pub fn number(x: f64) -> String {
    if x == 0.0 {
        return "0".to_string();
    }
    if !x.is_finite() {
        return format!("{x}");
    }
    let magnitude = x.abs().log10().floor();
    if (-3.0..5.0).contains(&magnitude) {
        // 0 ≤ decimals ≤ 7 here, so the cast is exact.
        let decimals = (4.0 - magnitude).max(0.0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.4e}")
    }
}

/// Left-aligned columns separated by two spaces; the last column is not padded.
pub fn table(rows: &[Vec<String>]) -> String {
    let n = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..n)
        .map(|i| {
            rows.iter()
                .filter_map(|r| r.get(i))
                .map(|c| c.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for row in rows {
        let mut line = String::from("  ");
        for (i, cell) in row.iter().enumerate() {
            line.push_str(cell);
            if i + 1 < row.len() {
                let pad = widths[i] - cell.chars().count() + 2;
                line.extend(std::iter::repeat_n(' ', pad));
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// Objects keyed in the model's order (shared with the Python package).
pub use leeway_report::Ordered;

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn numbers_keep_five_significant_digits() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(-0.050123456), "-0.050123");
        assert_eq!(number(1.0), "1.0000");
        assert_eq!(number(12345.678), "12346");
        assert_eq!(number(0.00030012), "3.0012e-4");
        assert_eq!(number(2.5e7), "2.5000e7");
        assert_eq!(number(f64::NAN), "NaN");
    }
}
