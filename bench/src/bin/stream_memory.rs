//! Streams N synthetic ship samples (paper §V, 10 m/s wind) through one IV3
//! estimate with refinement and standard errors, without ever storing the
//! experiment, and reports time and peak resident memory.
//!
//! `cargo run --release -p leeway-bench --bin stream-memory -- 10000000`
//!
//! `stream-memory write N FILE.csv [SEED]` writes the same N samples as a CSV log
//! (or, with SEED, another record of the same system)
//! instead (row by row, in flat memory), for measuring `leeway estimate` on
//! a file: `/usr/bin/time -v leeway estimate examples/models/ship.som --data FILE.csv`.

use leeway::estimate::EstimateOptions;
use leeway::estimate::Method;
use leeway::estimate::estimate;
use leeway::model::Source;
use leeway_scenarios::study;
use leeway_scenarios::study::InputDesign;
use leeway_scenarios::study::Pulses;
use leeway_scenarios::synth::Stream;

leeway::include_model!("../../../examples/models/ship.som");

/// Peak resident set size in KiB (`VmHWM`), where the platform reports it.
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Writes the stream as CSV, one row per sample, never holding it.
fn write(stream: &Stream, path: &str) -> std::io::Result<()> {
    use std::io::Write;
    let ir = leeway::model::Model::ir(&Ship);
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    let measured: Vec<usize> = (0..ir.components.len())
        .filter(|c| ir.disturbances[ir.components[*c].disturbance].measured)
        .collect();
    let mut header = vec!["time".to_string()];
    header.extend(ir.states.iter().cloned());
    header.push("psi".to_string());
    header.extend(ir.inputs.iter().cloned());
    header.extend(measured.iter().map(|c| ir.components[*c].name.clone()));
    writeln!(out, "{}", header.join(","))?;
    let mut k = 0usize;
    let mut failed = None;
    let mut line = String::new();
    stream.visit(&mut |row| {
        use std::fmt::Write as _;
        line.clear();
        let _ = write!(line, "{:?}", k as f64 * stream.step());
        for v in row.states.iter().chain([&row.heading]).chain(row.inputs) {
            let _ = write!(line, ",{v:?}");
        }
        for c in &measured {
            let _ = write!(line, ",{:?}", row.disturbances[*c]);
        }
        line.push('\n');
        if failed.is_none()
            && let Err(e) = out.write_all(line.as_bytes())
        {
            failed = Some(e);
        }
        k += 1;
    });
    match failed {
        Some(e) => Err(e),
        None => out.flush(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let writing = args.get(1).is_some_and(|a| a == "write");
    let n: usize = args
        .get(if writing { 2 } else { 1 })
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    // `write N FILE SEED`: another record of the same system (a campaign's runs).
    let seed: u64 = args
        .get(4)
        .filter(|_| writing)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let design = InputDesign::default();
    let stream = Stream {
        model: &Ship,
        system: study::true_system(10.0),
        name: format!("stream{n}"),
        x0: design.x0.to_vec(),
        psi0: 0.0,
        n,
        seed: 7 + 2 * seed,
        input: Box::new(move || Box::new(Pulses::new(&InputDesign::default(), 11 + 2 * seed))),
    };
    if writing {
        let path = args.get(3).map_or("stream.csv", String::as_str);
        if let Err(e) = write(&stream, path) {
            eprintln!("cannot write {path}: {e}");
            std::process::exit(2);
        }
        return;
    }
    let before = peak_rss_kib();
    let start = std::time::Instant::now();
    let result = estimate(
        &Ship,
        &[&stream as &dyn Source],
        &EstimateOptions {
            method: Method::Iv3,
            ..EstimateOptions::default()
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
