//! Resampling an irregularly stamped experiment onto a uniform grid
//! (`--resample H`): the grid `t0, t0 + H, …` within the experiment's time
//! span, each column read by the rules of [`crate::rates`] that a robot
//! log's join uses. A planar heading is interpolated along the short arc
//! between neighbouring samples (its unwrapped angle), so a heading that
//! wraps at ±π does not sweep through zero between two samples.

use crate::rates::{Between, Rule, on_grid};
use leeway_model::experiment::Experiment;
use leeway_structure::ir::{Ir, Rotation};

/// The grid `t0 + k·h` for every `k` with `t0 + k·h ≤ t_last` (up to rounding).
fn grid(times: &[f64], h: f64) -> Vec<f64> {
    let (Some(&t0), Some(&t1)) = (times.first(), times.last()) else {
        return Vec::new();
    };
    if h.is_nan() || h <= 0.0 || t1 < t0 {
        return Vec::new();
    }
    // A relative slack of 1e-9 keeps the last stamp of a span that is an exact
    // multiple of h despite rounding in the division.
    let n = ((t1 - t0) / h * (1.0 + 1e-9)).floor();
    // At most one sample per nanosecond of the span: bounded by the caller's data.
    let n = n.min(1e9) as usize;
    (0..=n).map(|k| t0 + k as f64 * h).collect()
}

/// The angle difference `b − a` brought into `[−π, π)`: the short arc a
/// heading turns between two samples (also the join of a robot log's).
pub fn short_arc(a: f64, b: f64) -> f64 {
    crate::rates::short_arc(a, b)
}

/// `e` (stamped `times`, strictly increasing, one per sample) resampled every
/// `h` seconds by the rules of [`crate::rates`]: each column interpolated
/// linearly (a planar heading, in radians after unit conversion, along the
/// short arc) when the rows are slower than the grid; when they are faster,
/// an input is its mean over the step and a measurement its centred mean.
/// One file declares no command to hold: its inputs are interpolated.
pub fn resample(ir: &Ir, e: &Experiment, times: &[f64], h: f64) -> Experiment {
    let grid = grid(times, h);
    let median = crate::gaps::median(&crate::gaps::steps(times)).unwrap_or(h);
    let span = match (times.first(), times.last()) {
        (Some(a), Some(b)) => (*a, *b),
        _ => (0.0, 0.0),
    };
    let read = |cols: &[Vec<f64>], between: Between, input: bool| -> Vec<Vec<f64>> {
        let rule = Rule::for_signal(between, input, median, h);
        cols.iter()
            .map(|c| {
                if c.is_empty() || c.len() != times.len() {
                    Vec::new()
                } else {
                    on_grid(times, c, rule, &grid, h, span).values
                }
            })
            .collect()
    };
    let angle = Between::Angle {
        turn: 2.0 * std::f64::consts::PI,
    };
    Experiment {
        name: e.name.clone(),
        h,
        states: read(&e.states, Between::Linear, false),
        inputs: read(&e.inputs, Between::Linear, true),
        heading: if matches!(ir.rotation, Rotation::Planar { .. }) {
            read(std::slice::from_ref(&e.heading), angle, false)
                .pop()
                .unwrap_or_default()
        } else {
            Vec::new()
        },
        rotation: read(&e.rotation, Between::Linear, false),
        disturbances: read(&e.disturbances, Between::Linear, false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csv::parse_csv_noted;
    use crate::options::LoadOptions;
    use leeway_model::experiment::Source;
    use std::f64::consts::PI;

    fn ship() -> Ir {
        let src = "model M { state u, v, r input d heading psi integrates r
            der u = X*u + T*d der v = Y*v der r = N*r }";
        leeway_structure::compile(src, &leeway_structure::CompileOptions::default())
            .ir
            .unwrap_or_else(|| panic!("the test model compiles"))
    }

    #[test]
    fn linear_data_are_resampled_exactly() {
        let ir = ship();
        // Irregular stamps; every signal a linear function of time.
        let times = [0.0, 0.3, 0.5, 1.1, 1.2, 2.0, 2.05];
        let mut e = Experiment::new(&ir, "x", 0.0);
        for t in times {
            e.states[0].push(2.0 * t + 1.0);
            e.states[1].push(-t);
            e.states[2].push(0.25 * t);
            e.inputs[0].push(3.0 - t);
            e.heading.push(0.1 * t);
        }
        let r = resample(&ir, &e, &times, 0.25);
        let grid: Vec<f64> = (0..=8).map(|k| f64::from(k) * 0.25).collect();
        assert_eq!(r.states[0].len(), grid.len());
        assert_eq!(r.h, 0.25);
        for (k, t) in grid.iter().enumerate() {
            assert!((r.states[0][k] - (2.0 * t + 1.0)).abs() < 1e-12);
            assert!((r.states[1][k] + t).abs() < 1e-12);
            assert!((r.inputs[0][k] - (3.0 - t)).abs() < 1e-12);
            assert!((r.heading[k] - 0.1 * t).abs() < 1e-12);
        }
    }

    #[test]
    fn the_heading_is_interpolated_across_the_wrap() {
        let ir = ship();
        let times = [0.0, 1.0, 2.0];
        let mut e = Experiment::new(&ir, "x", 0.0);
        // 3.0 → −3.0 rad is a turn of 2π − 6 ≈ 0.283 rad through ±π, not −6 rad through 0.
        for psi in [2.9, 3.1, -3.1] {
            e.heading.push(psi);
            for c in e.states.iter_mut().chain(e.inputs.iter_mut()) {
                c.push(0.0);
            }
        }
        let r = resample(&ir, &e, &times, 0.5);
        assert_eq!(r.heading.len(), 5);
        assert!((r.heading[1] - 3.0).abs() < 1e-12);
        let mid = r.heading[3];
        assert!(
            (mid - PI).abs() < 1e-12,
            "{mid} should be π, halfway along the short arc"
        );
        assert!((r.heading[4] - (-3.1)).abs() < 1e-12);
    }

    #[test]
    fn jittered_stamps_load_and_resample_from_csv() {
        let ir = ship();
        let mut text = String::from("# logger v2\ntime,u,v,r,d,psi\n");
        for k in 0..40 {
            let jitter = if k % 3 == 0 { 0.004 } else { -0.002 };
            let t = f64::from(k) * 0.5 + if k == 0 { 0.0 } else { jitter };
            text.push_str(&format!("{t},{t},0,0,1,0\n"));
        }
        let strict = LoadOptions {
            time_tolerance: 0.001,
            ..LoadOptions::default()
        };
        let err = parse_csv_noted("j.csv", text.as_bytes(), &ir, &strict)
            .err()
            .unwrap_or_else(|| panic!("jitter beyond 0.1 % is an error"));
        assert!(
            err.location.starts_with("j.csv:") && err.location.ends_with(":1 (time)"),
            "{err:?}"
        );
        assert!(
            err.message.starts_with("inconsistent sample time"),
            "{err:?}"
        );
        let loaded = parse_csv_noted("j.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let dev = loaded.notes.experiments[0]
            .max_step_deviation
            .unwrap_or_default();
        assert!(dev > 0.01 && dev < 0.05, "{dev}");
        assert_eq!(loaded.notes.comment_lines, 1);
        let resampled = LoadOptions {
            resample: Some(1.0),
            ..LoadOptions::default()
        };
        let loaded = parse_csv_noted("j.csv", text.as_bytes(), &ir, &resampled)
            .unwrap_or_else(|e| panic!("{e}"));
        let e = &loaded.experiments[0];
        assert_eq!(e.h, 1.0);
        assert_eq!(loaded.notes.experiments[0].resampled, Some(e.len()));
        // u equals the time stamp, so the grid reads back exactly.
        for (k, u) in e.states[0].iter().enumerate() {
            assert!((u - k as f64).abs() < 1e-9, "{k}: {u}");
        }
    }

    #[test]
    fn resampling_splits_at_a_hole_instead_of_bridging_it() {
        let ir = ship();
        let mut text = String::from("time,u,v,r,d,psi\n");
        // 30 samples, a 5.8 s hole, 40 samples, a 3 s hole, 4 samples.
        let stamps = (0..30)
            .map(|k| f64::from(k) * 0.5)
            .chain((0..40).map(|k| 20.3 + f64::from(k) * 0.5))
            .chain((0..4).map(|k| 42.8 + f64::from(k) * 0.5));
        for t in stamps {
            text.push_str(&format!("{t},{t},0,0,1,0\n"));
        }
        let options = LoadOptions {
            resample: Some(0.5),
            ..LoadOptions::default()
        };
        let loaded = parse_csv_noted("hole.csv", text.as_bytes(), &ir, &options)
            .unwrap_or_else(|e| panic!("{e}"));
        let names: Vec<&str> = loaded.experiments.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["hole/1", "hole/2"]);
        let notes = &loaded.notes.experiments[0];
        let gaps: Vec<(f64, f64)> = notes.gaps.iter().map(|g| (g.from, g.to)).collect();
        assert_eq!(gaps, [(14.5, 20.3), (39.8, 42.8)]);
        assert_eq!(notes.pieces.len(), 3);
        assert_eq!(
            notes.pieces[2].experiment, None,
            "the 4-sample tail is dropped"
        );
        assert_eq!(notes.pieces[2].samples, 4);
        // Nothing in the hole: u is the stamp, and every grid time lies in a piece.
        for e in &loaded.experiments {
            assert!(
                e.states[0].iter().all(|u| *u <= 14.5 || *u >= 20.3),
                "{:?}",
                e.states[0]
            );
        }
        let strict = LoadOptions {
            max_gap: crate::gaps::GapLimit::Seconds(10.0),
            ..options
        };
        let loaded = parse_csv_noted("hole.csv", text.as_bytes(), &ir, &strict)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            loaded.experiments.len(),
            1,
            "a 10 s limit bridges both holes"
        );
    }
}
