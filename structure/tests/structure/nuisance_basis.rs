//! The nuisance reduction keeps the column space: for every example model,
//! predictor and sign pattern, each dropped nuisance column is exactly the
//! stated combination of kept ones (or vanishes once constants are dropped),
//! and the kept columns are independent and span as much as all of them.
//! Checked exactly on the structural polynomials, with their own evaluation
//! of the sign variables, not the compiler's.

use leeway_structure::exact::{Q, echelon, parse_q};
use leeway_structure::identify::{Analysis, Centring, Patterns, relevant_signs};
use leeway_structure::ir::{Column, Entry, EvalVar, Ir, PredictorKind, SignPattern, StructVar};
use leeway_structure::{CompileOptions, compile};
use num_traits::Zero;
use proptest::prelude::*;
use std::collections::{BTreeMap, BTreeSet};

type Row = (usize, usize, Vec<(StructVar, u32)>);

/// Every example model, compiled once per test binary.
fn example_models() -> &'static [(String, Ir)] {
    static MODELS: std::sync::OnceLock<Vec<(String, Ir)>> = std::sync::OnceLock::new();
    MODELS.get_or_init(compile_examples)
}

fn compile_examples() -> Vec<(String, Ir)> {
    let dir = format!("{}/../examples/models", env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("examples/models") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "som") {
            let src = std::fs::read_to_string(&path).expect("read");
            let c = compile(&src, &CompileOptions::default());
            let name = path
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .to_string();
            out.push((
                name.clone(),
                c.ir.unwrap_or_else(|| panic!("{name}: {:?}", c.diagnostics)),
            ));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(out.len() >= 5);
    out
}

/// A column as a sparse vector over (experiment, output, monomial), signs
/// substituted for each experiment's pattern; constants within an experiment
/// dropped unless the centring keeps them.
fn vector(col: &Column, set: &[SignPattern], keep_constants: bool) -> BTreeMap<Row, Q> {
    let mut v: BTreeMap<Row, Q> = BTreeMap::new();
    for (x, pattern) in set.iter().enumerate() {
        for e in &col.structural {
            let mut q = parse_q(&e.coefficient).expect("exact coefficient");
            let mut rest = Vec::new();
            for (var, power) in &e.vars {
                match var {
                    StructVar::Sign(i)
                        if power % 2 == 1 && pattern.get(*i).copied().unwrap_or(1) < 0 =>
                    {
                        q = -q
                    }
                    StructVar::Sign(_) => {}
                    other => rest.push((*other, *power)),
                }
            }
            if rest.is_empty() && !keep_constants {
                continue;
            }
            *v.entry((x, e.output, rest)).or_insert_with(Q::zero) += q;
        }
    }
    v.retain(|_, q| !q.is_zero());
    v
}

fn rank(vectors: &[BTreeMap<Row, Q>]) -> usize {
    let rows: BTreeSet<&Row> = vectors.iter().flat_map(|v| v.keys()).collect();
    let matrix: Vec<Vec<Q>> = rows
        .iter()
        .map(|r| {
            vectors
                .iter()
                .map(|v| v.get(*r).cloned().unwrap_or_else(Q::zero))
                .collect()
        })
        .collect();
    echelon(&matrix, vectors.len()).rank()
}

/// The sets of experiments to check: every single pattern over the signs the
/// predictor fixes (at most 16 here), and the required set.
fn pattern_sets(ir: &Ir, kind: PredictorKind) -> Vec<Vec<SignPattern>> {
    let relevant = relevant_signs(ir, kind);
    let mut sets = Vec::new();
    for bits in 0..(1usize << relevant.len()) {
        let mut p = vec![1i8; ir.sign_args.len()];
        for (k, i) in relevant.iter().enumerate() {
            if bits >> k & 1 == 1 {
                p[*i] = -1;
            }
        }
        sets.push(vec![p]);
    }
    if !ir.report.required_patterns.is_empty() {
        sets.push(ir.report.required_patterns.clone());
    }
    sets
}

#[test]
fn reduced_nuisance_basis_spans_the_unreduced_one() {
    let mut checked = 0;
    for (name, ir) in example_models() {
        for kind in [PredictorKind::Augmented, PredictorKind::Measured] {
            let columns = ir.predictors.get(kind);
            let analysis = Analysis::new(ir, kind);
            let nuisance: Vec<usize> = (0..columns.len())
                .filter(|c| columns[*c].kind.is_nuisance())
                .collect();
            for set in pattern_sets(ir, kind) {
                let red = analysis.reduce(Patterns::Set(&set));
                let vectors: Vec<BTreeMap<Row, Q>> = columns
                    .iter()
                    .map(|c| vector(c, &set, analysis.names.centring != Centring::Experiment))
                    .collect();
                let kept: Vec<usize> = nuisance.iter().copied().filter(|c| red.pivot[*c]).collect();
                for &d in nuisance.iter().filter(|c| !red.pivot[**c]) {
                    // Rebuild the dropped column from the kept nuisance columns.
                    let mut rebuilt: BTreeMap<Row, Q> = BTreeMap::new();
                    for (k, q) in &red.combination[d] {
                        assert!(
                            kept.contains(k),
                            "{name} {kind:?}: {} uses non-kept column {k}",
                            columns[d].name
                        );
                        for (row, value) in &vectors[*k] {
                            *rebuilt.entry(row.clone()).or_insert_with(Q::zero) += value * q;
                        }
                    }
                    rebuilt.retain(|_, q| !q.is_zero());
                    assert_eq!(
                        rebuilt, vectors[d],
                        "{name} {kind:?} {set:?}: {}",
                        columns[d].name
                    );
                    checked += 1;
                }
                let kept_vectors: Vec<_> = kept.iter().rev().map(|k| vectors[*k].clone()).collect();
                let all_vectors: Vec<_> =
                    nuisance.iter().rev().map(|k| vectors[*k].clone()).collect();
                assert_eq!(
                    rank(&kept_vectors),
                    kept.len(),
                    "{name} {kind:?} {set:?}: kept columns are independent"
                );
                assert_eq!(
                    rank(&all_vectors),
                    kept.len(),
                    "{name} {kind:?} {set:?}: same column space"
                );
            }
        }
    }
    assert!(checked > 100, "only {checked} dropped columns checked");
}

/// The structural polynomial of a column is its evaluation entries with the
/// constant monomial dropped: the rank analysis sees what is evaluated.
#[test]
fn structural_polynomials_match_the_evaluated_entries() {
    for (name, ir) in example_models() {
        for kind in [PredictorKind::Augmented, PredictorKind::Measured] {
            for col in ir.predictors.get(kind) {
                if col.entries.iter().any(|e| matches!(e, Entry::Term { .. })) {
                    continue; // pointwise Φ2 columns: |·| of data, no monomials to compare
                }
                let mut from_entries: BTreeMap<(usize, Vec<(StructVar, u32)>), Q> = BTreeMap::new();
                for e in &col.entries {
                    let Entry::Poly {
                        output,
                        coefficient_exact,
                        signs,
                        vars,
                        ..
                    } = e
                    else {
                        continue;
                    };
                    let mut powers: BTreeMap<StructVar, u32> = BTreeMap::new();
                    for s in signs {
                        *powers.entry(StructVar::Sign(*s)).or_insert(0) += 1;
                    }
                    for v in vars {
                        let sv = match v {
                            EvalVar::State(i) => StructVar::State(*i),
                            EvalVar::Input(i) => StructVar::Input(*i),
                            EvalVar::AbsInput(i) => StructVar::AbsInput(*i),
                            EvalVar::Rot(i) => StructVar::Rot(*i),
                        };
                        *powers.entry(sv).or_insert(0) += 1;
                    }
                    let q = parse_q(coefficient_exact).expect("exact");
                    *from_entries
                        .entry((*output, powers.into_iter().collect()))
                        .or_insert_with(Q::zero) += q;
                }
                from_entries.retain(|_, q| !q.is_zero());
                let structural: BTreeMap<(usize, Vec<(StructVar, u32)>), Q> = col
                    .structural
                    .iter()
                    .map(|e| {
                        (
                            (e.output, e.vars.clone()),
                            parse_q(&e.coefficient).expect("exact"),
                        )
                    })
                    .collect();
                assert_eq!(from_entries, structural, "{name} {kind:?} {}", col.name);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(32)
    ))]
    /// The rank of the stacked columns ignores their order.
    #[test]
    fn rank_ignores_column_order(seed in any::<u64>(), model in 0usize..5, pattern in any::<u16>()) {
        let models = example_models();
        let (_, ir) = &models[model % models.len()];
        let columns = ir.predictors.get(PredictorKind::Augmented);
        let p: SignPattern = (0..ir.sign_args.len()).map(|i| if pattern >> i & 1 == 1 { -1 } else { 1 }).collect();
        let set = vec![p];
        let vectors: Vec<_> = columns.iter().map(|c| vector(c, &set, false)).collect();
        let mut shuffled = vectors.clone();
        // Fisher–Yates with a small LCG seeded by proptest.
        let mut state = seed;
        for i in (1..shuffled.len()).rev() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let j = (state >> 33) as usize % (i + 1);
            shuffled.swap(i, j);
        }
        prop_assert_eq!(rank(&vectors), rank(&shuffled));
    }
}
