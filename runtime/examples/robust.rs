//! Robustness of the refined IV over many seeds: failures per start.
#![allow(clippy::unwrap_used)] // an exploration script: a panic is its error report
use leeway_runtime::estimate::{Initial, Method, Options, estimate};
use leeway_runtime::simulate::{Disturbances, fits, simulate};
use leeway_runtime::{Interpreter, Source, study};
fn main() {
    let src = std::fs::read_to_string("examples/models/ship.som").unwrap();
    let m = Interpreter::new(
        leeway_runtime::structure::compile(&src, &Default::default())
            .ir
            .unwrap(),
    );
    let val = study::validation_experiment(&m, 1000);
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2000);
    for wind in [1.0, 10.0] {
        for initial in [Initial::Nominal, Initial::Delayed] {
            for meth in [Method::Iv2, Method::Iv3] {
                let mut bad = 0;
                let mut fitsum = [0.0; 3];
                let mut cnt = 0;
                for seed in 0..30u64 {
                    let (e, _) =
                        study::estimation_experiment(&m, &Default::default(), wind, n, 1000 + seed);
                    let r = estimate(
                        &m,
                        &[&e as &dyn Source],
                        &Options {
                            method: meth,
                            aggregate: true,
                            initial,
                            covariance: false,
                            ..Default::default()
                        },
                    );
                    match r {
                        Ok(est) => {
                            let f = fits(&val, &simulate(&m, &est.theta, &val, Disturbances::None));
                            if f.iter().any(|x| !x.is_finite() || *x < 0.0) {
                                bad += 1
                            } else {
                                for i in 0..3 {
                                    fitsum[i] += f[i];
                                }
                                cnt += 1;
                            }
                        }
                        Err(_) => bad += 1,
                    }
                }
                println!(
                    "wind {wind} {initial:?} {meth:?}: failures {bad}/30; mean fit of the rest {:.1} {:.1} {:.1}",
                    fitsum[0] / cnt as f64,
                    fitsum[1] / cnt as f64,
                    fitsum[2] / cnt as f64
                );
            }
        }
    }
}
