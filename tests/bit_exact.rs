//! Generated code (`include_model!`) and the run-time `Interpreter` of the
//! same IR agree bit for bit (`f64::to_bits`) on every regressor of every
//! predictor, on `rhs` and on `step`, over thousands of random samples
//! (states, inputs, heading or rotation entries, disturbances, θ) and random
//! sign patterns, for every example model and the fixtures in `tests/models/`;
//! and so does a whole estimate streamed from a file, by every method.
//!
//! To add a model: `include_model!` it in `models` below and list it in
//! `cases()`. `every_example_model_is_covered` fails until every
//! `examples/models/*.som` is listed.

use leeway::ir::{Ir, PredictorKind, Rotation};
use leeway::{CompileOptions, Interpreter, Model, Signals, compile, planar_rotation};
use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use std::path::Path;

mod models {
    pub mod ship {
        leeway::include_model!("../examples/models/ship.som");
    }
    pub mod blimp {
        leeway::include_model!("../examples/models/blimp.som");
    }
    pub mod hovercraft {
        leeway::include_model!("../examples/models/hovercraft.som");
    }
    pub mod rov {
        leeway::include_model!("../examples/models/rov.som");
    }
    pub mod tanker {
        // Constant terms and pointwise moduli of plain states.
        leeway::include_model!("../examples/models/tanker.som");
    }
    pub mod ferry {
        // A dead time of every input, in seconds.
        leeway::include_model!("../examples/models/ferry.som");
    }
    pub mod ship_iv2 {
        // θ is not identifiable from one sign pattern when both media are unmeasured.
        leeway::include_model!("../examples/models/ship_iv2.som", aggregate);
    }
    // Fixtures that cover what the examples do not: body-frame media, `next`
    // equations, moduli of inputs, exact fractions, a measured rotation, and
    // the shapes of the interpreter's plans.
    pub mod raft {
        leeway::include_model!("models/raft.som");
    }
    pub mod sub {
        leeway::include_model!("models/sub.som");
    }
    // The interpreter's plan shapes: a measured rotation with a measured
    // earth-frame medium beside a body-frame one, a column in two outputs,
    // a slot summing entries, a constant term, a pointwise modulus of a plain
    // state, a modulus alone (θ confounded, hence `aggregate`).
    pub mod barge {
        leeway::include_model!("models/barge.som", aggregate);
    }
    // Dead times of inputs, in samples and in seconds.
    pub mod thruster {
        leeway::include_model!("models/thruster.som");
    }
}

/// A generated model and the file it was generated from.
struct Case {
    /// Relative to the repository root.
    file: &'static str,
    model: &'static dyn Model,
    aggregate: bool,
}

fn cases() -> Vec<Case> {
    let case = |file, model, aggregate| Case {
        file,
        model,
        aggregate,
    };
    vec![
        case("examples/models/blimp.som", &models::blimp::Blimp, false),
        case(
            "examples/models/hovercraft.som",
            &models::hovercraft::Hovercraft,
            false,
        ),
        case("examples/models/rov.som", &models::rov::Rov, false),
        case("examples/models/ship.som", &models::ship::Ship, false),
        case("examples/models/tanker.som", &models::tanker::Tanker, false),
        case("examples/models/ferry.som", &models::ferry::Ferry, false),
        case(
            "examples/models/ship_iv2.som",
            &models::ship_iv2::ShipIv2,
            true,
        ),
        case("tests/models/raft.som", &models::raft::Raft, false),
        case("tests/models/sub.som", &models::sub::Sub, false),
        case("tests/models/barge.som", &models::barge::Barge, true),
        case(
            "tests/models/thruster.som",
            &models::thruster::Thruster,
            false,
        ),
    ]
}

const SAMPLES: usize = 4000;
const KINDS: [PredictorKind; 3] = [
    PredictorKind::Basic,
    PredictorKind::Augmented,
    PredictorKind::Measured,
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The IR the structure compiler makes of the case's file now.
fn compiled(case: &Case) -> Ir {
    let path = root().join(case.file);
    let source =
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let c = compile(
        &source,
        &CompileOptions {
            aggregate: case.aggregate,
            patterns: None,
            centring: None,
        },
    );
    c.ir.unwrap_or_else(|| panic!("{} must compile: {:?}", case.file, c.diagnostics))
}

#[test]
fn every_example_model_is_covered() {
    let listed: Vec<&str> = cases().iter().map(|c| c.file).collect();
    let dir = root().join("examples/models");
    let mut found = 0;
    for entry in std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
    {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(".som") {
            found += 1;
            let file = format!("examples/models/{name}");
            assert!(
                listed.contains(&file.as_str()),
                "{file} is not in the bit-exactness test: add it to `models` and `cases()`"
            );
        }
    }
    assert!(found >= 2, "no example models found in {}", dir.display());
}

#[test]
fn the_embedded_ir_is_the_compilers() {
    for case in cases() {
        assert!(
            *case.model.ir() == compiled(&case),
            "{}: the IR embedded by include_model! differs from the compiler's",
            case.file
        );
    }
}

/// Random signals of one sample, owned.
struct Sample {
    states: Vec<f64>,
    inputs: Vec<f64>,
    rotation: Vec<f64>,
    disturbances: Vec<f64>,
    signs: Vec<f64>,
    theta: Vec<f64>,
    h: f64,
}

/// A value in `[-scale, scale]`, now and then exactly `0.0` or `-0.0`
/// (where `|a|` and sign conventions could differ).
fn value(rng: &mut ChaCha8Rng, scale: f64) -> f64 {
    match rng.random_range(0..40) {
        0 => 0.0,
        1 => -0.0,
        _ => rng.random_range(-scale..scale),
    }
}

fn sample(ir: &Ir, rng: &mut ChaCha8Rng) -> Sample {
    let rotation = match ir.rotation {
        Rotation::Planar { .. } => planar_rotation(rng.random_range(-10.0..10.0)).to_vec(),
        Rotation::Measured { .. } | Rotation::None => (0..ir.rotation_vars.len())
            .map(|_| value(rng, 1.0))
            .collect(),
    };
    Sample {
        states: (0..ir.states.len()).map(|_| value(rng, 3.0)).collect(),
        inputs: (0..ir.inputs.len()).map(|_| value(rng, 30.0)).collect(),
        rotation,
        disturbances: (0..ir.components.len()).map(|_| value(rng, 2.0)).collect(),
        signs: (0..ir.sign_args.len())
            .map(|_| if rng.random::<bool>() { 1.0 } else { -1.0 })
            .collect(),
        theta: (0..ir.parameters.len()).map(|_| value(rng, 2.0)).collect(),
        h: rng.random_range(0.01..2.0),
    }
}

/// Buffers of `len` slots plus a tail that must stay untouched, filled with
/// different garbage for the two evaluators so an unwritten slot shows.
fn buffers(len: usize) -> (Vec<f64>, Vec<f64>) {
    (
        vec![f64::from_bits(0x7ff8_dead_beef_0001); len + 3],
        vec![-1.234_567e300; len + 3],
    )
}

/// The first slot where the two buffers differ in any bit, or where the
/// generated code wrote past its `len` slots. `n` is the number of columns
/// (0 for one slot per output).
#[allow(clippy::too_many_arguments)]
fn compare(
    case: &Case,
    what: &str,
    names: &[String],
    n: usize,
    k: usize,
    generated: &[f64],
    interpreted: &[f64],
    len: usize,
) -> Result<(), String> {
    for (i, (g, r)) in generated[..len].iter().zip(&interpreted[..len]).enumerate() {
        if g.to_bits() != r.to_bits() {
            // `n == 0`: one slot per output (rhs, step), `names` are the states.
            let slot = match (i.checked_div(n), i.checked_rem(n)) {
                (Some(o), Some(j)) => format!(
                    "output {o}, column {j} `{}`",
                    names.get(j).map_or("?", String::as_str)
                ),
                _ => format!("output {i} `{}`", names.get(i).map_or("?", String::as_str)),
            };
            return Err(format!(
                "{}: {what}, sample {k}, {slot}: generated {g:e} ≠ interpreted {r:e}",
                case.file
            ));
        }
    }
    if generated[len..]
        .iter()
        .any(|v| v.to_bits() != 0x7ff8_dead_beef_0001)
    {
        return Err(format!("{}: {what} wrote past its {len} slots", case.file));
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn assert_same(
    case: &Case,
    what: &str,
    names: &[String],
    n: usize,
    k: usize,
    generated: &[f64],
    interpreted: &[f64],
    len: usize,
) {
    if let Err(e) = compare(case, what, names, n, k, generated, interpreted, len) {
        panic!("{e}");
    }
}

#[test]
fn generated_code_matches_the_interpreter_bit_for_bit() {
    for (seed, case) in cases().iter().enumerate() {
        let ir = compiled(case);
        let interpreter = Interpreter::new(ir.clone());
        let generated = case.model;
        let n_out = ir.states.len();
        assert_eq!(generated.n_outputs(), n_out, "{}", case.file);
        let mut rng = ChaCha8Rng::seed_from_u64(0x1ee_3a7 + seed as u64);
        // One buffer per predictor, zeroed once and reused by
        // `regressors_update`, as an estimator's pass does: each sample it
        // must hold exactly what `regressors` writes into garbage.
        let mut reused: Vec<Vec<f64>> = KINDS
            .iter()
            .map(|kind| vec![0.0; ir.predictors.get(*kind).len() * n_out + 3])
            .collect();
        let mut reused_interpreted = reused.clone();
        for k in 0..SAMPLES {
            let s = sample(&ir, &mut rng);
            let sig = Signals {
                states: &s.states,
                inputs: &s.inputs,
                rotation: &s.rotation,
                disturbances: &s.disturbances,
            };
            for kind in KINDS {
                let n = ir.predictors.get(kind).len();
                assert_eq!(
                    generated.n_columns(kind),
                    n,
                    "{}: {kind:?} columns",
                    case.file
                );
                let names: Vec<String> = ir
                    .predictors
                    .get(kind)
                    .iter()
                    .map(|c| c.name.clone())
                    .collect();
                let len = n * n_out;
                let (mut g, mut r) = buffers(len);
                generated.regressors(kind, &sig, &s.signs, &mut g);
                interpreter.regressors(kind, &sig, &s.signs, &mut r);
                assert_same(
                    case,
                    &format!("{kind:?} regressors"),
                    &names,
                    n,
                    k,
                    &g,
                    &r,
                    len,
                );
                let i = KINDS.iter().position(|x| *x == kind).unwrap_or(0);
                generated.regressors_update(kind, &sig, &s.signs, &mut reused[i]);
                interpreter.regressors_update(kind, &sig, &s.signs, &mut reused_interpreted[i]);
                for (who, u) in [
                    ("generated", &reused[i]),
                    ("interpreted", &reused_interpreted[i]),
                ] {
                    assert!(
                        g[..len]
                            .iter()
                            .zip(&u[..len])
                            .all(|(a, b)| a.to_bits() == b.to_bits())
                            && u[len..].iter().all(|v| *v == 0.0),
                        "{}: {who} {kind:?} regressors_update, sample {k}, differs from regressors",
                        case.file
                    );
                }
            }
            let states = ir.states.clone();
            let (mut g, mut r) = buffers(n_out);
            generated.rhs(&s.theta, &sig, &mut g);
            interpreter.rhs(&s.theta, &sig, &mut r);
            assert_same(case, "rhs", &states, 0, k, &g, &r, n_out);
            let ((mut gf, mut rf), (mut gn, mut rn)) = (buffers(n_out), buffers(n_out));
            generated.step(&s.theta, s.h, &sig, &mut gf, &mut gn);
            interpreter.step(&s.theta, s.h, &sig, &mut rf, &mut rn);
            assert_same(case, "step (f)", &states, 0, k, &gf, &rf, n_out);
            assert_same(case, "step (next)", &states, 0, k, &gn, &rn, n_out);
        }
    }
}

/// The comparison above cannot pass vacuously: the regressors it compares
/// are not all zero, and a one-ulp change is seen.
#[test]
fn the_comparison_sees_one_ulp() {
    let cases = cases();
    let Some(case) = cases.iter().find(|c| c.file.ends_with("/ship.som")) else {
        panic!("the ship is listed")
    };
    let ir = compiled(case);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let s = sample(&ir, &mut rng);
    let sig = Signals {
        states: &s.states,
        inputs: &s.inputs,
        rotation: &s.rotation,
        disturbances: &s.disturbances,
    };
    let len = ir.states.len() * ir.predictors.measured.len();
    let mut g = vec![0.0; len];
    case.model.measured(&sig, &s.signs, &mut g);
    let nonzero = g.iter().filter(|v| **v != 0.0).count();
    assert!(
        nonzero > len / 4,
        "only {nonzero} of {len} regressors are non-zero"
    );
    let mut r = g.clone();
    let i = g.iter().position(|v| *v != 0.0).unwrap_or(0);
    r[i] = f64::from_bits(r[i].to_bits() + 1);
    let (mut gg, mut rr) = buffers(len);
    gg[..len].copy_from_slice(&g);
    rr[..len].copy_from_slice(&r);
    let n = ir.predictors.measured.len();
    assert!(
        compare(case, "probe", &[], n, 0, &gg, &rr, len).is_err(),
        "a one-ulp difference went unnoticed"
    );
    rr[..len].copy_from_slice(&g);
    assert!(compare(case, "probe", &[], n, 0, &gg, &rr, len).is_ok());
}

/// The generated model carries the dead times: simulated on a record, it
/// gives the interpreter's trajectory bit for bit, starting at sample 10
/// (the longest dead time) and driven by each input its dead time earlier.
#[test]
fn generated_code_simulates_with_the_dead_times_bit_for_bit() {
    use leeway::{Disturbances, simulate};
    let case = Case {
        file: "tests/models/thruster.som",
        model: &models::thruster::Thruster,
        aggregate: false,
    };
    let ir = compiled(&case);
    assert_eq!(case.model.ir().dead_times(0.1), Ok(vec![10, 3]));
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let n = 300;
    let mut e = leeway::Experiment::new(&ir, "run", 0.1);
    e.states = vec![vec![0.3; n], vec![-0.1; n]];
    e.inputs = (0..2)
        .map(|_| (0..n).map(|_| value(&mut rng, 20.0)).collect())
        .collect();
    let theta = [-0.2, -0.05, 0.05, -0.3, 0.02];
    let interpreter = Interpreter::new(ir);
    let g = simulate(case.model, &theta, &e, Disturbances::None);
    let r = simulate(&interpreter, &theta, &e, Disturbances::None);
    assert_eq!(g.states[0].len(), n - 10);
    let bits = |s: &[Vec<f64>]| -> Vec<u64> { s.iter().flatten().map(|v| v.to_bits()).collect() };
    assert_eq!(bits(&g.states), bits(&r.states));
    // u(11) = u(10) + h·(X_u·u + X_uu·u·|u| + X_tau·tau_x(0)): the input of sample 0.
    let u: f64 = 0.3;
    let expected = u + 0.1 * (-0.2 * u + -0.05 * u * u.abs() + 0.05 * e.inputs[0][0]);
    assert!(
        (g.states[0][1] - expected).abs() < 1e-12,
        "{} ≠ {expected}",
        g.states[0][1]
    );
}

/// A streamed estimate is the same, bit for bit, with the model compiled in
/// as interpreted (docs/rust.md says so): the estimator's walk evaluates
/// the interpreter's regressors a block of samples at a time and hands the
/// sinks whole blocks, and generated code's sample by sample, so the two
/// take different paths through every pass and must make each sum in the
/// same order. Two experiments of different lengths from one CSV file, the
/// ship in 10 m/s of wind, every method with standard errors.
#[test]
fn a_streamed_estimate_is_the_same_compiled_in_or_interpreted() {
    use leeway::data::{LoadOptions, open_file};
    use leeway::{EstimateOptions, Method, Source, estimate};
    use leeway_scenarios::study::estimation_experiment;
    let ship = models::ship::Ship;
    let interpreter = Interpreter::new(ship.ir().clone());
    let design = Default::default();
    let (a, _) = estimation_experiment(&ship, &design, 10.0, 1500, 1);
    let (b, _) = estimation_experiment(&ship, &design, 10.0, 900, 2);
    let path = std::env::temp_dir().join(format!("leeway-bit-exact-{}.csv", std::process::id()));
    let written = std::fs::File::create(&path)
        .and_then(|mut f| leeway::write_csv(ship.ir(), &[&a, &b], 0.0, &mut f));
    let opened = written.map(|()| open_file(&path, ship.ir(), &LoadOptions::default()));
    let estimates = opened.map(|file| {
        let file = file.unwrap_or_else(|e| panic!("the file opens: {e}"));
        let sources: Vec<&dyn Source> = file.sources.iter().map(|s| s as &dyn Source).collect();
        assert_eq!(sources.len(), 2);
        Method::ALL.map(|method| {
            let options = EstimateOptions {
                method,
                aggregate: true,
                ..EstimateOptions::default()
            };
            let models: [&dyn Model; 2] = [&ship, &interpreter];
            models.map(|m| estimate(m, &sources, &options))
        })
    });
    std::fs::remove_file(&path).ok();
    let estimates = estimates.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    for (method, [compiled, interpreted]) in Method::ALL.iter().zip(estimates) {
        let compiled = compiled.unwrap_or_else(|e| panic!("{}: {e}", method.name()));
        assert!(
            compiled.std_errors.iter().any(Option::is_some),
            "{}: standard errors, so that the covariance pass ran",
            method.name()
        );
        // Debug prints each f64 in the shortest form that reads back to
        // its bits: equal text, equal bits.
        assert_eq!(
            format!("{compiled:?}"),
            format!("{:?}", interpreted.unwrap_or_else(|e| panic!("{e}"))),
            "{}",
            method.name()
        );
    }
}
