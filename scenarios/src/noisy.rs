//! A simulation on a recorded input as a logger on a real craft would
//! record it: the model driven by disturbances that vary about their means
//! (first-order Gauss–Markov, [`GaussMarkov`]), its states, heading and
//! measured disturbances written with sensor noise ([`measure`]); seeded.
//! What `leeway simulate --disturbance-std/--noise` and `leeway.simulate`
//! with those keywords write.
//!
//! A measured medium's values in the input are its mean: a std given for it
//! adds a deviation that the craft feels and its sensor records, and the
//! sensor's noise is added to the written column only. The disturbances and
//! the sensor noise are drawn from two streams of the seed, so sensor noise
//! leaves the true trajectory as it was.

use crate::synth::{Draws, GaussMarkov, Sensors, measure};
use leeway_model::experiment::{Experiment, Row, Source};
use leeway_model::given::SimulationNoise;
use leeway_model::model::Model;
use leeway_model::simulate::{Disturbances, Written, simulate, written};

/// The stream of the seed the disturbances are drawn from.
const DISTURBANCE_STREAM: u64 = 1;
/// The stream of the seed the sensor noise is drawn from.
const SENSOR_STREAM: u64 = 2;

/// Simulates `model` with `theta` on the input `e` from its first sample
/// (the initial state and heading, as `leeway_data::input` reads them),
/// with each unmeasured disturbance component varying about `means` and
/// each measured one about the input's values as `noise` says, and returns
/// what the sensors record: the input with the measured states, heading and
/// disturbances, cut before a divergence (as
/// [`simulate_written`](leeway_model::simulate::simulate_written)). The
/// same seed gives the same bits.
pub fn simulate_noisy(
    model: &dyn Model,
    theta: &[f64],
    e: &Experiment,
    means: &[f64],
    noise: &SimulationNoise,
    seed: u64,
) -> Written {
    let driven = driven(model, e, means, noise, seed);
    let mut out = written(e, simulate(model, theta, &driven, Disturbances::Recorded));
    record(model, &driven, noise, seed, &mut out.experiment);
    out
}

/// The input with the true disturbance values of every component (measured
/// or not) on its rows.
struct Driven<'a> {
    input: &'a Experiment,
    /// `values[k·n + c]`, `n` components.
    values: Vec<f64>,
    n: usize,
}

impl Driven<'_> {
    fn at(&self, k: usize) -> &[f64] {
        &self.values[k * self.n..(k + 1) * self.n]
    }
}

impl Source for Driven<'_> {
    fn name(&self) -> &str {
        &self.input.name
    }
    fn len(&self) -> usize {
        self.input.len()
    }
    fn step(&self) -> f64 {
        self.input.h
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        let mut k = 0;
        self.input.rows(|row| {
            f(&Row {
                disturbances: self.at(k),
                ..*row
            });
            k += 1;
        });
    }
}

/// Draws the true disturbances: mean (`means`, or the input's value for a
/// measured component) plus the Gauss–Markov deviation.
fn driven<'a>(
    model: &dyn Model,
    e: &'a Experiment,
    means: &[f64],
    noise: &SimulationNoise,
    seed: u64,
) -> Driven<'a> {
    let ir = model.ir();
    let n = ir.components.len();
    let mut draws = Draws::stream(seed, DISTURBANCE_STREAM);
    let mut deviations = GaussMarkov::new(n, e.h, &noise.disturbance_std, &noise.correlation_time);
    let mut values = Vec::with_capacity(e.len() * n);
    for k in 0..e.len() {
        for (c, d) in deviations.next(&mut draws).iter().enumerate() {
            let mean = if ir.disturbances[ir.components[c].disturbance].measured {
                e.disturbances[c].get(k).copied().unwrap_or(0.0)
            } else {
                means.get(c).copied().unwrap_or(0.0)
            };
            values.push(mean + d);
        }
    }
    Driven {
        input: e,
        values,
        n,
    }
}

/// Replaces the true states, heading and measured disturbances of `out`
/// (the written samples of the true trajectory) by what the sensors record.
fn record(
    model: &dyn Model,
    driven: &Driven,
    noise: &SimulationNoise,
    seed: u64,
    out: &mut Experiment,
) {
    let ir = model.ir();
    let mut draws = Draws::stream(seed, SENSOR_STREAM);
    let sensors = Sensors {
        states: &noise.states,
        heading: noise.heading,
        disturbances: &noise.sensors,
    };
    let (mut x, mut y) = (vec![0.0; ir.states.len()], vec![0.0; ir.states.len()]);
    let mut m = vec![0.0; ir.components.len()];
    for k in 0..out.len() {
        for (x, column) in x.iter_mut().zip(&out.states) {
            *x = column[k];
        }
        let psi = out.heading.get(k).copied().unwrap_or(0.0);
        let v = driven.at(k);
        let y_psi = measure(&mut draws, ir, sensors, &x, psi, v, &mut y, &mut m);
        for (column, y) in out.states.iter_mut().zip(&y) {
            column[k] = *y;
        }
        if let Some(h) = out.heading.get_mut(k) {
            *h = y_psi;
        }
        for (c, column) in out.disturbances.iter_mut().enumerate() {
            if let Some(value) = column.get_mut(k) {
                *value = m[c];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_model::Interpreter;
    use leeway_model::simulate::simulate_written;

    fn ship() -> Interpreter {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/models/ship.som");
        let source = std::fs::read_to_string(path).unwrap_or_default();
        let c = leeway_structure::compile(&source, &Default::default());
        Interpreter::new(c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics)))
    }

    /// `n` samples of the ship at h = 1 s from (5, 0, 0), heading 0.3, with
    /// varying forces and a measured wind of (3, 1) m/s.
    fn input(model: &Interpreter, n: usize) -> Experiment {
        let mut e = Experiment::new(model.ir(), "in", 1.0);
        for k in 0..n {
            let t = k as f64;
            e.push(
                model.ir(),
                &Row {
                    states: &[5.0, 0.0, 0.0],
                    inputs: &[
                        50.0 + 10.0 * (t / 40.0).sin(),
                        160.0,
                        230.0 * (t / 70.0).cos(),
                    ],
                    heading: 0.3,
                    rotation: &[],
                    disturbances: &[0.0, 0.0, 3.0, 1.0],
                },
            );
        }
        e
    }

    fn std_dev(x: &[f64]) -> f64 {
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        (x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
    }

    const MEANS: [f64; 4] = [0.2, -0.1, 0.0, 0.0];

    #[test]
    fn without_noise_it_is_the_plain_simulation_bit_for_bit() {
        let model = ship();
        let e = input(&model, 300);
        let theta = crate::study::THETA0;
        let plain = simulate_written(&model, &theta, &e, Disturbances::Constant(&MEANS));
        let quiet = SimulationNoise::default();
        let noisy = simulate_noisy(&model, &theta, &e, &MEANS, &quiet, 3);
        assert_eq!(noisy.experiment, plain.experiment);
        assert_eq!((noisy.samples, noisy.diverged), (300, false));
    }

    #[test]
    fn sensor_noise_leaves_the_truth_and_has_its_std() {
        let model = ship();
        let n = 20_000;
        let e = input(&model, n);
        let theta = crate::study::THETA0;
        let plain = simulate_written(&model, &theta, &e, Disturbances::Constant(&MEANS));
        let noise = SimulationNoise {
            states: vec![0.01, 0.0, 0.002],
            heading: 0.005,
            sensors: vec![0.0, 0.0, 0.3, 0.0],
            ..SimulationNoise::default()
        };
        let noisy = simulate_noisy(&model, &theta, &e, &MEANS, &noise, 11);
        assert_eq!((noisy.samples, noisy.diverged), (n, false));
        let diff =
            |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(a, b)| a - b).collect() };
        // The std of a normal sample of N is off by about 1/√(2N) (0.5 %):
        // 3 % is six of those.
        let (got, plain) = (&noisy.experiment, &plain.experiment);
        for (column, std) in [
            (diff(&got.states[0], &plain.states[0]), 0.01),
            (diff(&got.states[2], &plain.states[2]), 0.002),
            (diff(&got.heading, &plain.heading), 0.005),
            (diff(&got.disturbances[2], &plain.disturbances[2]), 0.3),
        ] {
            assert!(
                (std_dev(&column) / std - 1.0).abs() < 0.03,
                "{}",
                std_dev(&column)
            );
        }
        assert_eq!(got.states[1], plain.states[1]);
        assert_eq!(got.disturbances[3], plain.disturbances[3]);
        assert_eq!(got.inputs, plain.inputs);
        // Another seed, other noise; the same seed, the same bits.
        let again = simulate_noisy(&model, &theta, &e, &MEANS, &noise, 11);
        assert_eq!(again.experiment, noisy.experiment);
        let other = simulate_noisy(&model, &theta, &e, &MEANS, &noise, 12);
        assert_ne!(other.experiment.states[0], noisy.experiment.states[0]);
    }

    #[test]
    fn a_varying_current_moves_the_craft_and_a_gusty_wind_reaches_the_sensor() {
        let model = ship();
        let e = input(&model, 2000);
        let theta = crate::study::THETA0;
        let plain = simulate_written(&model, &theta, &e, Disturbances::Constant(&MEANS));
        let noise = SimulationNoise {
            disturbance_std: vec![0.05, 0.05, 0.5, 0.0],
            correlation_time: vec![30.0, 30.0, 0.0, 0.0],
            ..SimulationNoise::default()
        };
        let noisy = simulate_noisy(&model, &theta, &e, &MEANS, &noise, 5);
        let (got, plain) = (&noisy.experiment, &plain.experiment);
        assert_eq!(got.states[0][0], plain.states[0][0]);
        assert_ne!(got.states[0][1..], plain.states[0][1..]);
        // The gusts are recorded (no sensor noise): wind_n about 3 with std 0.5.
        let gusts: Vec<f64> = got.disturbances[2].iter().map(|w| w - 3.0).collect();
        assert!(
            (std_dev(&gusts) / 0.5 - 1.0).abs() < 0.1,
            "{}",
            std_dev(&gusts)
        );
        assert_eq!(got.disturbances[3], plain.disturbances[3]);
    }
}
