//! Residual analysis on data simulated by the model itself with white
//! process noise: the one-step residuals are that noise, so they pass the
//! whiteness and input-independence tests; with a wrong θ, or a model that
//! misses a term of the data's dynamics, they fail. Fixed seeds.

use leeway_model::experiment::Row;
use leeway_model::residuals::{DEFAULT_LAGS, analyse, normal_quantile};
use leeway_model::{Experiment, Interpreter, Model, Signals};
use leeway_structure::ir::Ir;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const MODEL: &str = "
model Boat {
    step 0.1
    state u, r
    input tau, delta
    der u = X_u*u + X_uu*u*|u| + X_tau*tau
    der r = N_r*r + N_d*delta*u
    nominal { X_u = -0.3, X_uu = -0.1, X_tau = 0.5, N_r = -0.8, N_d = 0.4 }
}";

/// Without the `u·|u|` drag: a model that misses a term of the data's dynamics.
const MISSING: &str = "
model Boat {
    step 0.1
    state u, r
    input tau, delta
    der u = X_u*u + X_tau*tau
    der r = N_r*r + N_d*delta*u
}";

const THETA: [f64; 5] = [-0.3, -0.1, 0.5, -0.8, 0.4];

fn ir(source: &str) -> Ir {
    let c = leeway_structure::compile(source, &Default::default());
    c.ir.unwrap_or_else(|| panic!("the test model compiles: {:?}", c.diagnostics))
}

/// `n` samples of `x(k+1) = step(x(k), u(k)) + w(k)`, inputs a random
/// staircase (held 20 samples), `w` white Gaussian-like of deviation `sd`.
fn simulated(n: usize, seed: u64, sd: f64) -> Experiment {
    let ir = ir(MODEL);
    let model = Interpreter::new(ir.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut e = Experiment::new(&ir, "sim", 0.1);
    let (mut x, mut u) = (vec![1.0, 0.0], vec![0.0, 0.0]);
    let (mut f, mut next) = (vec![0.0; 2], vec![0.0; 2]);
    for k in 0..n {
        if k % 20 == 0 {
            u = vec![rng.random_range(0.0..2.0), rng.random_range(-1.0..1.0)];
        }
        let row = Row {
            states: &x,
            inputs: &u,
            heading: 0.0,
            rotation: &[],
            disturbances: &[],
        };
        e.push(&ir, &row);
        let sig = Signals {
            states: &x,
            inputs: &u,
            rotation: &[],
            disturbances: &[],
        };
        model.step(&THETA, 0.1, &sig, &mut f, &mut next);
        for (x, next) in x.iter_mut().zip(&next) {
            // A sum of 12 uniforms less 6: mean 0, deviation 1, nearly normal.
            let w: f64 = (0..12).map(|_| rng.random_range(0.0..1.0)).sum::<f64>() - 6.0;
            *x = next + sd * w;
        }
    }
    e
}

#[test]
fn residuals_of_the_true_model_are_its_process_noise_and_white() {
    let data = [simulated(3000, 1, 0.01), simulated(2000, 2, 0.01)];
    let model = Interpreter::new(ir(MODEL));
    let a = analyse(&model, &THETA, &data, &[], DEFAULT_LAGS).expect("enough samples");
    assert_eq!(a.tests.samples, 2999 + 1999);
    assert!((a.tests.band - 2.5758 / (4998f64).sqrt()).abs() < 1e-4);
    for s in &a.tests.states {
        assert!(
            s.white,
            "{}: lags outside {:?}, max {:?}",
            s.state, s.outside, s.max_abs
        );
        assert!(
            s.p_value.is_some_and(|p| p > 0.01),
            "{}: p {:?}",
            s.state,
            s.p_value
        );
        assert!(
            s.std.is_some_and(|sd| (sd - 0.01).abs() < 0.001),
            "{}: std {:?}",
            s.state,
            s.std
        );
        for i in &s.inputs {
            assert!(i.independent, "{} × {}: {:?}", s.state, i.input, i.outside);
        }
    }
    // The first sample of each experiment has no prediction.
    assert!(a.one_step[1].residuals[0][0].is_nan());
    assert_eq!(a.one_step[1].residuals[0].len(), 2000);
}

#[test]
fn a_wrong_theta_fails_whiteness_and_independence() {
    let data = [simulated(3000, 3, 0.01)];
    let model = Interpreter::new(ir(MODEL));
    let wrong = [-0.2, -0.1, 0.4, -0.8, 0.4];
    let a = analyse(&model, &wrong, &data, &[], DEFAULT_LAGS).expect("enough samples");
    let u = &a.tests.states[0];
    assert!(!u.white && u.p_value.is_some_and(|p| p < 1e-6), "{u:?}");
    assert!(u.inputs.iter().any(|i| !i.independent), "{u:?}");
    // The yaw rate's θ is right: its residual stays white.
    assert!(a.tests.states[1].white);
}

#[test]
fn a_missing_term_fails_whiteness() {
    let data = [simulated(3000, 4, 0.01)];
    let model = Interpreter::new(ir(MISSING));
    // θ of the reduced model: the drag folded into X_u at the mean speed.
    let a = analyse(&model, &[-0.45, 0.5, -0.8, 0.4], &data, &[], DEFAULT_LAGS).expect("enough");
    let u = &a.tests.states[0];
    assert!(!u.white, "{u:?}");
    assert!(u.inputs.iter().any(|i| !i.independent), "{u:?}");
}

#[test]
fn the_normal_quantile_is_the_tabulated_one() {
    assert!((normal_quantile(0.01) - 2.575_829_303_549).abs() < 1e-9);
    assert!((normal_quantile(0.05) - 1.959_963_984_540).abs() < 1e-9);
    assert!((normal_quantile(0.01 / 25.0) - 3.540_084_100_72).abs() < 1e-6);
}

#[test]
fn too_many_lags_is_an_error() {
    let data = [simulated(20, 5, 0.01)];
    let model = Interpreter::new(ir(MODEL));
    let e = analyse(&model, &THETA, &data, &[], 19).expect_err("19 lags on 19 samples");
    assert!(e.contains("19 residual samples"), "{e}");
}
