//! The paper's simulation study (§V): the true ship, its disturbances and
//! noises, and the input designs. The Monte Carlo loop, tables and plots
//! live in the CLI (`leeway reproduce`); what is here is shared with tests.
//!
//! Input design (estimation): a static offset `τ̄` that holds the ship in a
//! steady turn with surge ≈ 5 m/s, sway ≈ 3.3 m/s and yaw rate ≈ 0.15 rad/s,
//! plus smoothed pulses of random width (20–80 s) and amplitude on each
//! thruster; the sway thrust follows the yaw pulse so a harder turn does not
//! pull sway towards zero. The ship circles with small zigzags; surge and sway stay well
//! above the current (0.28 m/s) and, at 1 m/s wind, above the wind
//! (1.41 m/s), so IV2's sign assumption holds at low wind and fails at
//! 10 m/s, as in the paper. Validation: undisturbed, a zigzag-forward input
//! whose thrust is stepped too (else the surge fit would divide by ~0).

use crate::data::Experiment;
use crate::model::Model;
use crate::synth::{TrueSystem, Truth, experiment};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// θ0 of the paper's table, in `ship.som` order
/// (X_u, X_vr, X_uu, W_uu, X_tau, Y_v, Y_ur, Y_vv, Y_vr, W_vv, Y_tau, N_r, N_uv, N_vv, N_vr, W_uv, N_tau).
pub const THETA0: [f64; 17] = [
    -0.05, 1.0, -0.05, -0.0005, 0.02, -0.2, -0.65, -0.2, -0.1, -0.0015, 0.02, -0.1, -0.0015,
    -0.001, -0.04, -0.00003, 0.0003,
];

/// Mean of the current (north, east), m/s.
pub const CURRENT_MEAN: [f64; 2] = [0.2, 0.2];

/// The estimation input: a static offset plus smoothed pulses.
#[derive(Clone, Debug, PartialEq)]
pub struct InputDesign {
    /// Static offset `τ̄` (holds the steady turn).
    pub offset: [f64; 3],
    /// Pulse amplitude (half range) per thruster.
    pub pulse: [f64; 3],
    /// Pulse widths are drawn uniformly from this range (samples).
    pub width: (usize, usize),
    /// First-order smoothing factor per sample (1 = no smoothing).
    pub smoothing: f64,
    /// Initial state (the steady turn).
    pub x0: [f64; 3],
    /// Sway thrust added per unit of yaw pulse: a turn harder than the mean
    /// pulls sway down through `−Y_ur·u·r`; this keeps sway positive.
    pub sway_from_yaw: f64,
}

impl Default for InputDesign {
    fn default() -> InputDesign {
        InputDesign {
            offset: [50.0, 169.0, 235.0],
            pulse: [30.0, 40.0, 150.0],
            width: (20, 80),
            smoothing: 0.15,
            x0: [5.0, 3.3, 0.15],
            sway_from_yaw: 0.25,
        }
    }
}

/// The paper's true system with mean wind `wind` m/s in both north and east.
/// Current `N([0.2, 0.2], 1e-3·I)`, wind `N([w̄, w̄], 1e-3·I)`, i.i.d. in the
/// earth frame; `e_ν ~ N(0, 2e-4·I)`, `e_ψ ~ N(0, 1e-4)`, `e_aux ~ N(0, 1e-3·I)`.
pub fn true_system(wind: f64) -> TrueSystem {
    TrueSystem {
        theta: THETA0.to_vec(),
        h: 1.0,
        disturbance_mean: vec![CURRENT_MEAN[0], CURRENT_MEAN[1], wind, wind],
        disturbance_std: vec![1e-3f64.sqrt(); 4],
        state_noise: vec![2e-4f64.sqrt(); 3],
        heading_noise: 1e-4f64.sqrt(),
        aux_noise: 1e-3f64.sqrt(),
        process_noise: vec![0.0; 3],
    }
}

/// The estimation input: offset plus smoothed pulses of varying width.
pub fn estimation_input(design: &InputDesign, n: usize, seed: u64) -> Vec<Vec<f64>> {
    Pulses::new(design, seed).take(n).collect()
}

/// The estimation input as an endless stream (offset plus smoothed pulses),
/// for experiments too long to hold.
#[derive(Clone, Debug)]
pub struct Pulses {
    design: InputDesign,
    rng: ChaCha8Rng,
    current: [f64; 3],
    target: [f64; 3],
    left: [usize; 3],
}

impl Pulses {
    /// The pulse stream of a design and seed.
    pub fn new(design: &InputDesign, seed: u64) -> Pulses {
        Pulses { design: design.clone(), rng: ChaCha8Rng::seed_from_u64(seed), current: [0.0; 3], target: [0.0; 3], left: [0; 3] }
    }
}

impl Iterator for Pulses {
    type Item = Vec<f64>;
    fn next(&mut self) -> Option<Vec<f64>> {
        let d = &self.design;
        for i in 0..3 {
            if self.left[i] == 0 {
                self.left[i] = self.rng.random_range(d.width.0..d.width.1.max(d.width.0 + 1));
                self.target[i] = d.pulse[i] * self.rng.random_range(-1.0..1.0);
            }
            self.left[i] -= 1;
            // First-order smoothing.
            self.current[i] += d.smoothing * (self.target[i] - self.current[i]);
        }
        Some(vec![
            d.offset[0] + self.current[0],
            d.offset[1] + self.current[1] + d.sway_from_yaw * self.current[2],
            d.offset[2] + self.current[2],
        ])
    }
}

/// The validation input: zigzag forward (rudder-like sway/yaw steps every
/// 50 s), with the thrust stepped between two levels every 120 s.
pub fn validation_input(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|k| {
            let zig = if (k / 50) % 2 == 0 { 1.0 } else { -1.0 };
            let thrust = if (k / 120) % 2 == 0 { 70.0 } else { 45.0 };
            vec![thrust, 40.0 * zig, 150.0 * zig]
        })
        .collect()
}

/// One estimation experiment of the study.
pub fn estimation_experiment(
    model: &dyn Model,
    design: &InputDesign,
    wind: f64,
    n: usize,
    seed: u64,
) -> (Experiment, Truth) {
    let input = estimation_input(design, n, seed ^ 0x5eed_1e57);
    experiment(
        model,
        &true_system(wind),
        &format!("run{seed}"),
        &design.x0,
        0.0,
        &input,
        seed,
    )
}

/// The undisturbed, noise-free validation experiment.
pub fn validation_experiment(model: &dyn Model, n: usize) -> Experiment {
    let mut sys = true_system(0.0);
    sys.disturbance_mean = vec![0.0; 4];
    sys.disturbance_std = vec![0.0; 4];
    sys.state_noise = vec![0.0; 3];
    sys.heading_noise = 0.0;
    sys.aux_noise = 0.0;
    experiment(
        model,
        &sys,
        "validation",
        &[4.0, 0.0, 0.0],
        0.0,
        &validation_input(n),
        0,
    )
    .0
}

/// The identifiable aggregates of the ship's θ (in order): every parameter
/// except the wind ones, with the confounded pairs summed —
/// `X_uu + W_uu`, `Y_vv + W_vv`, `N_uv + W_uv` — which every estimator can
/// estimate whatever the wind, so all four compare on the same footing.
pub fn aggregates(theta: &[f64]) -> Vec<f64> {
    // Indices in ship.som order: W_uu = 3 pairs with X_uu = 2, W_vv = 9 with
    // Y_vv = 7, W_uv = 15 with N_uv = 12.
    let mut v = theta.to_vec();
    v[2] += theta[3];
    v[7] += theta[9];
    v[12] += theta[15];
    [0, 1, 2, 4, 5, 6, 7, 8, 10, 11, 12, 13, 14, 16]
        .iter()
        .map(|i| v[*i])
        .collect()
}

/// Mean relative error of the identifiable aggregates against θ0.
pub fn aggregate_error(theta: &[f64]) -> f64 {
    let est = aggregates(theta);
    let truth = aggregates(&THETA0);
    est.iter()
        .zip(&truth)
        .map(|(a, b)| ((a - b) / b).abs())
        .sum::<f64>()
        / truth.len() as f64
}
