//! Synthetic experiments from a "true system": any model with true θ,
//! i.i.d. Gaussian disturbances and measurement noises, seeded. Used by the
//! simulation study (paper §V) and by tests; reproducible for a given seed.
//! Samples are streamed to a caller ([`run`]) or stored ([`experiment`]).

use leeway_model::experiment::{Experiment, Row, Source};
use leeway_model::model::{Model, Signals, next_heading, planar_rotation};
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
    /// Standard deviation of each component about its mean.
    pub disturbance_std: Vec<f64>,
    /// Correlation time of each component, s: a first-order Gauss–Markov
    /// process `d(k+1) = a·d(k) + √(1−a²)·σ·ε`, `a = exp(−h/T)`, whose
    /// stationary std is `σ`. Zero or missing: i.i.d. over time.
    pub disturbance_time: Vec<f64>,
    /// Measurement noise std of each state.
    pub state_noise: Vec<f64>,
    /// Heading measurement noise std.
    pub heading_noise: f64,
    /// Noise std of each measured disturbance component (the auxiliary
    /// sensor; missing: noise-free).
    pub aux_noise: Vec<f64>,
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

/// One sample of the true system: the measurements, and the truth behind them.
#[derive(Clone, Copy, Debug)]
pub struct TrueSample<'a> {
    /// What a logger records.
    pub measured: Row<'a>,
    /// True states.
    pub states: &'a [f64],
    /// True heading.
    pub heading: f64,
    /// True disturbance values (earth frame for earth components).
    pub disturbances: &'a [f64],
}

/// Runs the true system on a stream of inputs from `x0`, `psi0`, calling `f`
/// with each sample. One generator seeded by `seed` draws everything in a
/// fixed order, so the samples depend only on the seed; nothing is stored.
#[allow(clippy::too_many_arguments)]
pub fn run(
    model: &dyn Model,
    system: &TrueSystem,
    x0: &[f64],
    psi0: f64,
    inputs: &mut dyn Iterator<Item = Vec<f64>>,
    seed: u64,
    f: &mut dyn FnMut(&TrueSample),
) {
    let ir = model.ir();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut g = move || -> f64 { StandardNormal.sample(&mut rng) };
    let n_out = ir.states.len();
    let n_comp = ir.components.len();
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let mut x = x0.to_vec();
    let mut psi = psi0;
    let mut next = vec![0.0; n_out];
    let mut rhs = vec![0.0; n_out];
    let mut v = vec![0.0; n_comp];
    let mut y = vec![0.0; n_out];
    let mut m = vec![0.0; n_comp];
    // The Gauss–Markov state of each component; the first sample is drawn
    // from the stationary law, so an i.i.d. component (a = 0) draws as before.
    let decay: Vec<f64> = (0..n_comp)
        .map(|c| match system.disturbance_time.get(c) {
            Some(t) if *t > 0.0 => (-system.h / t).exp(),
            _ => 0.0,
        })
        .collect();
    let mut deviation = vec![0.0; n_comp];
    let mut first = true;
    for u in inputs {
        for (c, value) in v.iter_mut().enumerate() {
            let std = system.disturbance_std.get(c).copied().unwrap_or(0.0);
            let a = decay[c];
            deviation[c] = if a == 0.0 || first {
                std * g()
            } else {
                a * deviation[c] + (1.0 - a * a).sqrt() * std * g()
            };
            *value = system.disturbance_mean.get(c).copied().unwrap_or(0.0) + deviation[c];
        }
        first = false;
        for o in 0..n_out {
            y[o] = x[o] + system.state_noise[o] * g();
        }
        let y_psi = psi + system.heading_noise * g();
        for c in 0..n_comp {
            m[c] = if ir.disturbances[ir.components[c].disturbance].measured {
                v[c] + system.aux_noise.get(c).copied().unwrap_or(0.0) * g()
            } else {
                0.0
            };
        }
        f(&TrueSample {
            measured: Row {
                states: &y,
                inputs: &u,
                heading: y_psi,
                rotation: &[],
                disturbances: &m,
            },
            states: &x,
            heading: psi,
            disturbances: &v,
        });
        let rot = if planar {
            planar_rotation(psi)
        } else {
            [0.0; 2]
        };
        let sig = Signals {
            states: &x,
            inputs: &u,
            rotation: if planar { &rot } else { &[] },
            disturbances: &v,
        };
        model.step(&system.theta, system.h, &sig, &mut rhs, &mut next);
        for (o, value) in next.iter_mut().enumerate() {
            *value += system.process_noise.get(o).copied().unwrap_or(0.0) * g();
        }
        psi = next_heading(ir, psi, system.h, &x);
        x.copy_from_slice(&next);
    }
}

/// Simulates the true system on `inputs[k]` (one vector per sample) from
/// `x0`, `psi0`, and records noisy measurements (see [`run`]).
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
    let mut e = Experiment::new(ir, name, system.h);
    let mut truth = Truth {
        states: vec![Vec::new(); ir.states.len()],
        heading: Vec::new(),
        disturbances: vec![Vec::new(); ir.components.len()],
    };
    run(
        model,
        system,
        x0,
        psi0,
        &mut inputs.iter().cloned(),
        seed,
        &mut |s| {
            e.push(ir, &s.measured);
            for (t, x) in truth.states.iter_mut().zip(s.states) {
                t.push(*x);
            }
            truth.heading.push(s.heading);
            for (t, v) in truth.disturbances.iter_mut().zip(s.disturbances) {
                t.push(*v);
            }
        },
    );
    (e, truth)
}

/// A synthetic experiment that is never stored: every visit re-runs the
/// true system from the seed, so memory stays flat whatever its length
/// (used to stream 10⁷ samples through an estimator).
pub struct Stream<'a> {
    /// The model of the true system.
    pub model: &'a dyn Model,
    /// The true system.
    pub system: TrueSystem,
    /// Its name.
    pub name: String,
    /// Initial state.
    pub x0: Vec<f64>,
    /// Initial heading.
    pub psi0: f64,
    /// Number of samples.
    pub n: usize,
    /// Noise seed.
    pub seed: u64,
    /// The input, produced afresh on every visit.
    pub input: Box<dyn Fn() -> Box<dyn Iterator<Item = Vec<f64>>> + Sync + 'a>,
}

impl Source for Stream<'_> {
    fn name(&self) -> &str {
        &self.name
    }
    fn len(&self) -> usize {
        self.n
    }
    fn step(&self) -> f64 {
        self.system.h
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        let mut input = (self.input)().take(self.n);
        run(
            self.model,
            &self.system,
            &self.x0,
            self.psi0,
            &mut input,
            self.seed,
            &mut |s| f(&s.measured),
        );
    }
}
