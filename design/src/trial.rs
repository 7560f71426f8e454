//! A designed run at sea: its base before the excitation ([`Base`]), the
//! excitation fitted to the bases ([`Fitted`]) and the run they make
//! ([`Run`]); simulated: the plan's true system
//! ([`true_system`]), the nominal trajectory (mean disturbances, no noise)
//! and a realisation (random disturbances and noise, seeded), and the
//! margins of the held sign arguments along a true trajectory.

use crate::excitation::Excitation;
use crate::operating::OperatingPoint;
use crate::plan::{Conditions, Family};
use crate::signs::Held;
use leeway_model::experiment::Experiment;
use leeway_model::model::{Model, Signals, planar_rotation};
use leeway_scenarios::synth::{TrueSystem, Truth, experiment};
use leeway_structure::ir::{Rotation, SignPattern};

/// One run of a design: where it starts and what it commands.
#[derive(Clone, Debug)]
pub struct Run {
    /// Initial state (the operating point's steady state).
    pub x0: Vec<f64>,
    /// `inputs[k][i]`.
    pub inputs: Vec<Vec<f64>>,
}

/// One experiment before its excitation: its pattern, what it holds, where.
#[derive(Clone, Debug)]
pub struct Base {
    /// ±1 per sign argument.
    pub pattern: SignPattern,
    /// The arguments it holds.
    pub held: Vec<Held>,
    /// Its operating point.
    pub operating: OperatingPoint,
}

/// An excitation fitted to the bases: one per run, and how it fared.
#[derive(Clone, Debug)]
pub struct Fitted {
    /// The family.
    pub family: Family,
    /// Per run.
    pub excitations: Vec<Excitation>,
    /// Fraction of each input's room used.
    pub scale: f64,
    /// Per run, per held argument: the smallest nominal margin over the
    /// samples and starting headings.
    pub min_margins: Vec<Vec<f64>>,
}

impl Fitted {
    /// Whether every held argument keeps its side with its band.
    pub fn feasible(&self) -> bool {
        self.min_margins.iter().flatten().all(|m| *m >= 0.0)
    }
    /// The runs at `n` samples each.
    pub fn runs(&self, bases: &[Base], n: usize, c: &Conditions) -> Vec<Run> {
        bases
            .iter()
            .zip(&self.excitations)
            .map(|(b, e)| Run {
                x0: b.operating.steady.states.clone(),
                inputs: e.generate(n, &c.limits),
            })
            .collect()
    }
}

/// The plan's true system: θ, the disturbances' means, spreads and
/// correlation times, and the noises (`noisy == false`: the nominal
/// system, every spread and noise zero).
pub fn true_system(c: &Conditions, noise: &[f64], heading_noise: f64, noisy: bool) -> TrueSystem {
    let on = |v: &[f64]| {
        if noisy {
            v.to_vec()
        } else {
            vec![0.0; v.len()]
        }
    };
    TrueSystem {
        theta: c.theta.clone(),
        h: c.h,
        disturbance_mean: c.mean.clone(),
        disturbance_std: on(&c.std),
        disturbance_time: c.correlation_time.clone(),
        state_noise: (0..c.state_noise.len())
            .map(|i| {
                if noisy {
                    noise.get(i).copied().unwrap_or(0.0)
                } else {
                    0.0
                }
            })
            .collect(),
        heading_noise: if noisy { heading_noise } else { 0.0 },
        aux_noise: on(&c.sensor_noise),
        process_noise: Vec::new(),
    }
}

/// θ drawn from the plan's prior: each parameter times `1 + prior·z`, `z`
/// standard normal clipped at ±2.5, from `seed`; the nominal θ itself
/// when the prior is 0 (no draw).
pub fn draw_theta(c: &Conditions, seed: u64) -> Vec<f64> {
    if c.prior == 0.0 {
        return c.theta.clone();
    }
    let mut draws = leeway_scenarios::synth::Draws::new(seed);
    c.theta
        .iter()
        .map(|t| t * (1.0 + c.prior * draws.normal().clamp(-2.5, 2.5)))
        .collect()
}

/// Simulates `run` on `system` from heading `psi0`: the recorded
/// experiment and the truth behind it.
pub fn simulate(
    model: &dyn Model,
    system: &TrueSystem,
    run: &Run,
    name: &str,
    psi0: f64,
    seed: u64,
) -> (Experiment, Truth) {
    experiment(model, system, name, &run.x0, psi0, &run.inputs, seed)
}

/// The headings a nominal run is checked from: a craft meets an earth-fixed
/// medium from any side, so four quarters when one has a mean; else one.
pub fn start_headings(model: &dyn Model, c: &Conditions) -> Vec<f64> {
    let ir = model.ir();
    let earth_mean = ir
        .disturbances
        .iter()
        .filter(|d| d.earth)
        .flat_map(|d| d.components.iter())
        .any(|comp| c.mean[*comp] != 0.0);
    if matches!(ir.rotation, Rotation::Planar { .. }) && earth_mean {
        (0..4)
            .map(|q| f64::from(q) * std::f64::consts::FRAC_PI_2)
            .collect()
    } else {
        vec![0.0]
    }
}

/// Per held argument, `sign·argument − band` at every sample of a true
/// trajectory (the margin; below zero the sign is at risk).
pub fn margins(
    model: &dyn Model,
    truth: &Truth,
    inputs: &[Vec<f64>],
    held: &[Held],
) -> Vec<Vec<f64>> {
    let ir = model.ir();
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let n = truth.states.first().map_or(0, Vec::len);
    let mut out = vec![Vec::with_capacity(n); held.len()];
    let mut states = vec![0.0; ir.states.len()];
    let mut dist = vec![0.0; ir.components.len()];
    for k in 0..n {
        for (s, t) in states.iter_mut().zip(&truth.states) {
            *s = t[k];
        }
        for (d, t) in dist.iter_mut().zip(&truth.disturbances) {
            *d = t[k];
        }
        let rotation = if planar {
            planar_rotation(truth.heading[k]).to_vec()
        } else {
            Vec::new()
        };
        let sig = Signals {
            states: &states,
            inputs: &inputs[k],
            rotation: &rotation,
            disturbances: &dist,
        };
        for (o, a) in out.iter_mut().zip(held) {
            o.push(a.value(&sig) - a.band);
        }
    }
    out
}

/// The fraction of samples of a true trajectory where each held argument
/// is on its side (the band aside).
pub fn kept(model: &dyn Model, truth: &Truth, inputs: &[Vec<f64>], held: &[Held]) -> Vec<f64> {
    let bands: Vec<Held> = held
        .iter()
        .map(|a| Held {
            band: 0.0,
            ..a.clone()
        })
        .collect();
    margins(model, truth, inputs, &bands)
        .iter()
        .map(|m| m.iter().filter(|v| **v > 0.0).count() as f64 / m.len().max(1) as f64)
        .collect()
}
