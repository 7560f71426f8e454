//! The human-readable result of `leeway estimate`: aligned plain-text tables
//! on stdout (warnings and errors go to stderr).

use crate::estimate::outcome::Outcome;
use crate::output::{number, table};
use leeway_estimate::{ColumnEstimate, Estimate};
use leeway_model::signs::ArgSign;
use std::fmt::Write;

fn optional(v: Option<f64>) -> String {
    v.map_or("-".to_string(), number)
}

fn column_row(c: &ColumnEstimate) -> Vec<String> {
    vec![
        c.name.clone(),
        optional(c.value),
        optional(c.std_error),
        c.status.clone(),
    ]
}

fn percent(f: f64) -> String {
    if f == 0.0 {
        "0%".to_string()
    } else {
        format!("{:.2}%", 100.0 * f)
    }
}

/// The signs of an experiment, at most `MAX_LISTED` (the JSON lists all).
fn signs(args: &[ArgSign]) -> String {
    leeway_structure::grammar::join_capped(
        args.iter().map(|a| {
            format!(
                "{} {} (other sign {})",
                a.argument,
                if a.sign < 0 { '-' } else { '+' },
                percent(a.minority_fraction)
            )
        }),
        ", ",
    )
}

pub use leeway_report::aggregate_of;

/// The whole text.
pub fn render(o: &Outcome) -> String {
    let e = &o.estimate;
    let d = &e.diagnostics;
    let mut s = String::new();
    let n = o.experiments.len();
    let _ = writeln!(
        s,
        "{}: {} estimate from {} experiment{} ({} equations)\n",
        o.model,
        e.method.name(),
        n,
        if n == 1 { "" } else { "s" },
        d.equations
    );
    for scan in &o.scans {
        delay_scan(&mut s, scan);
    }
    parameters(&mut s, e);
    nuisance(&mut s, e);
    disturbances(&mut s, e);
    sign_patterns(&mut s, e);
    diagnostics(&mut s, o);
    s
}

/// The scan's curve, one row per candidate dead time, the chosen one marked.
fn delay_scan(s: &mut String, scan: &leeway_estimate::DelayScan) {
    let by = leeway_estimate::Named::name(scan.by);
    let _ = writeln!(s, "dead time of {} (scanned by {by})", scan.input);
    let mut rows = vec![vec![
        "samples".to_string(),
        "seconds".to_string(),
        format!("{by} %"),
        String::new(),
    ]];
    for (i, p) in scan.points.iter().enumerate() {
        rows.push(vec![
            p.samples.to_string(),
            leeway_model::number::short_number(p.seconds),
            match (&p.error, p.criterion) {
                (Some(_), _) => "no estimate".to_string(),
                (None, Some(c)) => format!("{c:.2}"),
                (None, None) => "-".to_string(),
            },
            if i == scan.chosen {
                "<- chosen".to_string()
            } else {
                String::new()
            },
        ]);
    }
    s.push_str(&table(&rows));
    s.push('\n');
}

/// θ, an aggregate's sum on the row under it.
fn parameters(s: &mut String, e: &Estimate) {
    s.push_str("parameters\n");
    let mut rows = vec![vec![
        "name".to_string(),
        "estimate".to_string(),
        "std error".to_string(),
        "status".to_string(),
    ]];
    for c in e.columns.iter().filter(|c| c.kind == "theta") {
        match aggregate_of(c, &e.diagnostics.aggregates) {
            // An aggregate says so on its own row, and what it sums on the
            // next, under the status (the last column, so no column widens).
            Some(sum) => {
                let mut r = column_row(c);
                r[3] = "aggregate".to_string();
                rows.push(r);
                rows.push(vec![
                    String::new(),
                    String::new(),
                    String::new(),
                    format!("= {sum}"),
                ]);
            }
            None => rows.push(column_row(c)),
        }
    }
    s.push_str(&table(&rows));
}

/// The nuisance parameters and what each estimates.
fn nuisance(s: &mut String, e: &Estimate) {
    let nuisance: Vec<&ColumnEstimate> = e.columns.iter().filter(|c| c.kind != "theta").collect();
    if !nuisance.is_empty() {
        s.push_str("\nnuisance parameters\n");
        let mut rows = vec![vec![
            "name".to_string(),
            "estimate".to_string(),
            "std error".to_string(),
            "status".to_string(),
            "estimates".to_string(),
        ]];
        let mut reasons: Vec<(String, String)> = Vec::new();
        rows.extend(nuisance.iter().map(|c| {
            let mut r = column_row(c);
            let (word, reason) = status_words(&c.status);
            if let Some(reason) = reason
                && !reasons.iter().any(|(w, _)| *w == word)
            {
                reasons.push((word.clone(), reason));
            }
            r[3] = word;
            r.push(c.estimates.clone());
            r
        }));
        s.push_str(&table(&rows));
        for (word, reason) in reasons {
            let _ = writeln!(s, "  {word}: {reason}");
        }
    }
}

/// A column's status in short words (`dropped`, `held at 0`) and the reason
/// it gives in parentheses, said once under the table.
fn status_words(status: &str) -> (String, Option<String>) {
    match status.split_once(" (") {
        Some((word, reason)) => (
            word.to_string(),
            Some(reason.trim_end_matches(')').to_string()),
        ),
        None => (status.to_string(), None),
    }
}

/// The unmeasured disturbances' means.
fn disturbances(s: &mut String, e: &Estimate) {
    if !e.disturbances.is_empty() {
        s.push_str("\nunmeasured disturbance means (paper Corollary 1)\n");
        let rows: Vec<Vec<String>> = e
            .disturbances
            .iter()
            .map(|m| {
                vec![
                    format!("{}.{}", m.disturbance, m.component),
                    number(m.mean),
                    m.std_error.map_or("(no standard error)".to_string(), |se| {
                        format!("± {}", number(se))
                    }),
                ]
            })
            .collect();
        s.push_str(&table(&rows));
    }
}

/// Each experiment's sign pattern.
fn sign_patterns(s: &mut String, e: &Estimate) {
    if e.sign_patterns
        .iter()
        .any(|p| !p.arguments.is_empty() || !p.pointwise.is_empty())
    {
        s.push_str("\nsign patterns (paper A7: an argument relative to an unmeasured medium keeps one sign per experiment; pointwise ones may change sign)\n");
        let mut rows = Vec::new();
        for p in &e.sign_patterns {
            if !p.arguments.is_empty() {
                rows.push(vec![p.experiment.clone(), signs(&p.arguments)]);
            }
            if !p.pointwise.is_empty() {
                rows.push(vec![
                    if p.arguments.is_empty() {
                        p.experiment.clone()
                    } else {
                        String::new()
                    },
                    format!(
                        "pointwise (|x| evaluated sample by sample): {}",
                        signs(&p.pointwise)
                    ),
                ]);
            }
        }
        s.push_str(&table(&rows));
    }
}

/// The diagnostics table: predictor, experiments, rank, refinement, data notes.
fn diagnostics(s: &mut String, o: &Outcome) {
    let e = &o.estimate;
    let d = &e.diagnostics;
    s.push_str("\ndiagnostics\n");
    let mut rows = vec![
        vec![
            "predictor".to_string(),
            format!("{} ({})", d.predictor, e.method.name()),
        ],
        vec![
            "experiments".to_string(),
            leeway_structure::grammar::join_capped(
                o.experiments
                    .iter()
                    .map(|(name, k)| format!("{name} ({k} samples)")),
                ", ",
            ),
        ],
        vec![
            "columns".to_string(),
            format!(
                "{} in the predictor, {} estimated, numerical rank {}",
                d.columns, d.estimated, d.rank
            ),
        ],
        vec!["condition number".to_string(), number(d.condition_number)],
    ];
    if !d.dropped_at_start.is_empty() {
        rows.push(vec![
            "dropped at start".to_string(),
            leeway_structure::grammar::join_capped(
                d.dropped_at_start.iter().map(|x| {
                    format!(
                        "{}: {} equations (dead time {}, method {})",
                        x.experiment, x.equations, x.dead_time, x.method
                    )
                }),
                ", ",
            ),
        ]);
    }
    rows.extend([vec![
        "refinements".to_string(),
        format!(
            "{} ({})",
            d.refinements,
            if d.converged {
                "converged"
            } else {
                "not converged"
            }
        ),
    ]]);
    if let Some(s) = &d.subsample {
        rows.push(vec!["subsample".to_string(), subsample(s)]);
    }
    rows.extend([
        vec!["own simulation".to_string(), own_simulation(d)],
        vec!["instruments".to_string(), d.instruments.clone()],
        vec!["centring".to_string(), d.centring.clone()],
        vec![
            "combination".to_string(),
            if d.combine == "stacked" {
                "stacked: [H_i/n_i] ϑ = [g_i/n_i] by least squares (paper eq. IV_problem)"
                    .to_string()
            } else if d.combine == "summed" {
                "summed: (Σ H_i) ϑ = Σ g_i (pooled IV)".to_string()
            } else {
                d.combine.clone()
            },
        ],
        vec!["covariance lags".to_string(), d.lags.to_string()],
    ]);
    for (name, gain) in &o.heading_gains {
        rows.push(vec![
            "heading gain".to_string(),
            match gain {
                Some(g) => format!("{name}: {g:.3} (Δψ/h on the yaw rate; 1 when consistent)"),
                None => format!("{name}: too little yaw motion to check"),
            },
        ]);
    }
    for u in &o.units {
        rows.push(vec!["unit".to_string(), u.clone()]);
    }
    for note in crate::data::data_notes(&o.data_notes) {
        rows.push(vec!["data".to_string(), note]);
    }
    for u in &d.unexcited {
        rows.push(vec!["unexcited".to_string(), u.clone()]);
    }
    for a in &d.aggregates {
        rows.push(vec!["aggregate".to_string(), a.clone()]);
    }
    s.push_str(&table(&rows));
}

/// The estimate's own simulation on its data, in a line: the mean fit and
/// each state's, or where it diverged.
fn own_simulation(d: &leeway_estimate::Diagnostics) -> String {
    let Some(own) = &d.own_simulation else {
        return "not run".to_string();
    };
    if !own.diverged.is_empty() {
        return format!(
            "diverges on {}",
            leeway_structure::grammar::join_capped(&own.diverged, ", ")
        );
    }
    let fit = |f: Option<f64>| f.map_or("-".to_string(), |v| format!("{v:.1} %"));
    let states = own
        .fits
        .iter()
        .map(|s| format!("{} {}", s.state, fit(s.fit)));
    format!(
        "fit {} ({})",
        fit(own.mean_fit),
        leeway_structure::grammar::join_capped(states, ", ")
    )
}

/// The refinement on a subsample that began this one: where, how long, and
/// whether its estimate was used.
fn subsample(s: &leeway_estimate::SubsampleRefinement) -> String {
    let head = format!(
        "the first {} of every experiment ({} samples): {} refinement{}",
        leeway_model::number::short_number(s.fraction),
        s.samples,
        s.refinements,
        if s.refinements == 1 { "" } else { "s" }
    );
    match (&s.why_not, s.used) {
        (_, true) => format!("{head}, settled; the refinement over all samples went on from it"),
        (Some(why), false) => format!("{head}; not used ({why}): refined from the bootstrap"),
        (None, false) => format!("{head}; not used: refined from the bootstrap"),
    }
}
