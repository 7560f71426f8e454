//! How a signal sampled at its own stamps is read on the model's uniform
//! grid — one rule per kind of signal, shared by a robot log's join and
//! `--resample` on one file (docs/logs.md, "On the grid").
//!
//! The model steps by Euler, `x(k+1) = x(k) + h·f(x(k), u(k))`: the step
//! integrates the input over `[t_k, t_k + h)`, and reads the state at the
//! instant `t_k`. So:
//!
//! - a source **slower than the grid** (its median step at least `h`) is
//!   read at the grid time: a measurement interpolated between its samples
//!   (a heading along the short arc), a command held;
//! - an **input faster than the grid** is its mean over `[t_k, t_k + h)`, the
//!   interval the Euler step integrates: every sample counts, weighted by
//!   the time it held (or of its straight lines, for an input declared
//!   linear). One sample picked a step would alias the rest;
//! - a **measured state faster than the grid** is its mean over
//!   `[t_k − h/2, t_k + h/2)`: a box filter centred on the grid time, so it
//!   adds no lag, that averages the noise and the ripple above the grid's
//!   band instead of folding them into it.
//!
//! Windows never reach beyond the stretch being gridded (`span`), nor
//! beyond the signal's first and last sample; a centred window near an end
//! is narrowed on both sides, so that it stays centred.

use std::f64::consts::PI;

/// How a signal is read between its samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Between {
    /// The last sample until the next.
    Hold,
    /// Straight lines.
    Linear,
    /// An angle along the short arc; `turn` is a full turn in the signal's
    /// unit (2π for radians, 360 for degrees).
    Angle {
        /// A full turn.
        turn: f64,
    },
}

/// What a grid time reads of the signal around it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reduce {
    /// The signal at the grid time.
    Instant,
    /// Its mean over `[t, t + h)`: an input faster than the grid.
    StepMean,
    /// Its mean over `[t − h/2, t + h/2)`: a measurement faster than the grid.
    CentredMean,
}

/// A signal's rule on the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule {
    /// Between samples.
    pub between: Between,
    /// Around a grid time.
    pub reduce: Reduce,
}

impl Rule {
    /// The rule of a signal whose median step is `median` at grid step `h`:
    /// an input (`input`) or a measurement read between samples as `between`.
    pub fn for_signal(between: Between, input: bool, median: f64, h: f64) -> Rule {
        let reduce = match (median < h, input) {
            (false, _) => Reduce::Instant,
            (true, true) => Reduce::StepMean,
            (true, false) => Reduce::CentredMean,
        };
        Rule { between, reduce }
    }

    /// The rule in words, with the fewest and most samples a window held
    /// (`tau_x`: "mean over the step of 14–57 samples").
    pub fn describe(&self, samples: (usize, usize)) -> String {
        let between = match self.between {
            Between::Hold => "held",
            Between::Linear => "interpolated",
            Between::Angle { .. } => "interpolated along the short arc",
        };
        let count = if samples.0 == samples.1 {
            format!("{}", samples.0)
        } else {
            format!("{}–{}", samples.0, samples.1)
        };
        match self.reduce {
            Reduce::Instant => format!("{between} at the grid time"),
            Reduce::StepMean => {
                format!("mean over the step of {count} samples ({between} between)")
            }
            Reduce::CentredMean => {
                format!("centred mean over the step of {count} samples ({between} between)")
            }
        }
    }
}

/// The angle difference `b − a` brought into `[−turn/2, turn/2)`: the short
/// arc a heading turns between two samples.
pub fn short_arc_of(a: f64, b: f64, turn: f64) -> f64 {
    let d = b - a;
    d - turn * ((d + turn / 2.0) / turn).floor()
}

/// [`short_arc_of`] in radians.
pub fn short_arc(a: f64, b: f64) -> f64 {
    short_arc_of(a, b, 2.0 * PI)
}

/// A signal on the grid: per grid time its value, and the fewest and most
/// samples a window held (`(0, 0)` for [`Reduce::Instant`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Gridded {
    /// Per grid time.
    pub values: Vec<f64>,
    /// The fewest and most samples in a window.
    pub samples: (usize, usize),
}

/// The signal `(times, values)` (strictly increasing times, at least one
/// sample) read by `rule` at each of the increasing `grid` times, all
/// within `span` and within the signal's samples; `h` is the grid's step.
/// Times are in any one unit (the join passes nanoseconds from a piece's
/// start, exact as f64 below 2⁵³).
pub fn on_grid(
    times: &[f64],
    values: &[f64],
    rule: Rule,
    grid: &[f64],
    h: f64,
    span: (f64, f64),
) -> Gridded {
    let instants = instants(times, values, rule.between, grid);
    let (lo_off, hi_off) = match rule.reduce {
        Reduce::Instant => {
            return Gridded {
                values: instants,
                samples: (0, 0),
            };
        }
        Reduce::StepMean => (0.0, h),
        Reduce::CentredMean => (-h / 2.0, h / 2.0),
    };
    let (first, last) = (times[0], times[times.len() - 1]);
    let mut cursor = 0;
    let mut fewest = usize::MAX;
    let mut most = 0;
    let out = grid
        .iter()
        .zip(&instants)
        .map(|(&t, &at_t)| {
            let (lo, hi) = match rule.reduce {
                // Narrowed on both sides near an end, so that it stays centred.
                Reduce::CentredMean => {
                    let half = (h / 2.0)
                        .min(t - span.0.max(first))
                        .min(span.1.min(last) - t);
                    (t - half, t + half)
                }
                _ => (
                    (t + lo_off).max(span.0).max(first),
                    (t + hi_off).min(span.1).min(last),
                ),
            };
            if hi <= lo {
                return at_t;
            }
            let (mean, n) = window_mean(times, values, rule.between, lo, hi, &mut cursor);
            fewest = fewest.min(n);
            most = most.max(n);
            match rule.between {
                // On the branch of the sample nearer the grid time, as at an instant.
                Between::Angle { turn } => at_t + short_arc_of(at_t, mean, turn),
                _ => mean,
            }
        })
        .collect();
    Gridded {
        values: out,
        samples: (if most == 0 { 0 } else { fewest }, most),
    }
}

/// The signal at each grid time.
fn instants(times: &[f64], values: &[f64], between: Between, grid: &[f64]) -> Vec<f64> {
    let mut i = 0;
    grid.iter()
        .map(|&x| {
            while i + 1 < times.len() && times[i + 1] <= x {
                i += 1;
            }
            let a = values[i];
            if times[i] == x || between == Between::Hold || i + 1 == times.len() {
                return a;
            }
            let b = values[i + 1];
            let w = (x - times[i]) / (times[i + 1] - times[i]);
            match between {
                // On the branch of the nearer sample, so that a wrapped log stays wrapped.
                Between::Angle { turn } if w <= 0.5 => a + w * short_arc_of(a, b, turn),
                Between::Angle { turn } => b - (1.0 - w) * short_arc_of(a, b, turn),
                _ => a + w * (b - a),
            }
        })
        .collect()
}

/// The mean over `[lo, hi)` (within the samples, `lo < hi`) of the signal
/// read `between` its samples, and how many samples lie in the window.
/// `cursor` is the last sample at or before a previous window's start.
fn window_mean(
    times: &[f64],
    values: &[f64],
    between: Between,
    lo: f64,
    hi: f64,
    cursor: &mut usize,
) -> (f64, usize) {
    while *cursor + 1 < times.len() && times[*cursor + 1] <= lo {
        *cursor += 1;
    }
    let mut j = *cursor;
    // The angle unwrapped from sample `j` on: `value(k)` continues the arc.
    let mut unwrapped = values[j];
    let mut integral = 0.0;
    let mut count = 0;
    loop {
        if times[j] >= lo && times[j] < hi {
            count += 1;
        }
        let (t0, v0) = (times[j], unwrapped);
        let Some(&t1) = times.get(j + 1) else {
            // Past the last sample: its value holds (a zero-length rest).
            integral += v0 * (hi - lo.max(t0)).max(0.0);
            break;
        };
        let v1 = match between {
            Between::Angle { turn } => v0 + short_arc_of(values[j], values[j + 1], turn),
            _ => values[j + 1],
        };
        let (a, b) = (lo.max(t0), hi.min(t1));
        if b > a {
            integral += match between {
                Between::Hold => v0 * (b - a),
                _ => {
                    let at = |x: f64| v0 + (x - t0) / (t1 - t0) * (v1 - v0);
                    0.5 * (at(a) + at(b)) * (b - a)
                }
            };
        }
        if t1 >= hi {
            break;
        }
        j += 1;
        unwrapped = v1;
    }
    (integral / (hi - lo), count)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rule(between: Between, reduce: Reduce) -> Rule {
        Rule { between, reduce }
    }

    #[test]
    fn a_fast_held_input_is_its_time_weighted_mean_over_the_step() {
        // 0 on [0, 0.25), 4 on [0.25, 1), 8 from 1: the step [0, 1) means 3.
        let times = [0.0, 0.25, 1.0, 1.5, 2.0];
        let values = [0.0, 4.0, 8.0, 2.0, 2.0];
        let g = on_grid(
            &times,
            &values,
            rule(Between::Hold, Reduce::StepMean),
            &[0.0, 1.0, 2.0],
            1.0,
            (0.0, 2.0),
        );
        assert_eq!(g.values, [3.0, 5.0, 2.0]);
        assert_eq!(g.samples, (2, 2));
    }

    #[test]
    fn a_sine_above_the_grid_band_averages_out_where_a_pick_aliases_it() {
        // A 0.9 Hz ripple on 2.0, sampled at 50 Hz, on a 1 s grid.
        let times: Vec<f64> = (0..=5000).map(|k| f64::from(k) * 0.02).collect();
        let values: Vec<f64> = times
            .iter()
            .map(|t| 2.0 + (2.0 * PI * 0.9 * t).sin())
            .collect();
        let grid: Vec<f64> = (0..100).map(f64::from).collect();
        let span = (0.0, 100.0);
        let mean = on_grid(
            &times,
            &values,
            rule(Between::Linear, Reduce::CentredMean),
            &grid,
            1.0,
            span,
        );
        let pick = on_grid(
            &times,
            &values,
            rule(Between::Linear, Reduce::Instant),
            &grid,
            1.0,
            span,
        );
        let err = |g: &Gridded| {
            g.values[1..99]
                .iter()
                .map(|v| (v - 2.0).abs())
                .fold(0.0, f64::max)
        };
        // The box of 1 s passes 0.9 Hz at |sinc(0.9)| = 0.11; a pick keeps it whole.
        assert!(err(&mean) < 0.12, "{}", err(&mean));
        assert!(err(&pick) > 0.9, "{}", err(&pick));
        // The first window narrows to nothing at the span's start: the instant.
        assert_eq!(mean.samples, (50, 50));
    }

    #[test]
    fn a_centred_mean_adds_no_lag_to_a_ramp() {
        let times: Vec<f64> = (0..=400).map(|k| f64::from(k) * 0.05).collect();
        let values: Vec<f64> = times.iter().map(|t| 3.0 * t).collect();
        let grid: Vec<f64> = (1..19).map(f64::from).collect();
        let g = on_grid(
            &times,
            &values,
            rule(Between::Linear, Reduce::CentredMean),
            &grid,
            1.0,
            (0.0, 20.0),
        );
        for (t, v) in grid.iter().zip(&g.values) {
            assert!((v - 3.0 * t).abs() < 1e-9, "{t}: {v}");
        }
    }

    #[test]
    fn a_heading_in_degrees_turns_along_the_short_arc_of_degrees() {
        // 350° → 10° in 1 s: through north, 20°, not back through 180°.
        let g = on_grid(
            &[0.0, 1.0],
            &[350.0, 10.0],
            rule(Between::Angle { turn: 360.0 }, Reduce::Instant),
            &[0.25, 0.75],
            0.5,
            (0.0, 1.0),
        );
        assert_eq!(g.values, [355.0, 5.0]);
        // Mean of a heading across the wrap, on the nearer sample's branch.
        let times: Vec<f64> = (0..=20).map(|k| f64::from(k) * 0.1).collect();
        let values: Vec<f64> = times.iter().map(|t| (350.0 + 10.0 * t) % 360.0).collect();
        let g = on_grid(
            &times,
            &values,
            rule(Between::Angle { turn: 360.0 }, Reduce::CentredMean),
            &[1.0],
            1.0,
            (0.0, 2.0),
        );
        assert!(
            (g.values[0] - 360.0).abs() < 1e-9 || g.values[0].abs() < 1e-9,
            "{:?}",
            g.values
        );
    }

    #[test]
    fn windows_stop_at_the_span_and_at_the_last_sample() {
        let times = [0.0, 0.5, 1.0];
        let values = [1.0, 3.0, 5.0];
        let g = on_grid(
            &times,
            &values,
            rule(Between::Hold, Reduce::StepMean),
            &[0.0, 1.0],
            1.0,
            (0.0, 1.0),
        );
        // The last grid time's step lies beyond the samples: its instant.
        assert_eq!(g.values, [2.0, 5.0]);
    }

    #[test]
    fn a_slow_source_is_read_at_the_grid_time() {
        let r = Rule::for_signal(Between::Hold, true, 0.25, 0.1);
        assert_eq!(r.reduce, Reduce::Instant);
        let r = Rule::for_signal(Between::Linear, false, 0.02, 1.0);
        assert_eq!(r.reduce, Reduce::CentredMean);
        assert_eq!(
            r.describe((3, 8)),
            "centred mean over the step of 3–8 samples (interpolated between)"
        );
    }
}
