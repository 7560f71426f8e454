//! Time stamps as loggers write them, read exactly into nanoseconds since
//! the Unix epoch (UTC): decimal numbers in a unit (`s`, `ms`, `us`, `ns`)
//! read digit by digit rather than through a float, so epoch nanoseconds
//! (beyond 2⁵³) keep every digit; a pair of integer columns, seconds and
//! nanoseconds (ROS's `header.stamp`); ISO-8601 text with a UTC offset.

/// Nanoseconds since the Unix epoch.
pub type Nanos = i64;

/// The unit of a numeric time column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeUnit {
    /// Seconds.
    Seconds,
    /// Milliseconds.
    Millis,
    /// Microseconds.
    Micros,
    /// Nanoseconds.
    Nanos,
}

impl TimeUnit {
    /// The unit named `s`, `ms`, `us` or `ns`.
    pub fn parse(name: &str) -> Option<TimeUnit> {
        Some(match name {
            "s" => TimeUnit::Seconds,
            "ms" => TimeUnit::Millis,
            "us" | "µs" => TimeUnit::Micros,
            "ns" => TimeUnit::Nanos,
            _ => return None,
        })
    }
    /// Decimal digits of a nanosecond below one unit (9 for seconds).
    fn digits(self) -> u32 {
        match self {
            TimeUnit::Seconds => 9,
            TimeUnit::Millis => 6,
            TimeUnit::Micros => 3,
            TimeUnit::Nanos => 0,
        }
    }
}

/// A decimal number of `unit` (`1700000000.25`, `-3`, `1.7e9`) in
/// nanoseconds: exactly when written in plain digits, else through a
/// float (an exponent); `None` when the text is not a number or the value
/// lies beyond ±292 years of the epoch.
pub fn decimal_nanos(text: &str, unit: TimeUnit) -> Option<Nanos> {
    let text = text.trim();
    if text.contains(['e', 'E']) {
        let v: f64 = text.parse().ok()?;
        let ns = v * 10f64.powi_exact(unit.digits());
        return (ns.is_finite() && ns.abs() < 9.2e18).then(|| ns.round() as Nanos);
    }
    let (negative, digits) = match text.as_bytes().first()? {
        b'-' => (true, &text[1..]),
        b'+' => (false, &text[1..]),
        _ => (false, text),
    };
    let (whole, fraction) = digits.split_once('.').unwrap_or((digits, ""));
    if whole.is_empty() && fraction.is_empty()
        || !whole
            .bytes()
            .chain(fraction.bytes())
            .all(|b| b.is_ascii_digit())
    {
        return None;
    }
    let scale = unit.digits() as usize;
    let mut value: i128 = 0;
    for b in whole.bytes() {
        value = value.checked_mul(10)? + i128::from(b - b'0');
        if value > i128::from(i64::MAX) {
            return None;
        }
    }
    // The fraction to nanoseconds, rounded half away from zero.
    let mut frac: i128 = 0;
    for k in 0..scale {
        let d = fraction.as_bytes().get(k).map_or(0, |b| b - b'0');
        frac = frac * 10 + i128::from(d);
    }
    if fraction.as_bytes().get(scale).is_some_and(|b| *b >= b'5') {
        frac += 1;
    }
    let ns = value.checked_mul(10i128.pow(unit.digits()))? + frac;
    let ns = if negative { -ns } else { ns };
    Nanos::try_from(ns).ok()
}

/// `10^n` for small `n`, exact (clippy bans `powi`).
trait PowExact {
    fn powi_exact(self, n: u32) -> f64;
}

impl PowExact for f64 {
    fn powi_exact(self, n: u32) -> f64 {
        (0..n).fold(1.0, |p, _| p * self)
    }
}

/// A pair of integer cells, seconds and nanoseconds (ROS's
/// `builtin_interfaces/Time`: nanoseconds in `0..1e9`).
pub fn pair_nanos(secs: &str, nanos: &str) -> Result<Nanos, String> {
    let s: i64 = secs
        .trim()
        .parse()
        .map_err(|_| format!("`{}` is not a whole number of seconds", secs.trim()))?;
    let n: i64 = nanos
        .trim()
        .parse()
        .map_err(|_| format!("`{}` is not a whole number of nanoseconds", nanos.trim()))?;
    seconds_and_nanos(s, n)
}

/// Whole seconds and nanoseconds in `0..1e9` (as a CSV pair or a ROS 2
/// message's `header.stamp` holds them) → ns since the epoch.
pub fn seconds_and_nanos(s: i64, n: i64) -> Result<Nanos, String> {
    if !(0..1_000_000_000).contains(&n) {
        return Err(format!(
            "nanoseconds `{n}` outside 0..=999999999 (the fraction of the second, as ROS writes it)"
        ));
    }
    s.checked_mul(1_000_000_000)
        .and_then(|s| s.checked_add(n))
        .ok_or_else(|| format!("{s} s is beyond ±292 years of the epoch"))
}

/// ISO-8601 / RFC 3339 text with a UTC offset (`2026-05-14T10:22:03.5+02:00`,
/// `…Z`, a space for `T`). Text without an offset is refused: a local time is
/// ambiguous and goes backwards when the clocks change.
pub fn iso_nanos(text: &str) -> Result<Nanos, String> {
    let text = text.trim();
    match chrono::DateTime::parse_from_rfc3339(text) {
        Ok(t) => t
            .timestamp_nanos_opt()
            .ok_or_else(|| format!("`{text}` is beyond ±292 years of the epoch")),
        Err(_)
            if chrono::NaiveDateTime::parse_from_str(text, "%Y-%m-%dT%H:%M:%S%.f").is_ok()
                || chrono::NaiveDateTime::parse_from_str(text, "%Y-%m-%d %H:%M:%S%.f").is_ok() =>
        {
            Err(format!(
                "`{text}` has no UTC offset: a local time is ambiguous, and goes backwards when the clocks change"
            ))
        }
        Err(e) => Err(format!("`{text}` is not an ISO-8601 date and time ({e})")),
    }
}

/// `ns` as ISO-8601 UTC text, for messages.
pub fn iso(ns: Nanos) -> String {
    chrono::DateTime::from_timestamp_nanos(ns).to_rfc3339_opts(chrono::SecondsFormat::AutoSi, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_are_read_exactly() {
        let s = TimeUnit::Seconds;
        assert_eq!(
            decimal_nanos("1700000000.123456789", s),
            Some(1_700_000_000_123_456_789)
        );
        assert_eq!(
            decimal_nanos("1700000000.5", s),
            Some(1_700_000_000_500_000_000)
        );
        assert_eq!(decimal_nanos("-1.25", s), Some(-1_250_000_000));
        assert_eq!(decimal_nanos("12.0000000005", s), Some(12_000_000_001));
        assert_eq!(
            decimal_nanos("1700000000123456789", TimeUnit::Nanos),
            Some(1_700_000_000_123_456_789)
        );
        assert_eq!(
            decimal_nanos("1700000000123.5", TimeUnit::Millis),
            Some(1_700_000_000_123_500_000)
        );
        assert_eq!(decimal_nanos("1.5e3", s), Some(1_500_000_000_000));
        for bad in [
            "",
            ".",
            "1.2.3",
            "12:00",
            "NaN",
            "1e400",
            "99999999999999999999",
        ] {
            assert_eq!(decimal_nanos(bad, s), None, "{bad}");
        }
    }

    #[test]
    fn pairs_and_iso_text() {
        assert_eq!(pair_nanos("1700000000", "5"), Ok(1_700_000_000_000_000_005));
        assert!(pair_nanos("1700000000", "1000000000").is_err());
        assert!(pair_nanos("1.5", "0").is_err());
        assert_eq!(iso_nanos("1970-01-01T00:00:01.5Z"), Ok(1_500_000_000));
        assert_eq!(iso_nanos("1970-01-01T02:00:01+02:00"), Ok(1_000_000_000));
        assert_eq!(iso_nanos("1970-01-01 00:00:02Z"), Ok(2_000_000_000));
        let local = iso_nanos("2026-05-14T10:22:03.5").err().unwrap_or_default();
        assert!(local.contains("no UTC offset"), "{local}");
        assert!(iso_nanos("14/05/2026").is_err());
        assert_eq!(iso(1_500_000_000), "1970-01-01T00:00:01.500Z");
    }
}
