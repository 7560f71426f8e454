//! Dead times: a system whose inputs act late (`tests/models/thruster.som`:
//! 10 samples on `tau_x`, 3 on `tau_n`), simulated with seeded measurement
//! noise, is estimated consistently with its dead times declared and badly
//! without; a scan over `tau_x`'s dead time finds the true one; a streamed
//! record gives the in-memory estimate bit for bit.

use crate::Streamed;
use leeway_estimate::{
    DelayRange, EstimateOptions, Method, ScanBy, estimate, scan_delay, with_dead_time,
};
use leeway_model::simulate::{Disturbances, simulate_written};
use leeway_model::{Experiment, Interpreter, Model, Source};
use leeway_scenarios::synth::Draws;
use leeway_structure::ir::Ir;

/// θ of the true system, in the model's parameter order.
const TRUTH: [f64; 5] = [-0.2, -0.05, 0.05, -0.3, 0.02];

fn thruster() -> Ir {
    let path = format!(
        "{}/../tests/models/thruster.som",
        env!("CARGO_MANIFEST_DIR")
    );
    let src = std::fs::read_to_string(path).unwrap_or_default();
    let c = leeway_structure::compile(&src, &Default::default());
    c.ir.unwrap_or_else(|| panic!("thruster.som compiles: {:?}", c.diagnostics))
}

/// A level held for 5 to 60 samples, then another of either sign.
fn telegraph(draws: &mut Draws, n: usize, scale: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let level = scale * draws.normal();
        let run = 5 + (draws.normal().abs() * 25.0) as usize % 56;
        out.extend(std::iter::repeat_n(level, run));
    }
    out.truncate(n);
    out
}

/// `n` samples of the true system with its dead times, measured with noise.
fn record(ir: &Ir, n: usize, seed: u64) -> Experiment {
    let mut draws = Draws::new(seed);
    let mut e = Experiment::new(ir, "trial", 0.1);
    e.inputs = vec![
        telegraph(&mut draws, n, 20.0),
        telegraph(&mut draws, n, 10.0),
    ];
    e.states = vec![vec![0.0; n], vec![0.0; n]];
    let model = Interpreter::new(ir.clone());
    let mut w = simulate_written(&model, &TRUTH, &e, Disturbances::None).experiment;
    for (state, std) in w.states.iter_mut().zip([0.02, 0.005]) {
        for v in state.iter_mut() {
            *v += std * draws.normal();
        }
    }
    w
}

fn options() -> EstimateOptions {
    EstimateOptions {
        method: Method::Iv3,
        covariance: false,
        own_simulation: true,
        ..EstimateOptions::default()
    }
}

/// The largest relative error over θ.
fn worst_error(theta: &[f64]) -> f64 {
    theta
        .iter()
        .zip(TRUTH)
        .map(|(t, r)| ((t - r) / r).abs())
        .fold(0.0, f64::max)
}

#[test]
fn declared_dead_times_estimate_consistently_and_missing_ones_do_not() {
    let ir = thruster();
    let e = record(&ir, 4000, 7);
    let with = Interpreter::new(ir.clone());
    let without = Interpreter::new(Ir {
        delays: Vec::new(),
        ..ir.clone()
    });
    let est = |m: &Interpreter| {
        estimate(m, &[&e as &dyn Source], &options()).unwrap_or_else(|err| panic!("{err:?}"))
    };
    let (a, b) = (est(&with), est(&without));
    let fit = |x: &leeway_estimate::Estimate| {
        x.diagnostics
            .own_simulation
            .as_ref()
            .and_then(|o| o.mean_fit)
            .unwrap_or(f64::NEG_INFINITY)
    };
    eprintln!(
        "with: θ {:?} worst error {:.4} fit {:.2}; without: θ {:?} worst error {:.4} fit {:.2}",
        a.theta,
        worst_error(&a.theta),
        fit(&a),
        b.theta,
        worst_error(&b.theta),
        fit(&b)
    );
    assert!(worst_error(&a.theta) < 0.05, "{:?}", a.theta);
    assert!(worst_error(&b.theta) > 0.3, "{:?}", b.theta);
    assert!(fit(&a) > 95.0 && fit(&a) > fit(&b) + 10.0);
    // The dead time's equations are reported, and the equations counted
    // without them: the record's samples less 10, less the method's first
    // equation (N samples hold N − 1 equations).
    let dropped = &a.diagnostics.dropped_at_start;
    assert_eq!(dropped.len(), 1);
    assert_eq!(
        (
            dropped[0].dead_time,
            dropped[0].method,
            dropped[0].equations
        ),
        (10, 1, 11)
    );
    assert_eq!(a.diagnostics.equations, e.len() - 10 - 2);
    assert!(b.diagnostics.dropped_at_start.is_empty());
}

#[test]
fn a_streamed_record_gives_the_in_memory_estimate_bit_for_bit() {
    let ir = thruster();
    let e = record(&ir, 1500, 3);
    let model = Interpreter::new(ir);
    let opts = EstimateOptions {
        covariance: true,
        ..options()
    };
    let memory = estimate(&model, &[&e as &dyn Source], &opts).expect("in memory");
    let streamed = estimate(&model, &[&Streamed(&e) as &dyn Source], &opts).expect("streamed");
    let bits = |t: &[f64]| t.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&memory.theta), bits(&streamed.theta));
    assert_eq!(memory.diagnostics, streamed.diagnostics);
    // A subsample is the head of the record, less its dead time after (10
    // samples), in memory or streamed.
    let sub = EstimateOptions {
        refine_subsample: Some(0.3),
        ..opts
    };
    let memory = estimate(&model, &[&e as &dyn Source], &sub).expect("in memory");
    let streamed = estimate(&model, &[&Streamed(&e) as &dyn Source], &sub).expect("streamed");
    assert_eq!(bits(&memory.theta), bits(&streamed.theta));
    assert_eq!(memory.diagnostics, streamed.diagnostics);
    let s = memory.diagnostics.subsample.expect("reported");
    let head = leeway_estimate::head_samples(e.len(), 0.3);
    assert_eq!((s.samples, s.used), (head - 10, true), "{s:?}");
}

#[test]
fn the_scan_finds_the_true_dead_time() {
    let ir = thruster();
    let e = record(&ir, 3000, 11);
    // Declared at 0: the scan replaces it.
    let guess = with_dead_time(&ir, 0, 0);
    let range = DelayRange::parse("tau_x=0..1.5s").expect("a range");
    let opts = EstimateOptions {
        own_simulation: false,
        ..options()
    };
    for by in [ScanBy::Fit, ScanBy::Residual] {
        let scan = scan_delay(&guess, &[&e as &dyn Source], &opts, &range, by)
            .unwrap_or_else(|err| panic!("{err:?}"));
        let curve: Vec<String> = scan
            .points
            .iter()
            .map(|p| format!("{}:{:.1}", p.samples, p.criterion.unwrap_or(f64::NAN)))
            .collect();
        eprintln!("{by:?}: {}", curve.join(" "));
        assert_eq!(scan.points.len(), 16);
        assert_eq!(scan.points[scan.chosen].samples, 10, "{by:?}: {curve:?}");
        assert!(worst_error(&scan.estimate.theta) < 0.05);
        assert_eq!(scan.ir.dead_times(0.1), Ok(vec![10, 3]));
        let model = Interpreter::new(scan.ir.clone());
        assert_eq!(model.ir().delays.len(), 2);
    }
}
