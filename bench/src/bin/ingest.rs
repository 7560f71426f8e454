//! Times reading a data file the way the CLI does: opened for streaming
//! (the validating pass writing the spill file, `open_file`) and loaded
//! into memory (`load_file_noted`), best of K runs each, beside the same
//! with the exact CSV reader alone (`Records`, what every CSV file went
//! through before the parallel reader). Prints wall time, CPU time (user +
//! system, from `/proc/self/stat` where there is one, in 10 ms ticks) and
//! MB/s of the file, to set beside pandas' `read_csv`.
//!
//! `cargo run --release -p leeway-bench --bin ingest -- FILE.csv [MODEL.som] [K]`
//! (the model defaults to examples/models/ship.som, K to 3).

use leeway::Source;
use leeway::data::{LoadOptions, Records, load_file_noted, load_table, open_file, open_table};
use leeway::ir::Ir;
use leeway_bench::cpu_seconds;
use std::path::Path;
use std::time::Instant;

/// One way of reading the file: the rows read, or why not.
type Reading<'a> = Box<dyn FnMut() -> Result<usize, String> + 'a>;

/// Best wall and CPU seconds of `runs` runs of `f`.
fn best(
    runs: usize,
    f: &mut dyn FnMut() -> Result<usize, String>,
) -> Result<(f64, Option<f64>, usize), String> {
    let mut wall = f64::INFINITY;
    let mut cpu: Option<f64> = None;
    let mut rows = 0;
    for _ in 0..runs {
        let (c0, t0) = (cpu_seconds(), Instant::now());
        rows = f()?;
        let w = t0.elapsed().as_secs_f64();
        wall = wall.min(w);
        if let (Some(a), Some(b)) = (c0, cpu_seconds()) {
            cpu = Some(cpu.map_or(b - a, |c: f64| c.min(b - a)));
        }
    }
    Ok((wall, cpu, rows))
}

fn run(args: &[String]) -> Result<(), String> {
    let file = args
        .first()
        .ok_or("usage: ingest FILE.csv [MODEL.som] [K]")?;
    let model = args
        .get(1)
        .map_or("examples/models/ship.som", String::as_str);
    let runs: usize = args
        .get(2)
        .map_or(Ok(3), |k| k.parse())
        .map_err(|e| format!("K: {e}"))?;
    let source = std::fs::read_to_string(model).map_err(|e| format!("{model}: {e}"))?;
    let compiled = leeway::compile(&source, &leeway::CompileOptions::default());
    let ir: Ir = compiled
        .ir
        .ok_or_else(|| format!("{model} does not compile"))?;
    let path = Path::new(file);
    let bytes = std::fs::metadata(path)
        .map_err(|e| format!("{file}: {e}"))?
        .len();
    let options = LoadOptions::default();
    let rows_of = |f: &leeway::data::StreamedFile| f.sources.iter().map(|s| s.block().rows).sum();
    let rows_held = |f: &leeway::data::LoadedFile| f.experiments.iter().map(|e| e.len()).sum();
    let err = |e: leeway::DataError| e.to_string();
    let cases: Vec<(&str, Reading)> = vec![
        (
            "stream (validate + spill)",
            Box::new(|| {
                open_file(path, &ir, &options)
                    .map(|f| rows_of(&f))
                    .map_err(err)
            }),
        ),
        (
            "load into memory",
            Box::new(|| {
                load_file_noted(path, &ir, &options)
                    .map(|f| rows_held(&f))
                    .map_err(err)
            }),
        ),
        (
            "stream, exact reader only",
            Box::new(|| {
                open_table(
                    &mut Records::open(path, "--data").map_err(err)?,
                    &ir,
                    &options,
                )
                .map(|f| rows_of(&f))
                .map_err(err)
            }),
        ),
        (
            "load, exact reader only",
            Box::new(|| {
                load_table(
                    &mut Records::open(path, "--data").map_err(err)?,
                    &ir,
                    &options,
                )
                .map(|f| rows_held(&f))
                .map_err(err)
            }),
        ),
    ];
    println!("{file}: {:.1} MB, best of {runs}", bytes as f64 / 1e6);
    for (name, mut f) in cases {
        let (wall, cpu, rows) = best(runs, &mut *f)?;
        let cpu = cpu.map_or("n/a".to_string(), |c| format!("{c:.2} s"));
        println!(
            "{name:<28} {rows} rows  wall {wall:.3} s  cpu {cpu}  {:.0} MB/s",
            bytes as f64 / 1e6 / wall
        );
    }
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Err(e) = run(&args) {
        eprintln!("ingest: {e}");
        std::process::exit(1);
    }
}
