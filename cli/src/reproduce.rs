//! `leeway reproduce [--runs M] [--n LIST] [--case low|high|both] [--seed S]
//! [--out DIR] [--threads T] [--paper-iv]`: the paper's simulation study
//! (§V, SPEC §6) on the ship compiled into this binary. Runs the Monte Carlo
//! study of the runtime (`leeway_scenarios::study`), checks the input design
//! on the true trajectories, prints a table per case, the design margins and
//! the paper's four claims with their verdicts, and writes `DIR/results.json`
//! (the contract of the README) and the figures (SVG and PNG). Exit 0 when
//! everything was written (whatever the claims' verdicts), 2 on an option
//! error or a file that cannot be written (the results are still printed).

mod figures;
mod json;
mod margins;
mod text;

use crate::output::{Status, err, out, stderr_style};
use crate::problem::Problem;
use leeway_model::Model;
use leeway_scenarios::study;
use leeway_scenarios::study::Case;
use leeway_scenarios::study::StudyConfig;
use leeway_scenarios::study::StudyOutcomes;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The paper's ship, compiled into the binary at build time (about 12× faster
/// than interpreting its IR); the model file is `examples/models/ship.som`.
#[allow(dead_code)] // the macro emits the whole API; the study uses the model only
mod ship {
    leeway::include_model!("../../examples/models/ship.som");
}

/// The model file the binary was built with, as the README names it.
pub const MODEL_FILE: &str = "examples/models/ship.som";

/// Which wind cases to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CaseArg {
    /// `w̄ = 1` m/s.
    Low,
    /// `w̄ = 10` m/s.
    High,
    /// Both, low then high.
    Both,
}

/// Arguments of `leeway reproduce`.
#[derive(Debug, clap::Args)]
pub struct ReproduceArgs {
    /// Monte Carlo runs per case.
    #[arg(long, value_name = "M", default_value_t = 100, value_parser = runs)]
    pub runs: usize,
    /// Estimation record lengths N, comma-separated (sorted, duplicates dropped).
    /// Each run simulates one record of the largest N; smaller N use its beginning.
    #[arg(
        long = "n",
        value_name = "LIST",
        value_delimiter = ',',
        default_values_t = [1000usize, 2000, 3000, 4000, 5000],
        value_parser = record_length
    )]
    pub n: Vec<usize>,
    /// The wind cases: low (1 m/s), high (10 m/s) or both.
    #[arg(long, value_enum, default_value_t = CaseArg::Both)]
    pub case: CaseArg,
    /// Master seed; run r of case c draws its noises and input from (seed, c, r).
    #[arg(long, value_name = "S", default_value_t = StudyConfig::default().seed)]
    pub seed: u64,
    /// Where to write results.json and the figures (created if missing).
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub out: PathBuf,
    /// Worker threads (default: one per core). The results do not depend on it.
    #[arg(long, value_name = "T", value_parser = threads)]
    pub threads: Option<usize>,
    /// Run the paper's plain refined IV (instruments from the nominal model,
    /// no runaway guard) instead of leeway's (a delayed-instrument estimate
    /// starts the refinement; the iterate whose simulation fits best is kept).
    #[arg(long)]
    pub paper_iv: bool,
}

/// Shortest record length accepted: the data loader's minimum.
pub const MIN_N: usize = 10;

/// Longest record length accepted: each worker holds one record of the
/// largest N in memory (about 100 bytes a sample for the ship).
pub const MAX_N: usize = 1_000_000;
/// Most Monte Carlo runs per case.
pub const MAX_RUNS: usize = 10_000;
/// Bound on the study's total work: runs × largest N, samples simulated per case.
pub const MAX_WORK: usize = 100_000_000;
/// Most worker threads, whatever the machine: more would only cost memory
/// (one record each).
pub const MAX_THREADS: usize = 256;

fn runs(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(v) if (1..=MAX_RUNS).contains(&v) => Ok(v),
        Ok(v) if v > MAX_RUNS => Err(format!("`{s}` is more than {MAX_RUNS} runs")),
        _ => Err(format!("`{s}` is not a positive whole number")),
    }
}

/// The most worker threads on this machine: 8 per core, at most [`MAX_THREADS`].
pub fn max_threads() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    (8 * cores).clamp(1, MAX_THREADS)
}

fn threads(s: &str) -> Result<usize, String> {
    let max = max_threads();
    match s.trim().parse::<usize>() {
        Ok(v) if (1..=max).contains(&v) => Ok(v),
        Ok(v) if v > max => Err(format!(
            "`{s}` is more than {max} threads (8 per core of this machine, at most {MAX_THREADS})"
        )),
        _ => Err(format!("`{s}` is not a positive whole number")),
    }
}

fn record_length(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(v) if (MIN_N..=MAX_N).contains(&v) => Ok(v),
        Ok(v) if v < MIN_N => Err(format!(
            "N = {v} is too short: an estimation record needs at least {MIN_N} samples"
        )),
        Ok(v) => Err(format!(
            "N = {v} is too long: at most {MAX_N} samples per record (the study holds one record per worker in memory)"
        )),
        Err(_) => Err(format!("`{s}` is not a record length (a whole number)")),
    }
}

/// `--runs` × the largest `--n` within [`MAX_WORK`]: an error naming both
/// options, in clap's words, before any work starts.
pub fn check_work(args: &ReproduceArgs) -> Result<(), clap::Error> {
    let largest = args.n.iter().copied().max().unwrap_or(0);
    let work = args.runs.saturating_mul(largest);
    if work > MAX_WORK {
        let mut cmd = <crate::Cli as clap::CommandFactory>::command();
        return Err(cmd.error(
            clap::error::ErrorKind::ValueValidation,
            format!(
                "--runs {} with --n up to {largest} is {work} samples per case; at most {MAX_WORK} (lower --runs or the largest --n)",
                args.runs
            ),
        ));
    }
    Ok(())
}

impl ReproduceArgs {
    /// The study's configuration: the runtime's defaults with the options given.
    pub fn config(&self) -> StudyConfig {
        let mut n = self.n.clone();
        n.sort_unstable();
        n.dedup();
        let cases: Vec<Case> = study::paper_cases()
            .into_iter()
            .filter(|c| match self.case {
                CaseArg::Low => c.name == "low",
                CaseArg::High => c.name == "high",
                CaseArg::Both => true,
            })
            .collect();
        StudyConfig {
            runs: self.runs,
            n,
            cases,
            seed: self.seed,
            paper_iv: self.paper_iv,
            ..StudyConfig::default()
        }
    }
}

/// Everything the study produced, before it is printed and written.
pub struct Report {
    /// The outcomes of every run.
    pub outcomes: StudyOutcomes,
    /// Per case: the summaries of the results.json contract.
    pub summaries: BTreeMap<String, study::CaseSummary>,
    /// Per case and estimator: the parameter error over every estimate.
    pub all_estimates: BTreeMap<String, BTreeMap<String, AllEstimates>>,
    /// The paper's claims, checked.
    pub claims: Vec<study::Claim>,
    /// The input design checked on the true trajectories.
    pub margins: margins::DesignCheck,
    /// Wall time of the study and the design check, seconds.
    pub seconds: f64,
    /// Worker threads used.
    pub threads: usize,
}

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

/// The parameter error over every estimate an estimator returned, whether
/// or not its model then diverged on the validation record. The study's
/// summaries leave diverged runs out of every mean and median, which is
/// right for the fit but flatters an estimator whose worst estimates are
/// exactly the ones that diverge (survivor bias): at small N this is where
/// LS and the IV estimators part ways.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AllEstimates {
    /// Runs that returned an estimate, per N.
    pub estimated: Vec<usize>,
    /// Median parameter error over those runs, per N.
    pub median: Vec<f64>,
}

/// Per case, the record lengths at which LS's median parameter error over
/// every estimate is below IV3's: where LS is ahead (claim (a)'s breakpoint
/// lies above the largest of them).
pub fn ls_ahead(report: &Report) -> BTreeMap<String, Vec<usize>> {
    report
        .all_estimates
        .iter()
        .map(|(case, est)| {
            let n = &report.outcomes.config.n;
            let ahead = match (est.get("LS"), est.get("IV3")) {
                (Some(ls), Some(iv3)) => n
                    .iter()
                    .zip(ls.median.iter().zip(&iv3.median))
                    .filter(|(_, (a, b))| a < b || (a.is_finite() && b.is_nan()))
                    .map(|(n, _)| *n)
                    .collect(),
                _ => Vec::new(),
            };
            (case.clone(), ahead)
        })
        .collect()
}

fn all_estimates(out: &StudyOutcomes) -> BTreeMap<String, BTreeMap<String, AllEstimates>> {
    let cfg = &out.config;
    let mut cases = BTreeMap::new();
    for (c, case) in cfg.cases.iter().enumerate() {
        let mut estimators = BTreeMap::new();
        for (m, name) in study::ESTIMATORS.iter().enumerate() {
            let mut a = AllEstimates::default();
            for ni in 0..cfg.n.len() {
                let errors: Vec<f64> = out.outcomes[c]
                    .iter()
                    .filter_map(|run| run.get(ni).and_then(|o| o.get(m)))
                    .filter(|o| o.theta.is_some())
                    .map(|o| o.param_error)
                    .collect();
                a.estimated.push(errors.len());
                a.median.push(study::median(errors));
            }
            estimators.insert(name.to_string(), a);
        }
        cases.insert(case.name.clone(), estimators);
    }
    cases
}

/// Writes results.json and every figure; one entry per file, written or not.
fn write_outputs(model: &dyn Model, report: &Report, dir: &Path) -> Vec<Result<PathBuf, Problem>> {
    if let Err(e) = std::fs::create_dir_all(dir) {
        return vec![Err(Problem::error(
            "io",
            format!(
                "cannot create the output directory `{}`: {e}",
                dir.display()
            ),
        )
        .at(dir.display().to_string())
        .help("choose another directory with --out DIR"))];
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
    std::fs::write(path, format!("{text}\n")).map_err(|e| {
        Problem::error("io", format!("cannot write `{}`: {e}", path.display()))
            .at(path.display().to_string())
    })?;
    Ok(path.to_path_buf())
}
