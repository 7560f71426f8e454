//! The checks of the validating pass that look at a whole experiment:
//! gross outliers from the most extreme values of each column
//! ([`Extremes`]), and the time steps from the smallest and largest step
//! ([`TimeScan`], [`sample_time`]) — both in one pass and flat memory.
//!
//! An outlier is judged against the spread of the bulk (a column without
//! its 17 most extreme values at either end); a column constant but for a
//! few samples against its value or, when that value is 0, against an
//! absolute bound in base units.

use crate::error::DataError;
use crate::options::LoadOptions;
use leeway_model::number::short_number as num;
use leeway_structure::ir::Ir;

/// The most extreme samples of each signal column kept for the outlier check.
const EXTREMES: usize = 17;

/// How far outside the range of the bulk of a column a sample must lie to be
/// a gross outlier, in multiples of that range (see `Extremes`).
pub const OUTLIER_FACTOR: f64 = 1e4;

/// The gross-outlier bound for a column that is otherwise exactly 0, for
/// states, the heading, rotation entries and measured disturbances (base
/// units m/s, rad, rad/s: no physical value comes near).
pub const ZERO_OUTLIER: f64 = 1e6;

/// The same for inputs (forces, angles and rates in the user's units).
pub const ZERO_OUTLIER_INPUT: f64 = 1e12;

/// A gross outlier found by [`Extremes::outliers`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Outlier {
    pub(super) value: f64,
    pub(super) line: u64,
    /// The bulk's range (equal ends for a constant column).
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// The bound it broke, for a constant column of 0: `Some(bound)`.
    pub(super) zero_bound: Option<f64>,
}

/// The [`EXTREMES`] largest and smallest values of one column, with their
/// positions (physical lines in CSV): enough to find isolated gross outliers in one pass and
/// flat memory.
///
/// The rule: with `K = min(16, (n − 1)/4)`, the bulk of the column is the
/// range `[lo, hi]` of its values without the `K` smallest and `K` largest;
/// a value farther than [`OUTLIER_FACTOR`] × `(hi − lo)` outside it is a gross
/// outlier. A real zigzag (the rudder switching between ±35°, held for many
/// samples each time) has its extremes inside the bulk, and any physical
/// excursion held for more than `K` samples is part of the bulk. The rule is
/// scale-free: units do not change it.
///
/// A column constant apart from at most `K` samples (`hi = lo = c`: a
/// sensor stuck at one value) has no spread to compare with; there a value
/// farther than [`OUTLIER_FACTOR`] × `|c|` from `c` is a gross outlier (still
/// scale-free), and when `c = 0`, one beyond an absolute bound in base units:
/// [`ZERO_OUTLIER`] for states, heading, rotation and measured disturbances
/// (speeds in m/s, angles in rad, rates in rad/s), [`ZERO_OUTLIER_INPUT`]
/// for inputs, whose units are the user's. A short pulse on a column that is
/// otherwise zero (a thruster kick) stays accepted.
#[derive(Clone, Debug, Default)]
pub(super) struct Extremes {
    /// Largest first.
    high: Vec<(f64, u64)>,
    /// Smallest first.
    low: Vec<(f64, u64)>,
}

impl Extremes {
    pub(super) fn push(&mut self, v: f64, line: u64) {
        if self.high.len() < EXTREMES || v > self.high[EXTREMES - 1].0 {
            let i = self.high.partition_point(|(x, _)| *x >= v);
            self.high.insert(i, (v, line));
            self.high.truncate(EXTREMES);
        }
        if self.low.len() < EXTREMES || v < self.low[EXTREMES - 1].0 {
            let i = self.low.partition_point(|(x, _)| *x <= v);
            self.low.insert(i, (v, line));
            self.low.truncate(EXTREMES);
        }
    }
    /// The gross outliers among `n` samples, by line (`zero_bound`: the
    /// absolute bound of a column that is otherwise 0).
    pub(super) fn outliers(&self, n: usize, zero_bound: f64) -> Vec<Outlier> {
        let k = ((n.saturating_sub(1)) / 4).min(EXTREMES - 1);
        if k == 0 || self.high.len() <= k || self.low.len() <= k {
            return Vec::new();
        }
        let (lo, hi) = (self.low[k].0, self.high[k].0);
        let w = hi - lo;
        if !w.is_finite() || w < 0.0 {
            return Vec::new();
        }
        // A spread to compare with, else the constant's own magnitude, else
        // (a column of zeros) the absolute bound.
        let (far, bound) = if w > 0.0 {
            (OUTLIER_FACTOR * w, None)
        } else if lo != 0.0 {
            (OUTLIER_FACTOR * lo.abs(), None)
        } else {
            (zero_bound, Some(zero_bound))
        };
        let mut out: Vec<Outlier> = self.high[..k]
            .iter()
            .filter(|(x, _)| *x - hi > far)
            .chain(self.low[..k].iter().filter(|(x, _)| lo - *x > far))
            .map(|(x, l)| Outlier {
                value: *x,
                line: *l,
                lo,
                hi,
                zero_bound: bound,
            })
            .collect();
        out.sort_by_key(|o| o.line);
        out
    }
}

/// What one pass found about one experiment's time stamps: enough to check
/// them against the mean step without holding them.
#[derive(Clone, Debug, Default)]
pub(super) struct TimeScan {
    first: Option<f64>,
    last: f64,
    /// First non-increasing step: `(step, line)`.
    backwards: Option<(f64, u64)>,
    /// Smallest and largest step, first occurrence: `(step, line)`.
    min: Option<(f64, u64)>,
    max: Option<(f64, u64)>,
}

impl TimeScan {
    pub(super) fn push(&mut self, t: f64, line: u64) {
        if self.first.is_some() {
            let dt = t - self.last;
            if dt <= 0.0 && self.backwards.is_none() {
                self.backwards = Some((dt, line));
            }
            if self.min.is_none_or(|(m, _)| dt < m) {
                self.min = Some((dt, line));
            }
            if self.max.is_none_or(|(m, _)| dt > m) {
                self.max = Some((dt, line));
            }
        } else {
            self.first = Some(t);
        }
        self.last = t;
    }
}

/// What [`sample_time`] reads of one experiment's block.
#[derive(Clone, Copy)]
pub(super) struct BlockTimes<'a> {
    pub(super) times: &'a TimeScan,
    pub(super) rows: usize,
    pub(super) first: u64,
}

/// The sample time of one experiment and the largest relative deviation of
/// its steps from it (`None` without time stamps). The nominal step is the
/// mean step; every step must lie within `options.time_tolerance` of it, in
/// relative terms. The worst step is the smallest or the largest, which the
/// validating pass kept with their positions (`at` locates one in the time
/// column).
pub(super) fn sample_time(
    file: &str,
    ir: &Ir,
    block: BlockTimes<'_>,
    at: &dyn Fn(u64) -> String,
    options: &LoadOptions,
) -> Result<(f64, Option<f64>), DataError> {
    let declared = ir.step.or(options.step);
    let t = &block.times;
    let (Some(first), Some(min), Some(max)) = (t.first, t.min, t.max) else {
        let h = declared.ok_or_else(|| {
            DataError::new(
                file,
                "no sample time: the model declares no `step` and the data have no `time` column",
                "declare `step h` in the model or add a `time` column",
            )
        })?;
        return Ok((h, None));
    };
    // The nominal step is the mean step, the best estimate of a uniform h
    // under jitter. A gap shifts the mean of a short record, so that good
    // steps may fall outside the tolerance too: the error names the worst
    // step, which is the gap.
    let mean = (t.last - first) / (block.rows - 1) as f64;
    let tol = options.time_tolerance;
    let hint = "leeway needs uniformly sampled data: a larger jitter may be allowed with --time-tolerance, \
                --resample H interpolates onto a uniform grid, or split the log into experiments at the gaps";
    if let Some((dt, line)) = t.backwards {
        return Err(DataError::new(
            at(line),
            format!("time does not increase: step {} s here", num(dt)),
            hint,
        ));
    }
    let dev = |dt: f64| (dt - mean).abs() / mean;
    // The first of the two on a tie, as a scan in file order would find it.
    let (dmin, dmax) = (dev(min.0), dev(max.0));
    let ((dt, line), worst) = if dmax > dmin || (dmax == dmin && max.1 < min.1) {
        (max, dmax)
    } else {
        (min, dmin)
    };
    // Resampling interpolates over any spacing; only the order matters then.
    if options.resample.is_none() && worst > tol {
        return Err(DataError::new(
            at(line),
            format!(
                "inconsistent sample time: step {} s here, {:.1} % off the nominal (mean) step {} s; the tolerance is {:.1} %",
                num(dt),
                100.0 * worst,
                num(mean),
                100.0 * tol
            ),
            hint,
        ));
    }
    // Under resampling the grid step is the sample time, checked against the
    // model's step by the caller.
    let h = options.resample.unwrap_or(mean);
    if let Some(d) = declared
        && (h - d).abs() > 1e-3 * d
    {
        let what = if options.resample.is_some() {
            format!(
                "--resample {} conflicts with the model's step {}",
                num(h),
                num(d)
            )
        } else {
            format!(
                "the data are sampled every {} s but the model declares step {}",
                num(mean),
                num(d)
            )
        };
        return Err(DataError::new(
            at(block.first),
            what,
            "make `step` in the model match the data, or resample the data (--resample H)",
        ));
    }
    Ok((declared.unwrap_or(h), Some(worst)))
}
