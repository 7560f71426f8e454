//! Holes in a signal's time stamps — where a logger stalled or a topic went
//! quiet — found so that no interpolation bridges them: an experiment is
//! split at each hole, never interpolated across it.

/// A hole, by default: a step longer than this many times the signal's own
/// median step or the grid's step, whichever is longer. Jitter, a dropped
/// message or two, and a topic whose rate varies stay below it; a stall of
/// a second on a 10 Hz grid is above it.
pub const DEFAULT_GAP_STEPS: f64 = 5.0;

/// How long a step may be before it is a hole.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum GapLimit {
    /// This many times the signal's median step.
    Steps(f64),
    /// This many seconds.
    Seconds(f64),
}

impl Default for GapLimit {
    fn default() -> GapLimit {
        GapLimit::Steps(DEFAULT_GAP_STEPS)
    }
}

impl std::fmt::Display for GapLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GapLimit::Steps(n) => write!(f, "{n} median steps"),
            GapLimit::Seconds(s) => write!(f, "{s} s"),
        }
    }
}

impl GapLimit {
    /// The longest step, in seconds, of a signal whose steps are `steps`
    /// (seconds, in order) put on a grid of step `h`: infinite for a signal
    /// of fewer than two samples.
    pub fn seconds(self, steps: &[f64], h: f64) -> f64 {
        match self {
            GapLimit::Seconds(s) => s,
            GapLimit::Steps(n) => median(steps).map_or(f64::INFINITY, |m| n * m.max(h)),
        }
    }
    /// Whether the limit is one leeway accepts: a positive, finite number
    /// (of steps at least 1.5: a hole shorter than that is jitter).
    pub fn is_valid(self) -> bool {
        match self {
            GapLimit::Steps(n) => n.is_finite() && n >= 1.5,
            GapLimit::Seconds(s) => s.is_finite() && s > 0.0,
        }
    }
}

/// The median of `values` (the upper one of an even count), `None` when empty.
pub fn median(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// The steps between consecutive `times`.
pub fn steps(times: &[f64]) -> Vec<f64> {
    times.windows(2).map(|w| w[1] - w[0]).collect()
}

/// The indices `i` whose step `times[i] → times[i + 1]` is longer than `limit`
/// seconds: the holes, in order.
pub fn holes(times: &[f64], limit: f64) -> Vec<usize> {
    times
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[1] - w[0] > limit)
        .map(|(i, _)| i)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stall_is_a_hole_and_jitter_is_not() {
        let mut times: Vec<f64> = (0..50).map(|k| f64::from(k) * 0.1).collect();
        times[10] += 0.02;
        times.extend((0..50).map(|k| 10.0 + f64::from(k) * 0.1));
        let limit = GapLimit::default().seconds(&steps(&times), 0.05);
        assert!((limit - 0.5).abs() < 1e-9, "{limit}");
        assert_eq!(holes(&times, limit), vec![49]);
        assert_eq!(
            GapLimit::default().seconds(&steps(&times), 0.2),
            1.0,
            "five grid steps"
        );
        assert_eq!(
            holes(&times, GapLimit::Seconds(6.0).seconds(&[], 0.1)),
            vec![]
        );
        assert!(!GapLimit::Steps(1.0).is_valid() && !GapLimit::Seconds(-1.0).is_valid());
    }
}
