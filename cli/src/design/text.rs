//! The design as text: the runs, the excitation chosen, the predicted
//! standard errors against run length, the signs each estimator needs,
//! and the verification's table.

use crate::design::args::DesignArgs;
use leeway_design::report::{Design, PlannedRun, PredictionReport};
use leeway_design::verify::Verification;
use leeway_model::Interpreter;
use leeway_model::model::Model;
use leeway_model::number::short_number as num;
use std::fmt::Write;

/// Renders a design (and its verification).
pub fn render(
    model: &Interpreter,
    d: &Design,
    v: Option<&Verification>,
    args: &DesignArgs,
) -> String {
    let ir = model.ir();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "design for {} ({}, instrument centring {}): {} experiment{} of {} s ({} samples at {} s)",
        d.model,
        d.method,
        d.centring,
        d.experiments.len(),
        if d.experiments.len() == 1 { "" } else { "s" },
        num(d.seconds),
        d.samples,
        num(d.step)
    );
    for a in &d.assumptions {
        let _ = writeln!(s, "  assumed: {a}");
    }
    if !d.runs_reason.is_empty() {
        let _ = writeln!(s, "  runs: {}", d.runs_reason);
    }
    if d.runs_tried.len() > 1 {
        let tried: Vec<String> = d
            .runs_tried
            .iter()
            .map(|o| {
                format!(
                    "{} × {} s{}, {} centring: {}{}",
                    o.runs,
                    num(o.seconds),
                    differ_by(o.differ_by.as_deref()),
                    o.centring,
                    o.worst_relative
                        .map_or("no prediction".to_string(), |w| format!(
                            "worst {} % ({})",
                            num(100.0 * w),
                            o.worst_parameter.as_deref().unwrap_or("-")
                        )),
                    if o.chosen { " chosen" } else { "" }
                )
            })
            .collect();
        let _ = writeln!(s, "  runs tried: {}", tried.join("; "));
    }
    for (e, run) in d.experiments.iter().enumerate() {
        experiment(&mut s, ir, e, run, d);
    }
    families(&mut s, d);
    if let Some(p) = &d.prediction {
        prediction(&mut s, d, p);
    }
    signs(&mut s, d);
    if !d.shortfalls.is_empty() {
        let _ = writeln!(s, "\nno plan within the limits keeps every held sign:");
        for p in &d.proposals {
            let _ = writeln!(s, "  {p}");
        }
    } else if !d.sea_room.is_empty() {
        let _ = writeln!(
            s,
            "\nthe design cannot keep the track inside the trial area:"
        );
        for p in &d.proposals {
            let _ = writeln!(s, "  {p}");
        }
    }
    if let Some(v) = v {
        verification(&mut s, v);
    } else if args.verify.is_some() && !d.feasible {
        let _ = writeln!(
            s,
            "\nnot verified: the design does not keep its {}",
            if d.shortfalls.is_empty() && !d.sea_room.is_empty() {
                "track inside the trial area"
            } else {
                "signs"
            }
        );
    }
    s
}

fn experiment(
    s: &mut String,
    ir: &leeway_structure::ir::Ir,
    e: usize,
    run: &PlannedRun,
    d: &Design,
) {
    let _ = writeln!(s, "\nexperiment {} {}", e + 1, run.pattern);
    let inputs: Vec<String> = ir
        .inputs
        .iter()
        .filter_map(|i| {
            run.inputs.get(i).map(|p| {
                let unit = p.unit.as_ref().map_or(String::new(), |u| format!(" {u}"));
                format!("{i} = {} ± {}{unit}", num(p.offset), num(p.amplitude))
            })
        })
        .collect();
    let _ = writeln!(
        s,
        "  inputs      {} ({})",
        inputs.join(", "),
        d.excitation.name()
    );
    let steady: Vec<String> = ir
        .states
        .iter()
        .filter_map(|x| run.steady.get(x).map(|v| format!("{x} = {}", num(*v))))
        .collect();
    let _ = writeln!(
        s,
        "  steady      {} (calm, at the offsets)",
        steady.join(", ")
    );
    for h in &run.held {
        let _ = writeln!(
            s,
            "  held        {} {} 0: band {}, steady margin {}, smallest nominal margin {}{}",
            h.argument,
            if h.side == "-" { "<" } else { ">" },
            num(h.band),
            num(h.steady_margin),
            num(h.min_margin),
            if h.min_margin < 0.0 { "  (short)" } else { "" }
        );
    }
    for p in &run.pointwise {
        let _ = writeln!(
            s,
            "  pointwise   {}: {} % of the samples below zero",
            p.state,
            num(100.0 * p.negative_fraction)
        );
    }
    if let Some(span) = run.heading_span_deg {
        let _ = writeln!(
            s,
            "  heading     turns through {}°",
            num(span.min(99_999.0))
        );
    }
    if let Some(t) = &run.track {
        let _ = writeln!(
            s,
            "  track       at most {} m from the start, ends {} m north, {} m east (nominal, the mean media's drift included)",
            num(t.farthest.round()),
            num(t.end[0].round()),
            num(t.end[1].round())
        );
    }
    if run.full_range {
        let _ = writeln!(
            s,
            "  note        the offsets use the whole ranges: little room is left to excite"
        );
    }
}

fn families(s: &mut String, d: &Design) {
    let each: Vec<String> = d
        .families
        .iter()
        .map(|f| match f.status.as_str() {
            "chosen" | "scored" => format!(
                "{} {} ({} of the room){}",
                f.family.name(),
                num(f.score),
                num(f.scale),
                if f.status == "chosen" { " chosen" } else { "" }
            ),
            "failed" => format!(
                "{} failed ({})",
                f.family.name(),
                f.detail.as_deref().unwrap_or("")
            ),
            _ => format!("{} cannot keep the signs", f.family.name()),
        })
        .collect();
    let _ = writeln!(
        s,
        "\nexcitation (mean ln σ/|θ|, lower is better): {}",
        each.join("; ")
    );
}

fn prediction(s: &mut String, d: &Design, p: &PredictionReport) {
    let source = if p.trials > 0 {
        format!(
            "half the 95th percentile of |error| of {} simulated trials",
            p.trials
        )
    } else {
        "the estimator's asymptotic covariance".to_string()
    };
    let _ = writeln!(
        s,
        "\npredicted standard errors ({}), {} s per experiment ({source})",
        d.method,
        num(d.seconds)
    );
    let width = p
        .parameters
        .iter()
        .map(|q| q.name.len())
        .max()
        .unwrap_or(4)
        .max(9);
    let _ = writeln!(
        s,
        "  {:width$}  {:>10}  {:>10}  {:>8}  {:>10}",
        "parameter", "nominal", "std error", "relative", "asymptotic"
    );
    for q in &p.parameters {
        // Where the pilot's spread and the estimator's covariance part by
        // more than half, say so: the pilot's is the one used.
        let off = match (q.std_error, q.asymptotic) {
            (Some(pilot), Some(a))
                if p.trials > 0 && a > 0.0 && !(0.67..=1.5).contains(&(a / pilot)) =>
            {
                format!("  (asymptotic off ×{}: the pilot's used)", num(a / pilot))
            }
            _ => String::new(),
        };
        let _ = writeln!(
            s,
            "  {:width$}  {:>10}  {:>10}  {:>8}  {:>10}{off}",
            q.name,
            num(q.nominal),
            q.std_error.map_or("held".into(), num),
            q.relative
                .map_or("-".into(), |r| format!("{} %", num(100.0 * r))),
            q.asymptotic.map_or("-".into(), num)
        );
    }
    for m in &p.disturbances {
        let _ = writeln!(
            s,
            "  mean of {}: {} ± {}",
            m.name,
            num(m.mean),
            m.std_error.map_or("?".into(), num)
        );
    }
    let curve: Vec<String> = p
        .curve
        .iter()
        .map(|c| format!("{} s {} %", num(c.seconds), num(100.0 * c.worst_relative)))
        .collect();
    let _ = writeln!(
        s,
        "  worst relative error against run length: {}",
        curve.join(", ")
    );
    if let Some(t) = &p.target {
        match (t.samples, t.seconds) {
            (Some(samples), Some(seconds)) => {
                let _ = writeln!(
                    s,
                    "  target {} %: {} s per experiment ({samples} samples){}",
                    num(100.0 * t.relative),
                    num(seconds),
                    if t.within_budget {
                        ", within the budget"
                    } else {
                        ", beyond the budget"
                    }
                );
            }
            _ => {
                let _ = writeln!(
                    s,
                    "  target {} %: {} per experiment",
                    num(100.0 * t.relative),
                    leeway_design::bounds::needed_words(None)
                );
            }
        }
    }
    for q in &p.poorly_determined {
        let _ = writeln!(
            s,
            "  poorly determined: {} ({} %): {}",
            q.name,
            num(100.0 * q.relative),
            q.help
        );
    }
}

fn signs(s: &mut String, d: &Design) {
    let _ = writeln!(s);
    for m in &d.methods {
        let short: Vec<String> = m
            .arguments
            .iter()
            .filter(|a| a.min_margin < 0.0)
            .map(|a| {
                format!(
                    "{} in experiment {} (short by {})",
                    a.argument,
                    a.experiment,
                    num(-a.min_margin)
                )
            })
            .collect();
        let held: Vec<&str> = m.arguments.iter().map(|a| a.argument.as_str()).collect();
        let line = if held.is_empty() {
            format!("{}: holds no sign (every modulus pointwise)", m.method)
        } else if short.is_empty() {
            format!(
                "{}: keeps {} on their sides in every nominal run",
                m.method,
                dedup(&held).join(", ")
            )
        } else {
            format!("{}: crosses {}", m.method, short.join(", "))
        };
        let _ = writeln!(s, "signs {line}");
    }
}

fn dedup<'a>(v: &[&'a str]) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for x in v {
        if !out.contains(x) {
            out.push(x);
        }
    }
    out
}

fn verification(s: &mut String, v: &Verification) {
    let _ = writeln!(
        s,
        "\nverification: {} trials (seed {}), {} samples per experiment",
        v.runs, v.seed, v.samples
    );
    for k in &v.signs {
        let _ = writeln!(
            s,
            "  experiment {} {}: on its side in {} % of the samples (worst trial {} %)",
            k.experiment,
            k.argument,
            num(100.0 * k.mean),
            num(100.0 * k.min)
        );
    }
    for m in &v.methods {
        let fits: Vec<String> = m.fits.iter().map(|(_, f)| num(*f)).collect();
        let _ = writeln!(
            s,
            "  {}{}: {} failed, {} rank-deficient, {} unsettled, {} diverged; validation fit {} %{}",
            m.method,
            if m.designed_for {
                " (designed for)"
            } else {
                ""
            },
            m.failed,
            m.rank_deficient,
            m.unconverged,
            m.diverged,
            fits.join("/"),
            m.failure
                .as_ref()
                .map_or(String::new(), |f| format!("; {f}"))
        );
    }
    if let Some(m) = v.methods.iter().find(|m| m.designed_for) {
        let width = m
            .parameters
            .iter()
            .map(|q| q.name.len())
            .max()
            .unwrap_or(4)
            .max(9);
        let _ = writeln!(
            s,
            "  {:width$}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>8}",
            "parameter", "truth", "mean", "spread", "predicted", "reported", "±2σ"
        );
        for q in &m.parameters {
            let _ = writeln!(
                s,
                "  {:width$}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>8}",
                q.name,
                num(q.truth),
                num(q.mean),
                num(q.std),
                q.predicted.map_or("-".into(), num),
                q.reported.map_or("-".into(), num),
                q.coverage
                    .map_or("-".into(), |c| format!("{} %", num(100.0 * c)))
            );
        }
    }
    let truth: Vec<String> = v.true_fits.iter().map(|(_, f)| num(*f)).collect();
    let _ = writeln!(s, "  the true model's held-out fit {} %", truth.join("/"));
    if let Some(m) = v.methods.iter().find(|m| m.designed_for) {
        let join =
            |f: &[(String, f64)]| f.iter().map(|(_, x)| num(*x)).collect::<Vec<_>>().join("/");
        let _ = writeln!(
            s,
            "  over the held-out run's first {} s: {} {} %, the true model {} %",
            num(v.early_seconds),
            m.method,
            join(&m.early_fits),
            join(&v.true_early_fits)
        );
    }
    if v.verdict.passed {
        let _ = writeln!(
            s,
            "  verdict: passed (held-out fit within {} points of the true model's in every state{})",
            num(leeway_design::verify::FIT_POINTS),
            if v.runs >= leeway_design::verify::COVERAGE_TRIALS {
                ", ±2σ coverage 90–98 % for every parameter within the sampling error of the trials"
            } else {
                "; coverage is judged from 100 trials"
            }
        );
    } else {
        let _ = writeln!(
            s,
            "\nnot a success: the verified models are not what the trial needs"
        );
        for f in &v.verdict.failures {
            let _ = writeln!(s, "  fails: {f}");
        }
        for h in &v.verdict.help {
            let _ = writeln!(s, "  would help: {h}");
        }
    }
    if v.runs_verified.len() > 1 {
        let _ = writeln!(s, "\nverified the runs the design tried, in turn:");
        for r in &v.runs_verified {
            let what = format!(
                "{} × {} s{}, {} centring",
                r.runs,
                num(r.seconds),
                differ_by(r.differ_by.as_deref()),
                r.centring
            );
            let outcome = match r.passed {
                Some(true) => "passes".to_string(),
                Some(false) => format!("fails ({})", r.failures.first().map_or("", String::as_str)),
                None => "does not keep its signs or its area".to_string(),
            };
            let taken = if r.taken { " — the design above" } else { "" };
            let _ = writeln!(s, "  {what}: {outcome}{taken}");
        }
    }
}

/// ` (differ by speed)`: what sets a runs option's runs apart, or nothing.
fn differ_by(d: Option<&str>) -> String {
    d.map_or(String::new(), |d| format!(" (differ by {d})"))
}

/// The design beside the engineer's own input, per sample.
pub fn comparison(c: &leeway_design::compare::Comparison, files: &[std::path::PathBuf]) -> String {
    let mut s = String::new();
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    let _ = writeln!(
        s,
        "\ncompared with {} ({} samples per experiment)",
        names.join(", "),
        c.samples
    );
    for a in &c.held {
        let _ = writeln!(
            s,
            "  held        {} {} 0 in experiment {}: smallest nominal margin {}{}",
            a.argument,
            if a.side == "-" { "<" } else { ">" },
            a.experiment,
            num(a.min_margin),
            if a.min_margin < 0.0 { "  (short)" } else { "" }
        );
    }
    if let Some(f) = &c.failure {
        let _ = writeln!(s, "  its estimate fails: {f}");
        return s;
    }
    let width = c
        .parameters
        .iter()
        .map(|q| q.name.len())
        .max()
        .unwrap_or(4)
        .max(9);
    let _ = writeln!(s, "  σ·√N per parameter (lower is better):");
    let _ = writeln!(
        s,
        "  {:width$}  {:>10}  {:>10}  {:>8}",
        "parameter", "design", "yours", "ratio"
    );
    for q in &c.parameters {
        let _ = writeln!(
            s,
            "  {:width$}  {:>10}  {:>10}  {:>8}",
            q.name,
            q.design.map_or("-".into(), num),
            q.given.map_or("-".into(), num),
            q.ratio.map_or("-".into(), num)
        );
    }
    let _ = writeln!(
        s,
        "  mean ln(σ√N/|θ|): design {}, yours {}",
        num(c.scores.0),
        num(c.scores.1)
    );
    s
}
