//! The fit sums of a free run: the reported θ simulated on one experiment,
//! in a pass of its own ([`FreeRunSums::of`]) or alongside another pass's
//! walk over a streamed record ([`AlongsideFreeRun`]), which then reads the
//! record once for both.

use leeway_model::experiment::{Experiment, Row, Source};
use leeway_model::model::Model;
use leeway_model::simulate::{Disturbances, Stepper};
use serde::{Deserialize, Serialize};
use std::sync::{Mutex, PoisonError};

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
    /// The free run of `theta` on `e` (the equations' samples: a delayed
    /// view), unmeasured disturbances at `means`.
    pub(super) fn of(model: &dyn Model, theta: &[f64], means: &[f64], e: &dyn Source) -> Self {
        let mut run = FreeRun::new(model, theta, means, e.step());
        e.visit(&mut |row| run.push(row));
        run.finish()
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

/// A free run fed one sample at a time: its simulation and its fit sums.
struct FreeRun<'a> {
    stepper: Stepper<'a>,
    sums: FreeRunSums,
    /// The first measured states, the sums' shift.
    first: Option<Vec<f64>>,
}

impl<'a> FreeRun<'a> {
    fn new(model: &'a dyn Model, theta: &'a [f64], means: &'a [f64], h: f64) -> FreeRun<'a> {
        let n_out = model.ir().states.len();
        FreeRun {
            stepper: Stepper::new(model, theta, Disturbances::Constant(means), h),
            sums: FreeRunSums {
                diverged: false,
                n: 0,
                err2: vec![0.0; n_out],
                sum: vec![0.0; n_out],
                sum2: vec![0.0; n_out],
            },
            first: None,
        }
    }

    #[inline]
    fn push(&mut self, row: &Row) {
        let (sums, first) = (&mut self.sums, &mut self.first);
        self.stepper.push(row, |row, x, _| {
            let y0 = first.get_or_insert_with(|| row.states.to_vec());
            for (o, &y) in row.states.iter().enumerate() {
                let (y, d) = (y - y0[o], y - x[o]);
                sums.err2[o] += d * d;
                sums.sum[o] += y;
                sums.sum2[o] += y * y;
            }
            sums.n += 1;
        });
    }

    fn finish(mut self) -> FreeRunSums {
        self.sums.diverged = self.stepper.diverged();
        self.sums
    }
}

/// A streamed record whose visit also steps a free run over its rows: a
/// pass that walks the record for its own sums gets the free run's without
/// reading the record again (the same rows in the same order, so the same
/// sums as [`FreeRunSums::of`]).
pub(super) struct AlongsideFreeRun<'a> {
    inner: &'a dyn Source,
    run: Mutex<FreeRun<'a>>,
}

impl<'a> AlongsideFreeRun<'a> {
    /// `e` (the equations' samples), with the free run of `theta`,
    /// unmeasured disturbances at `means`, stepped along its one visit.
    pub(super) fn new(
        model: &'a dyn Model,
        theta: &'a [f64],
        means: &'a [f64],
        e: &'a dyn Source,
    ) -> AlongsideFreeRun<'a> {
        AlongsideFreeRun {
            inner: e,
            run: Mutex::new(FreeRun::new(model, theta, means, e.step())),
        }
    }

    /// The free run's sums, once the record was visited (once).
    pub(super) fn finish(self) -> FreeRunSums {
        self.run
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
            .finish()
    }
}

impl Source for AlongsideFreeRun<'_> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn len(&self) -> usize {
        self.inner.len()
    }
    fn step(&self) -> f64 {
        self.inner.step()
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        // Held for the one visit; a panic in an earlier one leaves sums
        // that are never read (the pass fails with it).
        let mut run = self.run.lock().unwrap_or_else(PoisonError::into_inner);
        self.inner.visit(&mut |row| {
            run.push(row);
            f(row);
        });
    }
    fn locate(&self, k: usize) -> String {
        self.inner.locate(k)
    }
    // Streamed only: an in-memory record's columns would be walked without
    // the visit that steps the free run.
    fn in_memory(&self) -> Option<&Experiment> {
        None
    }
    fn dead_time_applied(&self) -> bool {
        self.inner.dead_time_applied()
    }
}
