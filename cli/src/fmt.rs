//! `leeway fmt FILES`: rewrite `.som` models in the canonical layout
//! (leeway-format); `--check` writes nothing, lists the files that are not
//! laid out so and exits 1 (for CI).

use crate::output::{Status, err, headline, out, stderr_style};
use leeway_structure::grammar;
use std::path::PathBuf;

/// Arguments of `leeway fmt`.
#[derive(Debug, clap::Args)]
pub struct FmtArgs {
    /// The `.som` model files.
    #[arg(value_name = "MODEL.som", required = true)]
    pub models: Vec<PathBuf>,
    /// Write nothing: list the files whose layout differs on stdout and exit 1 if any.
    #[arg(long)]
    pub check: bool,
}

/// Runs `leeway fmt`: exit 0 when every file is (now) formatted, 1 with
/// `--check` when some are not, 2 when a file cannot be read, parsed or written.
pub fn run(args: &FmtArgs) -> Status {
    let mut status = Status::Success;
    for path in &args.models {
        let file = path.display().to_string();
        let source = match crate::files::read_model(path) {
            Ok(Ok(source)) => source,
            Ok(Err(refused)) => {
                let style = stderr_style();
                err(&grammar::render(
                    &[refused.diagnostic],
                    &file,
                    &refused.text,
                    style,
                ));
                status = Status::Error;
                continue;
            }
            Err(e) => {
                let message = format!("cannot read `{file}`: {}", crate::files::io_reason(&e));
                err(&headline(stderr_style(), "error", None, &message));
                status = Status::Error;
                continue;
            }
        };
        let formatted = match leeway_format::format(&source) {
            Ok(text) => text,
            Err(diagnostics) => {
                err(&grammar::render(
                    &diagnostics,
                    &file,
                    &source,
                    stderr_style(),
                ));
                let message = format!("`{file}` was not formatted: it does not parse");
                err(&headline(stderr_style(), "error", None, &message));
                status = Status::Error;
                continue;
            }
        };
        if formatted == source {
            continue;
        }
        if args.check {
            out(&format!("{file}\n"));
            if status == Status::Success {
                status = Status::Unsupported;
            }
        } else if let Err(e) = std::fs::write(path, formatted) {
            let message = format!("cannot write `{file}`: {}", crate::files::io_reason(&e));
            err(&headline(stderr_style(), "error", None, &message));
            status = Status::Error;
        }
    }
    status
}
