//! Compile time of the paper's ship: parse + resolve + expand + exact
//! identifiability (required-experiment search included). SPEC §8: < 10 ms.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const SHIP: &str = include_str!("../../examples/models/ship.som");
const SHIP_IV2: &str = include_str!("../../examples/models/ship_iv2.som");

fn compile(c: &mut Criterion) {
    let options = leeway_structure::CompileOptions::default();
    c.bench_function("compile ship.som", |b| {
        b.iter(|| leeway_structure::compile(black_box(SHIP), &options))
    });
    let aggregate = leeway_structure::CompileOptions {
        aggregate: true,
        ..Default::default()
    };
    c.bench_function("compile ship_iv2.som --aggregate", |b| {
        b.iter(|| leeway_structure::compile(black_box(SHIP_IV2), &aggregate))
    });
    c.bench_function("parse ship.som", |b| {
        b.iter(|| leeway_structure::grammar::parse(black_box(SHIP)))
    });
}

criterion_group!(benches, compile);
criterion_main!(benches);
