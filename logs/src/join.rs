//! Signals at their own stamps put on one uniform grid. The grid runs only
//! where every signal has samples — never extrapolated before a signal's
//! first sample or after its last — and a stretch of any signal without
//! samples longer than its gap limit ends the experiment there: the pieces
//! between holes become experiments of their own when long enough (the
//! model's minimum), and every hole and piece is noted. Each signal is read
//! on the grid by its rule ([`leeway_data::rates`]): a slow source at the
//! grid time (a measurement interpolated, a heading along the short arc, a
//! command held), a fast one by its mean over the step. Grid times are
//! whole nanoseconds from the piece's start, so a grid time that falls on a
//! stamp reads that sample exactly. Kept windows, when given, bound the
//! pieces: nothing outside them reaches the grid.

use crate::stamps::Nanos;
use leeway_data::notes::{GapNote, PieceNote};
pub use leeway_data::rates::{Between, Reduce, Rule};
use leeway_model::experiment::MIN_SAMPLES;

/// One signal's samples: strictly increasing stamps.
#[derive(Clone, Copy, Debug)]
pub struct Track<'a> {
    /// The model's signal.
    pub signal: &'a str,
    /// Its stamps.
    pub stamps: &'a [Nanos],
    /// Its values.
    pub values: &'a [f64],
    /// How it is read on the grid.
    pub rule: Rule,
    /// Its gap limit, in nanoseconds.
    pub limit: f64,
    /// A hole longer than this (nanoseconds) but within the limit is a
    /// stall: held or interpolated across, and noted.
    pub stall: f64,
}

/// A stretch of the grid where every signal has samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// The experiment it becomes.
    pub name: String,
    /// Its first grid time.
    pub start: Nanos,
    /// Per track, its values on the grid.
    pub columns: Vec<Vec<f64>>,
}

/// The tracks joined: the pieces kept and what was noted.
#[derive(Clone, Debug, Default)]
pub struct Joined {
    /// The earliest stamp of any track: what noted times count from.
    pub origin: Nanos,
    /// The pieces long enough, in time order.
    pub pieces: Vec<Piece>,
    /// Every hole inside the span where all tracks have samples.
    pub gaps: Vec<GapNote>,
    /// Every piece, kept or dropped, with its time span.
    pub notes: Vec<PieceNote>,
    /// Stalls inside the pieces: holes within the gap limit but longer
    /// than a signal's stall threshold.
    pub stalls: Vec<GapNote>,
    /// Per track, the fewest and most samples a window of its rule held.
    pub samples: Vec<(usize, usize)>,
}

/// The stretches `[a, b]` where a track has samples, split at its holes.
fn covered(t: &Track) -> Vec<(Nanos, Nanos)> {
    let mut out = Vec::new();
    let Some(&first) = t.stamps.first() else {
        return out;
    };
    let mut start = first;
    for w in t.stamps.windows(2) {
        #[allow(clippy::cast_precision_loss)]
        if (w[1] - w[0]) as f64 > t.limit {
            out.push((start, w[0]));
            start = w[1];
        }
    }
    out.push((start, *t.stamps.last().unwrap_or(&first)));
    out
}

/// The stretches in both `a` and `b` (each sorted, disjoint).
fn intersect(a: &[(Nanos, Nanos)], b: &[(Nanos, Nanos)]) -> Vec<(Nanos, Nanos)> {
    let (mut i, mut j, mut out) = (0, 0, Vec::new());
    while i < a.len() && j < b.len() {
        let lo = a[i].0.max(b[j].0);
        let hi = a[i].1.min(b[j].1);
        if lo <= hi {
            out.push((lo, hi));
        }
        if a[i].1 < b[j].1 {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// Seconds from `origin` to `t`.
#[allow(clippy::cast_precision_loss)]
pub(crate) fn seconds(t: Nanos, origin: Nanos) -> f64 {
    (t - origin) as f64 / 1e9
}

/// The grid `a + round(k·h)` within `[a, b]` (`h` in seconds).
fn grid(a: Nanos, b: Nanos, h: f64) -> Vec<Nanos> {
    let step = h * 1e9;
    #[allow(
        clippy::cast_precision_loss,
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss
    )]
    let n = (((b - a) as f64 / step) * (1.0 + 1e-12)).floor() as usize;
    #[allow(clippy::cast_possible_truncation, clippy::cast_precision_loss)]
    (0..=n)
        .map(|k| a + (k as f64 * step).round() as Nanos)
        .filter(|t| *t <= b)
        .collect()
}

/// A track's values at `times` (increasing, within its samples and
/// `[a, b]`), and the fewest and most samples a window held.
fn on_grid(
    t: &Track,
    times: &[Nanos],
    h: f64,
    (a, b): (Nanos, Nanos),
) -> (Vec<f64>, (usize, usize)) {
    // Nanoseconds from the piece's start: exact in f64 below 2⁵³ (104 days).
    #[allow(clippy::cast_precision_loss)]
    let rel = |x: Nanos| (x - a) as f64;
    let stamps: Vec<f64> = t.stamps.iter().map(|&x| rel(x)).collect();
    let grid: Vec<f64> = times.iter().map(|&x| rel(x)).collect();
    let g = leeway_data::rates::on_grid(&stamps, t.values, t.rule, &grid, h * 1e9, (0.0, rel(b)));
    (g.values, g.samples)
}

/// The stalls of `t` inside `[lo, hi]`: steps longer than its stall
/// threshold and within its gap limit, as notes.
fn stalls(t: &Track, lo: Nanos, hi: Nanos, origin: Nanos) -> Vec<GapNote> {
    t.stamps
        .windows(2)
        .filter(|w| w[0] < hi && w[1] > lo)
        .filter(|w| {
            #[allow(clippy::cast_precision_loss)]
            let d = (w[1] - w[0]) as f64;
            d > t.stall && d <= t.limit
        })
        .map(|w| GapNote {
            signal: Some(t.signal.to_string()),
            from: seconds(w[0], origin),
            to: seconds(w[1], origin),
            limit: t.stall / 1e9,
        })
        .collect()
}

/// The holes of `t` inside `[lo, hi]`, as notes (seconds from `origin`).
fn holes(t: &Track, lo: Nanos, hi: Nanos, origin: Nanos) -> Vec<GapNote> {
    let stretches = covered(t);
    stretches
        .windows(2)
        .filter(|w| w[0].1 < hi && w[1].0 > lo)
        .map(|w| GapNote {
            signal: Some(t.signal.to_string()),
            from: seconds(w[0].1, origin),
            to: seconds(w[1].0, origin),
            limit: t.limit / 1e9,
        })
        .collect()
}

/// The tracks on a grid of step `h` seconds, named `name` (`name/1`,
/// `name/2`, … when split), within the `keep` windows when given (sorted,
/// disjoint). Every piece is noted with its time span.
pub fn join(tracks: &[Track], h: f64, name: &str, keep: Option<&[(Nanos, Nanos)]>) -> Joined {
    let origin = tracks
        .iter()
        .filter_map(|t| t.stamps.first())
        .copied()
        .min()
        .unwrap_or(0);
    let mut common = match tracks.first() {
        Some(t) => covered(t),
        None => return Joined::default(),
    };
    for t in &tracks[1..] {
        common = intersect(&common, &covered(t));
    }
    let (lo, hi) = overlap(tracks);
    let mut gaps: Vec<GapNote> = tracks
        .iter()
        .flat_map(|t| holes(t, lo, hi, origin))
        .collect();
    if let Some(keep) = keep {
        common = intersect(&common, keep);
        // Only the holes that cut a kept window split anything.
        gaps.retain(|g| {
            keep.iter()
                .any(|&(a, b)| g.to > seconds(a, origin) && g.from < seconds(b, origin))
        });
    }
    let mut joined = Joined {
        origin,
        gaps: merged_notes(gaps),
        samples: vec![(0, 0); tracks.len()],
        ..Joined::default()
    };
    for (j, &(a, b)) in common.iter().enumerate() {
        let times = grid(a, b, h);
        let piece_name = if common.len() > 1 {
            format!("{name}/{}", j + 1)
        } else {
            name.to_string()
        };
        let kept = times.len() >= MIN_SAMPLES;
        // Every piece is noted, kept or not: its time span is in the report.
        joined.notes.push(PieceNote {
            experiment: kept.then(|| piece_name.clone()),
            from: seconds(a, origin),
            to: seconds(*times.last().unwrap_or(&a), origin),
            samples: times.len(),
        });
        if !kept {
            continue;
        }
        let mut columns = Vec::with_capacity(tracks.len());
        for (t, seen) in tracks.iter().zip(&mut joined.samples) {
            let (values, samples) = on_grid(t, &times, h, (a, b));
            if samples.1 > 0 {
                *seen = if seen.1 == 0 {
                    samples
                } else {
                    (seen.0.min(samples.0), seen.1.max(samples.1))
                };
            }
            columns.push(values);
            joined.stalls.extend(stalls(t, a, b, origin));
        }
        joined.pieces.push(Piece {
            name: piece_name,
            start: a,
            columns,
        });
    }
    joined.stalls = merged_notes(std::mem::take(&mut joined.stalls));
    joined
}

/// The span where every track has samples: the latest first stamp and the
/// earliest last one.
fn overlap(tracks: &[Track]) -> (Nanos, Nanos) {
    let lo = tracks
        .iter()
        .filter_map(|t| t.stamps.first())
        .copied()
        .max();
    let hi = tracks.iter().filter_map(|t| t.stamps.last()).copied().min();
    (lo.unwrap_or(0), hi.unwrap_or(0))
}

/// Notes in time order, those of one hole shared by several signals of a
/// source merged into one that names them all.
fn merged_notes(mut notes: Vec<GapNote>) -> Vec<GapNote> {
    notes.sort_by(|a, b| a.from.total_cmp(&b.from));
    notes.dedup_by(|b, a| {
        let same = a.from == b.from && a.to == b.to;
        if same && let (Some(x), Some(y)) = (&mut a.signal, &b.signal) {
            x.push_str(", ");
            x.push_str(y);
        }
        same
    });
    notes
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Nanos = 1_000_000_000;
    const ANGLE: Between = Between::Angle {
        turn: 2.0 * std::f64::consts::PI,
    };

    fn rule(between: Between) -> Rule {
        Rule {
            between,
            reduce: Reduce::Instant,
        }
    }

    #[test]
    fn held_commands_and_interpolated_measurements_on_the_grid() {
        // u at 10 Hz exactly on the grid, tau at 4 Hz off the grid.
        let u_t: Vec<Nanos> = (0..=100).map(|k| k * S / 10).collect();
        let u_v: Vec<f64> = (0..=100).map(|k| f64::from(k) * 0.5).collect();
        let tau_t: Vec<Nanos> = (0..=40).map(|k| k * S / 4 + S / 100).collect();
        let tau_v: Vec<f64> = (0..=40).map(f64::from).collect();
        let tracks = [
            Track {
                signal: "u",
                stamps: &u_t,
                values: &u_v,
                rule: rule(Between::Linear),
                limit: 0.5e9,
                stall: 0.5e9,
            },
            Track {
                signal: "tau",
                stamps: &tau_t,
                values: &tau_v,
                rule: rule(Between::Hold),
                limit: 1.25e9,
                stall: 1.25e9,
            },
        ];
        let j = join(&tracks, 0.1, "run", None);
        assert_eq!(j.pieces.len(), 1);
        let p = &j.pieces[0];
        // The grid starts at tau's first stamp, 10 ms in; u is interpolated there.
        assert_eq!(p.start, S / 100);
        assert!((p.columns[0][0] - 0.05).abs() < 1e-12);
        // At 0.21 s the last tau sample is the one of 0.01 s: held, not interpolated.
        assert_eq!(p.columns[1][2], 0.0);
        assert_eq!(p.columns[1][3], 1.0);
        // Never beyond u's last stamp (10 s).
        assert_eq!(p.columns[0].len(), 100);
        assert!(j.gaps.is_empty() && j.stalls.is_empty());
        assert_eq!(j.notes.len(), 1);
    }

    #[test]
    fn a_hole_splits_and_a_short_piece_is_dropped() {
        let mut t: Vec<Nanos> = (0..50).map(|k| k * S / 10).collect();
        t.extend((0..30).map(|k| 10 * S + k * S / 10));
        t.extend((0..5).map(|k| 20 * S + k * S / 10));
        let v: Vec<f64> = t.iter().map(|x| *x as f64 / 1e9).collect();
        let other: Vec<Nanos> = (0..=250).map(|k| k * S / 10).collect();
        let ov = vec![1.0; other.len()];
        let tracks = [
            Track {
                signal: "u",
                stamps: &t,
                values: &v,
                rule: rule(Between::Linear),
                limit: 0.5e9,
                stall: 0.5e9,
            },
            Track {
                signal: "psi",
                stamps: &other,
                values: &ov,
                rule: rule(ANGLE),
                limit: 0.5e9,
                stall: 0.5e9,
            },
        ];
        let j = join(&tracks, 0.1, "run", None);
        let names: Vec<&str> = j.pieces.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["run/1", "run/2"]);
        assert_eq!(j.gaps.len(), 2);
        assert_eq!((j.gaps[0].from, j.gaps[0].to), (4.9, 10.0));
        assert_eq!(j.notes.len(), 3);
        assert_eq!(j.notes[2].experiment, None);
        // Nothing from inside a hole: u equals its stamp.
        for p in &j.pieces {
            assert!(
                p.columns[0]
                    .iter()
                    .all(|u| *u <= 4.9 + 1e-12 || *u >= 10.0 - 1e-12)
            );
        }
    }

    #[test]
    fn a_stall_within_the_gap_limit_is_noted_and_a_window_bounds_the_pieces() {
        // Forces at 50 Hz with a 3.13 s hole; a limit of 5 s bridges it.
        let mut t: Vec<Nanos> = (0..=500).map(|k| k * S / 50).collect();
        t.extend((0..=2000).map(|k| 13_130_000_000 + k * S / 50));
        let v: Vec<f64> = t.iter().map(|x| (*x as f64 / 1e9).sin()).collect();
        let u_t: Vec<Nanos> = (0..=50).map(|k| k * S).collect();
        let u_v = vec![1.0; u_t.len()];
        let tracks = [
            Track {
                signal: "tau_x",
                stamps: &t,
                values: &v,
                rule: Rule::for_signal(Between::Hold, true, 0.02, 1.0),
                limit: 5e9,
                stall: 1e9,
            },
            Track {
                signal: "u",
                stamps: &u_t,
                values: &u_v,
                rule: rule(Between::Linear),
                limit: 5e9,
                stall: 10e9,
            },
        ];
        let j = join(&tracks, 1.0, "run", None);
        assert_eq!(j.pieces.len(), 1);
        assert!(j.gaps.is_empty());
        assert_eq!(j.stalls.len(), 1, "{:?}", j.stalls);
        assert_eq!((j.stalls[0].from, j.stalls[0].to), (10.0, 13.13));
        assert_eq!(j.stalls[0].signal.as_deref(), Some("tau_x"));
        // The forces by their mean over the step: 50 samples a whole step.
        assert_eq!(j.samples[0].1, 50);
        // A window from 20 to 30 s keeps one piece, its span noted.
        let j = join(&tracks, 1.0, "run", Some(&[(20 * S, 30 * S)]));
        assert_eq!(j.pieces.len(), 1);
        assert_eq!(
            (j.notes[0].from, j.notes[0].to, j.notes[0].samples),
            (20.0, 30.0, 11)
        );
        assert!(j.stalls.is_empty(), "the stall lies outside the window");
    }

    #[test]
    fn a_heading_wraps_along_the_short_arc() {
        let t = [0, S];
        let v = [3.1, -3.1];
        let tracks = [Track {
            signal: "psi",
            stamps: &t,
            values: &v,
            rule: rule(ANGLE),
            limit: 2e9,
            stall: 2e9,
        }];
        let j = join(&tracks, 0.1, "w", None);
        let mid = j.pieces[0].columns[0][5];
        assert!((mid - std::f64::consts::PI).abs() < 1e-12, "{mid}");
    }
}
