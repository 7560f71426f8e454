//! The interpreter's evaluation plans against the IR's evaluation order,
//! read literally (`leeway_structure::ir::Entry`): a reference evaluator that
//! walks the IR entry by entry, with no table, no shapes and no sharing.
//! Every regressor of every predictor, `rhs` and `step` agree bit for bit
//! (`f64::to_bits`) on every model in `examples/models/` and `tests/models/`,
//! and on hand-made IRs with what the model class never produces (products of
//! many factors, slots summing many entries, a column in several outputs, a
//! term index out of range). Every slot is written, none beyond the buffer.
//!
//! `tests/bit_exact.rs` (facade) holds the interpreter to generated code;
//! this test needs no compiler in the loop and covers IR shapes that
//! `include_model!` cannot be given.

use leeway_model::{Interpreter, Model, Signals, planar_rotation};
use leeway_structure::grammar::EquationKind;
use leeway_structure::ir::{
    Arg, Entry, EvalVar, Ir, Pointwise, PredictorKind, Rotation, Share, Signal, Term,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const KINDS: [PredictorKind; 3] = [
    PredictorKind::Basic,
    PredictorKind::Augmented,
    PredictorKind::Measured,
];

/// Every `.som` file of a folder (relative to the repository root), sorted.
fn models_in(folder: &str) -> Vec<String> {
    let dir = format!("{}/../{folder}", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "som"))
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    files.sort();
    files
}

fn compile_file(path: &str) -> Ir {
    let src = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    // `aggregate`: fixtures whose θ is confounded still get their IR.
    let options = leeway_structure::CompileOptions {
        aggregate: true,
        ..Default::default()
    };
    let c = leeway_structure::compile(&src, &options);
    c.ir.unwrap_or_else(|| panic!("{path} must compile: {:?}", c.diagnostics))
}

/// Every example model and fixture.
fn all_models() -> Vec<(String, Ir)> {
    let mut files = models_in("examples/models");
    files.extend(models_in("tests/models"));
    assert!(files.len() >= 8, "models not found: {files:?}");
    files
        .into_iter()
        .map(|f| {
            let ir = compile_file(&f);
            (f, ir)
        })
        .collect()
}

// ---- the reference: the IR's evaluation order, read literally ----

fn signal(sig: &Signals, s: Signal) -> f64 {
    match s {
        Signal::State(i) => sig.states[i],
        Signal::Input(i) => sig.inputs[i],
    }
}

/// `x − ((p0 + p1) + …)` over the argument's shares, or the plain signal.
fn argument(ir: &Ir, sig: &Signals, arg: &Arg, disturbed: bool) -> f64 {
    let x = signal(sig, arg.signal);
    let shares = ir.arg_shares(arg);
    if !disturbed || shares.is_empty() {
        return x;
    }
    let mut sum: Option<f64> = None;
    for (share, c) in shares {
        let d = sig.disturbances[c];
        let p = match share {
            Share::Rot(k) => sig.rotation[k] * d,
            Share::NegRot(k) => -(sig.rotation[k] * d),
            Share::One => d,
        };
        sum = Some(match sum {
            None => p,
            Some(s) => s + p,
        });
    }
    x - sum.unwrap_or(0.0)
}

/// `k*a`, `k*|a|`, `(k*a)*b`, `(k*a)*|b|`.
fn term(ir: &Ir, sig: &Signals, t: &Term, disturbed: bool) -> f64 {
    let mut v = t.coefficient;
    for f in &t.factors {
        let a = argument(ir, sig, &f.arg, disturbed);
        v *= if f.modulus { a.abs() } else { a };
    }
    v
}

fn entry(ir: &Ir, sig: &Signals, signs: &[f64], e: &Entry) -> f64 {
    match e {
        Entry::Poly {
            coefficient,
            signs: s,
            vars,
            ..
        } => {
            let mut t = *coefficient;
            for &i in s {
                t *= signs[i];
            }
            for v in vars {
                t *= match *v {
                    EvalVar::State(i) => sig.states[i],
                    EvalVar::Input(i) => sig.inputs[i],
                    EvalVar::AbsInput(i) => sig.inputs[i].abs(),
                    EvalVar::Rot(i) => sig.rotation[i],
                };
            }
            t
        }
        Entry::Term {
            term: i, pointwise, ..
        } => match ir.terms.get(*i) {
            Some(t) => term(ir, sig, t, *pointwise == Pointwise::Measured),
            None => f64::NAN,
        },
    }
}

/// The regressor buffer, slot by slot: `((e0 + e1) + e2) + …` over the
/// column's entries in one output, 0 where it has none.
fn reference_regressors(ir: &Ir, kind: PredictorKind, sig: &Signals, signs: &[f64]) -> Vec<f64> {
    let columns = ir.predictors.get(kind);
    let n = columns.len();
    let mut out = vec![0.0; n * ir.states.len()];
    for (j, col) in columns.iter().enumerate() {
        for o in 0..ir.states.len() {
            let mut acc: Option<f64> = None;
            for e in col.entries.iter().filter(|e| e.output() == o) {
                let v = entry(ir, sig, signs, e);
                acc = Some(match acc {
                    None => v,
                    Some(a) => a + v,
                });
            }
            if let Some(v) = acc {
                out[o * n + j] = v;
            }
        }
    }
    out
}

/// `θ_p0 · term0 + θ_p1 · term1 + …` per output, in term order.
fn reference_rhs(ir: &Ir, theta: &[f64], sig: &Signals) -> Vec<f64> {
    (0..ir.states.len())
        .map(|o| {
            let mut acc: Option<f64> = None;
            for t in ir.terms.iter().filter(|t| t.output == o) {
                let v = theta[t.parameter] * term(ir, sig, t, true);
                acc = Some(match acc {
                    None => v,
                    Some(a) => a + v,
                });
            }
            acc.unwrap_or(0.0)
        })
        .collect()
}

// ---- random samples ----

/// One sample's signals, owned, with a sign pattern, θ and a step.
struct Sample {
    states: Vec<f64>,
    inputs: Vec<f64>,
    rotation: Vec<f64>,
    disturbances: Vec<f64>,
    signs: Vec<f64>,
    theta: Vec<f64>,
    h: f64,
}

impl Sample {
    fn signals(&self) -> Signals<'_> {
        Signals {
            states: &self.states,
            inputs: &self.inputs,
            rotation: &self.rotation,
            disturbances: &self.disturbances,
        }
    }
}

/// A value in `[-scale, scale]`, now and then exactly `±0.0`, a power of
/// two or a value near the overflow and underflow ends, where a reordered
/// product would round (or overflow) differently.
fn value(rng: &mut ChaCha8Rng, scale: f64) -> f64 {
    match rng.random_range(0..60) {
        0 => 0.0,
        1 => -0.0,
        2 => 2.0,
        3 => -0.5,
        4 => 1e300,
        5 => -3e-300,
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

// ---- comparison ----

/// A garbage value the interpreter never writes.
const GARBAGE: f64 = -1.234_567e300;

/// The first slot where `got` differs from `want` in any bit, or a slot
/// past `want.len()` that was written.
fn differs(got: &[f64], want: &[f64]) -> Option<String> {
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        if g.to_bits() != w.to_bits() {
            return Some(format!("slot {i}: interpreted {g:e}, reference {w:e}"));
        }
    }
    got[want.len()..]
        .iter()
        .position(|v| v.to_bits() != GARBAGE.to_bits())
        .map(|i| format!("slot {} past the buffer was written", want.len() + i))
}

/// Holds the interpreter of `ir` to the reference on `samples` samples.
fn check(name: &str, ir: &Ir, samples: usize, seed: u64) {
    let interpreter = Interpreter::new(ir.clone());
    let n_out = ir.states.len();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for k in 0..samples {
        let s = sample(ir, &mut rng);
        let sig = s.signals();
        for kind in KINDS {
            let want = reference_regressors(ir, kind, &sig, &s.signs);
            let mut got = vec![GARBAGE; want.len() + 3];
            interpreter.regressors(kind, &sig, &s.signs, &mut got);
            if let Some(d) = differs(&got, &want) {
                panic!("{name}: {kind:?} regressors, sample {k}: {d}");
            }
        }
        let want = reference_rhs(ir, &s.theta, &sig);
        let mut got = vec![GARBAGE; n_out + 3];
        interpreter.rhs(&s.theta, &sig, &mut got);
        if let Some(d) = differs(&got, &want) {
            panic!("{name}: rhs, sample {k}: {d}");
        }
        let next: Vec<f64> = ir
            .equations
            .iter()
            .enumerate()
            .map(|(o, e)| match e.kind {
                EquationKind::Der => s.states[o] + s.h * want[o],
                EquationKind::Next => want[o],
            })
            .collect();
        let (mut f, mut x) = (vec![GARBAGE; n_out + 3], vec![GARBAGE; n_out + 3]);
        interpreter.step(&s.theta, s.h, &sig, &mut f, &mut x);
        if let Some(d) = differs(&f, &want).or_else(|| differs(&x, &next)) {
            panic!("{name}: step, sample {k}: {d}");
        }
    }
}

#[test]
fn every_model_matches_the_evaluation_order() {
    for (seed, (name, ir)) in all_models().iter().enumerate() {
        check(name, ir, 2000, 0x51a7e + seed as u64);
    }
}

/// The same plan evaluated again, with other signals in between, gives the
/// same bits: nothing of one call leaks into the next (the table is reused).
#[test]
fn calls_do_not_leak_into_each_other() {
    let (_, ir) = all_models()
        .into_iter()
        .find(|(n, _)| n.ends_with("/ship.som"))
        .unwrap_or_else(|| panic!("ship.som is an example"));
    let interpreter = Interpreter::new(ir.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (a, b) = (sample(&ir, &mut rng), sample(&ir, &mut rng));
    let len = ir.predictors.measured.len() * ir.states.len();
    let (mut first, mut other, mut again) = (vec![0.0; len], vec![0.0; len], vec![0.0; len]);
    interpreter.measured(&a.signals(), &a.signs, &mut first);
    interpreter.measured(&b.signals(), &b.signs, &mut other);
    interpreter.measured(&a.signals(), &a.signs, &mut again);
    assert!(
        first
            .iter()
            .zip(&again)
            .all(|(x, y)| x.to_bits() == y.to_bits())
    );
    assert!(first != other, "two samples gave the same regressors");
}

/// The model class yields products of at most three factors, slots of one
/// or two entries, and columns in one output; an IR (read from JSON, say)
/// may hold more, and more values than the table on the stack holds. The
/// general paths agree with the reference too.
#[test]
fn shapes_beyond_the_model_class_take_the_general_path() {
    let ships: Vec<(String, Ir)> = all_models()
        .into_iter()
        .filter(|(n, _)| n.ends_with("/ship.som") || n.ends_with("/barge.som"))
        .collect();
    assert_eq!(ships.len(), 2);
    for (name, mut ir) in ships {
        let n_out = ir.states.len();
        let n_rot = ir.rotation_vars.len();
        let n_s = ir.sign_args.len();
        let poly =
            |output: usize, coefficient: f64, signs: Vec<usize>, vars: Vec<EvalVar>| Entry::Poly {
                output,
                coefficient,
                coefficient_exact: String::new(),
                signs,
                vars,
            };
        let mut extra = vec![
            // Five and seven factors: the general product.
            vec![poly(
                0,
                1.5,
                vec![0, n_s - 1],
                vec![
                    EvalVar::State(0),
                    EvalVar::Input(0),
                    EvalVar::Rot(n_rot - 1),
                ],
            )],
            vec![poly(
                n_out - 1,
                -0.75,
                vec![1, 1, 0],
                vec![
                    EvalVar::AbsInput(1),
                    EvalVar::State(1),
                    EvalVar::State(1),
                    EvalVar::Rot(0),
                ],
            )],
            // Four entries in one slot, and entries in every output.
            (0..4)
                .map(|k| {
                    poly(
                        1,
                        k as f64 - 1.5,
                        vec![k % n_s],
                        vec![EvalVar::State(k % n_out)],
                    )
                })
                .chain((0..n_out).map(|o| poly(o, 2.0, vec![], vec![EvalVar::Input(0)])))
                .collect(),
            // A constant, and a term index out of range (NaN, as generated
            // code writes).
            vec![poly(2, 0.1, vec![], vec![])],
            vec![Entry::Term {
                output: 0,
                term: ir.terms.len() + 7,
                pointwise: Pointwise::Measured,
            }],
            // Every term, pointwise with and without disturbances, summed
            // in one slot per output.
            (0..ir.terms.len())
                .map(|t| Entry::Term {
                    output: ir.terms[t].output,
                    term: t,
                    pointwise: if t % 2 == 0 {
                        Pointwise::Measured
                    } else {
                        Pointwise::Undisturbed
                    },
                })
                .collect(),
        ];
        for (k, entries) in extra.drain(..).enumerate() {
            let mut column = ir.predictors.augmented[0].clone();
            column.name = format!("extra{k}");
            column.entries = entries;
            ir.predictors.augmented.push(column.clone());
            ir.predictors.measured.insert(0, column.clone());
            // The basic predictor has no sign pattern (`Model::basic`).
            let unsigned = column.entries.iter().all(|e| match e {
                Entry::Poly { signs, .. } => signs.is_empty(),
                Entry::Term { .. } => true,
            });
            if unsigned {
                ir.predictors.basic.push(column);
            }
        }
        // Seventy more inputs, each read by a column: a table too large
        // for the stack.
        let first = ir.inputs.len();
        for k in 0..70 {
            ir.inputs.push(format!("extra_input{k}"));
            let mut column = ir.predictors.augmented[0].clone();
            column.name = format!("extra_input{k}");
            column.entries = vec![poly(
                k % n_out,
                1.0,
                vec![],
                vec![EvalVar::AbsInput(first + k)],
            )];
            ir.predictors.augmented.push(column.clone());
            ir.predictors.measured.push(column.clone());
            ir.predictors.basic.push(column);
        }
        // A term with three factors and one with none, on the general and
        // constant paths of `rhs`.
        let Some(mut long) = ir.terms.iter().find(|t| !t.factors.is_empty()).cloned() else {
            panic!("{name} has a term with a factor")
        };
        long.factors.push(long.factors[0]);
        long.factors.push(long.factors[0]);
        ir.terms.push(long);
        let mut constant = ir.terms[1].clone();
        constant.factors.clear();
        ir.terms.push(constant);
        check(&name, &ir, 500, 0xba59e);
        check_blocks(&name, &ir, 0xba59e);
    }
}

/// A model without columns or terms in an output still writes that
/// output's slots (zeros) and its `rhs` (0).
#[test]
fn outputs_without_terms_are_written() {
    let (name, mut ir) = all_models()
        .into_iter()
        .find(|(n, _)| n.ends_with("/raft.som"))
        .unwrap_or_else(|| panic!("raft.som is a fixture"));
    ir.terms.retain(|t| t.output != 1);
    for columns in [
        &mut ir.predictors.basic,
        &mut ir.predictors.augmented,
        &mut ir.predictors.measured,
    ] {
        for c in columns.iter_mut() {
            c.entries.retain(|e| e.output() != 1);
        }
        columns.retain(|c| !c.entries.is_empty());
    }
    // Term entries refer to terms by index: point them at the kept ones.
    let kept: Vec<usize> = (0..ir.terms.len()).collect();
    for columns in [
        &mut ir.predictors.basic,
        &mut ir.predictors.augmented,
        &mut ir.predictors.measured,
    ] {
        for c in columns.iter_mut() {
            for e in &mut c.entries {
                if let Entry::Term { term, .. } = e {
                    *term = kept[*term % kept.len()];
                }
            }
        }
    }
    check(&name, &ir, 200, 11);
    check_blocks(&name, &ir, 11);
}

/// A block of samples evaluated at once gives, slot by slot, the bits of
/// the per-sample evaluation, for every model and predictor, blocks of
/// one, a few and many samples, each sample with its own sign pattern;
/// every slot of the block is written, nothing past it.
#[test]
fn blocks_match_sample_by_sample() {
    for (seed, (name, ir)) in all_models().iter().enumerate() {
        check_blocks(name, ir, 0xb10c + seed as u64);
    }
}

/// Holds `regressors_block` to `regressors` sample by sample.
fn check_blocks(name: &str, ir: &Ir, seed: u64) {
    let interpreter = Interpreter::new(ir.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for n in [1, 5, 32] {
        let samples: Vec<Sample> = (0..n).map(|_| sample(ir, &mut rng)).collect();
        let signals: Vec<Signals> = samples.iter().map(Sample::signals).collect();
        let signs: Vec<f64> = samples.iter().flat_map(|s| s.signs.clone()).collect();
        for kind in KINDS {
            let len = ir.predictors.get(kind).len() * ir.states.len();
            let mut block = vec![GARBAGE; len * n + 3];
            interpreter.regressors_block(kind, &signals, &signs, &mut block);
            let mut want = vec![0.0; len * n];
            for (s, (sig, sample)) in signals.iter().zip(&samples).enumerate() {
                let mut one = vec![0.0; len];
                interpreter.regressors(kind, sig, &sample.signs, &mut one);
                for (k, v) in one.into_iter().enumerate() {
                    want[k * n + s] = v;
                }
            }
            if let Some(d) = differs(&block, &want) {
                panic!("{name}: {kind:?} block of {n}: {d}");
            }
        }
    }
}

#[test]
fn some_slots_are_those_slots_of_the_whole_buffer() {
    for (seed, (name, ir)) in all_models().iter().enumerate() {
        check_slots(name, ir, 0x5107 + seed as u64);
    }
}

/// Holds `regressor_slots` to `regressors` in the slots wanted, and to
/// leaving every other slot as it was (past the buffer too), for random
/// sets of slots.
fn check_slots(name: &str, ir: &Ir, seed: u64) {
    let interpreter = Interpreter::new(ir.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for kind in KINDS {
        let len = ir.predictors.get(kind).len() * ir.states.len();
        for round in 0..8 {
            // Every slot, none, and random halves.
            let wanted: Vec<bool> = (0..len)
                .map(|_| match round {
                    0 => true,
                    1 => false,
                    _ => rng.random::<bool>(),
                })
                .collect();
            let slots = interpreter
                .regressor_slots(kind, &wanted)
                .unwrap_or_else(|| panic!("the interpreter evaluates some slots"));
            for k in 0..50 {
                let s = sample(ir, &mut rng);
                let sig = s.signals();
                let mut whole = vec![0.0; len];
                interpreter.regressors(kind, &sig, &s.signs, &mut whole);
                let want: Vec<f64> = whole
                    .iter()
                    .zip(&wanted)
                    .map(|(v, w)| if *w { *v } else { GARBAGE })
                    .collect();
                // As `regressors_update` is used: the wanted slots zeroed
                // once (the structurally zero ones are not written again).
                let mut got: Vec<f64> = wanted
                    .iter()
                    .map(|w| if *w { 0.0 } else { GARBAGE })
                    .chain([GARBAGE; 3])
                    .collect();
                slots.update(&sig, &s.signs, &mut got);
                if let Some(d) = differs(&got, &want) {
                    panic!("{name}: {kind:?} slots (round {round}), sample {k}: {d}");
                }
            }
        }
    }
}
