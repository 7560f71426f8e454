//! Closed loop in the data (paper A1: the inputs are independent of the
//! disturbances). In the spirit of the System Identification Toolbox's
//! `feedback`: an input that the craft's past motion predicts, beyond what
//! the input's own past explains, was computed from the measurements — a
//! dynamic-positioning or autopilot stretch, a zigzag's switching rule. Per
//! window of [`WINDOW_SECONDS`] and per input `u`, two least-squares fits of
//! `u(k)` are compared: on `1, u(k−1), u(k−2)`, and on those plus every
//! state at `k, k−1, k−2` (a controller acts on the latest measurement; in
//! open loop the state at `k` depends only on inputs before `k`). A window is flagged when the states explain at
//! least [`EXPLAINED`] of what the input's own past leaves, and the χ² test
//! of the added terms rejects open loop at 10⁻⁶.

use leeway_model::correlation::chi_squared_tail;
use leeway_model::experiment::{Row, Source};
use leeway_structure::ir::Ir;
use nalgebra::{DMatrix, DVector};

/// The window a fit covers, seconds (at least [`MIN_WINDOW`] samples).
pub const WINDOW_SECONDS: f64 = 30.0;
/// The fewest samples of a window.
pub const MIN_WINDOW: usize = 100;
/// The share of the input's innovation the past motion must explain.
pub const EXPLAINED: f64 = 0.3;
/// Lags of the input and of each state in the fits.
const LAGS: usize = 2;

/// A stretch of an experiment whose inputs its outputs predict.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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

/// One input's sums over a window: `X'X`, `X'u`, `u'u` of the full fit,
/// whose columns are `1`, the input's lags, then the states' lags.
struct Sums {
    gram: DMatrix<f64>,
    cross: DVector<f64>,
    square: f64,
    n: usize,
}

impl Sums {
    fn new(width: usize) -> Sums {
        Sums {
            gram: DMatrix::zeros(width, width),
            cross: DVector::zeros(width),
            square: 0.0,
            n: 0,
        }
    }
    fn push(&mut self, x: &DVector<f64>, u: f64) {
        self.gram.ger(1.0, x, x, 1.0);
        self.cross.axpy(u, x, 1.0);
        self.square += u * u;
        self.n += 1;
    }
    /// The residual sum of squares of the fit on the first `columns`.
    fn residual(&self, columns: usize) -> Option<f64> {
        let g = self.gram.view((0, 0), (columns, columns)).into_owned();
        let c = self.cross.rows(0, columns).into_owned();
        let b = g.svd(true, true).solve(&c, 1e-12).ok()?;
        Some((self.square - b.dot(&c)).max(0.0))
    }
    /// The share of the restricted fit's residual the states explain, when
    /// the χ² test rejects that they add nothing.
    fn explained(&self, restricted: usize) -> Option<f64> {
        let full_width = self.gram.nrows();
        let r = self.residual(restricted)?;
        let f = self.residual(full_width)?;
        if r <= 1e-12 * self.square || self.n <= full_width {
            return None;
        }
        let q = full_width - restricted;
        let stat = (self.n - full_width) as f64 * (r - f) / f.max(f64::MIN_POSITIVE);
        (chi_squared_tail(stat, q) < 1e-6).then_some((r - f) / r)
    }
}

/// The regressors of sample `k` for input `j`: `1`, `u_j(k−1..k−LAGS)`,
/// then every state at `k, k−1, …, k−LAGS` (`past[l]` is sample `k−1−l`).
fn regressors(now: &[f64], past: &[(Vec<f64>, Vec<f64>)], j: usize, x: &mut DVector<f64>) {
    let mut i = 0;
    x[i] = 1.0;
    for (_, inputs) in past {
        i += 1;
        x[i] = inputs[j];
    }
    for states in std::iter::once(now).chain(past.iter().map(|(s, _)| s.as_slice())) {
        for s in states {
            i += 1;
            x[i] = *s;
        }
    }
}

/// The stretches of `source` where the motion predicts an input.
pub fn feedback(ir: &Ir, source: &dyn Source) -> Vec<Feedback> {
    let h = source.step();
    let window = ((WINDOW_SECONDS / h).round() as usize).max(MIN_WINDOW);
    if ir.inputs.is_empty() || source.len() < MIN_WINDOW {
        return Vec::new();
    }
    let restricted = 1 + LAGS;
    let width = restricted + (LAGS + 1) * ir.states.len();
    let mut sums: Vec<Sums> = ir.inputs.iter().map(|_| Sums::new(width)).collect();
    let mut past: Vec<(Vec<f64>, Vec<f64>)> = Vec::with_capacity(LAGS);
    let mut flagged: Vec<(usize, usize, Vec<usize>, f64)> = Vec::new();
    let mut x = DVector::zeros(width);
    let mut k = 0;
    let mut start = 0;
    source.visit(&mut |row: &Row| {
        if past.len() == LAGS {
            for (j, s) in sums.iter_mut().enumerate() {
                regressors(row.states, &past, j, &mut x);
                s.push(&x, row.inputs[j]);
            }
        }
        past.insert(0, (row.states.to_vec(), row.inputs.to_vec()));
        past.truncate(LAGS);
        k += 1;
        let last = k == source.len();
        if k - start == window || (last && k - start >= MIN_WINDOW) {
            let shares: Vec<(usize, f64)> = sums
                .iter()
                .enumerate()
                .filter_map(|(j, s)| s.explained(restricted).map(|e| (j, e)))
                .filter(|(_, e)| *e >= EXPLAINED)
                .collect();
            if !shares.is_empty() {
                let most = shares.iter().map(|(_, e)| *e).fold(0.0, f64::max);
                flagged.push((start, k - 1, shares.iter().map(|(j, _)| *j).collect(), most));
            }
            sums.iter_mut().for_each(|s| *s = Sums::new(width));
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
