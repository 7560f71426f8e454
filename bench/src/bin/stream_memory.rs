//! Streams N synthetic ship samples (paper §V, 10 m/s wind) through one IV3
//! estimate with refinement and standard errors, without ever storing the
//! experiment, and reports time and peak resident memory.
//!
//! `cargo run --release -p leeway-bench --bin stream-memory -- 10000000`

use leeway::runtime::Source;
use leeway::runtime::estimate::{Method, Options, estimate};
use leeway::runtime::study::{self, InputDesign, Pulses};
use leeway::runtime::synth::Stream;

leeway::include_model!("../../../examples/models/ship.som");

/// Peak resident set size in KiB (`VmHWM`), where the platform reports it.
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    let design = InputDesign::default();
    let stream = Stream {
        model: &Ship,
        system: study::true_system(10.0),
        name: format!("stream{n}"),
        x0: design.x0.to_vec(),
        psi0: 0.0,
        n,
        seed: 7,
        input: Box::new(move || Box::new(Pulses::new(&InputDesign::default(), 11))),
    };
    let before = peak_rss_kib();
    let start = std::time::Instant::now();
    let result = estimate(
        &Ship,
        &[&stream as &dyn Source],
        &Options {
            method: Method::Iv3,
            ..Options::default()
        },
    );
    let seconds = start.elapsed().as_secs_f64();
    match result {
        Ok(est) => {
            let current: Vec<String> = est
                .disturbances
                .iter()
                .map(|d| {
                    format!(
                        "{} {:.4} ± {:.4}",
                        d.component,
                        d.mean,
                        d.std_error.unwrap_or(f64::NAN)
                    )
                })
                .collect();
            println!(
                "N = {n}: {seconds:.1} s, {} refinements, aggregate error {:.5}, current {}",
                est.diagnostics.refinements,
                study::aggregate_error(&est.theta),
                current.join(", ")
            );
        }
        Err(e) => println!("N = {n}: error {}", e.message),
    }
    println!(
        "peak RSS before {} KiB, after {} KiB",
        before.map_or("?".to_string(), |v| v.to_string()),
        peak_rss_kib().map_or("?".to_string(), |v| v.to_string())
    );
}
