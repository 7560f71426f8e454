//! Regressor evaluation of the ship, generated (`include_model!`) vs
//! interpreted (`Interpreter`), per predictor, and one simulation step
//! (`rhs` and the update). Each iteration evaluates a batch of `BATCH`
//! different samples, so the time per sample is the reported time divided
//! by `BATCH` (criterion also reports the throughput).
//!
//! `cargo bench -p leeway-bench --bench regressors`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use leeway::ir::PredictorKind;
use leeway::{Interpreter, Model};
use leeway_bench::Sample;
use std::hint::black_box;
use std::time::Duration;

leeway::include_model!("../../examples/models/ship.som");

const BATCH: usize = 1000;

fn run(
    model: &impl Model,
    kind: PredictorKind,
    samples: &[Sample],
    signs: &[f64],
    out: &mut [f64],
) {
    for s in samples {
        let sig = s.signals();
        match kind {
            PredictorKind::Basic => model.basic(black_box(&sig), out),
            PredictorKind::Augmented => model.augmented(black_box(&sig), black_box(signs), out),
            PredictorKind::Measured => model.measured(black_box(&sig), black_box(signs), out),
        }
        black_box(&mut *out);
    }
}

fn regressors(c: &mut Criterion) {
    let interpreter = Interpreter::new(Ship.ir().clone());
    let samples = leeway_bench::samples(&Ship, BATCH);
    let signs = vec![1.0; Ship::SIGN_ARGS.len()];
    let mut out = vec![
        0.0;
        Ship::AUGMENTED_LEN
            .max(Ship::MEASURED_LEN)
            .max(Ship::BASIC_LEN)
    ];
    for (name, kind) in [
        ("basic", PredictorKind::Basic),
        ("augmented", PredictorKind::Augmented),
        ("measured", PredictorKind::Measured),
    ] {
        let mut group = c.benchmark_group(format!("ship/{name}"));
        group
            .throughput(Throughput::Elements(BATCH as u64))
            .sample_size(20)
            .measurement_time(Duration::from_secs(2));
        group.bench_function("generated", |b| {
            b.iter(|| run(&Ship, kind, &samples, &signs, &mut out))
        });
        group.bench_function("interpreted", |b| {
            b.iter(|| run(&interpreter, kind, &samples, &signs, &mut out))
        });
        group.finish();
    }
    let theta = vec![0.3; Ship::PARAMETERS.len()];
    let mut group = c.benchmark_group("ship/step");
    group
        .throughput(Throughput::Elements(BATCH as u64))
        .sample_size(20)
        .measurement_time(Duration::from_secs(2));
    group.bench_function("generated", |b| {
        b.iter(|| step(&Ship, &samples, &theta, &mut out))
    });
    group.bench_function("interpreted", |b| {
        b.iter(|| step(&interpreter, &samples, &theta, &mut out))
    });
    group.finish();
}

/// One simulation step per sample (`h` = 1): `rhs`, then `x⁺ = x + h f`.
fn step(model: &impl Model, samples: &[Sample], theta: &[f64], out: &mut [f64]) {
    let n = Ship::STATES.len();
    let (f, next) = out.split_at_mut(n);
    for s in samples {
        let sig = s.signals();
        model.step(black_box(theta), 1.0, black_box(&sig), f, next);
        black_box(&mut *next);
    }
}

criterion_group!(benches, regressors);
criterion_main!(benches);
