//! The text report of `leeway reproduce` on stdout: what was run, a table per
//! case, the input design's margins, and the paper's claims with their
//! verdicts and evidence.

use crate::output::table;
use crate::reproduce::args::MIN_N;
use crate::reproduce::args::ReproduceArgs;
use crate::reproduce::margins::{CaseCheck, DesignCheck, medium_of};
use crate::reproduce::report::Report;
use leeway_scenarios::study::ESTIMATORS;
use leeway_scenarios::study::OUTPUTS;
use leeway_scenarios::study::StudyConfig;
use std::fmt::Write;

/// `mean ± std` of a fit, `-` when no run gave a finite fit.
fn fit(mean: f64, std: f64) -> String {
    if mean.is_finite() {
        format!("{mean:.1} ± {:.1}", if std.is_finite() { std } else { 0.0 })
    } else {
        "-".to_string()
    }
}

/// A relative error as a percentage.
fn percent(x: f64) -> String {
    if x.is_finite() {
        format!("{:.1} %", 100.0 * x)
    } else {
        "-".to_string()
    }
}

fn header(cfg: &StudyConfig, args: &ReproduceArgs) -> String {
    let n: Vec<String> = cfg.n.iter().map(ToString::to_string).collect();
    let iv = if cfg.paper_iv {
        "the paper's plain refined IV (instruments from the nominal model, no runaway guard)"
    } else {
        "leeway's refined IV (a delayed-instrument estimate starts the refinement; the iterate whose simulation fits best is kept)"
    };
    format!(
        "leeway reproduce: the paper's simulation study (§V) on {model}\n\
         {cases} case{s} × N ∈ {{{n}}} × {runs} run{rs} × LS, IV1, IV2, IV3; seed {seed}; {iv}.\n\
         Fit = 100·(1 − ‖y − ŷ‖/‖y − ȳ‖) in % on an undisturbed zigzag validation record of {val} samples;\n\
         parameter error = mean relative error of the identifiable aggregates (X_uu + W_uu, Y_vv + W_vv, N_uv + W_uv and the other parameters);\n\
         diverged = runs whose estimate failed or whose model's simulation diverged on the validation record: left out of every\n\
         figure but \"median, all\", the median parameter error over every estimate returned (diverged models included).\n",
        model = crate::reproduce::ship::MODEL_FILE,
        cases = cfg.cases.len(),
        s = if cfg.cases.len() == 1 { "" } else { "s" },
        n = n.join(", "),
        runs = cfg.runs,
        rs = if cfg.runs == 1 { "" } else { "s" },
        seed = args.seed,
        val = cfg.validation_len,
    )
}

/// The table of one case.
fn case_table(report: &Report, name: &str, wind: f64) -> String {
    let mut s = String::new();
    let Some(case) = report.summaries.get(name) else {
        return s;
    };
    let _ = writeln!(
        s,
        "\n{name} wind (w̄ = {wind} m/s north and east), {} runs: validation fit (mean ± std, %), parameter error, diverged runs\n",
        report.outcomes.config.runs
    );
    let mut rows = vec![vec![
        "estimator".to_string(),
        "N".to_string(),
        "surge".to_string(),
        "sway".to_string(),
        "yaw".to_string(),
        "param. error: mean".to_string(),
        "median".to_string(),
        "median, all".to_string(),
        "diverged".to_string(),
    ]];
    for (i, est) in ESTIMATORS.iter().enumerate() {
        let Some(e) = case.estimators.get(*est) else {
            continue;
        };
        if i > 0 {
            rows.push(Vec::new());
        }
        for (ni, n) in case.n.iter().enumerate() {
            let mut row = vec![est.to_string(), n.to_string()];
            for o in OUTPUTS {
                let m = e.fit_mean.get(o).and_then(|v| v.get(ni)).copied();
                let sd = e.fit_std.get(o).and_then(|v| v.get(ni)).copied();
                row.push(fit(m.unwrap_or(f64::NAN), sd.unwrap_or(f64::NAN)));
            }
            row.push(percent(e.param_error.get(ni).copied().unwrap_or(f64::NAN)));
            row.push(percent(
                e.param_error_median.get(ni).copied().unwrap_or(f64::NAN),
            ));
            let all = report
                .all_estimates
                .get(name)
                .and_then(|a| a.get(*est))
                .and_then(|a| a.median.get(ni))
                .copied()
                .unwrap_or(f64::NAN);
            row.push(percent(all));
            row.push(e.diverged.get(ni).copied().unwrap_or(0).to_string());
            rows.push(row);
        }
    }
    s.push_str(&table(&rows));
    s
}

fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "-".to_string()
    }
}

fn margin_rows(c: &CaseCheck, rows: &mut Vec<Vec<String>>) {
    for (name, r) in &c.arguments {
        rows.push(vec![
            c.case.clone(),
            name.clone(),
            num(r.min),
            num(r.max),
            num(r.mean()),
            format!("{:.1} %", 100.0 * r.negative_fraction()),
        ]);
    }
}

/// The design check.
fn design(d: &DesignCheck) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nInput design, checked on the true trajectories of all {} estimation experiments per case ({} samples each):\n",
        d.experiments, d.samples
    );
    let mut rows = vec![vec![
        "case".to_string(),
        "relative velocity".to_string(),
        "min (m/s)".to_string(),
        "max".to_string(),
        "mean".to_string(),
        "below 0".to_string(),
    ]];
    for c in &d.cases {
        margin_rows(c, &mut rows);
    }
    s.push_str(&table(&rows));
    s.push('\n');
    for c in &d.cases {
        let water = c.min_of("water");
        let air = c.min_of("air");
        let water_text = if water > 0.0 {
            format!("stay positive (margin {water:.2} m/s)")
        } else {
            format!("DO NOT stay positive (min {water:.2} m/s): the design violates paper A7")
        };
        let air_text = if air > 0.0 {
            format!("stay positive (margin {air:.2} m/s): IV2's sign assumption holds")
        } else {
            let negative: Vec<String> = c
                .arguments
                .iter()
                .filter(|(n, _)| medium_of(n) == "air")
                .map(|(n, r)| format!("{n} < 0 in {:.0} %", 100.0 * r.negative_fraction()))
                .collect();
            format!(
                "change sign ({}): IV2's sign assumption fails, IV3's holds (it evaluates them pointwise)",
                negative.join(", ")
            )
        };
        let _ = writeln!(
            s,
            "  {} wind ({} m/s): water-relative surge and sway {water_text}; wind-relative {air_text}.",
            c.case, c.wind
        );
        let (y, b, runs) = (&c.yaw_rate, &c.yaw_rate_blocks, &c.yaw_rate_runs);
        let _ = writeln!(
            s,
            "    yaw rate {}: mean {:.3}, std {:.3} (measurement noise std {:.4}: excitation/noise {:.1}), range [{:.3}, {:.3}] rad/s, below 0 in {:.1} % of the samples;",
            d.yaw_name,
            y.mean(),
            y.std(),
            d.yaw_noise_std,
            y.std() / d.yaw_noise_std,
            y.min,
            y.max,
            100.0 * y.negative_fraction(),
        );
        let _ = writeln!(
            s,
            "      each run's mean in [{:.3}, {:.3}]; averaged over each minute in [{:.3}, {:.3}], below 0 in {:.1} % of the minutes{}",
            runs.min,
            runs.max,
            b.min,
            b.max,
            100.0 * b.negative_fraction(),
            if b.min > 0.0 {
                " (the ship never stops turning for a minute)"
            } else {
                " (the turn stops or reverses for a minute or more)"
            }
        );
    }
    let val: Vec<String> = d
        .validation_std
        .iter()
        .map(|(n, v)| format!("{n} {v:.3}"))
        .collect();
    let _ = writeln!(
        s,
        "  validation record: std of each output (the fit's normaliser) {}",
        val.join(", ")
    );
    s
}

fn claims(report: &Report) -> String {
    let mut s = String::from("\nThe paper's claims (§V), checked on these figures:\n");
    for c in &report.claims {
        let verdict = match c.holds {
            Some(true) => "holds",
            Some(false) => "does not hold",
            None => "not checked",
        };
        let _ = writeln!(s, "  ({}) {}: {verdict}", c.id, c.statement);
        let _ = writeln!(s, "      criterion: {}", c.criterion);
        let _ = writeln!(s, "      evidence: {}", c.evidence);
        if c.id == "a" {
            let ahead: Vec<String> = crate::reproduce::report::ls_ahead(report)
                .iter()
                .map(|(case, ns)| {
                    if ns.is_empty() {
                        format!("{case} wind at no N run")
                    } else {
                        let ns: Vec<String> = ns.iter().map(ToString::to_string).collect();
                        format!("{case} wind at N = {}", ns.join(", "))
                    }
                })
                .collect();
            let run = &report.outcomes.config.n;
            let all_ahead: Vec<usize> = crate::reproduce::report::ls_ahead(report)
                .into_values()
                .flatten()
                .collect();
            let hint = match finer_grid(run, &all_ahead) {
                Some(grid) => {
                    let grid: Vec<String> = grid.iter().map(ToString::to_string).collect();
                    format!("; try --n {}", grid.join(","))
                }
                None => String::new(),
            };
            let _ = writeln!(
                s,
                "      investigation: LS's median parameter error over every estimate is below IV3's: {} \
                 (the breakpoint lies below the smallest N where it is not{hint})",
                ahead.join("; ")
            );
        }
    }
    s
}

/// Record lengths that locate claim (a)'s breakpoint more closely than the
/// `run` ones: between the largest N at which LS was ahead (`ahead`) and the
/// smallest run N above it at which it was not, or (none ahead) below the
/// smallest N run. `None` when every N is run already or LS is ahead at
/// every N (no breakpoint within reach).
fn finer_grid(run: &[usize], ahead: &[usize]) -> Option<Vec<usize>> {
    let lo = ahead.iter().copied().max();
    let hi = run
        .iter()
        .copied()
        .filter(|n| lo.is_none_or(|lo| *n > lo))
        .min()?;
    let grid: Vec<usize> = match lo {
        // The original investigation's grid below 1000: 150, 200, 300, 400, 600.
        None => [3, 4, 6, 8, 12]
            .iter()
            .map(|k| round_n(hi * k / 20))
            .collect(),
        Some(lo) => (1..5).map(|k| round_n(lo + (hi - lo) * k / 5)).collect(),
    };
    let mut grid: Vec<usize> = grid
        .into_iter()
        .filter(|n| *n >= MIN_N && *n < hi && lo.is_none_or(|lo| *n > lo) && !run.contains(n))
        .collect();
    grid.dedup();
    (!grid.is_empty()).then_some(grid)
}

/// A record length rounded to two significant digits.
fn round_n(n: usize) -> usize {
    let step = 10usize.pow((n.max(1).ilog10()).saturating_sub(1));
    (n + step / 2) / step * step
}

/// The whole report.
pub fn render(report: &Report, args: &ReproduceArgs) -> String {
    let cfg = &report.outcomes.config;
    let mut s = header(cfg, args);
    for case in &cfg.cases {
        s.push_str(&case_table(report, &case.name, case.wind));
    }
    s.push_str(&design(&report.margins));
    s.push_str(&claims(report));
    let _ = writeln!(
        s,
        "\nstudy: {:.1} s on {} thread{}",
        report.seconds,
        report.threads,
        if report.threads == 1 { "" } else { "s" }
    );
    s
}

#[cfg(test)]
mod tests {
    use super::finer_grid;

    #[test]
    fn the_hint_suggests_record_lengths_not_run() {
        let default = [1000, 2000, 3000, 4000, 5000];
        assert_eq!(
            finer_grid(&default, &[]),
            Some(vec![150, 200, 300, 400, 600])
        );
        // Run with the suggested grid, LS ahead at none: look lower still.
        let suggested = [150, 200, 300, 400, 600];
        let again = finer_grid(&suggested, &[]).unwrap_or_default();
        assert!(
            again.iter().all(|n| !suggested.contains(n) && *n < 150),
            "{again:?}"
        );
        // LS ahead up to 200: between 200 and 300.
        assert_eq!(
            finer_grid(&suggested, &[150, 200]),
            Some(vec![220, 240, 260, 280])
        );
        // LS ahead everywhere: nothing to suggest.
        assert_eq!(finer_grid(&suggested, &suggested), None);
    }
}
