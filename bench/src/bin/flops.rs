//! The arithmetic floor of an estimate on a data file: the moment sums'
//! FLOP per sample and pass (`leeway_bench::moment_flops` over the columns
//! the exact analysis keeps for the file's first experiment), for
//! `bench/scale.py`, which multiplies it by the samples and passes of the
//! timed estimate and divides by the core's peak.
//!
//! `flops MODEL.som DATA.csv|DATA.parquet METHOD [--aggregate]` prints the
//! number and the peak (GFLOP/s) it is compared with.

use leeway::data::load_file_noted;
use leeway::estimate::Method;
use leeway::{CompileOptions, LoadOptions, compile};
use leeway_bench::{PEAK_GFLOPS, kept_columns, moment_flops};
use std::process::ExitCode;

fn run(args: &[String]) -> Result<String, String> {
    let [model, data, method, rest @ ..] = args else {
        return Err("usage: flops MODEL.som DATA METHOD [--aggregate]".into());
    };
    let aggregate = rest.iter().any(|a| a == "--aggregate");
    let method: Method = method
        .parse()
        .map_err(|_| format!("unknown method `{method}`"))?;
    let source = std::fs::read_to_string(model).map_err(|e| format!("{model}: {e}"))?;
    let options = CompileOptions {
        aggregate,
        ..CompileOptions::default()
    };
    let ir = compile(&source, &options)
        .ir
        .ok_or_else(|| format!("{model} does not compile"))?;
    let loaded = load_file_noted(std::path::Path::new(data), &ir, &LoadOptions::default())
        .map_err(|e| e.to_string())?;
    let first = loaded
        .experiments
        .first()
        .ok_or_else(|| format!("{data} holds no experiment"))?;
    let kind = method.predictor();
    let flops = moment_flops(&ir, kind, &kept_columns(&ir, kind, first));
    Ok(format!("{flops} {PEAK_GFLOPS}"))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(line) => {
            println!("{line}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("flops: {e}");
            ExitCode::from(2)
        }
    }
}
