//! The estimators on synthetic ship data (paper §V setting, fixed seeds):
//! consistency of IV3 against the bias of LS, the current's mean recovered,
//! IV1 consistent only with zero-mean disturbances, and the diagnostics a
//! user relies on (unexcited combinations, sign violations, low wind).

use leeway_estimate::EstimateOptions;
use leeway_estimate::Method;
use leeway_estimate::estimate;
use leeway_model::Experiment;
use leeway_model::Interpreter;
use leeway_model::Model;
use leeway_model::Signals;
use leeway_model::Source;
use leeway_model::planar_rotation;
use leeway_scenarios::study;
use leeway_scenarios::study::InputDesign;
use leeway_scenarios::synth::TrueSystem;
use leeway_scenarios::synth::experiment;

fn ship() -> Interpreter {
    let path = format!("{}/../examples/models/ship.som", env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(path).unwrap_or_default();
    let c = leeway_structure::compile(&src, &Default::default());
    Interpreter::new(c.ir.unwrap_or_else(|| panic!("ship.som compiles: {:?}", c.diagnostics)))
}

/// Mean relative error on the identifiable aggregates (`X_uu + W_uu`, ...).
fn relative_error(theta: &[f64]) -> f64 {
    study::aggregate_error(theta)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn options(method: Method) -> EstimateOptions {
    // IV1's basic predictor sees water.u*|water.u| and air.u*|air.u| alike at
    // v = 0: it can only estimate the aggregates.
    EstimateOptions {
        method,
        covariance: false,
        aggregate: method == Method::Iv1,
        ..EstimateOptions::default()
    }
}

fn run(model: &Interpreter, e: &Experiment, method: Method) -> leeway_estimate::Estimate {
    estimate(model, &[e as &dyn Source], &options(method))
        .unwrap_or_else(|err| panic!("{method:?}: {} ({})", err.message, err.hint))
}

#[test]
fn iv3_error_shrinks_with_n_while_least_squares_stays_biased() {
    let model = ship();
    let design = InputDesign::default();
    let mut table = Vec::new();
    for n in [1000usize, 8000] {
        let (mut iv3, mut ls) = (Vec::new(), Vec::new());
        for seed in 0..4 {
            let (e, _) = study::estimation_experiment(&model, &design, 10.0, n, 100 + seed);
            iv3.push(relative_error(&run(&model, &e, Method::Iv3).theta));
            ls.push(relative_error(&run(&model, &e, Method::Ls).theta));
        }
        table.push((n, median(iv3), median(ls)));
    }
    let (small, large) = (table[0], table[1]);
    eprintln!("N, IV3 error, LS error: {table:?}");
    // 8× the data: a consistent estimator's error falls by about √8 ≈ 2.8.
    assert!(large.1 < 0.6 * small.1, "IV3 error must shrink: {table:?}");
    // LS converges to a biased value: its error does not shrink like 1/√N.
    assert!(large.2 > 0.7 * small.2, "LS error stays: {table:?}");
    assert!(
        large.2 > 2.0 * large.1,
        "LS is worse than IV3 at large N: {table:?}"
    );
}

#[test]
fn current_mean_is_recovered_within_three_standard_errors() {
    let model = ship();
    for seed in 0..4 {
        let (e, _) =
            study::estimation_experiment(&model, &InputDesign::default(), 10.0, 5000, 200 + seed);
        let est = estimate(
            &model,
            &[&e as &dyn Source],
            &EstimateOptions {
                method: Method::Iv3,
                ..EstimateOptions::default()
            },
        )
        .unwrap_or_else(|err| panic!("{}", err.message));
        assert_eq!(
            est.disturbances.len(),
            2,
            "north and east means of the current"
        );
        for (d, truth) in est.disturbances.iter().zip(study::CURRENT_MEAN) {
            let se = d.std_error.unwrap_or(f64::INFINITY);
            assert!(se > 0.0 && se < 0.05, "{} std error {se}", d.component);
            assert!(
                (d.mean - truth).abs() < 3.0 * se,
                "seed {seed}: {} = {} ± {se}, truth {truth}",
                d.component,
                d.mean
            );
        }
    }
}

/// Estimation data with chosen disturbance means (current and wind).
fn data_with_means(
    model: &Interpreter,
    current: f64,
    wind: f64,
    n: usize,
    seed: u64,
) -> Experiment {
    let mut sys: TrueSystem = study::true_system(wind);
    sys.disturbance_mean = vec![current, current, wind, wind];
    let design = InputDesign::default();
    experiment(
        model,
        &sys,
        "run",
        &design.x0,
        0.0,
        &study::estimation_input(&design, n, seed + 7),
        seed,
    )
    .0
}

#[test]
fn iv1_is_consistent_with_zero_mean_disturbances_only() {
    let model = ship();
    let err = |current: f64, n: usize| {
        median(
            (0..4)
                .map(|s| {
                    relative_error(
                        &run(
                            &model,
                            &data_with_means(&model, current, 0.0, n, 300 + s),
                            Method::Iv1,
                        )
                        .theta,
                    )
                })
                .collect(),
        )
    };
    let (zero_small, zero_large) = (err(0.0, 2000), err(0.0, 16000));
    let (mean_small, mean_large) = (err(0.2, 2000), err(0.2, 16000));
    eprintln!("IV1 zero-mean: {zero_small} → {zero_large}; mean 0.2: {mean_small} → {mean_large}");
    assert!(
        zero_large < 0.6 * zero_small,
        "zero-mean current: IV1 converges"
    );
    assert!(
        zero_large < 0.3,
        "zero-mean current: IV1 close to θ0 at N = 16000"
    );
    assert!(
        mean_large > 3.0 * zero_large && mean_large > 0.5,
        "current with a mean: IV1 stays biased"
    );
}

#[test]
fn low_wind_names_the_unexcited_wind_parameters_and_returns_aggregates() {
    let model = ship();
    let (e, _) = study::estimation_experiment(&model, &InputDesign::default(), 1.0, 5000, 400);
    let est = run(&model, &e, Method::Iv3);
    for w in ["W_uu", "W_vv", "W_uv"] {
        assert!(
            est.diagnostics
                .unexcited
                .iter()
                .any(|u| u.starts_with(&format!("{w} is not separately excited"))),
            "{w} named: {:?}",
            est.diagnostics.unexcited
        );
        assert!(
            est.warnings
                .iter()
                .any(|m| m.contains(&format!("`{w}` is not separately excited"))),
            "{w} warned"
        );
        assert_eq!(est.get(w), Some(0.0), "{w} held at its nominal value");
    }
    // The aggregates absorb the wind parameters: X_uu + W_uu ≈ θ0's sum.
    assert!(
        est.diagnostics
            .aggregates
            .iter()
            .any(|a| a.starts_with("X_uu estimates X_uu + ")),
        "{:?}",
        est.diagnostics.aggregates
    );
    let x_uu = est.get("X_uu").unwrap_or(f64::NAN);
    assert!(
        (x_uu - (study::THETA0[2] + study::THETA0[3])).abs() < 0.01,
        "X_uu aggregate {x_uu}"
    );
}

#[test]
fn wind_changing_sign_relative_to_the_ship_gives_the_a7_warning_with_its_fraction() {
    let model = ship();
    let (e, _) = study::estimation_experiment(&model, &InputDesign::default(), 10.0, 3000, 500);
    let est = estimate(
        &model,
        &[&e as &dyn Source],
        &EstimateOptions {
            method: Method::Iv2,
            aggregate: true,
            covariance: false,
            ..EstimateOptions::default()
        },
    )
    .unwrap_or_else(|err| panic!("{}", err.message));
    let air_u = est.sign_patterns[0]
        .arguments
        .iter()
        .find(|a| a.argument == "air.u")
        .map(|a| a.minority_fraction)
        .unwrap_or(0.0);
    assert!(
        air_u > 0.05 && air_u < 0.5,
        "air.u changes sign in part of the circle: {air_u}"
    );
    assert!(
        est.warnings
            .iter()
            .any(|w| w.contains("air.u has sign") && w.contains('%') && w.contains("A7")),
        "{:?}",
        est.warnings
    );
    let strict = estimate(
        &model,
        &[&e as &dyn Source],
        &EstimateOptions {
            method: Method::Iv2,
            aggregate: true,
            strict: true,
            ..EstimateOptions::default()
        },
    );
    assert_eq!(strict.err().map(|e| e.code), Some("sign-violation"));
}

#[test]
fn a_constant_heading_leaves_the_current_terms_collinear() {
    // A ship on a perfect heading autopilot: the yaw moment cancels every yaw
    // term, so r ≡ 0 and ψ is constant (measured with noise). Surge and sway
    // are excited; the current acts.
    let model = ship();
    let ir = model.ir().clone();
    let sys = study::true_system(1.0);
    let design = InputDesign::default();
    let pulses = study::estimation_input(&design, 3000, 9);
    let mut e = Experiment::new(&ir, "straight", 1.0);
    let mut x = vec![5.0, 3.3, 0.0];
    let psi = 0.7;
    let mut rng_state = 12345u64;
    let mut noise = || {
        // A small deterministic LCG-based noise (the shape does not matter here).
        rng_state = rng_state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((rng_state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02
    };
    let mut f = vec![0.0; 3];
    let mut next = vec![0.0; 3];
    for u in &pulses {
        let dist = [0.2, 0.2, 1.0, 1.0];
        let rot = planar_rotation(psi);
        let mut input = vec![u[0], u[1], 0.0];
        let sig = Signals {
            states: &x,
            inputs: &input,
            rotation: &rot,
            disturbances: &dist,
        };
        model.rhs(&sys.theta, &sig, &mut f);
        input[2] = -f[2] / sys.theta[16];
        let y: Vec<f64> = x.iter().map(|v| v + noise()).collect();
        let m = [0.0, 0.0, 1.0 + noise(), 1.0 + noise()];
        e.push(
            &ir,
            &leeway_model::Row {
                states: &y,
                inputs: &input,
                heading: psi + noise(),
                rotation: &[],
                disturbances: &m,
            },
        );
        let sig = Signals {
            states: &x,
            inputs: &input,
            rotation: &rot,
            disturbances: &dist,
        };
        model.step(&sys.theta, 1.0, &sig, &mut f, &mut next);
        x.copy_from_slice(&next);
    }
    let err = estimate(&model, &[&e as &dyn Source], &options(Method::Iv3))
        .err()
        .unwrap_or_else(|| panic!("must fail"));
    eprintln!("{}\nhint: {}", err.message, err.hint);
    assert_eq!(err.code, "unidentifiable");
    assert!(
        err.message.contains("rho[north,X_uu]") || err.message.contains("rho["),
        "names the current terms: {}",
        err.message
    );
    assert!(
        err.message.contains("X_u"),
        "names the parameter: {}",
        err.message
    );
    assert!(err.hint.contains("Remark 2"), "{}", err.hint);
}

#[test]
fn estimates_are_bit_identical_across_runs() {
    let model = ship();
    let (e, _) = study::estimation_experiment(&model, &InputDesign::default(), 10.0, 1500, 600);
    let a = estimate(&model, &[&e as &dyn Source], &EstimateOptions::default()).map(|x| x.theta);
    let b = estimate(&model, &[&e as &dyn Source], &EstimateOptions::default()).map(|x| x.theta);
    let bits = |v: &Vec<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(a.as_ref().map(bits), b.as_ref().map(bits));
}

/// A yaw-rate model (one state, a rudder, a constant moment) and a record of
/// it under an autopilot that holds the heading: the rudder answers the
/// measured heading and yaw rate (closed loop), with a seeded process and
/// measurement noise and a slow sweep of the set heading.
fn yaw_under_autopilot(n_r: f64, seed: u64) -> (Interpreter, Experiment) {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let src = "model Yaw { state r input delta der r = N_r*r + N_d*delta + N_0 \
               nominal { N_r = -0.1, N_d = 0.05 } }";
    let c = leeway_structure::compile(src, &Default::default());
    let model = Interpreter::new(c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics)));
    let (h, n_d, n_0) = (0.5, 0.05, 0.002);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut noise = move || -> f64 { StandardNormal.sample(&mut rng) };
    let mut e = Experiment::new(model.ir(), "autopilot", h);
    let (mut r, mut psi) = (0.0f64, 0.0f64);
    for k in 0..6000 {
        let t = k as f64 * h;
        let measured = r + 0.0005 * noise();
        let set = 0.3 * (0.01 * t).sin();
        let delta = (-4.0 * (psi - set) - 12.0 * measured).clamp(-0.6, 0.6) + 0.005 * noise();
        e.states[0].push(measured);
        e.inputs[0].push(delta);
        let w = 0.001 * noise();
        psi += h * r;
        r += h * (n_r * r + n_d * delta + n_0 + w);
    }
    (model, e)
}

#[test]
fn an_estimate_whose_own_simulation_diverges_is_never_called_converged() {
    // Regression: a craft unstable in open loop, logged under an autopilot: the
    // right estimate's free run on the recorded rudder diverges, and the
    // estimate must say so (a warning, not "converged"; an error under
    // --strict), whatever the method.
    let (model, e) = yaw_under_autopilot(0.05, 7);
    for method in [Method::Ls, Method::Iv3] {
        let options = EstimateOptions {
            method,
            ..EstimateOptions::default()
        };
        let est = estimate(&model, &[&e as &dyn Source], &options)
            .unwrap_or_else(|err| panic!("{method:?}: {}", err.message));
        let own = est
            .diagnostics
            .own_simulation
            .clone()
            .unwrap_or_else(|| panic!("{method:?}: no own simulation"));
        eprintln!("{method:?}: θ {:?}, {own:?}", est.theta);
        assert_eq!(own.diverged, ["autopilot"], "{method:?}: {own:?}");
        assert!(!est.diagnostics.converged, "{method:?}");
        assert!(
            est.warnings
                .iter()
                .any(|w| w.contains("does not reproduce its own data") && w.contains("A1")),
            "{method:?}: {:?}",
            est.warnings
        );
        let strict = EstimateOptions {
            strict: true,
            ..options
        };
        let failed = estimate(&model, &[&e as &dyn Source], &strict);
        assert_eq!(
            failed.err().map(|e| e.code),
            Some("own-simulation"),
            "{method:?}"
        );
    }
    // A stable craft in the same loop: its own simulation stays bounded and
    // fits better than the mean (the closed loop still biases θ: 14.8 %).
    let (model, e) = yaw_under_autopilot(-0.1, 7);
    let est = estimate(&model, &[&e as &dyn Source], &EstimateOptions::default())
        .unwrap_or_else(|err| panic!("{}", err.message));
    let own = est.diagnostics.own_simulation.clone();
    eprintln!("stable: θ {:?}, {own:?}", est.theta);
    assert!(
        own.as_ref()
            .is_some_and(|o| o.diverged.is_empty() && o.mean_fit.is_some_and(|f| f > 0.0)),
        "{own:?}"
    );
    assert!(est.diagnostics.converged);
    assert!(
        !est.warnings.iter().any(|w| w.contains("own data")),
        "{:?}",
        est.warnings
    );
}

#[test]
fn an_interrupt_stops_the_estimate_between_passes() {
    // Regression: Ctrl-C from Python; the interrupt is asked around every pass.
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let model = ship();
    let (e, _) = study::estimation_experiment(&model, &InputDesign::default(), 10.0, 1500, 3);
    let asked = Arc::new(AtomicUsize::new(0));
    let counter = asked.clone();
    let options = EstimateOptions {
        interrupt: Some(leeway_estimate::Interrupt::new(move || {
            counter.fetch_add(1, Ordering::SeqCst) >= 3
        })),
        ..EstimateOptions::default()
    };
    let result = estimate(&model, &[&e as &dyn Source], &options);
    assert_eq!(result.err().map(|e| e.code), Some("interrupted"));
    assert_eq!(asked.load(Ordering::SeqCst), 4, "stopped at the first yes");
    // Never asked to stop: the same estimate as without an interrupt.
    let never = EstimateOptions {
        interrupt: Some(leeway_estimate::Interrupt::new(|| false)),
        ..EstimateOptions::default()
    };
    let a = estimate(&model, &[&e as &dyn Source], &never).map(|e| e.theta);
    let b = estimate(&model, &[&e as &dyn Source], &EstimateOptions::default()).map(|e| e.theta);
    assert_eq!(a, b);
}
