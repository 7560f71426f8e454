//! Signals at their own stamps put on one uniform grid. The grid runs only
//! where every signal has samples — never extrapolated before a signal's
//! first sample or after its last — and a stretch of any signal without
//! samples longer than its gap limit ends the experiment there: the pieces
//! between holes become experiments of their own when long enough (the
//! model's minimum), and every hole and piece is noted. Between samples a
//! measurement is interpolated linearly (a heading along the short arc), a
//! command held (zero-order hold). Grid times are whole nanoseconds from
//! the piece's start, so a grid time that falls on a stamp reads that
//! sample exactly.

use crate::stamps::Nanos;
use leeway_data::notes::{GapNote, PieceNote};
use leeway_data::resample::short_arc;
use leeway_model::experiment::MIN_SAMPLES;

/// How a signal is read between its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Between {
    /// The last sample until the next.
    Hold,
    /// Straight lines.
    Linear,
    /// An angle in radians along the short arc.
    Angle,
}

/// One signal's samples: strictly increasing stamps.
#[derive(Clone, Copy, Debug)]
pub struct Track<'a> {
    /// The model's signal.
    pub signal: &'a str,
    /// Its stamps.
    pub stamps: &'a [Nanos],
    /// Its values.
    pub values: &'a [f64],
    /// How it is read between samples.
    pub between: Between,
    /// Its gap limit, in nanoseconds.
    pub limit: f64,
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
    /// Every piece, kept or dropped (empty when there is one piece).
    pub notes: Vec<PieceNote>,
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

/// A track's values at `times` (increasing, within its samples).
fn on_grid(t: &Track, times: &[Nanos]) -> Vec<f64> {
    let mut i = 0;
    times
        .iter()
        .map(|&x| {
            while i + 1 < t.stamps.len() && t.stamps[i + 1] <= x {
                i += 1;
            }
            let a = t.values[i];
            if t.stamps[i] == x || t.between == Between::Hold || i + 1 == t.stamps.len() {
                return a;
            }
            let b = t.values[i + 1];
            #[allow(clippy::cast_precision_loss)]
            let w = (x - t.stamps[i]) as f64 / (t.stamps[i + 1] - t.stamps[i]) as f64;
            match t.between {
                // On the branch of the nearer sample, as `--resample` does.
                Between::Angle if w <= 0.5 => a + w * short_arc(a, b),
                Between::Angle => b - (1.0 - w) * short_arc(a, b),
                _ => a + w * (b - a),
            }
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
/// `name/2`, … when split).
pub fn join(tracks: &[Track], h: f64, name: &str) -> Joined {
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
    let lo = tracks
        .iter()
        .filter_map(|t| t.stamps.first())
        .copied()
        .max()
        .unwrap_or(0);
    let hi = tracks
        .iter()
        .filter_map(|t| t.stamps.last())
        .copied()
        .min()
        .unwrap_or(0);
    let mut joined = Joined {
        origin,
        gaps: tracks
            .iter()
            .flat_map(|t| holes(t, lo, hi, origin))
            .collect(),
        ..Joined::default()
    };
    joined.gaps.sort_by(|a, b| a.from.total_cmp(&b.from));
    // Signals of one source share their holes: one note names them all.
    joined.gaps.dedup_by(|b, a| {
        let same = a.from == b.from && a.to == b.to;
        if same && let (Some(x), Some(y)) = (&mut a.signal, &b.signal) {
            x.push_str(", ");
            x.push_str(y);
        }
        same
    });
    let split = common.len() > 1;
    for (j, &(a, b)) in common.iter().enumerate() {
        let times = grid(a, b, h);
        let piece_name = if split {
            format!("{name}/{}", j + 1)
        } else {
            name.to_string()
        };
        let kept = times.len() >= MIN_SAMPLES;
        if split {
            joined.notes.push(PieceNote {
                experiment: kept.then(|| piece_name.clone()),
                from: seconds(a, origin),
                to: seconds(*times.last().unwrap_or(&a), origin),
                samples: times.len(),
            });
        }
        if kept {
            joined.pieces.push(Piece {
                name: piece_name,
                start: a,
                columns: tracks.iter().map(|t| on_grid(t, &times)).collect(),
            });
        }
    }
    joined
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Nanos = 1_000_000_000;

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
                between: Between::Linear,
                limit: 0.5e9,
            },
            Track {
                signal: "tau",
                stamps: &tau_t,
                values: &tau_v,
                between: Between::Hold,
                limit: 1.25e9,
            },
        ];
        let j = join(&tracks, 0.1, "run");
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
        assert!(j.gaps.is_empty() && j.notes.is_empty());
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
                between: Between::Linear,
                limit: 0.5e9,
            },
            Track {
                signal: "psi",
                stamps: &other,
                values: &ov,
                between: Between::Angle,
                limit: 0.5e9,
            },
        ];
        let j = join(&tracks, 0.1, "run");
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
    fn a_heading_wraps_along_the_short_arc() {
        let t = [0, S];
        let v = [3.1, -3.1];
        let tracks = [Track {
            signal: "psi",
            stamps: &t,
            values: &v,
            between: Between::Angle,
            limit: 2e9,
        }];
        let j = join(&tracks, 0.1, "w");
        let mid = j.pieces[0].columns[0][5];
        assert!((mid - std::f64::consts::PI).abs() < 1e-12, "{mid}");
    }
}
