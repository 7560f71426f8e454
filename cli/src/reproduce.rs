//! `leeway reproduce [--runs M] [--n LIST] [--case low|high|both] [--seed S]
//! [--out DIR] [--threads T] [--paper-iv]`: the paper's simulation study
//! (§V, SPEC §6) on the ship compiled into this binary. Runs the Monte Carlo
//! study of `leeway_scenarios::study` in a rayon pool of `--threads` (with
//! a progress bar on a terminal), checks the input design
//! on the true trajectories, prints a table per case, the design margins and
//! the paper's four claims with their verdicts, and writes `DIR/results.json`
//! (the contract of docs/json.md) and the figures (SVG and PNG). Exit 0 when
//! everything was written (whatever the claims' verdicts), 2 on an option
//! error or a file that cannot be written (the results are still printed).
//! The results and figures are bit-identical for any thread count: every run
//! has its own seed and results are merged in run order.

pub mod args;
mod figures;
mod json;
mod margins;
mod report;
mod ship;
mod text;

use crate::files::write_output;
use crate::output::{Status, err, io_reason, out, stderr_style};
use crate::problem::Problem;
use crate::reproduce::args::ReproduceArgs;
use crate::reproduce::report::Report;
use crate::reproduce::report::all_estimates;
use leeway_model::Model;
use leeway_scenarios::study;
use leeway_scenarios::study::StudyConfig;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Runs `leeway reproduce`.
pub fn run(args: &ReproduceArgs) -> Status {
    let style = stderr_style();
    let config = args.config();
    let pool = {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(t) = args.threads {
            builder = builder.num_threads(t);
        }
        match builder.build() {
            Ok(pool) => pool,
            Err(e) => {
                err(&Problem::error(
                    "invalid-option",
                    format!("cannot start the worker threads: {e}"),
                )
                .render(style));
                return Status::Error;
            }
        }
    };
    // A directory that cannot be written fails now, not after the study.
    if let Err(p) = writable(&args.out) {
        err(&p.render(style));
        return Status::Error;
    }
    let model = ship::Ship;
    let report = pool.install(|| execute(&model, &config));
    out(&text::render(&report, args));
    let problems = pool.install(|| write_outputs(&model, &report, &args.out));
    let mut written = Vec::new();
    for item in &problems {
        match item {
            Ok(path) => written.push(path.display().to_string()),
            Err(p) => err(&p.render(style)),
        }
    }
    if !written.is_empty() {
        out(&format!("\nwrote {}\n", written.join(", ")));
    }
    if problems.iter().any(Result::is_err) {
        Status::Error
    } else {
        Status::Success
    }
}

/// Runs the study and the design check, with a progress bar on a terminal.
fn execute(model: &dyn Model, config: &StudyConfig) -> Report {
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    use std::io::IsTerminal;
    let start = Instant::now();
    let total = (config.cases.len() * config.runs) as u64;
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    if let Ok(style) = ProgressStyle::with_template(
        "{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} runs (eta {eta})",
    ) {
        bar.set_style(style);
    }
    bar.set_message("leeway reproduce");
    // The design check measures the records as the study simulates them.
    let (outcomes, measured) =
        study::run_study_inspecting(model, config, &|| bar.inc(1), &|_, run, truth| {
            margins::measure(model, config, run, truth)
        });
    bar.finish_and_clear();
    let margins = margins::collect(model, config, measured);
    let summaries = study::summarise(&outcomes);
    let claims = study::claims(&summaries);
    let all_estimates = all_estimates(&outcomes);
    Report {
        outcomes,
        summaries,
        all_estimates,
        claims,
        margins,
        seconds: start.elapsed().as_secs_f64(),
        threads: rayon::current_num_threads(),
    }
}

/// Creates the output directory and writes (then removes) a probe file in
/// it: the study's minutes are not spent for outputs that cannot be written.
fn writable(dir: &Path) -> Result<(), Problem> {
    let problem = |what: &str, e: std::io::Error| {
        Problem::error(
            "io",
            format!(
                "cannot {what} the output directory `{}`: {}",
                dir.display(),
                io_reason(&e)
            ),
        )
        .at(dir.display().to_string())
        .help("choose another directory with --out DIR")
    };
    std::fs::create_dir_all(dir).map_err(|e| problem("create", e))?;
    let probe = dir.join(format!(".leeway-probe-{}", std::process::id()));
    write_output(&probe, b"").map_err(|e| problem("write into", e))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Writes results.json and every figure; one entry per file, written or not.
fn write_outputs(model: &dyn Model, report: &Report, dir: &Path) -> Vec<Result<PathBuf, Problem>> {
    if let Err(p) = writable(dir) {
        return vec![Err(p)];
    }
    use rayon::prelude::*;
    let mut results = vec![write_json(report, &dir.join("results.json"))];
    // Every file drawn on its own worker, listed in the same order.
    let figures = figures::all(model, report);
    let files: Vec<(PathBuf, &figures::AnyFigure)> = figures
        .iter()
        .flat_map(|(name, figure)| {
            ["svg", "png"].map(|ext| (dir.join(format!("{name}.{ext}")), figure))
        })
        .collect();
    results.par_extend(files.par_iter().map(|(path, figure)| {
        figure
            .save(path)
            .map(|()| path.clone())
            .map_err(|e| Problem::error("io", format!("cannot draw `{}`: {e}", path.display())))
    }));
    results
}

fn write_json(report: &Report, path: &Path) -> Result<PathBuf, Problem> {
    let text = serde_json::to_string_pretty(&json::document(report))
        .map_err(|e| Problem::error("io", format!("cannot serialise the results: {e}")))?;
    write_output(path, format!("{text}\n").as_bytes()).map_err(|e| {
        Problem::error(
            "io",
            format!("cannot write `{}`: {}", path.display(), io_reason(&e)),
        )
        .at(path.display().to_string())
    })?;
    Ok(path.to_path_buf())
}
