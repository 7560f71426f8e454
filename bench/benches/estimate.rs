//! One estimate of the ship at N = 5000 (paper §V data, 10 m/s wind), each
//! method, with and without standard errors (the covariance pass), with the
//! generated model (`include_model!`) and the interpreter. IV estimates
//! include the refinement (re-simulation until the instruments settle).
//!
//! After each group a table gives, per estimate, N, the moment passes
//! (refinements + 1; the covariance pass is not counted), the FLOP of the
//! moment sums (`leeway_bench::moment_flops`), the median time over
//! criterion's samples, and the rate achieved against the core's peak.
//!
//! `cargo bench -p leeway-bench --bench estimate` (about two minutes; a
//! filter such as `-- iv3` runs one method).

use criterion::{Criterion, criterion_group, criterion_main};
use leeway::estimate::EstimateOptions;
use leeway::estimate::Method;
use leeway::estimate::estimate;
use leeway::model::Source;
use leeway::{Interpreter, Model};
use leeway_bench::{flop_line, kept_columns, moment_flops};
use leeway_scenarios::study;
use std::cell::RefCell;
use std::hint::black_box;
use std::time::{Duration, Instant};

leeway::include_model!("../../examples/models/ship.som");

const N: usize = 5000;

/// Per-iteration times of every sample criterion took, for the table.
type Times = RefCell<Vec<f64>>;

fn median(times: &Times) -> f64 {
    let mut t = times.borrow().clone();
    t.sort_by(f64::total_cmp);
    t.get(t.len() / 2).copied().unwrap_or(f64::NAN)
}

fn bench(c: &mut Criterion) {
    let generated = Ship;
    let interpreted = Interpreter::new(generated.ir().clone());
    let ir = generated.ir();
    let (data, _) = study::estimation_experiment(&generated, &Default::default(), 10.0, N, 1);
    let record = [&data as &dyn Source];
    let mut group = c.benchmark_group("estimate-ship-5000");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let mut lines = Vec::new();
    for method in Method::ALL {
        let kind = method.predictor();
        let flops = moment_flops(ir, kind, &kept_columns(ir, kind, &data));
        for covariance in [true, false] {
            let options = EstimateOptions {
                method,
                aggregate: true,
                covariance,
                ..EstimateOptions::default()
            };
            let passes = estimate(&generated, &record, &options)
                .map(|e| e.diagnostics.refinements + 1)
                .unwrap_or(0);
            let se = if covariance { "se" } else { "no-se" };
            let models: [(&str, &dyn Model); 2] =
                [("generated", &generated), ("interpreted", &interpreted)];
            for (name, model) in models {
                let times = Times::default();
                let id = format!("{}/{se}/{name}", method.name());
                group.bench_function(&id, |b| {
                    b.iter_custom(|iters| {
                        let start = Instant::now();
                        for _ in 0..iters {
                            black_box(estimate(model, &record, &options).map(|e| e.theta).ok());
                        }
                        let elapsed = start.elapsed();
                        times
                            .borrow_mut()
                            .push(elapsed.as_secs_f64() / iters.max(1) as f64);
                        elapsed
                    })
                });
                // Skipped by a filter: nothing timed, nothing to report.
                if !times.borrow().is_empty() {
                    lines.push(flop_line(&id, N, passes, flops, median(&times)));
                }
            }
        }
    }
    group.finish();
    println!("\nmoment sums of one estimate (ship, N = {N}, 10 m/s wind):");
    for line in lines {
        println!("  {line}");
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
