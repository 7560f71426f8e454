//! `leeway`: the command line of leeway, and the only crate that touches the
//! terminal (colours, exit codes). Each subcommand is a sibling module;
//! `main` parses the arguments and dispatches.
//!
//! Exit codes, for scripts: 0 success (for `check`: the model is
//! identifiable, or valid and aggregated with `--aggregate`; warnings
//! allowed); 1 the model and data are valid but cannot support the result
//! (`check`: θ not identifiable; `estimate`: θ not identifiable or not
//! excited by these data, or a sign violation under `--strict`; `simulate`,
//! `validate`: the simulation diverges); 2 a usage, input/output, syntax,
//! semantic, data or parameter-file error, or output that cannot be written
//! to stdout (for `reproduce`: an option error or a result file that cannot
//! be written; the verdicts on the paper's claims never change the exit
//! code); 141 stdout closed under it (`| head`), quietly. Never a panic.
//!
//! Computation stays in the libraries: this crate reads, validates its own
//! arguments, calls them and prints. Every numeric option is bounded before
//! any work, with clap's error naming the option (`reproduce`'s runs, sample
//! counts, their product and threads; the estimator's lags and refinements;
//! sample times and resampling; given values). `check --json` and
//! `estimate --json` print their documents for every outcome, errors
//! included; like `reproduce`'s `results.json`, their fields may grow but
//! are never renamed or removed. `cli/tests/` holds the shapes, every
//! malformed-CSV class, the round trips estimate → validate and simulate →
//! validate, the data reproducers (physical rows, outliers, overflow,
//! units, option bounds) and a proptest of CSV layouts (`csv_layouts.rs`).

// Estimates allocate and free record-sized buffers many times a second
// (the study: thousands of estimates); mimalloc reuses freed pages where
// the system allocator hands them back and faults them in again.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod check;
mod data;
mod design;
mod disturbances;
mod estimate;
mod files;
mod fmt;
mod input;
mod lsp;
mod model;
mod noise;
mod options;
mod output;
mod params;
mod plot;
mod problem;
mod reproduce;
mod residuals;
mod select;
mod simulate;
mod units;
mod validate;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Identify grey-box models of vessels under wind and current.
#[derive(Debug, Parser)]
#[command(name = "leeway", version, about, long_about = None)]
pub(crate) struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Derive a model's regressors and prove whether θ is identifiable, and from which experiments.
    Check(check::CheckArgs),
    /// Estimate θ, the nuisance parameters and the disturbance means from experiments (CSV).
    Estimate(estimate::args::EstimateArgs),
    /// Choose among a model's candidate terms (`?name`) by IV backward elimination; write the chosen model.
    Select(select::SelectArgs),
    /// Simulate a model with given parameters on an input file; write the trajectory as CSV.
    Simulate(simulate::SimulateArgs),
    /// Fit of models with given parameters on validation data (like MATLAB's compare); a plot with --plot.
    Validate(validate::ValidateArgs),
    /// Re-run the paper's simulation study (§V): tables, claims, results.json and figures.
    Reproduce(reproduce::args::ReproduceArgs),
    /// Plan the trial for a craft: runs, operating points, excitation, predicted accuracy; --verify by Monte Carlo.
    Design(design::args::DesignArgs),
    /// Rewrite .som models in the canonical layout; --check lists those that differ (exit 1).
    Fmt(fmt::FmtArgs),
    /// The language server for editors, over stdin and stdout (docs/editor.md).
    Lsp(lsp::LspArgs),
}

fn main() -> ExitCode {
    // clap prints usage errors itself and exits with code 2, help and version with 0.
    let cli = Cli::parse();
    let status = match cli.command {
        Command::Check(args) => check::run(&args),
        Command::Estimate(args) => estimate::run(&args),
        Command::Select(args) => select::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Validate(args) => validate::run(&args),
        Command::Design(args) => design::run(&args),
        Command::Fmt(args) => fmt::run(&args),
        Command::Lsp(args) => lsp::run(&args),
        Command::Reproduce(args) => {
            // Bounds across options, reported like clap's own (exit 2).
            if let Err(message) = reproduce::args::check_work(&args) {
                let mut cmd = <Cli as clap::CommandFactory>::command();
                cmd.error(clap::error::ErrorKind::ValueValidation, message)
                    .exit();
            }
            reproduce::run(&args)
        }
    };
    output::finish(status)
}
