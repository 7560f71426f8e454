//! Generated code against the interpreter, measured in pairs: each round
//! times the generated model and then the interpreter on the same work, back
//! to back, and the figures are quantiles over the rounds. On a machine shared
//! with other jobs a round that was preempted is slow for one side only and
//! lands in the upper quantiles, so the lower quantiles and their ratio hold
//! still where criterion's separate runs drift by tens of percent.
//!
//! ```text
//! cargo run --release -p leeway-bench --bin paired [-- regressors|estimates [ROUNDS]]
//! ```
//!
//! `regressors`: the ship's regressors of each predictor and one simulation
//! step, ns per sample (a batch of 1000 samples per round, 400 rounds); for
//! the regressors also the interpreter's block evaluation
//! (`Interpreter::regressors_block`, 32 samples a call).
//! `estimates`: one estimate of the ship per method at N = 5000 (10 m/s
//! wind, with standard errors), ms (15 rounds); the two models' estimates
//! are checked to be equal. Without an argument, both.

use leeway::estimate::EstimateOptions;
use leeway::estimate::Method;
use leeway::estimate::estimate;
use leeway::ir::PredictorKind;
use leeway::model::Source;
use leeway::{Interpreter, Model, Signals};
use leeway_bench::Sample;
use leeway_scenarios::study;
use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

leeway::include_model!("../../../examples/models/ship.som");

/// Samples per round of the regressor measurements.
const BATCH: usize = 1000;

/// What one round evaluates on every sample.
#[derive(Clone, Copy)]
enum Work {
    Basic,
    Augmented,
    Measured,
    Step,
}

/// Nanoseconds per sample of one round.
fn round(model: &dyn Model, work: Work, samples: &[Sample], out: &mut [f64]) -> f64 {
    let signs = [1.0; Ship::SIGN_ARGS.len()];
    let theta = [0.3; Ship::PARAMETERS.len()];
    let start = Instant::now();
    for s in samples {
        let sig = s.signals();
        let sig = black_box(&sig);
        match work {
            Work::Basic => model.basic(sig, out),
            Work::Augmented => model.augmented(sig, black_box(&signs), out),
            Work::Measured => model.measured(sig, black_box(&signs), out),
            Work::Step => {
                let (f, next) = out.split_at_mut(Ship::STATES.len());
                model.step(black_box(&theta), 1.0, sig, f, next);
            }
        }
        black_box(&mut *out);
    }
    start.elapsed().as_nanos() as f64 / samples.len() as f64
}

/// The `q`-quantile of a sorted list.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q) as usize]
}

/// One line: minimum and lower quartile of each side, and the quartiles' ratio.
fn line(what: &str, unit: &str, mut generated: Vec<f64>, mut interpreted: Vec<f64>) -> String {
    generated.sort_by(f64::total_cmp);
    interpreted.sort_by(f64::total_cmp);
    let (g, i) = (quantile(&generated, 0.25), quantile(&interpreted, 0.25));
    format!(
        "{what:<10} generated min {:>7.2} p25 {g:>7.2} {unit} | interpreted min {:>7.2} p25 {i:>7.2} {unit} | ratio {:.2}",
        quantile(&generated, 0.0),
        quantile(&interpreted, 0.0),
        i / g
    )
}

/// Samples per call of the block evaluation.
const BLOCK: usize = 32;

/// Nanoseconds per sample of one round of the interpreter's block
/// evaluation (`BLOCK` samples per call, sign pattern `+1`).
fn block_round(
    interpreter: &Interpreter,
    kind: PredictorKind,
    samples: &[Sample],
    out: &mut [f64],
) -> f64 {
    let signs = [1.0; Ship::SIGN_ARGS.len() * BLOCK];
    let signals: Vec<Signals> = samples.iter().map(|s| s.signals()).collect();
    let start = Instant::now();
    for block in signals.chunks(BLOCK) {
        let signs = &signs[..block.len() * Ship::SIGN_ARGS.len()];
        interpreter.regressors_block(kind, black_box(block), black_box(signs), out);
        black_box(&mut *out);
    }
    start.elapsed().as_nanos() as f64 / samples.len() as f64
}

fn regressors(rounds: usize) {
    let interpreter = Interpreter::new(Ship.ir().clone());
    let samples = leeway_bench::samples(&Ship, BATCH);
    let mut out = vec![
        0.0;
        Ship::AUGMENTED_LEN
            .max(Ship::MEASURED_LEN)
            .max(2 * Ship::STATES.len())
    ];
    let mut block = vec![0.0; Ship::AUGMENTED_LEN.max(Ship::MEASURED_LEN) * BLOCK];
    println!("ns per sample, {rounds} rounds of {BATCH} samples:");
    for (name, work, kind) in [
        ("basic", Work::Basic, Some(PredictorKind::Basic)),
        ("augmented", Work::Augmented, Some(PredictorKind::Augmented)),
        ("measured", Work::Measured, Some(PredictorKind::Measured)),
        ("step", Work::Step, None),
    ] {
        let (mut g, mut i, mut b) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..rounds {
            g.push(round(&Ship, work, &samples, &mut out));
            i.push(round(&interpreter, work, &samples, &mut out));
            if let Some(kind) = kind {
                b.push(block_round(&interpreter, kind, &samples, &mut block));
            }
        }
        let mut text = line(name, "ns", g.clone(), i);
        if !b.is_empty() {
            b.sort_by(f64::total_cmp);
            g.sort_by(f64::total_cmp);
            text += &format!(
                " | blocks of {BLOCK}: min {:>6.2} p25 {:>6.2} ns, ratio {:.2}",
                quantile(&b, 0.0),
                quantile(&b, 0.25),
                quantile(&b, 0.25) / quantile(&g, 0.25)
            );
        }
        println!("{text}");
    }
}

fn estimates(rounds: usize) -> Result<(), String> {
    let interpreter = Interpreter::new(Ship.ir().clone());
    let (data, _) = study::estimation_experiment(&Ship, &Default::default(), 10.0, 5000, 1);
    let record = [&data as &dyn Source];
    println!("ms per estimate (ship, N = 5000, with standard errors), {rounds} rounds:");
    for method in Method::ALL {
        let options = EstimateOptions {
            method,
            aggregate: true,
            ..EstimateOptions::default()
        };
        let time = |model: &dyn Model| {
            let start = Instant::now();
            let e = estimate(model, &record, &options).map(|e| e.theta);
            (start.elapsed().as_secs_f64() * 1e3, e)
        };
        let (mut g, mut i) = (Vec::new(), Vec::new());
        for _ in 0..rounds {
            let (tg, eg) = time(&Ship);
            let (ti, ei) = time(&interpreter);
            if format!("{eg:?}") != format!("{ei:?}") {
                return Err(format!(
                    "{}: the two models' estimates differ",
                    method.name()
                ));
            }
            g.push(tg);
            i.push(ti);
        }
        println!("{}", line(method.name(), "ms", g, i));
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let rounds = |default: usize| {
        args.get(1)
            .and_then(|r| r.parse::<usize>().ok())
            .filter(|r| *r > 0)
            .unwrap_or(default)
    };
    let result = match args.first().map(String::as_str) {
        None => {
            regressors(400);
            estimates(15)
        }
        Some("regressors") => {
            regressors(rounds(400));
            Ok(())
        }
        Some("estimates") => estimates(rounds(15)),
        Some(other) => Err(format!(
            "unknown `{other}`: usage: paired [regressors|estimates [ROUNDS]]"
        )),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
