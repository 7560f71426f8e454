//! The expansion is exact: for every example model (`examples/models/*.som`)
//! and random states, inputs, heading and disturbances with a sign pattern
//! consistent with them, `Φᵀθ + Φ_ρᵀρ + Φ_λᵀλ` (unreduced, `ρ = vθ`,
//! `λ = vvθ`) equals the model evaluated directly with `|·|`.

use leeway_model::{Interpreter, Model, Signals, planar_rotation};
use leeway_structure::ir::{ColumnKind, Ir, PredictorKind};
use proptest::prelude::*;

fn load(name: &str) -> Ir {
    use std::collections::BTreeMap;
    use std::sync::{Mutex, OnceLock};
    static CACHE: OnceLock<Mutex<BTreeMap<String, Ir>>> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(BTreeMap::new()));
    if let Some(ir) = cache.lock().ok().and_then(|c| c.get(name).cloned()) {
        return ir;
    }
    let ir = compile_file(name);
    if let Ok(mut c) = cache.lock() {
        c.insert(name.to_string(), ir.clone());
    }
    ir
}

/// The file names of every example model, sorted.
fn example_models() -> &'static [String] {
    static NAMES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    NAMES.get_or_init(|| {
        let dir = format!("{}/../examples/models", env!("CARGO_MANIFEST_DIR"));
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{dir}: {e}"))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "som"))
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        names.sort();
        names
    })
}

fn compile_file(name: &str) -> Ir {
    let path = format!("{}/../examples/models/{name}", env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(&path).unwrap_or_default();
    let c = leeway_structure::compile(&src, &Default::default());
    c.ir.unwrap_or_else(|| panic!("{name} must compile: {:?}", c.diagnostics))
}

/// Coefficient of each augmented column given θ and disturbance values.
fn coefficients(ir: &Ir, kind: PredictorKind, theta: &[f64], v: &[f64]) -> Vec<f64> {
    ir.predictors
        .get(kind)
        .iter()
        .map(|c| match &c.kind {
            ColumnKind::Theta { parameter } => theta[*parameter],
            ColumnKind::Rho {
                component,
                parameter,
            } => v[*component] * theta[*parameter],
            ColumnKind::Lambda {
                components: [a, b],
                parameter,
            } => v[*a] * v[*b] * theta[*parameter],
        })
        .collect()
}

fn check(name: &str, kind: PredictorKind, seed: &[f64]) -> Result<(), TestCaseError> {
    let ir = load(name);
    let m = Interpreter::new(ir.clone());
    let n_out = ir.states.len();
    let mut it = seed.iter().copied().cycle();
    let mut next = || it.next().unwrap_or(0.5);
    let states: Vec<f64> = (0..n_out).map(|_| 4.0 * next() - 2.0).collect();
    let inputs: Vec<f64> = (0..ir.inputs.len()).map(|_| 40.0 * next() - 20.0).collect();
    let rotation: Vec<f64> =
        if ir.rotation_vars.len() == 2 && ir.rotation_vars[0].starts_with("cos") {
            planar_rotation(7.0 * next()).to_vec()
        } else {
            (0..ir.rotation_vars.len())
                .map(|_| 2.0 * next() - 1.0)
                .collect()
        };
    let dist: Vec<f64> = (0..ir.components.len())
        .map(|_| 3.0 * next() - 1.5)
        .collect();
    let theta: Vec<f64> = (0..ir.parameters.len())
        .map(|_| 2.0 * next() - 1.0)
        .collect();
    let sig = Signals {
        states: &states,
        inputs: &inputs,
        rotation: &rotation,
        disturbances: &dist,
    };
    // The sign of each sign argument at the true disturbance values.
    let signs: Vec<f64> = ir
        .sign_args
        .iter()
        .map(|s| {
            if leeway_model::interp::arg_plan(&ir, &s.arg).eval(&sig, true) < 0.0 {
                -1.0
            } else {
                1.0
            }
        })
        .collect();
    let mut f = vec![0.0; n_out];
    m.rhs(&theta, &sig, &mut f);
    let n = m.n_columns(kind);
    let mut phi = vec![0.0; n * n_out];
    m.regressors(kind, &sig, &signs, &mut phi);
    let coef = coefficients(&ir, kind, &theta, &dist);
    for o in 0..n_out {
        let pred: f64 = (0..n).map(|j| phi[o * n + j] * coef[j]).sum();
        let scale = 1.0 + f[o].abs();
        prop_assert!(
            (pred - f[o]).abs() <= 1e-9 * scale,
            "{name} {kind:?} output {o}: {pred} vs {}",
            f[o]
        );
    }
    Ok(())
}

#[test]
fn every_example_model_is_covered() {
    let names = example_models();
    for required in [
        "ship.som",
        "ship_iv2.som",
        "blimp.som",
        "rov.som",
        "hovercraft.som",
    ] {
        assert!(
            names.iter().any(|n| n == required),
            "{required} missing from {names:?}"
        );
    }
}

proptest! {
    // `PROPTEST_CASES` (CI: 2000) overrides the default.
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(300)
    ))]
    #[test]
    fn augmented_expansion_equals_direct_evaluation(seed in proptest::collection::vec(0.0f64..1.0, 32)) {
        for name in example_models() {
            check(name, PredictorKind::Augmented, &seed)?;
            check(name, PredictorKind::Measured, &seed)?;
        }
    }
}
