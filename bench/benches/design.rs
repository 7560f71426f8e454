//! `leeway design`'s phases on the ROV (two experiments, 600 s each at
//! 20 Hz) and on a generated craft of 20 states and 20 held signs:
//!
//! * `design/<model>`: the whole design with the estimator's asymptotic
//!   errors (`pilot 0`: patterns, operating points, four families fitted
//!   and scored);
//! * `pilot/<model>`: the same with 20 pilot trials (the default is 100:
//!   the pilot's cost is linear in its trials);
//! * `verify/<model>`: 10 Monte Carlo trials of the design (every method
//!   estimated and validated), on the pool's threads.
//!
//! `cargo bench -p leeway-bench --bench design` (a few minutes).

use criterion::{Criterion, criterion_group, criterion_main};
use leeway::{Interpreter, Model};
use leeway_design::design::{DesignOptions, design};
use leeway_design::plan::parse;
use leeway_design::verify::verify;
use std::hint::black_box;
use std::time::Duration;

fn rov() -> (Interpreter, String) {
    let model = include_str!("../../examples/models/rov.som");
    let plan = include_str!("../../examples/plans/rov.toml");
    (compile(model), plan.to_string())
}

/// The `states 20 current` model of `gen-model`, with a stable nominal θ.
fn states20() -> (Interpreter, String) {
    let source = leeway_bench::models::many_states(20, true);
    let mut plan = String::from("step = 0.1\n[nominal]\n");
    for i in 0..20 {
        plan.push_str(&format!("A{i} = -0.5\nD{i} = -0.1\nB{i} = 0.1\n"));
    }
    for i in 0..20 {
        plan.push_str(&format!("[inputs.t{i}]\nrange = [-10, 10]\n"));
    }
    plan.push_str("[disturbances.current]\nmean = 0.1\nstd = 0.02\n[budget]\nsamples = 3000\n");
    (compile(&source), plan)
}

fn compile(source: &str) -> Interpreter {
    let c = leeway::compile(source, &Default::default());
    match c.ir {
        Some(ir) => Interpreter::new(ir),
        None => panic!("the bench's model compiles: {:?}", c.diagnostics),
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("design");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    for (name, (model, plan)) in [("rov", rov()), ("states20", states20())] {
        let conditions = match parse(&plan, false).and_then(|p| p.conditions(model.ir())) {
            Ok(c) => c,
            Err(e) => panic!("{name}: {e:?}"),
        };
        for (phase, pilot) in [("design", 0), ("pilot", 20)] {
            let options = DesignOptions {
                pilot,
                ..Default::default()
            };
            group.bench_function(format!("{phase}/{name}"), |b| {
                b.iter(|| black_box(design(&model, &conditions, &options).map(|d| d.feasible)))
            });
        }
        let options = DesignOptions {
            pilot: 0,
            ..Default::default()
        };
        let Ok(d) = design(&model, &conditions, &options) else {
            panic!("{name}: no design");
        };
        group.bench_function(format!("verify/{name}"), |b| {
            b.iter(|| black_box(verify(&model, &d, 10, 0, &|| ()).map(|v| v.runs)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
