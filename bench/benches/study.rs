//! The phases of one run of the study (`leeway reproduce`), with the ship
//! compiled in as `reproduce` has it, at the default settings: the high-wind
//! case (10 m/s), run 0 of seed 2024, N = 1000 … 5000.
//!
//! * `simulate-record`: the estimation record, simulated once at the largest
//!   N (`study::estimation_experiment`);
//! * `estimate/<method>`: one estimate at each N with the study's options
//!   (`study::study_options`: refined IV, aggregated, no standard errors);
//! * `validate`: the validation record simulated with one estimate and its
//!   fit (`simulate::simulate`, `simulate::fits` on
//!   `study::validation_experiment`), as the study does for every estimate
//!   (20 per run: 5 N × 4 methods).
//!
//! A table after the group gives the moment sums' FLOP of each method's
//! estimates beside their median time. One run of the whole study costs
//! about `simulate-record + Σ estimate + 20 × validate`.
//!
//! `cargo bench -p leeway-bench --bench study` (under a minute).

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, criterion_group, criterion_main};
use leeway::estimate::Method;
use leeway::estimate::estimate;
use leeway::model::Source;
use leeway::model::simulate::Disturbances;
use leeway::model::simulate::fits;
use leeway::model::simulate::simulate;
use leeway::{Experiment, Model};
use leeway_bench::{kept_columns, moment_flops, rate};
use leeway_scenarios::study;
use leeway_scenarios::study::StudyConfig;
use std::cell::RefCell;
use std::hint::black_box;
use std::time::{Duration, Instant};

leeway::include_model!("../../examples/models/ship.som");

/// Per-iteration times of every sample criterion took, for the table.
type Times = RefCell<Vec<f64>>;

fn median(times: &Times) -> f64 {
    let mut t = times.borrow().clone();
    t.sort_by(f64::total_cmp);
    t.get(t.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Times `f` under `id` and keeps criterion's per-iteration times.
fn timed<F: FnMut()>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: &str,
    mut f: F,
) -> Times {
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
    times
}

/// Every method's estimates at every N, timed, with their passes and FLOP
/// in `report`; the θ of IV1… estimated on the whole record, for the
/// validation's timing.
fn bench_estimates(
    group: &mut BenchmarkGroup<'_, WallTime>,
    records: &[Experiment],
    data: &Experiment,
    config: &StudyConfig,
    report: &mut Vec<String>,
) -> Option<Vec<f64>> {
    let model = Ship;
    let ir = model.ir();
    let mut theta = None;
    for method in Method::ALL {
        let options = study::study_options(method, config.max_refinements, config.paper_iv);
        // Moment passes and FLOP per record, from one untimed estimate each.
        let kind = method.predictor();
        let work: Vec<(usize, usize, u64)> = records
            .iter()
            .map(|r| {
                let passes = estimate(&model, &[r as &dyn Source], &options)
                    .map(|e| e.diagnostics.refinements + 1)
                    .unwrap_or(0);
                (
                    r.len(),
                    passes,
                    moment_flops(ir, kind, &kept_columns(ir, kind, r)),
                )
            })
            .collect();
        if theta.is_none() {
            theta = estimate(&model, &[data as &dyn Source], &options)
                .ok()
                .map(|e| e.theta);
        }
        let id = format!("estimate/{}", method.name());
        let t = timed(group, &id, || {
            for r in records {
                black_box(estimate(&model, &[r as &dyn Source], &options).ok());
            }
        });
        if !t.borrow().is_empty() {
            // One line for the method's estimates at every N.
            let sample_passes: usize = work.iter().map(|(n, p, _)| n * p).sum();
            let flop: u64 = work.iter().map(|(n, p, f)| (*n * *p) as u64 * f).sum();
            let passes: Vec<String> = work.iter().map(|(n, p, _)| format!("{n}:{p}")).collect();
            report.push(format!(
                "{id:<16} {sample_passes:>6} samples × passes  {}",
                rate(flop as f64, median(&t))
            ));
            report.push(format!("    passes at each N: {}", passes.join(" ")));
        }
    }

    theta
}

fn bench(c: &mut Criterion) {
    let model = Ship;
    let config = StudyConfig::default();
    let Some(index) = config.cases.iter().position(|c| c.name == "high") else {
        return;
    };
    let case = &config.cases[index];
    let n_max = config.n.iter().copied().max().unwrap_or(0);
    let seed = study::run_seed(config.seed, case, 0);
    let (data, _) = study::estimation_experiment(&model, &config.design, case.wind, n_max, seed);
    let validation = study::validation_experiment(&model, config.validation_len);
    let records: Vec<_> = config.n.iter().map(|&n| data.truncated(n)).collect();

    let mut group = c.benchmark_group("study-run");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    let mut report = Vec::new();

    let t = timed(&mut group, "simulate-record", || {
        black_box(study::estimation_experiment(
            &model,
            &config.design,
            case.wind,
            n_max,
            seed,
        ));
    });
    if !t.borrow().is_empty() {
        report.push(format!(
            "{:<16} {:>8.3} ms",
            "simulate-record",
            median(&t) * 1e3
        ));
    }

    // The whole run as the study makes it: every method at every N, warm
    // starts, passes shared between methods and continued along the
    // prefixes, each estimate validated.
    let t = timed(&mut group, "run", || {
        black_box(study::study_run(&model, &config, &validation, index, 0));
    });
    if !t.borrow().is_empty() {
        report.push(format!("{:<16} {:>8.3} ms", "run", median(&t) * 1e3));
    }

    let theta = bench_estimates(&mut group, &records, &data, &config, &mut report);
    if let Some(theta) = theta {
        let t = timed(&mut group, "validate", || {
            let sim = simulate(&model, &theta, &validation, Disturbances::None);
            black_box(fits(&validation, &sim));
        });
        if !t.borrow().is_empty() {
            report.push(format!("{:<16} {:>8.3} ms", "validate", median(&t) * 1e3));
        }
    }
    group.finish();
    println!(
        "\none run of the study (case {}, N = {:?}; moment sums' FLOP of the estimates at every N):",
        case.name, config.n
    );
    for line in report {
        println!("  {line}");
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
