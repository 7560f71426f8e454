//! Structure selection against one estimate: the tanker as a candidate
//! model of 40 candidate terms (select/tests/models/candidate-tanker.som)
//! on four long zigzag runs of the synthetic tanker (`leeway_scenarios::
//! zigzag`, the campaign's logger and measurement noise), 10⁵ samples in
//! all:
//!
//! * `estimate/iv3`: one IV3 estimate of the full candidate model (every
//!   candidate kept), with standard errors, `estimate`'s defaults;
//! * `select/iv3`: `leeway_select::select` on the same data (each run held
//!   out in turn for the free-run criterion), the chosen model's estimate
//!   and the missing-term suggestions included.
//!
//! After the group a table gives the median times, their ratio and the
//! passes over the data each one made.
//!
//! `cargo bench -p leeway-bench --bench select` (a few minutes).

use criterion::{Criterion, criterion_group, criterion_main};
use leeway::estimate::{EstimateOptions, estimate};
use leeway::model::Source;
use leeway::{Experiment, Interpreter, Model};
use leeway_scenarios::zigzag;
use leeway_select::{SelectOptions, select};
use std::cell::RefCell;
use std::hint::black_box;
use std::time::{Duration, Instant};

const CANDIDATE_TANKER: &str = include_str!("../../select/tests/models/candidate-tanker.som");

/// Samples of each of the four runs: 10⁵ in all.
const RUN: usize = 25_000;

/// Per-iteration times of every sample criterion took, for the table.
type Times = RefCell<Vec<f64>>;

fn median(times: &Times) -> f64 {
    let mut t = times.borrow().clone();
    t.sort_by(f64::total_cmp);
    t.get(t.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Four zigzag runs of [`RUN`] samples as the campaign logs them
/// (filtered, decimated, with its measurement noise).
fn runs(model: &Interpreter) -> Vec<Experiment> {
    let options = zigzag::CampaignOptions::default();
    let noise = options.noise.unwrap_or_default();
    (0..4)
        .map(|i| {
            let z = zigzag::Zigzag {
                samples: RUN,
                ..zigzag::zigzag_of(&options.tanker, options.seed, "train", i)
            };
            let mut run =
                zigzag::log_run(&options.tanker, &format!("long-{i}"), &z, options.cutoff);
            zigzag::add_noise(&mut run, &noise, zigzag::run_seed(options.seed, "noise", i));
            match run.experiment(model.ir()) {
                Ok(e) => e,
                Err(e) => panic!("{}", e.message),
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let compiled = leeway::compile(CANDIDATE_TANKER, &Default::default());
    let Some(ir) = compiled.ir else {
        panic!("the candidate tanker compiles: {:?}", compiled.diagnostics)
    };
    let model = Interpreter::new(ir);
    let data = runs(&model);
    let sources: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let samples: usize = data.iter().map(|e| e.len()).sum();
    let estimate_options = EstimateOptions::default();
    let select_options = SelectOptions::default();
    let full = match estimate(&model, &sources, &estimate_options) {
        Ok(e) => e,
        Err(e) => panic!("{}", e.message),
    };
    let selection = match select(CANDIDATE_TANKER, &data, &[], &select_options) {
        Ok(s) => s,
        Err(e) => panic!("{}", e.message),
    };
    let mut group = c.benchmark_group("select-tanker-100000");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10));
    let mut timed = |id: &str, f: &mut dyn FnMut()| {
        let times = Times::default();
        group.bench_function(id, |b| {
            b.iter_custom(|iters| {
                let start = Instant::now();
                for _ in 0..iters {
                    f();
                }
                let elapsed = start.elapsed();
                times
                    .borrow_mut()
                    .push(elapsed.as_secs_f64() / iters.max(1) as f64);
                elapsed
            })
        });
        median(&times)
    };
    let t_estimate = timed("estimate/iv3", &mut || {
        black_box(
            estimate(&model, &sources, &estimate_options)
                .map(|e| e.theta)
                .ok(),
        );
    });
    let t_select = timed("select/iv3", &mut || {
        black_box(
            select(CANDIDATE_TANKER, &data, &[], &select_options)
                .map(|s| s.kept)
                .ok(),
        );
    });
    group.finish();
    let p = &selection.passes;
    // A refined IV estimate: the first estimate's pass, one pass per
    // refinement (its simulation and its moment sums in one read), one
    // covariance pass.
    let estimate_passes = |refinements: usize| refinements + 2;
    let full_passes = estimate_passes(full.diagnostics.refinements);
    // Each round estimates the full model and its chosen one; the last
    // round's suggestions read the data twice.
    let select_passes = p.full_estimate_refinements
        + p.free_runs
        + p.chosen_estimate_refinements
        + 4 * p.rounds
        + 2;
    println!(
        "\nselection of {} candidates (kept {}) on {samples} samples in {} runs:",
        selection.candidates.len(),
        selection.kept.len(),
        data.len()
    );
    println!(
        "  estimate/iv3  {:>9.3} s  passes {full_passes:>3} (refinements {})",
        t_estimate, full.diagnostics.refinements
    );
    println!(
        "  select/iv3    {:>9.3} s  passes {select_passes:>3} ({} rounds: full estimates' refinements {}, free runs {}, chosen estimates' refinements {}; suggestions 2)",
        t_select, p.rounds, p.full_estimate_refinements, p.free_runs, p.chosen_estimate_refinements
    );
    println!("  ratio         {:>9.2}", t_select / t_estimate);
}

criterion_group!(benches, bench);
criterion_main!(benches);
