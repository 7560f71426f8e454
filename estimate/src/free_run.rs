//! The fit sums of a free run: the reported θ simulated on one experiment.

use leeway_model::experiment::Source;
use leeway_model::model::Model;
use leeway_model::simulate::{Disturbances, simulate_each};
use serde::{Deserialize, Serialize};

/// What one experiment's free run contributes, per state: the sum of the
/// squared simulation errors, and the sums of the measurement and of its
/// square, shifted by its first value (so the spread keeps its digits).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct FreeRunSums {
    pub(crate) diverged: bool,
    n: usize,
    err2: Vec<f64>,
    sum: Vec<f64>,
    sum2: Vec<f64>,
}

impl FreeRunSums {
    /// The free run of `theta` on `e`, unmeasured disturbances at `means`.
    pub(super) fn of(model: &dyn Model, theta: &[f64], means: &[f64], e: &dyn Source) -> Self {
        let n_out = model.ir().states.len();
        let mut sums = FreeRunSums {
            diverged: false,
            n: 0,
            err2: vec![0.0; n_out],
            sum: vec![0.0; n_out],
            sum2: vec![0.0; n_out],
        };
        let mut first: Option<Vec<f64>> = None;
        let constant = Disturbances::Constant(means);
        sums.diverged = simulate_each(model, theta, e, constant, &mut |row, x, _| {
            let y0 = first.get_or_insert_with(|| row.states.to_vec());
            for o in 0..n_out {
                let (y, d) = (row.states[o] - y0[o], row.states[o] - x[o]);
                sums.err2[o] += d * d;
                sums.sum[o] += y;
                sums.sum2[o] += y * y;
            }
            sums.n += 1;
        });
        sums
    }

    /// The fit per state, `100·(1 − ‖y − ŷ‖/‖y − ȳ‖)`; `None` where the
    /// measurement is constant or the simulation diverged.
    pub(crate) fn fits(&self) -> Vec<Option<f64>> {
        let n = self.n.max(1) as f64;
        (0..self.err2.len())
            .map(|o| {
                let spread = self.sum2[o] - self.sum[o] * self.sum[o] / n;
                (!self.diverged && spread > 0.0 && self.err2[o].is_finite())
                    .then(|| 100.0 * (1.0 - (self.err2[o] / spread).sqrt()))
            })
            .collect()
    }
}
