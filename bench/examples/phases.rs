//! Throwaway: the study's phases on 10 runs per case, one thread: record
//! simulation, estimation per method (time, refinements), validation.
use leeway::runtime::Source;
use leeway::runtime::estimate::{Method, estimate};
use leeway::runtime::simulate::{Disturbances, fits, simulate};
use leeway::runtime::study;
use std::time::Instant;

leeway::include_model!("../../examples/models/ship.som");

fn main() {
    let model = Ship;
    let config = study::StudyConfig::default();
    let runs: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10);
    let validation = study::validation_experiment(&model, config.validation_len);
    let (mut t_sim, mut t_val) = (0.0, 0.0);
    let mut t_est = [0.0f64; 4];
    let mut refinements = [0usize; 4];
    let mut count = 0usize;
    for case in &config.cases {
        for r in 0..runs {
            let t0 = Instant::now();
            let (data, _) = study::estimation_experiment(
                &model,
                &config.design,
                case.wind,
                5000,
                study::run_seed(config.seed, case, r),
            );
            t_sim += t0.elapsed().as_secs_f64();
            #[allow(unused_mut)]
            let mut starts: Vec<Option<leeway::runtime::estimate::Start>> = vec![None; 4];
            for &n in &config.n {
                let d = data.truncated(n);
                count += 1;
                for (i, m) in Method::ALL.iter().enumerate() {
                    let options = leeway::runtime::estimate::Options {
                        start: starts[i].take(),
                        ..study::study_options(*m, 8, false)
                    };
                    let t0 = Instant::now();
                    let e = estimate(&model, &[&d as &dyn Source], &options);
                    t_est[i] += t0.elapsed().as_secs_f64();
                    if let Ok(e) = e {
                        refinements[i] += e.diagnostics.refinements;
                        if e.diagnostics.converged {
                            starts[i] = Some(leeway::runtime::estimate::Start::from_estimate(
                                leeway::Model::ir(&model),
                                &e,
                            ));
                        }
                        let t0 = Instant::now();
                        let sim = simulate(&model, &e.theta, &validation, Disturbances::None);
                        let _ = fits(&validation, &sim);
                        t_val += t0.elapsed().as_secs_f64();
                    }
                }
            }
        }
    }
    println!("record simulation {:8.1} ms", t_sim * 1e3);
    for (i, m) in Method::ALL.iter().enumerate() {
        println!(
            "estimate {:4}     {:8.1} ms  ({:.3} ms/estimate, {:.2} refinements)",
            m.name(),
            t_est[i] * 1e3,
            t_est[i] * 1e3 / count as f64,
            refinements[i] as f64 / count as f64
        );
    }
    println!("validation        {:8.1} ms", t_val * 1e3);
    println!(
        "total             {:8.1} ms",
        (t_sim + t_val + t_est.iter().sum::<f64>()) * 1e3
    );
}
