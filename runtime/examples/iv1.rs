//! Exploration: IV1 with zero-mean vs non-zero-mean disturbances.
#![allow(clippy::unwrap_used)] // an exploration script: a panic is its error report
use leeway_runtime::estimate::{Method, Options, estimate};
use leeway_runtime::{Interpreter, Source, study, synth};
fn main() {
    let src = std::fs::read_to_string("examples/models/ship.som").unwrap();
    let model = Interpreter::new(
        leeway_runtime::structure::compile(&src, &Default::default())
            .ir
            .unwrap(),
    );
    for mean in [0.0, 0.2] {
        for n in [1000usize, 4000, 16000] {
            let mut errs = vec![];
            for seed in 0..4u64 {
                let mut sys = study::true_system(0.0);
                sys.disturbance_mean = vec![mean, mean, 0.0, 0.0];
                let input = study::estimation_input(&study::InputDesign::default(), n, seed + 99);
                let (e, _) = synth::experiment(
                    &model,
                    &sys,
                    "x",
                    &study::InputDesign::default().x0,
                    0.0,
                    &input,
                    seed,
                );
                for m in [Method::Iv1, Method::Iv3, Method::Ls] {
                    let r = estimate(
                        &model,
                        &[&e as &dyn Source],
                        &Options {
                            method: m,
                            aggregate: true,
                            covariance: false,
                            ..Default::default()
                        },
                    );
                    let err = r
                        .map(|est| {
                            est.theta
                                .iter()
                                .zip(&study::THETA0)
                                .enumerate()
                                .filter(|(i, _)| ![3usize, 9, 15].contains(i))
                                .map(|(_, (a, b))| ((a - b) / b).abs())
                                .sum::<f64>()
                                / 14.0
                        })
                        .unwrap_or(f64::NAN);
                    errs.push((m, err));
                }
            }
            for m in [Method::Iv1, Method::Iv3, Method::Ls] {
                let v: Vec<f64> = errs
                    .iter()
                    .filter(|(mm, _)| *mm == m)
                    .map(|(_, e)| *e)
                    .collect();
                println!(
                    "mean {mean} N {n} {m:?}: {:?}",
                    v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>()
                );
            }
        }
    }
}
