//! `leeway`: the command line of leeway, and the only crate that touches the
//! terminal (colours, exit codes). Each subcommand is a sibling module;
//! `main` parses the arguments and dispatches.
//!
//! Exit codes, for scripts: 0 success (the model is identifiable, or valid and
//! aggregated with `--aggregate`); 1 the model is valid but θ is not
//! identifiable; 2 a usage, input/output, syntax or semantic error.

mod check;
mod output;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Identify grey-box models of vessels under wind and current.
#[derive(Debug, Parser)]
#[command(name = "leeway", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Derive a model's regressors and prove whether θ is identifiable, and from which experiments.
    Check(check::CheckArgs),
}

fn main() -> ExitCode {
    // clap prints usage errors itself and exits with code 2, help and version with 0.
    let cli = Cli::parse();
    let status = match cli.command {
        Command::Check(args) => check::run(&args),
    };
    status.code()
}
