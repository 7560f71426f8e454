//! Closed loop in the data (paper A1: the inputs are independent of the
//! disturbances). In the spirit of the System Identification Toolbox's
//! `feedback`: an input that the craft's past motion predicts, beyond what
//! the input's own past explains, was computed from the measurements — a
//! dynamic-positioning or autopilot stretch, a zigzag's switching rule. Per
//! window of [`WINDOW_SECONDS`] and per input `u`, two least-squares fits of
//! `u(k)` are compared: on `1, u(k−1), u(k−2)`, and on those plus every
//! state at `k, k−1, k−2` (a controller acts on the latest measurement; in
//! open loop the state at `k` depends only on inputs before `k`). A window
//! is judged only when the input's innovations there — the samples its own
//! past does not predict — are many (five per added regressor): an input
//! that steps a few times a window carries too little evidence, however
//! well a dozen regressors happen to fit its steps. A window is flagged when the states explain at
//! least [`EXPLAINED`] of what the input's own past leaves, and the χ² test
//! of the added terms rejects open loop at 10⁻⁶.

use crate::parallel::{in_order, threads_for};
use leeway_model::correlation::chi_squared_tail;
use leeway_model::experiment::{Row, Source};
use leeway_structure::ir::Ir;
use nalgebra::{DMatrix, DVector};

/// The window a fit covers, seconds (at least [`MIN_WINDOW`] samples).
pub const WINDOW_SECONDS: f64 = 30.0;
/// The fewest samples of a window.
pub const MIN_WINDOW: usize = 100;
/// The share of the input's innovation the past motion must explain.
pub const EXPLAINED: f64 = 0.5;
/// Lags of the input and of each state in the fits.
const LAGS: usize = 2;
/// The fewest innovations per added regressor a window needs to judge.
const MIN_INNOVATIONS: usize = 5;

/// A stretch of an experiment whose inputs its outputs predict.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Feedback {
    /// The experiment.
    pub experiment: String,
    /// The inputs predicted there.
    pub inputs: Vec<String>,
    /// Its first sample (from 0).
    pub first: usize,
    /// Its last sample.
    pub last: usize,
    /// Its first and last time, seconds from the experiment's first sample.
    pub from: f64,
    /// See `from`.
    pub to: f64,
    /// The largest share of an input's innovation the motion explains there.
    pub explained: f64,
}

/// The sums of one window. The full fit of input `j` has the columns `1`,
/// `u_j`'s lags (its own block, `own` wide), then the states' lags (shared
/// by every input's fit): the Gram matrix of the states' lags is summed
/// once for all inputs, each input's rows of its own columns against every
/// column apart. Each entry is the sum of the same products in the same
/// order as a full rank-1 update would make it, so the fits' bits are those
/// of one Gram matrix per input.
struct Sums {
    /// Columns of the full fit.
    width: usize,
    /// Upper triangle of the states' lags' Gram matrix, row by row
    /// (`width − own` square).
    states: Vec<f64>,
    inputs: Vec<InputSums>,
}

/// One input's sums over a window: its own columns' rows of `X'X`, `X'u`,
/// `u'u`; and per sample the input with its own lags (the restricted fit's
/// rows), whose residuals say how many innovations the window holds.
struct InputSums {
    /// `own × width`, row by row.
    rows: Vec<f64>,
    cross: Vec<f64>,
    square: f64,
    own: Vec<[f64; OWN + 1]>,
}

/// The restricted fit's columns: `1` and the input's lags.
const OWN: usize = 1 + LAGS;

impl Sums {
    fn new(width: usize, inputs: usize) -> Sums {
        let s = width - OWN;
        Sums {
            width,
            states: vec![0.0; s * (s + 1) / 2],
            inputs: (0..inputs)
                .map(|_| InputSums {
                    rows: vec![0.0; OWN * width],
                    cross: vec![0.0; width],
                    square: 0.0,
                    own: Vec::new(),
                })
                .collect(),
        }
    }
    fn clear(&mut self) {
        self.states.fill(0.0);
        for i in &mut self.inputs {
            i.rows.fill(0.0);
            i.cross.fill(0.0);
            i.square = 0.0;
            i.own.clear();
        }
    }
    /// Adds a sample: `x` holds the states' lags from column `OWN` on;
    /// its first `OWN` columns are each input's own, written here.
    fn push(&mut self, x: &mut [f64], lags: &[[f64; LAGS]], inputs: &[f64]) {
        let mut at = 0;
        for (i, a) in x[OWN..].iter().enumerate() {
            for b in &x[OWN + i..] {
                self.states[at] += a * b;
                at += 1;
            }
        }
        for (j, sums) in self.inputs.iter_mut().enumerate() {
            x[0] = 1.0;
            x[1..OWN].copy_from_slice(&lags[j]);
            let u = inputs[j];
            for (r, a) in x[..OWN].iter().enumerate() {
                for (g, b) in sums.rows[r * x.len()..(r + 1) * x.len()]
                    .iter_mut()
                    .zip(&*x)
                {
                    *g += b * a;
                }
            }
            for (c, a) in sums.cross.iter_mut().zip(&*x) {
                *c += u * a;
            }
            sums.square += u * u;
            let mut row = [u; OWN + 1];
            row[..OWN].copy_from_slice(&x[..OWN]);
            sums.own.push(row);
        }
    }
    /// Input `j`'s Gram matrix of the first `columns` columns.
    fn gram(&self, j: usize, columns: usize) -> DMatrix<f64> {
        let rows = &self.inputs[j].rows;
        let s = self.width - OWN;
        DMatrix::from_fn(columns, columns, |a, b| {
            let (lo, hi) = (a.min(b), a.max(b));
            if lo < OWN {
                rows[lo * self.width + hi]
            } else {
                let (i, k) = (lo - OWN, hi - OWN);
                self.states[i * s - i * (i.saturating_sub(1)) / 2 + k - i]
            }
        })
    }
    /// The coefficients and residual sum of squares of input `j`'s fit on
    /// the first `columns`.
    fn fit(&self, j: usize, columns: usize) -> Option<(DVector<f64>, f64)> {
        let g = self.gram(j, columns);
        let sums = &self.inputs[j];
        let c = DVector::from_column_slice(&sums.cross[..columns]);
        // Squares beyond f64's range (a column of 1e200) make no fit; an SVD
        // of infinities would not converge.
        if !(sums.square.is_finite() && g.iter().chain(c.iter()).all(|v| v.is_finite())) {
            return None;
        }
        // A bounded number of sweeps: a fit that does not converge is no fit.
        let b = g
            .try_svd(true, true, f64::EPSILON, 500)?
            .solve(&c, 1e-12)
            .ok()?;
        let rss = (sums.square - b.dot(&c)).max(0.0);
        Some((b, rss))
    }
    /// The innovations the restricted fit leaves: the samples whose
    /// residual exceeds 10⁻⁴ of their RMS. Dense noise counts every sample;
    /// an input held (or smoothed) between steps counts only its steps.
    fn innovations(&self, j: usize, b: &DVector<f64>, rss: f64) -> f64 {
        let own = &self.inputs[j].own;
        let floor = 1e-4 * (rss / own.len().max(1) as f64).sqrt();
        let count = own
            .iter()
            .filter(|row| {
                let e = row[OWN] - (0..OWN).map(|i| b[i] * row[i]).sum::<f64>();
                e.abs() > floor
            })
            .count();
        count as f64
    }
    /// The share of input `j`'s restricted fit's residual the states
    /// explain, when the window holds enough innovations and the χ² test (on
    /// them) rejects that the states add nothing. The full fit is solved
    /// only for a window that can be judged.
    fn explained(&self, j: usize) -> Option<f64> {
        let (b, r) = self.fit(j, OWN)?;
        let q = self.width - OWN;
        let n = self.innovations(j, &b, r);
        if r <= 1e-12 * self.inputs[j].square || n < (MIN_INNOVATIONS * q) as f64 {
            return None;
        }
        let (_, f) = self.fit(j, self.width)?;
        let stat = (n - self.width as f64).max(0.0) * (r - f) / f.max(f64::MIN_POSITIVE);
        (chi_squared_tail(stat, q) < 1e-6).then_some((r - f) / r)
    }
}

/// The stretches of every experiment where the motion predicts an input,
/// in experiment order: each experiment checked on its own thread, on the
/// machine's cores.
pub fn feedback_each(ir: &Ir, experiments: &[&dyn Source]) -> Vec<Feedback> {
    let threads = threads_for(experiments.len());
    in_order(experiments.len(), threads, |i| feedback(ir, experiments[i]))
        .into_iter()
        .flatten()
        .collect()
}

/// The stretches of `source` where the motion predicts an input.
pub fn feedback(ir: &Ir, source: &dyn Source) -> Vec<Feedback> {
    let h = source.step();
    let window = ((WINDOW_SECONDS / h).round() as usize).max(MIN_WINDOW);
    if ir.inputs.is_empty() || source.len() < MIN_WINDOW {
        return Vec::new();
    }
    let n_states = ir.states.len();
    let width = OWN + (LAGS + 1) * n_states;
    let mut sums = Sums::new(width, ir.inputs.len());
    // The states at k, k−1, …, k−LAGS (the regressors from column OWN on),
    // and each input's lags k−1, …, k−LAGS.
    let mut x = vec![0.0; width];
    let mut lags = vec![[0.0; LAGS]; ir.inputs.len()];
    let mut seen = 0;
    let mut flagged: Vec<(usize, usize, Vec<usize>, f64)> = Vec::new();
    let mut k = 0;
    let mut start = 0;
    source.visit(&mut |row: &Row| {
        x.copy_within(OWN..width - n_states, OWN + n_states);
        x[OWN..OWN + n_states].copy_from_slice(row.states);
        if seen == LAGS {
            sums.push(&mut x, &lags, row.inputs);
        } else {
            seen += 1;
        }
        for (l, u) in lags.iter_mut().zip(row.inputs) {
            l.copy_within(0..LAGS - 1, 1);
            l[0] = *u;
        }
        k += 1;
        let last = k == source.len();
        if k - start == window || (last && k - start >= MIN_WINDOW) {
            let shares: Vec<(usize, f64)> = (0..ir.inputs.len())
                .filter_map(|j| sums.explained(j).map(|e| (j, e)))
                .filter(|(_, e)| *e >= EXPLAINED)
                .collect();
            if !shares.is_empty() {
                let most = shares.iter().map(|(_, e)| *e).fold(0.0, f64::max);
                flagged.push((start, k - 1, shares.iter().map(|(j, _)| *j).collect(), most));
            }
            sums.clear();
            start = k;
        }
    });
    merge(ir, source, h, flagged)
}

/// Adjacent flagged windows as one stretch each.
fn merge(
    ir: &Ir,
    source: &dyn Source,
    h: f64,
    flagged: Vec<(usize, usize, Vec<usize>, f64)>,
) -> Vec<Feedback> {
    let mut out: Vec<Feedback> = Vec::new();
    for (first, last, inputs, explained) in flagged {
        let names: Vec<String> = inputs.iter().map(|j| ir.inputs[*j].clone()).collect();
        if let Some(prev) = out.last_mut()
            && prev.last + 1 == first
        {
            prev.last = last;
            prev.to = last as f64 * h;
            prev.explained = prev.explained.max(explained);
            for n in names {
                if !prev.inputs.contains(&n) {
                    prev.inputs.push(n);
                }
            }
            continue;
        }
        out.push(Feedback {
            experiment: source.name().to_string(),
            inputs: names,
            first,
            last,
            from: first as f64 * h,
            to: last as f64 * h,
            explained,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_model::experiment::Experiment;

    fn ir() -> Ir {
        let src = "model M { step 0.1 state u input tau der u = X*u + T*tau }";
        leeway_structure::compile(src, &leeway_structure::CompileOptions::default())
            .ir
            .unwrap_or_else(|| panic!("the test model compiles"))
    }

    /// 600 s of `u' = −0.2u + tau` (with noise), `tau` held at random
    /// levels, or set from the measured `u` where `closed` says.
    fn record(closed: impl Fn(usize) -> bool, scale: f64) -> Experiment {
        let ir = ir();
        let mut e = Experiment::new(&ir, "run", 0.1);
        let (mut u, mut level, mut seed) = (0.0f64, 1.0f64, 7u64);
        let mut noise = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for k in 0..6000 {
            if k % 47 == 0 {
                level = 2.0 * noise();
            }
            let measured = u + 0.01 * noise();
            let tau = if closed(k) { -3.0 * measured } else { level };
            e.states[0].push(measured * scale);
            e.inputs[0].push(tau);
            u += 0.1 * (-0.2 * u + tau);
        }
        e
    }

    #[test]
    fn a_controller_is_found_where_it_acts_and_nowhere_else() {
        let ir = ir();
        assert_eq!(feedback(&ir, &record(|_| false, 1.0)), vec![]);
        let found = feedback(&ir, &record(|k| (3000..4200).contains(&k), 1.0));
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].first, found[0].last), (3000, 4199));
        assert!(found[0].explained > 0.9, "{found:?}");
    }

    #[test]
    fn squares_beyond_range_are_no_fit_and_no_hang() {
        assert_eq!(feedback(&ir(), &record(|_| true, 1e200)), vec![]);
    }
}
