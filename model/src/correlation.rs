//! Sample correlations of residual series that are cut into experiments,
//! with the portmanteau statistic of Ljung and Box and the χ² tail it is
//! read against (the regularized upper incomplete gamma function), so that
//! whiteness tests need no statistics library. Products are summed within
//! an experiment only: no lag reaches across an experiment boundary.

/// Each segment minus its own mean (segments of fewer than one sample stay
/// empty). Non-finite values make the segment's values non-finite.
pub fn centred(segments: &[&[f64]]) -> Vec<Vec<f64>> {
    segments
        .iter()
        .map(|s| {
            let mean = s.iter().sum::<f64>() / s.len().max(1) as f64;
            s.iter().map(|v| v - mean).collect()
        })
        .collect()
}

/// `Σ_segments Σ_t a(t)·b(t − lag)` over the sample pairs that lie in the
/// same segment (`lag` may be negative).
fn lagged_sum(a: &[Vec<f64>], b: &[Vec<f64>], lag: i64) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| {
            let n = a.len().min(b.len()) as i64;
            let (from, to) = (lag.max(0), n.min(n + lag));
            (from..to)
                .map(|t| a[t as usize] * b[(t - lag) as usize])
                .sum::<f64>()
        })
        .sum()
}

/// `Σ a²` over every segment.
fn energy(a: &[Vec<f64>]) -> f64 {
    a.iter().flatten().map(|v| v * v).sum()
}

/// The normalised cross-correlation `r_ab(τ) = Σ a(t)·b(t−τ) / √(Σa²·Σb²)`
/// of centred segments for each lag; `None` where it is undefined (a
/// constant series, or non-finite values).
pub fn cross_correlation(a: &[Vec<f64>], b: &[Vec<f64>], lags: &[i64]) -> Vec<Option<f64>> {
    let scale = (energy(a) * energy(b)).sqrt();
    lags.iter()
        .map(|&lag| {
            let r = lagged_sum(a, b, lag) / scale;
            (scale > 0.0 && r.is_finite()).then_some(r)
        })
        .collect()
}

/// The autocorrelation `r(τ)` of centred segments at lags `1..=max_lag`.
pub fn autocorrelation(a: &[Vec<f64>], max_lag: usize) -> Vec<Option<f64>> {
    let lags: Vec<i64> = (1..=max_lag as i64).collect();
    cross_correlation(a, a, &lags)
}

/// The Ljung–Box statistic `Q = N(N+2)·Σ_τ r(τ)²/(N−τ)` over the
/// autocorrelations at lags `1..=r.len()` of `n` samples; `None` when an
/// autocorrelation is undefined or `n` does not exceed the largest lag.
pub fn ljung_box(r: &[Option<f64>], n: usize) -> Option<f64> {
    let n = n as f64;
    if n <= r.len() as f64 {
        return None;
    }
    let mut sum = 0.0;
    for (i, r) in r.iter().enumerate() {
        sum += r.map(|r| r * r / (n - (i + 1) as f64))?;
    }
    Some(n * (n + 2.0) * sum)
}

/// `P(χ²_df > q)`: the upper tail of the χ² distribution with `df`
/// degrees of freedom, `Q(df/2, q/2)`.
pub fn chi_squared_tail(q: f64, df: usize) -> f64 {
    upper_gamma(df as f64 / 2.0, q / 2.0)
}

/// The regularized upper incomplete gamma function `Q(a, x)` for `a > 0`,
/// `x ≥ 0`: its power series below `x < a + 1`, else its continued fraction
/// (modified Lentz), each to about 1e-15 relative.
pub fn upper_gamma(a: f64, x: f64) -> f64 {
    if x.is_nan() || a.is_nan() || a <= 0.0 {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    if x.is_infinite() {
        return 0.0;
    }
    let log_prefix = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) = e^{−x} x^a / Γ(a) · Σ x^n / (a(a+1)…(a+n)).
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..1000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * log_prefix.exp()).clamp(0.0, 1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            d = if d.abs() < tiny { tiny } else { d };
            c = b + an / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (log_prefix.exp() * h).clamp(0.0, 1.0)
    }
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, nine terms: about 1e-15).
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut sum = G[0];
    for (i, g) in G.iter().enumerate().skip(1) {
        sum += g / (x + i as f64);
    }
    let t = x + 7.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chi_squared_tail_matches_tabulated_quantiles() {
        // χ² quantiles (df, q) with P(χ² > q) = p, from standard tables.
        for (df, q, p) in [
            (1, 3.841_458_820_694_124, 0.05),
            (1, 6.634_896_601_021_214, 0.01),
            (2, 5.991_464_547_107_979, 0.05),
            (10, 18.307_038_053_275_146, 0.05),
            (25, 37.652_484_133_482_79, 0.05),
            (25, 44.314_104_896_219_16, 0.01),
            (40, 63.690_739_751_564_46, 0.01),
        ] {
            let got = chi_squared_tail(q, df);
            assert!((got - p).abs() < 1e-9, "df {df}, q {q}: {got} vs {p}");
        }
        // df = 2: the tail is e^{−q/2} exactly.
        assert!((chi_squared_tail(3.0, 2) - (-1.5f64).exp()).abs() < 1e-14);
        assert_eq!(chi_squared_tail(0.0, 5), 1.0);
    }

    #[test]
    fn ln_gamma_matches_factorials() {
        let mut factorial = 1.0f64;
        for n in 1..20 {
            assert!(
                (ln_gamma(n as f64) - factorial.ln()).abs() < 1e-12,
                "Γ({n})"
            );
            factorial *= n as f64;
        }
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-14);
    }

    #[test]
    fn lags_never_reach_across_segments() {
        // Two segments, each a ramp: a lag-1 product pairs only samples of
        // the same segment.
        let a = vec![vec![1.0, 2.0], vec![10.0, 20.0]];
        assert_eq!(lagged_sum(&a, &a, 1), 2.0 + 200.0);
        assert_eq!(lagged_sum(&a, &a, -1), 2.0 + 200.0);
        assert_eq!(lagged_sum(&a, &a, 2), 0.0);
        let r = autocorrelation(&centred(&[&[1.0, -1.0], &[2.0, -2.0]]), 1);
        assert_eq!(r, vec![Some(-(1.0 + 4.0) / (2.0 + 8.0))]);
    }

    #[test]
    fn a_constant_series_has_no_correlation() {
        let a = centred(&[&[3.0, 3.0, 3.0]]);
        assert_eq!(autocorrelation(&a, 2), vec![None, None]);
        assert_eq!(ljung_box(&[None], 10), None);
    }
}
