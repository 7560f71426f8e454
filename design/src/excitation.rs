//! The excitation around an operating point: one signal per input from a
//! family ([`Family`]), scaled to an amplitude, seeded per input so the
//! inputs are uncorrelated, then held within the actuator's range and rate.
//!
//! Time scales follow the craft: `T` is the nominal time constant in
//! samples. Pulses last `T`–`4T` and are smoothed over `T/3` (the paper's
//! §V input at its ship's `T ≈ 20 s`), the PRBS holds each level `T/2`–`2T`,
//! the multisine spans periods `T`–`8T`, and the zigzag of input `i` switches
//! every `(2 + 0.618·i)·T` samples (incommensurate periods).

use crate::plan::{Family, Limits};
use leeway_scenarios::engine::keyed_seed;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// What to generate.
#[derive(Clone, Debug, PartialEq)]
pub struct Excitation {
    /// The family.
    pub family: Family,
    /// Static offsets (the operating point).
    pub offsets: Vec<f64>,
    /// Amplitude (half range) per input.
    pub amplitudes: Vec<f64>,
    /// The craft's time constant, samples.
    pub time_scale: usize,
    /// Seed of the random families.
    pub seed: u64,
}

impl Excitation {
    /// `n` samples of every input (`inputs[k][i]`), within `limits`.
    pub fn generate(&self, n: usize, limits: &[Limits]) -> Vec<Vec<f64>> {
        let columns: Vec<Vec<f64>> = (0..self.offsets.len())
            .map(|i| {
                let seed = keyed_seed(self.seed, self.family.name(), i);
                let wave = wave(self.family, i, n, self.time_scale.max(1), seed);
                held_within(&wave, self.offsets[i], self.amplitudes[i], &limits[i])
            })
            .collect();
        (0..n)
            .map(|k| columns.iter().map(|c| c[k]).collect())
            .collect()
    }
}

/// A unit wave (peak 1) of `n` samples.
fn wave(family: Family, input: usize, n: usize, t: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    match family {
        Family::Pulses => {
            let alpha = (3.0 / t as f64).min(1.0);
            let (mut left, mut target, mut level) = (0usize, 0.0, 0.0);
            (0..n)
                .map(|_| {
                    if left == 0 {
                        left = rng.random_range(t..=4 * t);
                        target = rng.random_range(-1.0..=1.0);
                    }
                    left -= 1;
                    level += alpha * (target - level);
                    level
                })
                .collect()
        }
        Family::Prbs => {
            let (mut left, mut level) = (0usize, if rng.random::<bool>() { 1.0 } else { -1.0 });
            (0..n)
                .map(|_| {
                    if left == 0 {
                        left = rng.random_range((t / 2).max(1)..=2 * t);
                        level = -level;
                    }
                    left -= 1;
                    level
                })
                .collect()
        }
        Family::Multisine => {
            // Twelve sines, log-spaced over periods T … 8T (8^(j/11)),
            // random phases.
            const PERIODS: [f64; 12] = [
                1.0, 1.208, 1.459, 1.763, 2.129, 2.572, 3.107, 3.753, 4.533, 5.476, 6.615, 8.0,
            ];
            let sines: Vec<(f64, f64)> = PERIODS
                .iter()
                .map(|m| {
                    let period = t as f64 * m;
                    (
                        std::f64::consts::TAU / period,
                        rng.random_range(0.0..std::f64::consts::TAU),
                    )
                })
                .collect();
            let raw: Vec<f64> = (0..n)
                .map(|k| sines.iter().map(|(w, p)| (w * k as f64 + p).sin()).sum())
                .collect();
            let peak = raw.iter().fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()));
            raw.into_iter().map(|v| v / peak).collect()
        }
        Family::Zigzag => {
            let half = ((2.0 + 0.618 * input as f64) * t as f64).round().max(1.0) as usize;
            (0..n)
                .map(|k| {
                    if (k / half).is_multiple_of(2) {
                        1.0
                    } else {
                        -1.0
                    }
                })
                .collect()
        }
    }
}

/// `offset + amplitude·wave`, clamped to the range and slewed at the rate.
fn held_within(wave: &[f64], offset: f64, amplitude: f64, l: &Limits) -> Vec<f64> {
    let mut out = Vec::with_capacity(wave.len());
    let mut last = offset;
    for w in wave {
        let target = (offset + amplitude * w).clamp(l.low, l.high);
        let step = (target - last).clamp(-l.per_sample, l.per_sample);
        last += step;
        out.push(last);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> Vec<Limits> {
        vec![
            Limits {
                low: -1.0,
                high: 3.0,
                per_sample: f64::INFINITY,
            },
            Limits {
                low: 0.0,
                high: 10.0,
                per_sample: 0.5,
            },
        ]
    }

    #[test]
    fn every_family_stays_within_range_and_rate() {
        for family in Family::ALL {
            let e = Excitation {
                family,
                offsets: vec![1.0, 5.0],
                amplitudes: vec![5.0, 4.0],
                time_scale: 10,
                seed: 7,
            };
            let u = e.generate(2000, &limits());
            let mut last = 5.0;
            for row in &u {
                assert!((-1.0..=3.0).contains(&row[0]), "{family:?}");
                assert!((0.0..=10.0).contains(&row[1]), "{family:?}");
                assert!((row[1] - last).abs() <= 0.5 + 1e-12, "{family:?}");
                last = row[1];
            }
            // It excites: both sides of the offset are visited.
            assert!(
                u.iter().any(|r| r[1] > 7.0) && u.iter().any(|r| r[1] < 3.0),
                "{family:?}"
            );
            assert_eq!(u, e.generate(2000, &limits()), "{family:?} is seeded");
        }
    }

    #[test]
    fn inputs_are_uncorrelated() {
        let lim = vec![
            Limits {
                low: -2.0,
                high: 2.0,
                per_sample: f64::INFINITY
            };
            2
        ];
        for family in [Family::Pulses, Family::Prbs, Family::Multisine] {
            let e = Excitation {
                family,
                offsets: vec![0.0, 0.0],
                amplitudes: vec![1.0, 1.0],
                time_scale: 5,
                seed: 1,
            };
            let u = e.generate(20_000, &lim);
            let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
            for r in &u {
                sab += r[0] * r[1];
                saa += r[0] * r[0];
                sbb += r[1] * r[1];
            }
            let rho = sab / (saa * sbb).sqrt();
            assert!(rho.abs() < 0.15, "{family:?}: {rho}");
        }
    }
}
