//! The arguments of `leeway reproduce` and their bounds.

use leeway_scenarios::study;
use leeway_scenarios::study::{Case, StudyConfig};
use std::path::PathBuf;

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
        default_value = "1000,2000,3000,4000,5000",
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

/// `--runs` × the largest `--n` within [`MAX_WORK`]: the message naming both
/// options (`main` reports it in clap's words, before any work starts).
pub fn check_work(args: &ReproduceArgs) -> Result<(), String> {
    let largest = args.n.iter().copied().max().unwrap_or(0);
    let work = args.runs.saturating_mul(largest);
    if work > MAX_WORK {
        return Err(format!(
            "--runs {} with --n up to {largest} is {work} samples per case; at most {MAX_WORK} (lower --runs or the largest --n)",
            args.runs
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
