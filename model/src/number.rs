//! Numbers in messages meant for people: a few significant digits, never
//! the 17 of a raw `f64` (`step -0.10000000000000142 s`). JSON documents keep
//! full precision; only words use this.

/// A time in seconds to the millisecond, trailing zeros dropped (`1799.7`,
/// `300`): a time in a report names the instant, where four significant
/// digits would round 1799.7 s to 1800.
pub fn time_number(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let text = trim_zeros(format!("{x:.3}"));
    if text == "-0" { "0".to_string() } else { text }
}

/// A number for a message: four significant digits, `-0` as `0`, no
/// trailing zeros (`0.1`, `-1.45`, `1.234e-5`). JSON keeps full precision.
pub fn short_number(x: f64) -> String {
    if x == 0.0 {
        return "0".to_string();
    }
    if !x.is_finite() {
        return format!("{x}");
    }
    let magnitude = x.abs().log10().floor();
    let text = if (-4.0..6.0).contains(&magnitude) {
        // 0 ≤ decimals ≤ 7 here, so the cast is exact.
        let decimals = (3.0 - magnitude).max(0.0) as usize;
        trim_zeros(format!("{x:.decimals$}"))
    } else {
        let s = format!("{x:.3e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim_zeros(m.to_string())),
            None => s,
        }
    };
    if text == "-0" { "0".to_string() } else { text }
}

fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers_read_as_written() {
        assert_eq!(short_number(-0.10000000000000142), "-0.1");
        assert_eq!(short_number(-1.4502839118780384), "-1.45");
        assert_eq!(short_number(1234.5678), "1235");
        assert_eq!(short_number(1.23456e-7), "1.235e-7");
        assert_eq!(short_number(-0.00001), "-1e-5");
        assert_eq!(short_number(-1e-12 * 0.0), "0");
        assert_eq!(short_number(-0.00004), "-4e-5");
    }
}
