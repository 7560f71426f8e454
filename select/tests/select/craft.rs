//! The simulated craft: the paper's ship with plausible extra candidate
//! terms, its truth a sparse subset of them, in a coloured (Gauss–Markov)
//! current and a measured, gusty wind.

use leeway_model::Experiment;
use leeway_model::Interpreter;
use leeway_model::Model;
use leeway_scenarios::study::{InputDesign, estimation_input};
use leeway_scenarios::synth::{TrueSystem, experiment};

/// The candidate model: 14 required or true terms (8 of them marked as
/// candidates) and 14 false candidates.
pub const CANDIDATE_SHIP: &str = r#"model CandidateShip {
    step 1.0
    state u, v, r
    input tau1, tau2, tau3
    heading psi integrates r

    disturbance current unmeasured earth(north, east)
    disturbance wind    measured   earth(wind_n, wind_e)

    water = relative(current)
    air   = relative(wind)

    der u = X_u*water.u + ?X_vr*water.v*r + ?X_uu*water.u*|water.u| + X_tau*tau1
          + ?W_u*air.u + ?X_r*r + ?X_rr*r*|r| + ?X_vv*water.v*|water.v| + ?X_t2*tau2
    der v = Y_v*water.v + ?Y_ur*water.u*r + ?Y_vv*water.v*|water.v| + Y_tau*tau2
          + ?W_v*air.v + ?Y_r*r + ?Y_rr*r*|r| + ?Y_vr*r*|water.v| + ?Y_t3*tau3 + ?Y_t1*tau1
    der r = N_r*r + ?N_uv*water.u*water.v + ?N_vr*r*|water.v| + N_tau*tau3
          + ?N_v*water.v + ?N_rr*r*|r| + ?N_vv*water.v*|water.v| + ?N_t2*tau2 + ?N_t1*tau1

    nominal { X_u = -0.2, X_vr = 0.8, X_tau = 0.01, Y_v = -0.3, Y_ur = -0.8,
              Y_tau = 0.01, N_r = -0.15, N_tau = 0.00015 }
}
"#;

/// The true parameters (every other candidate is truly zero).
pub const TRUTH: [(&str, f64); 14] = [
    ("X_u", -0.05),
    ("X_vr", 1.0),
    ("X_uu", -0.05),
    ("X_tau", 0.02),
    ("W_u", -0.03),
    ("Y_v", -0.2),
    ("Y_ur", -0.65),
    ("Y_vv", -0.2),
    ("Y_tau", 0.02),
    ("W_v", -0.03),
    ("N_r", -0.1),
    ("N_uv", -0.0015),
    ("N_vr", -0.04),
    ("N_tau", 0.0003),
];

/// The true candidates: the truth's terms marked `?`.
pub fn true_candidates() -> Vec<&'static str> {
    vec!["X_vr", "X_uu", "W_u", "Y_ur", "Y_vv", "W_v", "N_uv", "N_vr"]
}

pub fn model() -> Interpreter {
    let c = leeway_structure::compile(CANDIDATE_SHIP, &Default::default());
    Interpreter::new(
        c.ir.unwrap_or_else(|| panic!("the candidate ship compiles: {:?}", c.diagnostics)),
    )
}

/// The true system: current mean (0.2, 0.2) m/s with 0.05 m/s deviations
/// correlated over 60 s; wind 3 m/s north and east with 1 m/s gusts
/// correlated over 10 s, measured with noise.
pub fn system(model: &Interpreter) -> TrueSystem {
    let names: Vec<&str> = model
        .ir()
        .parameters
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    let theta = names
        .iter()
        .map(|n| TRUTH.iter().find(|(t, _)| t == n).map_or(0.0, |(_, v)| *v))
        .collect();
    TrueSystem {
        theta,
        h: 1.0,
        disturbance_mean: vec![0.2, 0.2, 3.0, 3.0],
        disturbance_std: vec![0.05, 0.05, 1.0, 1.0],
        disturbance_time: vec![60.0, 60.0, 10.0, 10.0],
        state_noise: vec![2e-4f64.sqrt(); 3],
        heading_noise: 1e-4f64.sqrt(),
        aux_noise: vec![1e-3f64.sqrt(); 4],
        process_noise: vec![0.0; 3],
    }
}

/// `count` estimation experiments of `n` samples from `seed`.
pub fn experiments(model: &Interpreter, seed: u64, count: usize, n: usize) -> Vec<Experiment> {
    let design = InputDesign::default();
    let sys = system(model);
    (0..count as u64)
        .map(|k| {
            let s = seed * 1000 + k;
            let input = estimation_input(&design, n, s ^ 0x5eed_1e57);
            experiment(model, &sys, &format!("run{k}"), &design.x0, 0.0, &input, s).0
        })
        .collect()
}
