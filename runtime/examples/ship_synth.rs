//! Exploration: the study's synthetic ship data, all four estimators.
#![allow(clippy::unwrap_used)] // an exploration script: a panic is its error report
use leeway_runtime::estimate::{Method, Options, estimate};
use leeway_runtime::simulate::{Disturbances, fits, simulate};
use leeway_runtime::{Interpreter, Source, study};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(5000);
    let wind: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let verbose = args.iter().any(|a| a == "-v");
    let src = std::fs::read_to_string("examples/models/ship.som").unwrap();
    let ir = leeway_runtime::structure::compile(&src, &Default::default())
        .ir
        .unwrap();
    let model = Interpreter::new(ir);
    let (e, _) =
        study::estimation_experiment(&model, &study::InputDesign::default(), wind, n, seed);
    let val = study::validation_experiment(&model, 1000);
    for m in Method::ALL {
        let delayed = args.iter().any(|a| a == "--delayed");
        let opts = Options {
            method: m,
            aggregate: true,
            instruments: if delayed {
                leeway_runtime::Instruments::Delayed
            } else {
                leeway_runtime::Instruments::Simulated
            },
            ..Options::default()
        };
        let t = std::time::Instant::now();
        match estimate(&model, &[&e as &dyn Source], &opts) {
            Ok(est) => {
                let el = t.elapsed();
                let sim = simulate(&model, &est.theta, &val, Disturbances::None);
                let f = fits(&val, &sim);
                let rel: f64 = est
                    .theta
                    .iter()
                    .zip(&study::THETA0)
                    .map(|(a, b)| ((a - b) / b).abs())
                    .sum::<f64>()
                    / 17.0;
                println!(
                    "{m:?}: {el:?} fit {:.1} {:.1} {:.1} rel {:.3} ref {} conv {} cond {:.1e}",
                    f[0],
                    f[1],
                    f[2],
                    rel,
                    est.diagnostics.refinements,
                    est.diagnostics.converged,
                    est.diagnostics.condition_number
                );
                if verbose {
                    for (i, p) in est.parameters.iter().enumerate() {
                        print!(
                            "{}={:.5}({:.1e}) ",
                            p,
                            est.theta[i],
                            est.std_errors[i].unwrap_or(f64::NAN)
                        );
                    }
                    println!();
                    for w in &est.warnings {
                        println!("  warn: {}", &w[..w.len().min(200)]);
                    }
                }
                for d in &est.disturbances {
                    println!(
                        "  {} {} = {:.4} ± {:.4}",
                        d.disturbance,
                        d.component,
                        d.mean,
                        d.std_error.unwrap_or(f64::NAN)
                    );
                }
            }
            Err(e) => println!("{m:?}: error {} ({})", e.message, e.hint),
        }
    }
}
