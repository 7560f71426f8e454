//! Checks of an input design on the true trajectory behind a synthetic
//! experiment ([`Truth`]): how far each sign argument (a relative velocity
//! under a modulus, e.g. `water.u`, `air.v`) stays from zero (paper A7), the
//! range of any state (the yaw rate), and the craft's track in the earth
//! frame. Nothing here estimates: these are the figures that say whether a
//! design meets the assumptions the estimators rely on.

use crate::synth::Truth;
use leeway_model::model::{Model, Signals, planar_rotation};

/// Running summary of a signal: count, sum, sum of squares, extremes, and
/// how many samples were negative. Merging in a fixed order gives the same
/// bits whatever the thread count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Samples seen.
    pub count: usize,
    /// Sum of the samples.
    pub sum: f64,
    /// Sum of their squares.
    pub sum_sq: f64,
    /// Smallest sample (`+∞` when empty).
    pub min: f64,
    /// Largest sample (`−∞` when empty).
    pub max: f64,
    /// Samples below zero.
    pub negative: usize,
}

impl Default for Range {
    fn default() -> Range {
        Range {
            count: 0,
            sum: 0.0,
            sum_sq: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            negative: 0,
        }
    }
}

impl Range {
    /// Adds one sample.
    pub fn push(&mut self, x: f64) {
        self.count += 1;
        self.sum += x;
        self.sum_sq += x * x;
        self.min = self.min.min(x);
        self.max = self.max.max(x);
        if x < 0.0 {
            self.negative += 1;
        }
    }

    /// Adds every sample of another summary.
    pub fn merge(&mut self, other: &Range) {
        self.count += other.count;
        self.sum += other.sum;
        self.sum_sq += other.sum_sq;
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
        self.negative += other.negative;
    }

    /// Mean (NaN when empty).
    pub fn mean(&self) -> f64 {
        if self.count == 0 {
            return f64::NAN;
        }
        self.sum / self.count as f64
    }

    /// Standard deviation (population; NaN when empty).
    pub fn std(&self) -> f64 {
        if self.count == 0 {
            return f64::NAN;
        }
        let m = self.mean();
        (self.sum_sq / self.count as f64 - m * m).max(0.0).sqrt()
    }

    /// Fraction of the samples below zero (NaN when empty).
    pub fn negative_fraction(&self) -> f64 {
        if self.count == 0 {
            return f64::NAN;
        }
        self.negative as f64 / self.count as f64
    }
}

/// The range of every sign argument of the model (in the IR's order, named
/// like `water.u`) over a true trajectory, evaluated exactly as the model
/// defines it: the true state minus the true disturbance rotated by the true
/// heading. Empty for a model without a planar heading.
pub fn sign_argument_ranges(model: &dyn Model, truth: &Truth) -> Vec<(String, Range)> {
    let ir = model.ir();
    if truth.heading.is_empty() {
        return Vec::new();
    }
    let plans: Vec<_> = ir
        .sign_args
        .iter()
        .map(|a| leeway_model::interp::arg_plan(ir, &a.arg))
        .collect();
    let mut ranges = vec![Range::default(); plans.len()];
    let n = truth.heading.len();
    let mut states = vec![0.0; truth.states.len()];
    let mut dist = vec![0.0; truth.disturbances.len()];
    for k in 0..n {
        for (s, t) in states.iter_mut().zip(&truth.states) {
            *s = t.get(k).copied().unwrap_or(f64::NAN);
        }
        for (d, t) in dist.iter_mut().zip(&truth.disturbances) {
            *d = t.get(k).copied().unwrap_or(f64::NAN);
        }
        let rotation = planar_rotation(truth.heading[k]);
        let sig = Signals {
            states: &states,
            inputs: &[],
            rotation: &rotation,
            disturbances: &dist,
        };
        for (range, plan) in ranges.iter_mut().zip(&plans) {
            // Sign arguments of a vessel model are relative velocities of
            // states; an argument of an input cannot be read from the truth.
            if matches!(plan.signal, leeway_structure::ir::Signal::State(_)) {
                range.push(plan.eval(&sig, true));
            }
        }
    }
    ir.sign_args
        .iter()
        .map(|a| a.name.clone())
        .zip(ranges)
        .collect()
}

/// The range of one state of a true trajectory.
pub fn state_range(truth: &Truth, state: usize) -> Range {
    let mut r = Range::default();
    for x in truth.states.get(state).into_iter().flatten() {
        r.push(*x);
    }
    r
}

/// The range of the means of consecutive blocks of `block` samples of a
/// state (a trailing partial block is left out): e.g. the yaw rate averaged
/// over each minute, which says whether the craft ever stops turning for
/// that long.
pub fn block_mean_range(truth: &Truth, state: usize, block: usize) -> Range {
    let mut r = Range::default();
    if block == 0 {
        return r;
    }
    for chunk in truth
        .states
        .get(state)
        .into_iter()
        .flat_map(|x| x.chunks_exact(block))
    {
        r.push(chunk.iter().sum::<f64>() / block as f64);
    }
    r
}

/// The earth-frame track `(north, east)` of a planar craft from its
/// body-frame surge `u`, sway `v` and heading `ψ` (explicit Euler with step
/// `h`, from the origin): `ẋ = u cos ψ − v sin ψ`, `ẏ = u sin ψ + v cos ψ`.
/// One point per sample; the shortest of the three series sets the length.
pub fn track(u: &[f64], v: &[f64], heading: &[f64], h: f64) -> Vec<(f64, f64)> {
    let n = u.len().min(v.len()).min(heading.len());
    let mut out = Vec::with_capacity(n);
    let (mut north, mut east) = (0.0, 0.0);
    for k in 0..n {
        out.push((north, east));
        let (s, c) = heading[k].sin_cos();
        north += h * (u[k] * c - v[k] * s);
        east += h * (u[k] * s + v[k] * c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_merge_like_one_pass() {
        let xs = [0.5, -1.0, 2.0, 3.5, -0.25, 1.0];
        let mut all = Range::default();
        xs.iter().for_each(|x| all.push(*x));
        let (mut a, mut b) = (Range::default(), Range::default());
        xs[..2].iter().for_each(|x| a.push(*x));
        xs[2..].iter().for_each(|x| b.push(*x));
        a.merge(&b);
        assert_eq!(a, all);
        assert_eq!((all.min, all.max, all.negative), (-1.0, 3.5, 2));
        assert!((all.mean() - 5.75 / 6.0).abs() < 1e-15);
        let var = xs
            .iter()
            .map(|x| (x - all.mean()) * (x - all.mean()))
            .sum::<f64>()
            / 6.0;
        assert!((all.std() - var.sqrt()).abs() < 1e-12);
        assert!(Range::default().mean().is_nan());
    }

    #[test]
    fn block_means_leave_out_the_partial_block() {
        let truth = Truth {
            states: vec![vec![1.0, 3.0, -2.0, 0.0, 10.0]],
            ..Truth::default()
        };
        let r = block_mean_range(&truth, 0, 2);
        assert_eq!((r.count, r.min, r.max), (2, -1.0, 2.0));
        assert_eq!(block_mean_range(&truth, 0, 0).count, 0);
        assert_eq!(block_mean_range(&truth, 3, 2).count, 0);
    }

    #[test]
    fn a_steady_turn_tracks_a_circle() {
        // u = 1 m/s, v = 0, r = 0.1 rad/s: a circle of radius u/r = 10 m.
        let n = 6284; // two turns at h = 0.02
        let h = 0.02;
        let heading: Vec<f64> = (0..n).map(|k| 0.1 * h * k as f64).collect();
        let pts = track(&vec![1.0; n], &vec![0.0; n], &heading, h);
        let centre = (0.0, 10.0);
        for (x, y) in pts {
            let radius = ((x - centre.0) * (x - centre.0) + (y - centre.1) * (y - centre.1)).sqrt();
            assert!((radius - 10.0).abs() < 0.2, "{radius}");
        }
    }
}
