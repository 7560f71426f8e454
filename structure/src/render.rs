//! Human-readable rendering of a compiled structure: the text of
//! `leeway check` and of the snapshot tests. Plain text, no terminal codes.

use crate::identify::analysis::Analysis;
use crate::identify::pattern::{pattern_text, patterns_text};
use crate::identify::reduce::Patterns;
use crate::ir::{Column, Entry, EvalVar, Ir, PredictorKind, Rotation, columns_by_output};
use leeway_grammar::{EquationKind, join_capped};
use std::collections::BTreeMap;
use std::fmt::Write;

/// The name of an evaluation variable.
pub fn var_name(ir: &Ir, v: &EvalVar) -> String {
    match v {
        EvalVar::State(i) => ir.states[*i].clone(),
        EvalVar::Input(i) => ir.inputs[*i].clone(),
        EvalVar::AbsInput(i) => format!("|{}|", ir.inputs[*i]),
        EvalVar::Rot(i) => ir.rotation_vars[*i].clone(),
    }
}

/// One output's part of a column, e.g. `s[water.u]*u^2` or `air.u*|air.u| (Φ2, pointwise)`.
pub fn column_text(ir: &Ir, col: &Column, output: usize) -> String {
    let mut parts: Vec<(bool, String)> = Vec::new();
    for e in col.entries.iter().filter(|e| e.output() == output) {
        match e {
            Entry::Poly {
                coefficient_exact,
                signs,
                vars,
                ..
            } => {
                let neg = coefficient_exact.starts_with('-');
                let mag = coefficient_exact.trim_start_matches('-');
                let mut factors: Vec<String> = signs
                    .iter()
                    .map(|s| format!("s[{}]", ir.sign_args[*s].name))
                    .collect();
                let mut i = 0;
                while i < vars.len() {
                    let mut j = i;
                    while j < vars.len() && vars[j] == vars[i] {
                        j += 1;
                    }
                    let name = var_name(ir, &vars[i]);
                    factors.push(if j - i == 1 {
                        name
                    } else {
                        format!("{name}^{}", j - i)
                    });
                    i = j;
                }
                let body = factors.join("*");
                let text = match (mag, body.is_empty()) {
                    (m, true) => m.to_string(),
                    ("1", false) => body,
                    (m, false) => format!("{m}*{body}"),
                };
                parts.push((neg, text));
            }
            Entry::Term { term, .. } => {
                let t = &ir.terms[*term];
                let k = t.coefficient_exact.trim_start_matches('-');
                let text = if k == "1" {
                    t.text.clone()
                } else {
                    format!("{k}*{}", t.text)
                };
                parts.push((
                    t.coefficient_exact.starts_with('-'),
                    format!("{text} (pointwise)"),
                ));
            }
        }
    }
    let mut out = String::new();
    for (i, (neg, t)) in parts.iter().enumerate() {
        if i == 0 {
            if *neg {
                out.push('-');
            }
        } else {
            out.push_str(if *neg { " - " } else { " + " });
        }
        out.push_str(t);
    }
    if out.is_empty() { "0".to_string() } else { out }
}

/// The terms as written of each (parameter, output), joined with their
/// signs (`T_p - T_s` for `N_T*T_p - N_T*T_s`), in one pass over the terms
/// (a model may have 10⁴ of them: no scan per column).
pub fn written_terms(ir: &Ir) -> BTreeMap<(usize, usize), String> {
    let mut written: BTreeMap<(usize, usize), String> = BTreeMap::new();
    for t in &ir.terms {
        let text = written.entry((t.parameter, t.output)).or_default();
        // The sign only: the numeric factor shows in the regressor beside it.
        let neg = t.coefficient_exact.starts_with('-');
        match (text.is_empty(), neg) {
            (true, true) => text.push('-'),
            (true, false) => {}
            (false, true) => text.push_str(" - "),
            (false, false) => text.push_str(" + "),
        }
        text.push_str(&t.text);
    }
    written
}

/// The full structure report.
pub fn render(ir: &Ir) -> String {
    render_except(ir, &[])
}

/// The structure report without the notes in `shown` (those a caller shows
/// as rendered diagnostics beside it, so none is said twice).
pub fn render_except(ir: &Ir, shown: &[&str]) -> String {
    let mut o = String::new();
    render_header(&mut o, ir);
    render_disturbances(&mut o, ir);
    render_sign_args(&mut o, ir);
    render_theta(&mut o, ir);
    render_nuisance(&mut o, ir);
    render_verdict(&mut o, ir);
    render_groups(&mut o, ir, shown);
    o
}

/// The model line: states, inputs, parameters, equations, step and rotation.
fn render_header(o: &mut String, ir: &Ir) {
    let _ = writeln!(
        o,
        "model {}: {} states ({}), {} inputs ({}), {} parameters",
        ir.name,
        ir.states.len(),
        join_capped(&ir.states, ", "),
        ir.inputs.len(),
        join_capped(&ir.inputs, ", "),
        ir.parameters.len()
    );
    let kinds: Vec<String> = ir
        .equations
        .iter()
        .map(|e| {
            format!(
                "{} {}",
                if e.kind == EquationKind::Der {
                    "der"
                } else {
                    "next"
                },
                ir.states[e.state]
            )
        })
        .collect();
    let _ = writeln!(
        o,
        "  equations: {}; step {}",
        join_capped(&kinds, ", "),
        ir.step
            .map_or("from the data's sample time".to_string(), |h| format!(
                "{h}"
            ))
    );
    match &ir.rotation {
        Rotation::None => {}
        Rotation::Planar {
            heading,
            integrates,
            axes,
        } => {
            let _ = writeln!(
                o,
                "  R = Rz({heading})^T on ({}, {}); {heading} integrates {}",
                ir.states[axes[0]], ir.states[axes[1]], ir.states[*integrates]
            );
        }
        Rotation::Measured { .. } => {
            let _ = writeln!(
                o,
                "  R measured from data columns {}",
                ir.rotation_vars.join(", ")
            );
        }
    }
    render_delays(o, ir);
}

/// The declared dead times of inputs, one line: what the equations see.
fn render_delays(o: &mut String, ir: &Ir) {
    if ir.delays.is_empty() {
        return;
    }
    let lags: Vec<String> = ir
        .delays
        .iter()
        .map(|d| {
            let input = ir.inputs.get(d.input).map_or("?", String::as_str);
            match (d.lag, ir.step) {
                (crate::ir::Lag::Samples(n), Some(h)) => {
                    #[allow(clippy::cast_precision_loss)]
                    let seconds = n as f64 * h;
                    format!("{input} {n} samples ({seconds} s)")
                }
                (crate::ir::Lag::Samples(n), None) => format!("{input} {n} samples"),
                (crate::ir::Lag::Seconds(s), _) => {
                    format!("{input} {s} s (whole samples of the data's sample time)")
                }
            }
        })
        .collect();
    let _ = writeln!(
        o,
        "  dead times: {} (the equations at sample k see the input at k − d)",
        join_capped(&lags, ", ")
    );
}

/// One line per disturbance: frame, components and relative velocities.
fn render_disturbances(o: &mut String, ir: &Ir) {
    let mut relatives_of: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for r in &ir.relatives {
        relatives_of
            .entry(ir.disturbances[r.disturbance].name.as_str())
            .or_default()
            .push(r.name.as_str());
    }
    for d in &ir.disturbances {
        let comps: Vec<String> = d
            .components
            .iter()
            .map(|c| {
                let comp = &ir.components[*c];
                match comp.state {
                    Some(s) => format!("{}: {}", ir.states[s], comp.name),
                    None => comp.name.clone(),
                }
            })
            .collect();
        let rel: Vec<&str> = relatives_of
            .get(d.name.as_str())
            .cloned()
            .unwrap_or_default();
        let _ = writeln!(
            o,
            "  disturbance {} {} {}({}){}",
            d.name,
            if d.measured { "measured" } else { "unmeasured" },
            if d.earth { "earth" } else { "body" },
            join_capped(&comps, ", "),
            if rel.is_empty() {
                String::new()
            } else {
                format!(", seen through {}", join_capped(&rel, ", "))
            }
        );
    }
}

/// The sign arguments, by how the predictors evaluate them.
fn render_sign_args(o: &mut String, ir: &Ir) {
    let fixed: Vec<&str> = ir
        .sign_args
        .iter()
        .filter(|s| !s.measured && !s.pointwise)
        .map(|s| s.name.as_str())
        .collect();
    let measured: Vec<&str> = ir
        .sign_args
        .iter()
        .filter(|s| s.measured)
        .map(|s| s.name.as_str())
        .collect();
    let plain: Vec<&str> = ir
        .sign_args
        .iter()
        .filter(|s| s.pointwise)
        .map(|s| s.name.as_str())
        .collect();
    let mut parts = Vec::new();
    if !fixed.is_empty() {
        parts.push(format!(
            "{} (one sign per experiment)",
            join_capped(&fixed, ", ")
        ));
    }
    if !measured.is_empty() {
        parts.push(format!(
            "{} (measured medium, pointwise in IV3, fixed in IV2)",
            join_capped(&measured, ", ")
        ));
    }
    if !plain.is_empty() {
        parts.push(format!(
            "{} (plain states: pointwise in every predictor, as simulated)",
            join_capped(&plain, ", ")
        ));
    }
    let _ = writeln!(
        o,
        "  sign arguments: {}",
        if parts.is_empty() {
            "none".to_string()
        } else {
            parts.join("; ")
        }
    );
}

/// Φ: the θ regressors of each output.
fn render_theta(o: &mut String, ir: &Ir) {
    let cols = &ir.predictors.measured;
    let _ = writeln!(o, "\nΦ: θ regressors ({} parameters)", ir.parameters.len());
    let by_output = columns_by_output(
        cols.iter().filter(|c| !c.kind.is_nuisance()),
        ir.states.len(),
    );
    let written = written_terms(ir);
    for ((out, state), theta) in ir.states.iter().enumerate().zip(by_output) {
        let kind = if ir.equations[out].kind == EquationKind::Der {
            "der"
        } else {
            "next"
        };
        let _ = writeln!(o, "  {kind} {state} ({} terms)", theta.len());
        for c in theta {
            let p = c.kind.parameter();
            let text = written.get(&(p, out)).map_or("", String::as_str);
            let tag = if ir.parameters[p].measured {
                "  [Φ2]"
            } else {
                ""
            };
            let _ = writeln!(
                o,
                "    {:<8} {:<22} = {}{tag}",
                c.name,
                text,
                column_text(ir, c, out)
            );
        }
    }
}

/// The nuisance regressors of each output, and their reduction.
fn render_nuisance(o: &mut String, ir: &Ir) {
    let cols = &ir.predictors.measured;
    let nuis: Vec<&Column> = cols.iter().filter(|c| c.kind.is_nuisance()).collect();
    let unmeasured: Vec<&str> = ir
        .disturbances
        .iter()
        .filter(|d| !d.measured)
        .map(|d| d.name.as_str())
        .collect();
    let _ = writeln!(
        o,
        "\nNuisance regressors ({} unreduced; moments of {})",
        nuis.len(),
        if unmeasured.is_empty() {
            "no unmeasured disturbance".to_string()
        } else {
            join_capped(&unmeasured, ", ")
        }
    );
    let by_output = columns_by_output(nuis.iter().copied(), ir.states.len());
    for ((out, state), mine) in ir.states.iter().enumerate().zip(by_output) {
        if mine.is_empty() {
            continue;
        }
        let _ = writeln!(o, "  {state}");
        for c in mine {
            let _ = writeln!(o, "    {:<24} {}", c.name, column_text(ir, c, out));
        }
    }
    let r = &ir.report;
    let _ = writeln!(
        o,
        "\nNuisance reduction at {}{}: {} -> {}",
        patterns_text(ir, &r.patterns, PredictorKind::Measured),
        if r.any_single_pattern && r.patterns.len() == 1 {
            " (one pattern shown; any single one identifies θ)"
        } else {
            ""
        },
        r.nuisance.before,
        r.nuisance.after
    );
    for k in &r.nuisance.kept {
        let _ = writeln!(o, "  kept    {:<24} estimates {}", k.name, k.estimates);
    }
    for d in &r.nuisance.dropped {
        let _ = writeln!(o, "  dropped {:<24} {}", d.name, d.reason);
    }
}

/// What the data must also do for a structurally identifiable θ to be
/// estimated: conditions on the data, not on the structure, which
/// `estimate` checks on the data it is given and `design` plans for. One
/// line per measured medium whose parameters need it to vary.
pub fn data_conditions(ir: &Ir) -> Vec<String> {
    ir.disturbances
        .iter()
        .enumerate()
        .filter(|(_, d)| d.measured)
        .filter_map(|(i, d)| {
            let names: Vec<String> = ir
                .parameters
                .iter()
                .filter(|p| p.medium == Some(i))
                .map(|p| format!("`{}`", p.name))
                .collect();
            (!names.is_empty()).then(|| {
                format!(
                    "{} ({}, measured): only from data in which the {} varies and moves differently from the other media; in a steady {} their regressors are combinations of the others, and `estimate` holds them with a warning",
                    names.join(", "),
                    d.name,
                    d.name,
                    d.name
                )
            })
        })
        .collect()
}

/// The verdict section of the report alone (`Identifiability of θ` and
/// its lines), for a caller that shows it apart (the language server).
pub fn verdict(ir: &Ir) -> String {
    let mut o = String::new();
    render_verdict(&mut o, ir);
    o
}

/// Whether θ is identifiable, and from which experiments.
fn render_verdict(o: &mut String, ir: &Ir) {
    let r = &ir.report;
    let _ = writeln!(o, "\nIdentifiability of θ");
    if let Some(c) = r.centring {
        let _ = writeln!(
            o,
            "  instrument centring: {} ({})",
            c.name(),
            r.centring_reason
        );
    }
    if r.identifiable && r.required_patterns.len() <= 1 {
        if r.any_single_pattern {
            let _ = writeln!(o, "  identifiable from one experiment of any sign pattern");
        } else {
            let _ = writeln!(
                o,
                "  identifiable from one experiment with sign pattern {}",
                patterns_text(ir, &r.required_patterns, PredictorKind::Measured)
            );
        }
    } else if r.identifiable {
        let _ = writeln!(
            o,
            "  identifiable from {} experiments with sign patterns {}",
            r.required_patterns.len(),
            patterns_text(ir, &r.required_patterns, PredictorKind::Measured)
        );
    }
    let conditions = data_conditions(ir);
    if r.identifiable && !conditions.is_empty() {
        let _ = writeln!(
            o,
            "  (structurally: from data that excite every regressor; conditions on the data, checked by `estimate` and planned for by `design`:)"
        );
        for c in conditions {
            let _ = writeln!(o, "    - {c}");
        }
    }
    if let Some(cut) = r.search_cut.as_ref().filter(|_| r.identifiable) {
        let _ = writeln!(
            o,
            "  verdict undecided: whether fewer experiments suffice ({cut})"
        );
    }
    if r.identifiable {
        // Said above.
    } else if Analysis::new(ir, PredictorKind::Measured).identifiable(Patterns::All) {
        // Every sign pattern together identifies θ, but not the analysed ones.
        let _ = writeln!(
            o,
            "  NOT identifiable from the analysed experiments {}; more experiments would identify it",
            patterns_text(ir, &r.patterns, PredictorKind::Measured)
        );
    } else {
        let _ = writeln!(o, "  NOT identifiable from any set of experiments");
    }
}

/// The unidentifiable groups, what separates them, the aggregates and the notes.
fn render_groups(o: &mut String, ir: &Ir, shown: &[&str]) {
    let r = &ir.report;
    if !r.unidentifiable.is_empty() {
        let base = r
            .patterns
            .first()
            .map(|p| pattern_text(ir, p, PredictorKind::Measured))
            .unwrap_or_default();
        let _ = writeln!(o, "  from one experiment {base}:");
        for c in &r.unidentifiable {
            let _ = writeln!(o, "    {}", c.message);
        }
    }
    for s in &r.separations {
        let _ = writeln!(o, "    {}", s.message);
    }
    if !r.aggregates.is_empty() {
        let _ = writeln!(
            o,
            "  aggregated (absorbed parameters held at their nominal values):"
        );
        for a in &r.aggregates {
            let _ = writeln!(
                o,
                "    {} estimates {}",
                ir.parameters[a.parameter].name, a.estimates
            );
        }
    }
    for n in r.notes.iter().filter(|n| !shown.contains(&n.as_str())) {
        let _ = writeln!(o, "  note: {n}");
    }
}
