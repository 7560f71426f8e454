//! One estimate of the ship at N = 5000 (paper §V data, 10 m/s wind), each
//! method, with the generated model (`include_model!`) and the interpreter.
//! IV estimates include the refinement (re-simulation until the instruments
//! settle) and the covariance pass (standard errors, current mean).
//!
//! `cargo bench -p leeway-bench --bench estimate`

use criterion::{Criterion, criterion_group, criterion_main};
use leeway::runtime::Source;
use leeway::runtime::estimate::{Method, Options, estimate};
use leeway::runtime::study;
use leeway::{Interpreter, Model};
use std::hint::black_box;

leeway::include_model!("../../examples/models/ship.som");

fn bench(c: &mut Criterion) {
    let generated = Ship;
    let interpreted = Interpreter::new(generated.ir().clone());
    let (data, _) = study::estimation_experiment(&generated, &Default::default(), 10.0, 5000, 1);
    let mut group = c.benchmark_group("estimate-ship-5000");
    group.sample_size(20);
    for method in Method::ALL {
        let options = Options {
            method,
            aggregate: true,
            ..Options::default()
        };
        let refinements = estimate(&generated, &[&data as &dyn Source], &options)
            .map(|e| e.diagnostics.refinements)
            .unwrap_or(0);
        eprintln!("{}: {refinements} refinements", method.name());
        group.bench_function(format!("{}/generated", method.name()), |b| {
            b.iter(|| {
                black_box(estimate(&generated, &[&data as &dyn Source], &options).map(|e| e.theta))
            })
        });
        group.bench_function(format!("{}/interpreted", method.name()), |b| {
            b.iter(|| {
                black_box(
                    estimate(&interpreted, &[&data as &dyn Source], &options).map(|e| e.theta),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
