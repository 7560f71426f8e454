//! The operating point of an experiment: static input offsets whose nominal
//! steady state puts every held sign argument on its side with the largest
//! margin the actuator limits allow (paper A7, A13), leaving room to excite
//! around it, and plain states that need sign changes near zero.
//!
//! A grid over the offsets (coarser as inputs grow), then a pattern search
//! from its best point. Offsets first stay in the middle 60 % of each range
//! (the rest is the excitation's room); only if no margin is positive there
//! do they use the whole range.

use crate::plan::{Conditions, Limits};
use crate::signs::Held;
use crate::steady::{Steady, steady_state};
use leeway_model::model::{Model, Signals};

/// A chosen operating point.
#[derive(Clone, Debug)]
pub struct OperatingPoint {
    /// The static input offsets.
    pub offsets: Vec<f64>,
    /// Their nominal steady state (calm).
    pub steady: Steady,
    /// Per held argument: its steady margin against the worst mean and the band.
    pub margins: Vec<f64>,
    /// Whether the offsets had to leave the middle of the ranges.
    pub full_range: bool,
}

impl OperatingPoint {
    /// The smallest margin (`+∞` with nothing held).
    pub fn min_margin(&self) -> f64 {
        self.margins.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// What a candidate offset is worth.
struct Candidate {
    offsets: Vec<f64>,
    steady: Steady,
    margins: Vec<f64>,
}

/// The best operating point for the held arguments; `None` when no offset
/// within the limits reaches a steady state.
pub fn operating_point(
    model: &dyn Model,
    c: &Conditions,
    held: &[Held],
    pointwise: &[usize],
) -> Option<OperatingPoint> {
    let inner = search(model, c, held, pointwise, 0.2);
    match inner {
        Some(p) if p.min_margin() > 0.0 => Some(p),
        _ => {
            let full = search(model, c, held, pointwise, 0.0)?;
            Some(OperatingPoint {
                full_range: true,
                ..full
            })
        }
    }
}

fn search(
    model: &dyn Model,
    c: &Conditions,
    held: &[Held],
    pointwise: &[usize],
    reserve: f64,
) -> Option<OperatingPoint> {
    let bounds: Vec<(f64, f64)> = c
        .limits
        .iter()
        .map(|l: &Limits| (l.low + reserve * l.span(), l.high - reserve * l.span()))
        .collect();
    let evaluate = |offsets: Vec<f64>| candidate(model, c, held, offsets);
    let grid: Vec<Candidate> = grid_points(&bounds)
        .into_iter()
        .filter_map(evaluate)
        .collect();
    let scale = Scale::of(&grid, pointwise);
    let score = |cand: &Candidate| scale.score(cand, pointwise);
    let mut best = grid
        .into_iter()
        .max_by(|a, b| score(a).total_cmp(&score(b)))
        .or_else(|| evaluate(bounds.iter().map(|(lo, hi)| 0.5 * (lo + hi)).collect()))?;
    // Pattern search: a step per input, halved when no move improves.
    let per_axis = grid_size(bounds.len());
    let mut steps: Vec<f64> = bounds
        .iter()
        .map(|(lo, hi)| (hi - lo) / (2.0 * (per_axis.max(2) - 1) as f64))
        .collect();
    for _ in 0..200 {
        let mut improved = false;
        for i in 0..bounds.len() {
            for dir in [1.0, -1.0] {
                let mut offsets = best.offsets.clone();
                offsets[i] = (offsets[i] + dir * steps[i]).clamp(bounds[i].0, bounds[i].1);
                if let Some(cand) = evaluate(offsets)
                    && score(&cand) > score(&best)
                {
                    best = cand;
                    improved = true;
                }
            }
        }
        if !improved {
            steps.iter_mut().for_each(|s| *s *= 0.5);
            let small = steps
                .iter()
                .zip(&bounds)
                .all(|(s, (lo, hi))| *s <= 1e-3 * (hi - lo).max(f64::MIN_POSITIVE));
            if small {
                break;
            }
        }
    }
    Some(OperatingPoint {
        offsets: best.offsets,
        steady: best.steady,
        margins: best.margins,
        full_range: false,
    })
}

fn candidate(
    model: &dyn Model,
    c: &Conditions,
    held: &[Held],
    offsets: Vec<f64>,
) -> Option<Candidate> {
    let steady = steady_state(model, &c.theta, c.h, &offsets)?;
    let zeros = vec![0.0; model.ir().components.len()];
    let sig = Signals {
        states: &steady.states,
        inputs: &offsets,
        rotation: &[1.0, 0.0],
        disturbances: &zeros,
    };
    let margins = held
        .iter()
        .map(|a| a.value(&sig) - a.worst_mean - a.band)
        .collect();
    Some(Candidate {
        offsets,
        steady,
        margins,
    })
}

/// Normalises margins and plain states over the grid so they can be traded.
struct Scale {
    margin: f64,
    states: Vec<f64>,
    /// Plain states that take both signs somewhere on the grid (the others
    /// cannot be brought to zero and are left alone).
    crossing: Vec<bool>,
}

impl Scale {
    fn of(grid: &[Candidate], pointwise: &[usize]) -> Scale {
        let margin = grid
            .iter()
            .map(|c| {
                c.margins
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min)
                    .abs()
            })
            .filter(|m| m.is_finite())
            .fold(f64::MIN_POSITIVE, f64::max);
        let range = |s: usize| {
            grid.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                    (lo.min(c.steady.states[s]), hi.max(c.steady.states[s]))
                })
        };
        let (states, crossing) = pointwise
            .iter()
            .map(|s| {
                let (lo, hi) = range(*s);
                ((hi - lo).max(f64::MIN_POSITIVE), lo < 0.0 && hi > 0.0)
            })
            .unzip();
        Scale {
            margin,
            states,
            crossing,
        }
    }

    /// The smallest margin with a twentieth of the mean (normalised), less
    /// a quarter of how far the crossing plain states sit from zero
    /// (normalised, averaged).
    fn score(&self, c: &Candidate, pointwise: &[usize]) -> f64 {
        let min = c.margins.iter().copied().fold(f64::INFINITY, f64::min);
        // The smallest margin, plus a twentieth of the mean: with many held
        // arguments a move of one offset raises one margin, not the
        // smallest, and the search would stall on a plateau of the minimum.
        let mean = c.margins.iter().sum::<f64>() / c.margins.len().max(1) as f64;
        let margin = if min.is_finite() {
            (min + 0.05 * mean) / self.margin
        } else {
            0.0
        };
        let (mut off, mut n) = (0.0, 0usize);
        for (k, s) in pointwise.iter().enumerate() {
            if self.crossing[k] {
                off += c.steady.states[*s].abs() / self.states[k];
                n += 1;
            }
        }
        margin - if n > 0 { 0.25 * off / n as f64 } else { 0.0 }
    }
}

/// Points per input of the grid: fewer as inputs grow (about 2500 at most);
/// beyond six inputs the pattern search starts from the middle alone.
fn grid_size(inputs: usize) -> usize {
    match inputs {
        0 | 1 => 41,
        2 => 21,
        3 => 11,
        4 => 7,
        5 => 5,
        6 => 4,
        _ => 1,
    }
}

fn grid_points(bounds: &[(f64, f64)]) -> Vec<Vec<f64>> {
    let g = grid_size(bounds.len());
    let axis = |(lo, hi): (f64, f64)| -> Vec<f64> {
        if g == 1 {
            return vec![0.5 * (lo + hi)];
        }
        (0..g)
            .map(|k| lo + (hi - lo) * k as f64 / (g - 1) as f64)
            .collect()
    };
    let mut points = vec![Vec::new()];
    for b in bounds {
        let values = axis(*b);
        points = points
            .into_iter()
            .flat_map(|p: Vec<f64>| {
                values.iter().map(move |v| {
                    let mut q = p.clone();
                    q.push(*v);
                    q
                })
            })
            .collect();
    }
    points
}

/// Operating points for further runs of the same pattern at other speeds:
/// among the grid's offsets (the middle of the ranges first) whose steady
/// margin is at least half the first point's, greedily the one whose steady
/// state is farthest from those chosen (states normalised by their span
/// over the grid). Runs at several operating points separate a drag level
/// from the medium's mean, which one steady point leaves confounded under
/// per-experiment centring. Fewer than `more` when the grid has no other
/// distinct point.
pub fn other_points(
    model: &dyn Model,
    c: &Conditions,
    held: &[Held],
    first: &OperatingPoint,
    more: usize,
) -> Vec<OperatingPoint> {
    let reserve = if first.full_range { 0.0 } else { 0.2 };
    let bounds: Vec<(f64, f64)> = c
        .limits
        .iter()
        .map(|l: &Limits| (l.low + reserve * l.span(), l.high - reserve * l.span()))
        .collect();
    let floor = 0.5 * first.min_margin();
    let grid: Vec<Candidate> = grid_points(&bounds)
        .into_iter()
        .filter_map(|o| candidate(model, c, held, o))
        .filter(|cand| {
            let m = cand.margins.iter().copied().fold(f64::INFINITY, f64::min);
            m > 0.0 && (m >= floor || !floor.is_finite())
        })
        .collect();
    let states = first.steady.states.len();
    let span: Vec<f64> = (0..states)
        .map(|s| {
            let (lo, hi) = grid
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), c| {
                    (l.min(c.steady.states[s]), h.max(c.steady.states[s]))
                });
            (hi - lo).max(f64::MIN_POSITIVE)
        })
        .collect();
    let distance = |a: &[f64], b: &[f64]| -> f64 {
        a.iter()
            .zip(b)
            .zip(&span)
            .map(|((x, y), s)| {
                let d = (x - y) / s;
                d * d
            })
            .sum::<f64>()
            .sqrt()
    };
    let mut chosen: Vec<Vec<f64>> = vec![first.steady.states.clone()];
    let mut out = Vec::new();
    for _ in 0..more {
        let best = grid
            .iter()
            .map(|cand| {
                let d = chosen
                    .iter()
                    .map(|x| distance(&cand.steady.states, x))
                    .fold(f64::INFINITY, f64::min);
                (d, cand)
            })
            .max_by(|a, b| a.0.total_cmp(&b.0));
        // A point within a tenth of the spans of one already chosen is the
        // same operating point.
        let Some((_, cand)) = best.filter(|(d, _)| *d > 0.1) else {
            break;
        };
        chosen.push(cand.steady.states.clone());
        out.push(OperatingPoint {
            offsets: cand.offsets.clone(),
            steady: cand.steady.clone(),
            margins: cand.margins.clone(),
            full_range: first.full_range,
        });
    }
    out
}
