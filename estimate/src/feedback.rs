//! Closed loop in the data (paper A1: the inputs are independent of the
//! disturbances). In the spirit of the System Identification Toolbox's
//! `feedback`: an input that the craft's past motion predicts, beyond what
//! the input's own past explains, was computed from the measurements — a
//! dynamic-positioning or autopilot stretch, a zigzag's switching rule. Per
//! window and per input `u`, two least-squares fits of `u(k)` are
//! compared: on `1, u(k−1), u(k−2)`, and on those plus the motion at `k,
//! k−1, k−2` — every state, and the heading of a model with a planar one
//! (a controller on heading acts on the heading error; an autopilot's rate
//! term may be the heading's last step rather than the gyro's yaw rate).
//! A controller acts on the latest measurement; in open loop the motion at
//! `k` depends only on inputs before `k`.
//!
//! The heading is unwrapped along the record (a step from one sample to the
//! next is taken modulo 2π), not replaced by its sine and cosine: a
//! controller is linear in the heading error, and one column a lag costs
//! half of two. Its lags enter taken from its value at the window's first
//! sample (the intercept absorbs a constant). A heading logged in degrees
//! is unwrapped wrongly where it steps more than π (3.1°) in a sample; the
//! model's rotation is wrong then too, and the heading check of the data
//! warns about it. The model carries no position (a `Row` has
//! the states, the inputs and the heading), and none is integrated from the
//! body velocities: a DP controller's position estimate is fast where it
//! integrates the velocities, which are among the regressors, and slow
//! where it follows the satellite fixes, which the input's own lags
//! absorb; on the synthetic ferry the DP windows explain the same with
//! and without it, and it would cost two regressors.
//!
//! A window is [`WINDOW_SECONDS`] long, but at least [`WIDTHS`] times the
//! full fit's width in samples, and at least [`MIN_WINDOW`]: at 1 Hz the
//! ferry's fit (three states and the heading, three lags each, and its own
//! three columns) is 15 wide, so five widths would be 75 s, but on 75
//! samples the study's smoothed open-loop rudder is "explained" by chance
//! (82 % in one window), so a window stays 100 samples. A window is
//! judged only when the input's innovations there — the samples its own
//! past does not predict — are many (five per added regressor, so a
//! window of [`WIDTHS`] widths can be judged): an input that steps a few
//! times a window carries too little evidence, however well a dozen
//! regressors happen to fit its steps. The last window is judged too: what
//! is left after a whole window is judged alone when it has at least
//! [`WIDTHS`] widths, and joins the window before otherwise (alone it
//! could never hold enough innovations; joined, its samples are judged
//! with their neighbours rather than not at all). A window is flagged when
//! the motion explains at least [`EXPLAINED`] of what the input's own past
//! leaves, and the χ² test of the added terms rejects open loop at 10⁻⁶.

use crate::parallel::{in_order, threads_for};
use leeway_model::correlation::chi_squared_tail;
use leeway_model::experiment::{Row, Source};
use leeway_structure::ir::{Ir, Rotation};
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use std::f64::consts::TAU;

/// The window a fit covers, seconds (at least [`WIDTHS`] times the full
/// fit's width, in samples).
pub const WINDOW_SECONDS: f64 = 30.0;
/// The fewest samples of a window, in widths of the full fit: five, as a
/// window is judged on five innovations per added regressor.
pub const WIDTHS: usize = 5;
/// The fewest samples of any window: on fewer, a smoothed open-loop input
/// is explained by chance (the study's ship, at 75 samples a window: 82 %).
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
/// `u_j`'s lags (its own block, `OWN` wide), then the states' lags (shared
/// by every input's fit): the Gram matrix of the states' lags is summed
/// once for all inputs, each input's rows of its own columns against every
/// column apart. Each entry is the sum of the same products in the same
/// order as a full rank-1 update per sample would make it, so the fits'
/// bits are those of one Gram matrix per input.
///
/// The window's samples are kept, and the sums made from them once the
/// window is whole ([`Sums::settle`]): each entry's products are then
/// added sample after sample in a register, several entries side by side,
/// rather than loaded and stored again at every sample.
struct Sums {
    /// Columns of the full fit.
    width: usize,
    /// The window's samples, a row each: the states' lags (`width − OWN`),
    /// then per input its own columns and itself, `1, u(k−1), …, u(k)`.
    window: Vec<f64>,
    /// Upper triangle of the states' lags' Gram matrix, row by row
    /// (`width − OWN` square).
    states: Vec<f64>,
    inputs: Vec<InputSums>,
}

/// One input's sums over a window: its own columns' rows of `X'X` (the
/// upper triangle's part), `X'u`, `u'u`.
struct InputSums {
    /// `OWN × width`, row by row.
    rows: Vec<f64>,
    cross: Vec<f64>,
    square: f64,
}

/// The restricted fit's columns: `1` and the input's lags.
const OWN: usize = 1 + LAGS;

impl Sums {
    fn new(width: usize, inputs: usize) -> Sums {
        let s = width - OWN;
        Sums {
            width,
            window: Vec::new(),
            states: vec![0.0; s * (s + 1) / 2],
            inputs: (0..inputs)
                .map(|_| InputSums {
                    rows: vec![0.0; OWN * width],
                    cross: vec![0.0; width],
                    square: 0.0,
                })
                .collect(),
        }
    }
    fn clear(&mut self) {
        self.window.clear();
    }
    /// A window row's length: the values, then [`PAD`] zeros that let
    /// every tile of [`Sums::settle`] be whole.
    fn stride(&self) -> usize {
        self.width - OWN + (OWN + 1) * self.inputs.len() + PAD
    }
    /// Where input `j`'s own columns begin in a window row.
    fn own_at(&self, j: usize) -> usize {
        self.width - OWN + (OWN + 1) * j
    }
    /// Adds a sample: the states' lags `lagged` (`width − OWN`), each
    /// input's lags and the inputs.
    fn push(&mut self, lagged: &[f64], lags: &[[f64; LAGS]], inputs: &[f64]) {
        self.window.extend_from_slice(lagged);
        for (l, u) in lags.iter().zip(inputs) {
            let mut own = [*u; OWN + 1];
            own[0] = 1.0;
            own[1..OWN].copy_from_slice(l);
            self.window.extend_from_slice(&own);
        }
        self.window.extend_from_slice(&[0.0; PAD]);
    }
    /// The window's samples, a row each.
    fn samples(&self) -> std::slice::ChunksExact<'_, f64> {
        self.window.chunks_exact(self.stride())
    }
    /// Makes the sums of the window's samples, a tile of entries at a time
    /// (those of a tile beyond the wanted ones are dropped).
    fn settle(&mut self) {
        let (s, stride) = (self.width - OWN, self.stride());
        let window = &self.window;
        // The states' triangle, two rows at a time: row i's entries from
        // column i on, row i + 1's from i + 1 on.
        let mut row_at = 0;
        for i in (0..s).step_by(2) {
            let next_at = row_at + (s - i);
            for b0 in (i..s).step_by(LANES) {
                let tile = tile::<2, LANES>(window, stride, i, b0);
                for (r, sums) in tile.iter().enumerate() {
                    let (a, at) = (i + r, if r == 0 { row_at } else { next_at });
                    for b in b0.max(a)..(b0 + LANES).min(s) {
                        self.states[at + b - a] = sums[b - b0];
                    }
                }
            }
            row_at = next_at + (s - i).saturating_sub(1);
        }
        for j in 0..self.inputs.len() {
            let own = self.own_at(j);
            let sums = &mut self.inputs[j];
            // The own columns and the input (`1, u(k−1), u(k−2), u(k)`)
            // against the states' lags: rows of the Gram matrix, then `X'u`.
            for a0 in (own..own + OWN + 1).step_by(2) {
                for b0 in (0..s).step_by(LANES) {
                    let tile = tile::<2, LANES>(window, stride, a0, b0);
                    for (r, part) in tile.iter().enumerate() {
                        let (a, n) = (a0 + r - own, (s - b0).min(LANES));
                        let dest = match a.checked_sub(OWN) {
                            None => &mut sums.rows[a * self.width + OWN + b0..][..n],
                            Some(_) => &mut sums.cross[OWN + b0..][..n],
                        };
                        dest.copy_from_slice(&part[..n]);
                    }
                }
            }
            // The own columns and the input against themselves.
            let tile = tile::<{ OWN + 1 }, { OWN + 1 }>(window, stride, own, own);
            for (r, part) in tile[..OWN].iter().enumerate() {
                sums.rows[r * self.width + r..(r + 1) * self.width][..OWN - r]
                    .copy_from_slice(&part[r..OWN]);
            }
            sums.cross[..OWN].copy_from_slice(&tile[OWN][..OWN]);
            sums.square = tile[OWN][OWN];
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
        let b = solve_normal(g, &c)?;
        let rss = self.residual_squares(j, &b);
        Some((b, rss))
    }
    /// `Σ (u − x·b)²` over the window, from its samples: `u'u − b'c`
    /// cancels most of its digits when the fit is close (a smoothed input
    /// its own lags predict to 10⁻⁵ of its square), where the residuals
    /// themselves lose none, whichever way `b` was solved.
    fn residual_squares(&self, j: usize, b: &DVector<f64>) -> f64 {
        let (s, own) = (self.width - OWN, self.own_at(j));
        let full = b.len() > OWN;
        let mut sum = 0.0;
        for row in self.samples() {
            let mut fitted = 0.0;
            for (v, bi) in row[own..own + OWN].iter().zip(b.iter()) {
                fitted += bi * v;
            }
            if full {
                for (v, bi) in row[..s].iter().zip(&b.as_slice()[OWN..]) {
                    fitted += bi * v;
                }
            }
            let e = row[own + OWN] - fitted;
            sum += e * e;
        }
        sum
    }
    /// The innovations the restricted fit leaves: the samples whose
    /// residual exceeds 10⁻⁴ of their RMS. Dense noise counts every sample;
    /// an input held (or smoothed) between steps counts only its steps.
    fn innovations(&self, j: usize, b: &DVector<f64>, rss: f64) -> f64 {
        let own = self.own_at(j);
        let n = self.window.len() / self.stride();
        let floor = 1e-4 * (rss / n.max(1) as f64).sqrt();
        let count = self
            .samples()
            .filter(|row| {
                let row = &row[own..own + OWN + 1];
                let e = row[OWN] - (0..OWN).map(|i| b[i] * row[i]).sum::<f64>();
                e.abs() > floor
            })
            .count();
        count as f64
    }
    /// The share of input `j`'s restricted fit's residual the motion
    /// explains, and whether the χ² test (on the innovations) rejects that
    /// the motion adds nothing; `None` when the window does not hold enough
    /// innovations to judge. The full fit is solved only for a window that
    /// can be judged.
    fn judge(&self, j: usize) -> Option<(f64, bool)> {
        let (b, r) = self.fit(j, OWN)?;
        let q = self.width - OWN;
        let n = self.innovations(j, &b, r);
        if r <= 1e-12 * self.inputs[j].square || n < (MIN_INNOVATIONS * q) as f64 {
            return None;
        }
        let (_, f) = self.fit(j, self.width)?;
        let stat = (n - self.width as f64).max(0.0) * (r - f) / f.max(f64::MIN_POSITIVE);
        Some(((r - f) / r, chi_squared_tail(stat, q) < 1e-6))
    }
}

/// Entries a tile of [`Sums::settle`] sums side by side per row.
const LANES: usize = 8;
/// Zeros after each window row, so that a tile reaching past the last
/// value reads zeros (its entries there are dropped).
const PAD: usize = LANES;

/// `Σ_k m[k][a + r] · m[k][b + c]` for `r < A`, `c < L`, over the rows
/// `m[k]` (`stride` wide): each entry summed from `0.0` in row order, one
/// multiply and one add a product, so the bits of adding them one sample
/// at a time. The tile's sums stay in registers through the rows, and its
/// `A × L` independent additions keep the adder busy (an entry alone
/// would wait on its last addition at every row).
#[inline(always)]
fn tile<const A: usize, const L: usize>(
    m: &[f64],
    stride: usize,
    a: usize,
    b: usize,
) -> [[f64; L]; A] {
    let mut acc = [[0.0; L]; A];
    if a + A > stride || b + L > stride {
        return acc; // no such columns (never, by the callers)
    }
    for row in m.chunks_exact(stride) {
        let y = &row[b..b + L];
        for (acc, x) in acc.iter_mut().zip(&row[a..a + A]) {
            for (acc, y) in acc.iter_mut().zip(y) {
                *acc += x * y;
            }
        }
    }
    acc
}

/// The smallest Cholesky pivot of the equilibrated Gram matrix (unit
/// diagonal) that the fast solve accepts: below it the columns are nearly
/// dependent, and the SVD decides what the fit is.
const PIVOT_FLOOR: f64 = 1e-10;

/// `b` of the normal equations `G b = c`, solved on `G` equilibrated to a
/// unit diagonal: a state in rad/s beside a force in newtons makes `G`
/// look singular by its units alone, and equilibrating takes that away
/// (`b` is scaled back). Most windows' matrices are then well conditioned:
/// a Cholesky factorisation solves them in a few hundred operations, where
/// an SVD costs tens of microseconds. A window whose columns are nearly
/// dependent (a held input, a constant state) goes to the SVD, which drops
/// what the data cannot tell apart.
fn solve_normal(g: DMatrix<f64>, c: &DVector<f64>) -> Option<DVector<f64>> {
    let (g, scale) = equilibrated(&g);
    let c = c.component_mul(&scale);
    let y = match well_conditioned(&g) {
        Some(ch) => ch.solve(&c),
        // A bounded number of sweeps: a fit that does not converge is no fit.
        None => g
            .try_svd(true, true, f64::EPSILON, 500)?
            .solve(&c, 1e-12)
            .ok()?,
    };
    Some(y.component_mul(&scale))
}

/// `S G S` with `S` the diagonal that makes its diagonal 1 (1 for a zero
/// column), and `S`.
fn equilibrated(g: &DMatrix<f64>) -> (DMatrix<f64>, DVector<f64>) {
    let scale = g
        .diagonal()
        .map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 });
    let g = DMatrix::from_fn(g.nrows(), g.ncols(), |i, j| g[(i, j)] * scale[i] * scale[j]);
    (g, scale)
}

/// The Cholesky factor of `g` (unit diagonal) when its every pivot is
/// above [`PIVOT_FLOOR`].
fn well_conditioned(g: &DMatrix<f64>) -> Option<Cholesky<f64, Dyn>> {
    let ch = g.clone().cholesky()?;
    let l = ch.l_dirty();
    let smallest = (0..l.nrows())
        .map(|i| l[(i, i)] * l[(i, i)])
        .fold(f64::INFINITY, f64::min);
    (smallest > PIVOT_FLOOR).then_some(ch)
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
    let Some(mut scan) = FeedbackScan::new(ir, source) else {
        return Vec::new();
    };
    source.visit(&mut |row: &Row| scan.push(row));
    scan.finish()
}

/// The closed-loop check of one experiment as its rows go by, so that it
/// can share a visit with the other checks of the data: [`FeedbackScan::push`]
/// every row in order, then [`FeedbackScan::finish`].
pub struct FeedbackScan<'a> {
    ir: &'a Ir,
    source: &'a dyn Source,
    /// Samples a window holds.
    window: usize,
    /// The fewest samples a window is judged on ([`WIDTHS`] × the full
    /// fit's width): a last stretch shorter joins the window before it.
    least: usize,
    sums: Sums,
    /// The motion's regressors: the states at k, k−1, …, k−LAGS, then the
    /// heading unwrapped at k, …, k−LAGS (when the model has one).
    x: Vec<f64>,
    /// The heading's unwrapping, when the model has a planar heading.
    heading: Option<Heading>,
    /// The row of regressors a window's sample gets: `x`, the heading taken
    /// from its value at the window's first sample (the intercept absorbs
    /// a constant, and the values stay small however far the craft turned).
    lagged: Vec<f64>,
    /// Each input's lags k−1, …, k−LAGS.
    lags: Vec<[f64; LAGS]>,
    /// Rows seen before the first whole set of lags (at most `LAGS`).
    seen: usize,
    /// Every judged window: first and last sample, each input's share and
    /// whether its test rejected open loop (`None`: not judged).
    judged: Vec<Judged>,
    /// Rows pushed.
    k: usize,
    /// The current window's first row.
    start: usize,
}

/// A window and what the check found there.
#[derive(Clone, Debug)]
pub(crate) struct Judged {
    pub(crate) first: usize,
    pub(crate) last: usize,
    /// Per input: the share of its innovation the motion explains, and
    /// whether the χ² test rejects open loop (`None`: too little evidence).
    pub(crate) inputs: Vec<Option<(f64, bool)>>,
}

impl Judged {
    /// The inputs flagged, and the largest share among them.
    fn flagged(&self) -> Option<(Vec<usize>, f64)> {
        let flagged: Vec<(usize, f64)> = self
            .inputs
            .iter()
            .enumerate()
            .filter_map(|(j, e)| match e {
                Some((e, true)) if *e >= EXPLAINED => Some((j, *e)),
                _ => None,
            })
            .collect();
        let most = flagged.iter().map(|(_, e)| *e).fold(0.0, f64::max);
        (!flagged.is_empty()).then(|| (flagged.into_iter().map(|(j, _)| j).collect(), most))
    }
}

/// The heading unwrapped along the record.
struct Heading {
    /// The last finite heading read (wrapped, as logged), and its value
    /// unwrapped: the first read, then steps of less than π.
    last: Option<(f64, f64)>,
    /// The heading at the current window's first sample.
    base: f64,
}

impl Heading {
    /// The heading of a model with a planar one.
    fn of(ir: &Ir) -> Option<Heading> {
        matches!(ir.rotation, Rotation::Planar { .. }).then_some(Heading {
            last: None,
            base: 0.0,
        })
    }
    /// The heading `psi` of the next row, unwrapped: a step from the last
    /// is taken modulo 2π into `[−π, π]`. A heading that is not finite is
    /// passed on (its window then has no fit), and the unwrapping goes on
    /// from the last finite one.
    fn unwrap(&mut self, psi: f64) -> f64 {
        if !psi.is_finite() {
            return psi;
        }
        let unwrapped = match self.last {
            None => psi,
            Some((read, unwrapped)) => {
                let step = psi - read;
                unwrapped + step - TAU * (step / TAU).round()
            }
        };
        self.last = Some((psi, unwrapped));
        unwrapped
    }
}

impl<'a> FeedbackScan<'a> {
    /// The check of `source`, or `None` when there is nothing to check (a
    /// model without inputs, a record shorter than the fewest samples a
    /// window is judged on).
    pub fn new(ir: &'a Ir, source: &'a dyn Source) -> Option<FeedbackScan<'a>> {
        let heading = Heading::of(ir);
        let motion = (LAGS + 1) * (ir.states.len() + usize::from(heading.is_some()));
        let width = OWN + motion;
        let least = (WIDTHS * width).max(MIN_WINDOW);
        if ir.inputs.is_empty() || source.len() < least {
            return None;
        }
        let window = ((WINDOW_SECONDS / source.step()).round() as usize).max(least);
        Some(FeedbackScan {
            ir,
            source,
            window,
            least,
            sums: Sums::new(width, ir.inputs.len()),
            x: vec![0.0; motion],
            heading,
            lagged: vec![0.0; motion],
            lags: vec![[0.0; LAGS]; ir.inputs.len()],
            seen: 0,
            judged: Vec::new(),
            k: 0,
            start: 0,
        })
    }

    /// The next row of the experiment.
    pub fn push(&mut self, row: &Row) {
        let n_states = self.ir.states.len();
        let states = (LAGS + 1) * n_states;
        self.x.copy_within(0..states - n_states, n_states);
        self.x[..n_states].copy_from_slice(row.states);
        self.lagged[..states].copy_from_slice(&self.x[..states]);
        if let Some(heading) = &mut self.heading {
            let psi = heading.unwrap(row.heading);
            if self.k == self.start {
                heading.base = psi;
            }
            let lags = &mut self.x[states..];
            lags.copy_within(0..LAGS, 1);
            lags[0] = psi;
            for (l, x) in self.lagged[states..].iter_mut().zip(&self.x[states..]) {
                *l = x - heading.base;
            }
        }
        if self.seen == LAGS {
            self.sums.push(&self.lagged, &self.lags, row.inputs);
        } else {
            self.seen += 1;
        }
        for (l, u) in self.lags.iter_mut().zip(row.inputs) {
            l.copy_within(0..LAGS - 1, 1);
            l[0] = *u;
        }
        self.k += 1;
        let (k, start, n) = (self.k, self.start, self.source.len());
        // A whole window is judged, unless what is left after it is too
        // short to be judged alone: the window then runs to the end.
        let whole = k - start == self.window && n.saturating_sub(k) >= self.least;
        if whole || (k == n && k - start >= self.least) {
            self.judge_window();
        }
    }

    /// Judges the window that ends at the last row pushed, and starts the next.
    fn judge_window(&mut self) {
        self.sums.settle();
        let inputs = (0..self.ir.inputs.len())
            .map(|j| self.sums.judge(j))
            .collect();
        self.judged.push(Judged {
            first: self.start,
            last: self.k - 1,
            inputs,
        });
        self.sums.clear();
        self.start = self.k;
    }

    /// Every window judged, in order.
    #[cfg(test)]
    pub(crate) fn windows(&self) -> &[Judged] {
        &self.judged
    }

    /// The flagged stretches, adjacent windows merged.
    pub fn finish(self) -> Vec<Feedback> {
        let flagged = self
            .judged
            .iter()
            .filter_map(|w| {
                w.flagged()
                    .map(|(inputs, most)| (w.first, w.last, inputs, most))
            })
            .collect();
        merge(self.ir, self.source, self.source.step(), flagged)
    }
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
mod power;

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

    /// The SVD's solution of `G b = c`, as every window was solved before
    /// the Cholesky path.
    fn by_svd(g: &DMatrix<f64>, c: &DVector<f64>) -> DVector<f64> {
        g.clone()
            .try_svd(true, true, f64::EPSILON, 500)
            .and_then(|s| s.solve(c, 1e-12).ok())
            .unwrap_or_else(|| panic!("the SVD converges"))
    }

    #[test]
    fn the_fast_solve_agrees_with_the_svd_and_leaves_dependent_columns_to_it() {
        // 12 columns of a record, well conditioned enough for the Cholesky
        // path, as most windows are.
        let e = record(|_| false, 1.0);
        let x = DMatrix::from_fn(300, 12, |k, j| {
            (0.37 * (k * (j + 1)) as f64 + j as f64).sin() + 0.1 * e.states[0][k + j]
        });
        let g = x.transpose() * &x;
        let c = x.transpose() * DVector::from_fn(300, |k, _| e.inputs[0][k]);
        assert!(well_conditioned(&equilibrated(&g).0).is_some());
        let fast = solve_normal(g.clone(), &c).unwrap_or_else(|| panic!("solved"));
        let svd = by_svd(&g, &c);
        let scale = svd.amax();
        assert!((fast - &svd).amax() <= 1e-8 * scale, "{svd}");
        // A column repeated: the Gram matrix is singular, the SVD decides.
        let mut dup = x.clone();
        dup.set_column(5, &x.column(4).clone_owned());
        let g = dup.transpose() * &dup;
        assert!(well_conditioned(&equilibrated(&g).0).is_none());
        let c = dup.transpose() * DVector::from_fn(300, |k, _| e.inputs[0][k]);
        let solved = solve_normal(g.clone(), &c).unwrap_or_else(|| panic!("solved"));
        assert!((&g * &solved - &c).amax() <= 1e-9 * c.amax(), "{solved}");
        assert!(
            (solved[4] - solved[5]).abs() <= 1e-9 * solved.amax(),
            "{solved}"
        );
    }

    #[test]
    fn residual_sums_of_a_close_fit_keep_their_digits() {
        // A smooth input its own lags predict to about 10⁻⁶ of its square,
        // and two states that follow it: `u'u − b'c` loses most of the
        // residual's digits here (it flagged open-loop windows as closed).
        let (n, n_states) = (300, 2);
        let width = OWN + (LAGS + 1) * n_states;
        let u: Vec<f64> = (0..n + LAGS)
            .map(|k| {
                let t = k as f64;
                300.0 * ((0.05 * t).sin() + 0.5 * (0.013 * t).cos() + 1e-4 * (1.7 * t).sin())
            })
            .collect();
        let mut states = vec![[0.0; 2]; n + LAGS];
        for k in 1..n + LAGS {
            let [a, b] = states[k - 1];
            states[k] = [a + 0.2 * (u[k - 1] - a), b + 0.1 * (a - b)];
        }
        // Measured with noise: else each state's lags and the input's are
        // exactly dependent.
        for (k, s) in states.iter_mut().enumerate() {
            let t = k as f64;
            s[0] += 0.3 * (2.3 * t).sin();
            s[1] = 1e-4 * (s[1] + 0.3 * (3.1 * t + 1.0).cos());
        }
        let mut sums = Sums::new(width, 1);
        let mut rows = Vec::new();
        for k in LAGS..n + LAGS {
            let mut x = vec![0.0; width];
            for lag in 0..=LAGS {
                x[OWN + lag * n_states..OWN + (lag + 1) * n_states]
                    .copy_from_slice(&states[k - lag]);
            }
            x[..OWN].copy_from_slice(&[1.0, u[k - 1], u[k - 2]]);
            sums.push(&x[OWN..], &[[u[k - 1], u[k - 2]]], &[u[k]]);
            rows.push(x);
        }
        sums.settle();
        for columns in [OWN, width] {
            let (_, rss) = sums.fit(0, columns).unwrap_or_else(|| panic!("a fit"));
            // The reference: least squares on the samples themselves (QR).
            let a = DMatrix::from_fn(n, columns, |k, c| rows[k][c]);
            let y = DVector::from_fn(n, |k, _| u[k + LAGS]);
            let qr = a.clone().qr();
            let b = qr
                .r()
                .solve_upper_triangular(&(qr.q().transpose() * &y))
                .unwrap_or_else(|| panic!("solved"));
            let reference = (&y - &a * b).norm_squared();
            assert!(reference < 1e-5 * y.norm_squared(), "{reference}");
            assert!(
                (rss - reference).abs() <= 1e-6 * reference,
                "{columns} columns: {rss} against {reference}"
            );
        }
    }

    /// A sample of a window: the states' lags, each input's lags, the inputs.
    type Sample = (Vec<f64>, Vec<[f64; LAGS]>, Vec<f64>);
    /// An input's sums: rows, cross products, square.
    type InputReference = (Vec<f64>, Vec<f64>, f64);

    /// The sums as a rank-1 update per sample made them (before the window
    /// was kept and summed whole): the states' triangle, then each input's
    /// rows, cross products and square.
    fn summed_sample_by_sample(
        width: usize,
        samples: &[Sample],
    ) -> (Vec<f64>, Vec<InputReference>) {
        let s = width - OWN;
        let m = samples.first().map_or(0, |x| x.2.len());
        let mut states = vec![0.0; s * (s + 1) / 2];
        let mut inputs = vec![(vec![0.0; OWN * width], vec![0.0; width], 0.0); m];
        for (lagged, lags, us) in samples {
            let mut x = vec![0.0; width];
            x[OWN..].copy_from_slice(lagged);
            let mut at = 0;
            for (i, a) in x[OWN..].iter().enumerate() {
                for b in &x[OWN + i..] {
                    states[at] += a * b;
                    at += 1;
                }
            }
            for (j, (rows, cross, square)) in inputs.iter_mut().enumerate() {
                x[0] = 1.0;
                x[1..OWN].copy_from_slice(&lags[j]);
                let u = us[j];
                for r in 0..OWN {
                    for c in r..width {
                        rows[r * width + c] += x[c] * x[r];
                    }
                }
                for (c, a) in cross.iter_mut().zip(&x) {
                    *c += u * a;
                }
                *square += u * u;
            }
        }
        (states, inputs)
    }

    #[test]
    fn window_sums_have_the_bits_of_sums_made_sample_by_sample() {
        let mut seed = 11u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (n_states, n_inputs, n) in
            [(1, 1, 1), (3, 3, 100), (2, 1, 37), (4, 2, 129), (6, 3, 300)]
        {
            let width = OWN + (LAGS + 1) * n_states;
            let samples: Vec<Sample> = (0..n)
                .map(|k| {
                    // Magnitudes far apart, and a negative zero now and then.
                    let lagged = (0..width - OWN)
                        .map(|c| {
                            if (k + c) % 17 == 0 {
                                -0.0
                            } else {
                                next() * [1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0, 1e3][c % 7]
                            }
                        })
                        .collect();
                    let lags = (0..n_inputs)
                        .map(|_| [next() * 1e3, next() * 1e3])
                        .collect();
                    let us = (0..n_inputs).map(|_| next() * 1e3).collect();
                    (lagged, lags, us)
                })
                .collect();
            let mut sums = Sums::new(width, n_inputs);
            // A window before, to show the sums start afresh.
            sums.push(
                &vec![1e9; width - OWN],
                &vec![[1e9; LAGS]; n_inputs],
                &vec![1e9; n_inputs],
            );
            sums.settle();
            sums.clear();
            for (lagged, lags, us) in &samples {
                sums.push(lagged, lags, us);
            }
            sums.settle();
            let (states, inputs) = summed_sample_by_sample(width, &samples);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&sums.states), bits(&states), "{n_states} states");
            for (j, (rows, cross, square)) in inputs.iter().enumerate() {
                let got = &sums.inputs[j];
                for r in 0..OWN {
                    // The upper triangle's part, which the fits read.
                    let part = r * width + r..(r + 1) * width;
                    assert_eq!(
                        bits(&got.rows[part.clone()]),
                        bits(&rows[part]),
                        "input {j} row {r}"
                    );
                }
                assert_eq!(bits(&got.cross), bits(cross), "input {j}");
                assert_eq!(got.square.to_bits(), square.to_bits(), "input {j}");
            }
        }
    }

    #[test]
    fn the_last_stretch_is_judged_alone_or_with_the_window_before() {
        let ir = ir();
        // 10 Hz: windows of 300 samples, the fewest judged 100 (5 × 6 = 30
        // widths, at least MIN_WINDOW). 100 samples left after 19 windows
        // are judged alone.
        let e = record(|k| k >= 5700, 1.0).truncated(5800);
        let found = feedback(&ir, &e);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].first, found[0].last), (5700, 5799));
        // 20 are too few: they join the window before.
        let e = record(|k| k >= 5400, 1.0).truncated(5720);
        let found = feedback(&ir, &e);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].first, found[0].last), (5400, 5719));
    }

    #[test]
    fn the_heading_is_unwrapped_along_the_record() {
        let mut h = Heading {
            last: None,
            base: 0.0,
        };
        let read = [3.0, -3.0, 3.1, -3.1, 0.5, f64::NAN, 0.6, -0.3];
        let got: Vec<f64> = read.iter().map(|psi| h.unwrap(*psi)).collect();
        let want = [3.0, TAU - 3.0, 3.1, TAU - 3.1, 0.5, f64::NAN, 0.6, -0.3];
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g - w).abs() < 1e-12 || (g.is_nan() && w.is_nan()),
                "{got:?}"
            );
        }
    }

    #[test]
    fn squares_beyond_range_are_no_fit_and_no_hang() {
        assert_eq!(feedback(&ir(), &record(|_| true, 1e200)), vec![]);
    }
}
