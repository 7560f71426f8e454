//! Synthetic experiments from a "true system": any model with true θ,
//! i.i.d. Gaussian disturbances and measurement noises, seeded. Used by the
//! simulation study (paper §V) and by tests; reproducible for a given seed.

use crate::data::{Experiment, Row};
use crate::model::{Model, Signals, next_heading, planar_rotation};
use leeway_structure::ir::Rotation;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The true system and its noises.
#[derive(Clone, Debug)]
pub struct TrueSystem {
    /// True θ.
    pub theta: Vec<f64>,
    /// Sample time.
    pub h: f64,
    /// Mean of each disturbance component (global index; earth frame for earth ones).
    pub disturbance_mean: Vec<f64>,
    /// Standard deviation of each component (i.i.d. over time).
    pub disturbance_std: Vec<f64>,
    /// Measurement noise std of each state.
    pub state_noise: Vec<f64>,
    /// Heading measurement noise std.
    pub heading_noise: f64,
    /// Noise std of measured disturbance components (the auxiliary sensor).
    pub aux_noise: f64,
    /// Process noise std per state (additive `w`).
    pub process_noise: Vec<f64>,
}

/// The noise-free trajectory behind a synthetic experiment (for checks).
#[derive(Clone, Debug, Default)]
pub struct Truth {
    /// True states `x[i][k]`.
    pub states: Vec<Vec<f64>>,
    /// True heading.
    pub heading: Vec<f64>,
    /// True disturbance values `v[c][k]`.
    pub disturbances: Vec<Vec<f64>>,
}

/// Simulates the true system on `inputs[k]` (one vector per sample) from
/// `x0`, `psi0`, and records noisy measurements. One generator seeded by
/// `seed` draws everything in a fixed order, so the experiment depends only
/// on the seed.
pub fn experiment(
    model: &dyn Model,
    system: &TrueSystem,
    name: &str,
    x0: &[f64],
    psi0: f64,
    inputs: &[Vec<f64>],
    seed: u64,
) -> (Experiment, Truth) {
    let ir = model.ir();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut g = move || -> f64 { StandardNormal.sample(&mut rng) };
    let n_out = ir.states.len();
    let n_comp = ir.components.len();
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let mut e = Experiment::new(ir, name, system.h);
    let mut truth = Truth {
        states: vec![Vec::new(); n_out],
        heading: Vec::new(),
        disturbances: vec![Vec::new(); n_comp],
    };
    let mut x = x0.to_vec();
    let mut psi = psi0;
    let mut next = vec![0.0; n_out];
    let mut f = vec![0.0; n_out];
    let mut v = vec![0.0; n_comp];
    let mut y = vec![0.0; n_out];
    let mut m = vec![0.0; n_comp];
    for u in inputs {
        for c in 0..n_comp {
            v[c] = system.disturbance_mean[c] + system.disturbance_std[c] * g();
        }
        for o in 0..n_out {
            y[o] = x[o] + system.state_noise[o] * g();
        }
        let y_psi = psi + system.heading_noise * g();
        for c in 0..n_comp {
            m[c] = if ir.disturbances[ir.components[c].disturbance].measured {
                v[c] + system.aux_noise * g()
            } else {
                0.0
            };
        }
        e.push(
            ir,
            &Row {
                states: &y,
                inputs: u,
                heading: y_psi,
                rotation: &[],
                disturbances: &m,
            },
        );
        for o in 0..n_out {
            truth.states[o].push(x[o]);
        }
        truth.heading.push(psi);
        for c in 0..n_comp {
            truth.disturbances[c].push(v[c]);
        }
        let rot = if planar {
            planar_rotation(psi).to_vec()
        } else {
            Vec::new()
        };
        let sig = Signals {
            states: &x,
            inputs: u,
            rotation: &rot,
            disturbances: &v,
        };
        model.step(&system.theta, system.h, &sig, &mut f, &mut next);
        for o in 0..n_out {
            next[o] += system.process_noise.get(o).copied().unwrap_or(0.0) * g();
        }
        psi = next_heading(ir, psi, system.h, &x);
        x.copy_from_slice(&next);
    }
    (e, truth)
}
