//! What compiled model code buys a streamed estimate, end to end: the ship
//! (`examples/models/ship.som`) estimated from data files as `leeway
//! estimate` streams them, once with the model generated at compile time
//! (`include_model!`) and once with the interpreter the CLI uses for a
//! `.som` file read at run time, alternating, best of K each. Both give the
//! same bits (checked); only the time differs.
//!
//! The files are opened (validated and spilled) and checked once, as the
//! CLI does, and those phases' times printed beside; they do not depend on
//! the model's code.
//!
//! `cargo run --release -p leeway-bench --bin generated -- [--only MODEL] METHOD K FILE...`
//! (METHOD `ls`, `iv1`, `iv2` or `iv3`; all with `--aggregate` and standard
//! errors, as `bench/scale.py` runs the CLI). `--only generated` or `--only
//! interpreted` runs one of the two, for a profiler.

use leeway::data::{LoadOptions, open_file};
use leeway::estimate::{EstimateOptions, Method, estimate};
use leeway::model::Source;
use leeway::report::checks::data_checks;
use leeway::{Interpreter, Model};
use leeway_bench::cpu_seconds;
use std::path::Path;
use std::time::Instant;

leeway::include_model!("../../../examples/models/ship.som");

/// Wall and CPU seconds of `f`, with its result.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, Option<f64>) {
    let (c0, t0) = (cpu_seconds(), Instant::now());
    let out = f();
    let wall = t0.elapsed().as_secs_f64();
    let cpu = c0.zip(cpu_seconds()).map(|(a, b)| b - a);
    (out, wall, cpu)
}

fn seconds(cpu: Option<f64>) -> String {
    cpu.map_or("n/a".to_string(), |c| format!("{c:.2} s"))
}

fn run(mut args: &[String]) -> Result<(), String> {
    let usage = "usage: generated [--only MODEL] METHOD K FILE...";
    let mut only = None;
    if let [flag, model, rest @ ..] = args
        && flag == "--only"
    {
        only = Some(model.as_str());
        args = rest;
    }
    let method = Method::ALL
        .into_iter()
        .find(|m| Some(m.name()) == args.first().map(String::as_str))
        .ok_or(usage)?;
    let runs: usize = args
        .get(1)
        .ok_or(usage)?
        .parse()
        .map_err(|e| format!("K: {e}"))?;
    let files = args.get(2..).filter(|f| !f.is_empty()).ok_or(usage)?;
    let generated = Ship;
    let interpreted = Interpreter::new(generated.ir().clone());
    let ir = generated.ir();
    let (opened, wall, cpu) = timed(|| {
        files
            .iter()
            .map(|f| open_file(Path::new(f), ir, &LoadOptions::default()))
            .collect::<Result<Vec<_>, _>>()
    });
    let opened = opened.map_err(|e| e.to_string())?;
    println!(
        "opening {} file(s): wall {wall:.3} s, cpu {}",
        files.len(),
        seconds(cpu)
    );
    let sources: Vec<&dyn Source> = opened
        .iter()
        .flat_map(|f| f.sources.iter().map(|s| s as &dyn Source))
        .collect();
    let (_, wall, cpu) = timed(|| data_checks(ir, &sources));
    println!("the data checks: wall {wall:.3} s, cpu {}", seconds(cpu));
    let options = EstimateOptions {
        method,
        aggregate: true,
        ..EstimateOptions::default()
    };
    let models: [(&str, &dyn Model); 2] =
        [("generated", &generated), ("interpreted", &interpreted)];
    if let Some(name) = only {
        let (_, model) = models
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| format!("--only {name}: `generated` or `interpreted`"))?;
        for _ in 0..runs {
            let (est, wall, cpu) = timed(|| estimate(*model, &sources, &options));
            let est = est.map_err(|e| format!("{name}: {e}"))?;
            println!(
                "{name}: wall {wall:.3} s, cpu {}, θ: {:?}",
                seconds(cpu),
                est.theta.as_slice()
            );
        }
        return Ok(());
    }
    let mut best = [(f64::INFINITY, f64::INFINITY); 2];
    let mut thetas: [Vec<f64>; 2] = Default::default();
    for _ in 0..runs {
        for (i, (name, model)) in models.iter().enumerate() {
            let (est, wall, cpu) = timed(|| estimate(*model, &sources, &options));
            let est = est.map_err(|e| format!("{name}: {e}"))?;
            println!(
                "{} estimate, {name:<11}: wall {wall:.3} s, cpu {}, refinements {}",
                method.name(),
                seconds(cpu),
                est.diagnostics.refinements
            );
            best[i] = (best[i].0.min(wall), best[i].1.min(cpu.unwrap_or(f64::NAN)));
            thetas[i] = est.theta.as_slice().to_vec();
        }
    }
    let [theta, interpreted_theta] = thetas;
    let bits = |t: &[f64]| t.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let same = bits(&theta) == bits(&interpreted_theta);
    println!(
        "best of {runs}: generated wall {:.3} s cpu {:.2} s; interpreted wall {:.3} s cpu {:.2} s; \
         interpreted / generated {:.2} (wall); θ {}",
        best[0].0,
        best[0].1,
        best[1].0,
        best[1].1,
        best[1].0 / best[0].0,
        if same { "bit-identical" } else { "DIFFERS" }
    );
    if !same {
        return Err("the two models' estimates differ".into());
    }
    // In full, to set beside the `theta` of `leeway estimate --json`.
    println!("θ: {theta:?}");
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Err(e) = run(&args) {
        eprintln!("generated: {e}");
        std::process::exit(1);
    }
}
