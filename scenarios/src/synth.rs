//! Synthetic experiments from a "true system": any model with true θ,
//! Gaussian disturbances (i.i.d. or Gauss–Markov) and measurement noises,
//! seeded. Its generator pieces ([`Draws`], [`GaussMarkov`], [`measure`])
//! also drive a noisy simulation on a recorded input
//! ([`noisy`](crate::noisy)). Used by the
//! simulation study (paper §V) and by tests; reproducible for a given seed.
//! Samples are streamed to a caller ([`run`]) or stored ([`experiment`]).

use leeway_model::experiment::{Experiment, Row, Source};
use leeway_model::model::{Model, Signals, next_heading, planar_rotation};
use leeway_structure::ir::{Ir, Rotation};
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

/// Standard normal draws from one generator seeded by a `u64`: the whole
/// randomness of a true system, drawn in a fixed order.
pub struct Draws(ChaCha8Rng);

impl Draws {
    /// The generator of `seed` (its stream 0).
    pub fn new(seed: u64) -> Draws {
        Draws(ChaCha8Rng::seed_from_u64(seed))
    }

    /// Stream `stream` of the generator of `seed`: independent of the
    /// seed's other streams, so that one purpose's draws do not shift when
    /// another draws more or fewer.
    pub fn stream(seed: u64, stream: u64) -> Draws {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Draws(rng)
    }

    /// The next standard normal draw.
    pub fn normal(&mut self) -> f64 {
        StandardNormal.sample(&mut self.0)
    }
}

/// The deviation of each disturbance component from its mean, sample by
/// sample: a first-order Gauss–Markov process `d(k+1) = a·d(k) +
/// √(1−a²)·σ·ε`, `a = exp(−h/T)`, whose stationary std is `σ`; the first
/// sample is drawn from the stationary law, so an i.i.d. component
/// (`T = 0`, `a = 0`) draws `σ·ε` every sample. One draw per component and
/// sample, whatever its std.
#[derive(Clone, Debug)]
pub struct GaussMarkov {
    std: Vec<f64>,
    decay: Vec<f64>,
    deviation: Vec<f64>,
    first: bool,
}

impl GaussMarkov {
    /// `n` components sampled every `h` s with stds `std` and correlation
    /// times `time` (missing: 0; zero or missing time: i.i.d.).
    pub fn new(n: usize, h: f64, std: &[f64], time: &[f64]) -> GaussMarkov {
        let decay = (0..n)
            .map(|c| match time.get(c) {
                Some(t) if *t > 0.0 => (-h / t).exp(),
                _ => 0.0,
            })
            .collect();
        GaussMarkov {
            std: (0..n).map(|c| std.get(c).copied().unwrap_or(0.0)).collect(),
            decay,
            deviation: vec![0.0; n],
            first: true,
        }
    }

    /// The deviations at the next sample.
    pub fn next(&mut self, draws: &mut Draws) -> &[f64] {
        for (c, d) in self.deviation.iter_mut().enumerate() {
            let (a, std) = (self.decay[c], self.std[c]);
            *d = if a == 0.0 || self.first {
                std * draws.normal()
            } else {
                a * *d + (1.0 - a * a).sqrt() * std * draws.normal()
            };
        }
        self.first = false;
        &self.deviation
    }
}

/// The noise of each sensor: per state, the heading's, per measured
/// disturbance component (missing: noise-free).
#[derive(Clone, Copy, Debug)]
pub struct Sensors<'a> {
    /// Std per state.
    pub states: &'a [f64],
    /// Std of the heading.
    pub heading: f64,
    /// Std per disturbance component (read for measured ones).
    pub disturbances: &'a [f64],
}

/// What the sensors record of one sample of the truth (states `x`, heading
/// `psi`, disturbances `v`): the states into `y`, the measured components
/// into `m` (unmeasured ones 0), and the heading returned. Draws one
/// normal per state, one for the heading, then one per measured component.
#[allow(clippy::too_many_arguments)]
pub fn measure(
    draws: &mut Draws,
    ir: &Ir,
    sensors: Sensors,
    x: &[f64],
    psi: f64,
    v: &[f64],
    y: &mut [f64],
    m: &mut [f64],
) -> f64 {
    let std = |s: &[f64], i: usize| s.get(i).copied().unwrap_or(0.0);
    for (o, y) in y.iter_mut().enumerate() {
        *y = x[o] + std(sensors.states, o) * draws.normal();
    }
    let y_psi = psi + sensors.heading * draws.normal();
    for (c, m) in m.iter_mut().enumerate() {
        *m = if ir.disturbances[ir.components[c].disturbance].measured {
            v[c] + std(sensors.disturbances, c) * draws.normal()
        } else {
            0.0
        };
    }
    y_psi
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
    let mut draws = Draws::new(seed);
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
    let mut deviations = GaussMarkov::new(
        n_comp,
        system.h,
        &system.disturbance_std,
        &system.disturbance_time,
    );
    let sensors = Sensors {
        states: &system.state_noise,
        heading: system.heading_noise,
        disturbances: &system.aux_noise,
    };
    for u in inputs {
        for (c, (value, d)) in v.iter_mut().zip(deviations.next(&mut draws)).enumerate() {
            *value = system.disturbance_mean.get(c).copied().unwrap_or(0.0) + d;
        }
        let y_psi = measure(&mut draws, ir, sensors, &x, psi, &v, &mut y, &mut m);
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
            *value += system.process_noise.get(o).copied().unwrap_or(0.0) * draws.normal();
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

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_model::Interpreter;

    fn ship() -> Interpreter {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/models/ship.som");
        let source = std::fs::read_to_string(path).unwrap_or_default();
        let c = leeway_structure::compile(&source, &Default::default());
        Interpreter::new(c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics)))
    }

    /// Every bit of an experiment, folded (FNV-1a over `to_bits`).
    fn fingerprint(e: &Experiment, truth: &Truth) -> u64 {
        let mut hash = 0xcbf2_9ce4_8422_2325u64;
        let columns = e
            .states
            .iter()
            .chain([&e.heading])
            .chain(&e.disturbances)
            .chain(&truth.states)
            .chain(&truth.disturbances);
        for v in columns.flatten() {
            hash = (hash ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3);
        }
        hash
    }

    #[test]
    fn the_draws_of_a_seed_never_change() {
        // `leeway reproduce`'s figures rest on these bits: one correlated
        // component, one i.i.d., sensor and process noise.
        let model = ship();
        let system = TrueSystem {
            theta: crate::study::THETA0.to_vec(),
            h: 1.0,
            disturbance_mean: vec![0.2, -0.1, 3.0, 1.0],
            disturbance_std: vec![0.02, 0.03, 0.5, 0.4],
            disturbance_time: vec![20.0, 0.0, 5.0],
            state_noise: vec![0.01, 0.01, 0.001],
            heading_noise: 0.002,
            aux_noise: vec![0.0, 0.0, 0.1, 0.1],
            process_noise: vec![0.001, 0.001, 0.0001],
        };
        let inputs: Vec<Vec<f64>> = (0..200)
            .map(|k| vec![50.0 + (k % 7) as f64, 160.0, 230.0 - (k % 3) as f64])
            .collect();
        let (e, truth) = experiment(&model, &system, "pin", &[5.0, 0.0, 0.0], 0.3, &inputs, 7);
        assert_eq!(fingerprint(&e, &truth), 10_788_905_112_966_161_234);
    }

    /// The lag-1 autocorrelation and std of a series.
    fn lag1_and_std(x: &[f64]) -> (f64, f64) {
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
        let lag1 = x
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>()
            / n;
        (lag1 / var, var.sqrt())
    }

    #[test]
    fn a_gauss_markov_deviation_decays_as_its_correlation_time_says() {
        // h = 0.5 s; T = 5 s (a = e^−0.1 ≈ 0.905), T = 0.5 s (a ≈ 0.368),
        // and an i.i.d. component (T = 0).
        let (n, h) = (20_000, 0.5);
        let mut process = GaussMarkov::new(3, h, &[0.2, 1.5, 0.7], &[5.0, 0.5]);
        let mut draws = Draws::stream(4, 1);
        let mut series = vec![Vec::new(); 3];
        for _ in 0..n {
            for (s, d) in series.iter_mut().zip(process.next(&mut draws)) {
                s.push(*d);
            }
        }
        for ((s, std), time) in series.iter().zip([0.2, 1.5, 0.7]).zip([5.0, 0.5, 0.0]) {
            let a = if time > 0.0 { f64::exp(-h / time) } else { 0.0 };
            let (lag1, got) = lag1_and_std(s);
            // The sample lag-1 autocorrelation is off by about √((1−a²)/N)
            // (≤ 0.007 here); the std by about √((1+a²)/(1−a²)/(2N)) (≤ 1.6 %
            // for a = 0.905): bounds of four of those.
            assert!(
                (lag1 - a).abs() < 4.0 * ((1.0 - a * a) / n as f64).sqrt() + 1e-3,
                "T = {time}: {lag1} vs {a}"
            );
            let relative = ((1.0 + a * a) / (1.0 - a * a) / (2.0 * n as f64)).sqrt();
            assert!(
                (got / std - 1.0).abs() < 4.0 * relative,
                "T = {time}: std {got} vs {std}"
            );
        }
    }

    #[test]
    fn streams_of_a_seed_differ_and_stream_zero_is_the_seed() {
        let draw = |mut d: Draws| -> Vec<u64> { (0..4).map(|_| d.normal().to_bits()).collect() };
        assert_eq!(draw(Draws::stream(9, 0)), draw(Draws::new(9)));
        assert_ne!(draw(Draws::stream(9, 1)), draw(Draws::new(9)));
        assert_ne!(draw(Draws::stream(9, 1)), draw(Draws::stream(9, 2)));
    }
}
