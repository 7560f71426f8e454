//! The JSON document of `leeway check --json`: a contract scripts rely on
//! (docs/json.md). Fields may be added; none is renamed or removed.

use leeway_select::CandidateSummary;
use leeway_structure::Compilation;
use leeway_structure::grammar::{self, Diagnostic, Severity};
use leeway_structure::identify::{relevant_signs, shown_signs};
use leeway_structure::ir::{
    ColumnKind, Ir, PredictorKind, Report, Separation as IrSeparation, SignPattern,
};
use leeway_structure::render::{column_text, written_terms};
use serde::Serialize;
use std::collections::BTreeMap;

/// The whole document.
#[derive(Debug, Serialize)]
pub struct CheckReport {
    /// `model Name`, or null when the file does not parse.
    model: Option<String>,
    /// The file as given on the command line.
    file: String,
    /// The states (one equation, one output each).
    outputs: Vec<String>,
    /// θ, in order of first appearance.
    parameters: Vec<String>,
    /// θ identifiable from the required (or the given) sign patterns.
    identifiable: bool,
    /// `identifiable` (exit 0), `not-identifiable` (exit 1), `undecided` (θ
    /// identifiable from `required_sign_patterns`, exit 0, but the search for
    /// a smaller set was cut by its budget); null when the model has errors.
    verdict: Option<&'static str>,
    /// With `undecided`: what the search did not try; null otherwise.
    search_cut: Option<String>,
    /// θ identifiable from one experiment whatever its sign pattern.
    any_single_pattern: bool,
    /// Conditions on the data, not on the structure, for the verdict to
    /// hold on a record (a measured medium must vary); `estimate` checks
    /// them on its data, `design` plans for them.
    data_conditions: Vec<String>,
    /// `--aggregate` was given.
    aggregate: bool,
    /// The instruments' centring the verdicts assume (`--centring`, or the
    /// model's) and why it is valid; null when the model has errors.
    centring: Option<CentringJson>,
    /// The `Φ` part: one entry per (parameter, output).
    regressors: Vec<Regressor>,
    /// The nuisance parameters before and after reduction.
    nuisance: Nuisance,
    /// Arguments under a modulus and whether the analysed predictor fixes their sign.
    sign_arguments: Vec<SignArgument>,
    /// The smallest set of experiments identifying θ, each `{argument: "+" | "-"}`; empty if none.
    required_sign_patterns: Vec<BTreeMap<String, String>>,
    /// The experiments the nuisance reduction and the verdicts were computed for.
    analysed_sign_patterns: Vec<BTreeMap<String, String>>,
    /// Parameter groups that enter only through combinations at the analysed patterns.
    unidentifiable: Vec<Unidentifiable>,
    /// What separates each unidentifiable group, if anything does.
    separations: Vec<Separation>,
    /// With `--aggregate`: what each kept parameter estimates.
    aggregates: Vec<Aggregate>,
    /// A candidate model's candidates (`?name`), the full set's verdict and
    /// the exchangeable candidates; null without candidates.
    candidates: Option<CandidateSummary>,
    /// Diagnostics by severity.
    errors: Vec<JsonDiagnostic>,
    warnings: Vec<JsonDiagnostic>,
    notes: Vec<JsonDiagnostic>,
    /// Diagnostics left out: at most the first 50 of each severity are listed.
    omitted: usize,
}

/// The centring a check analysed.
#[derive(Debug, Serialize)]
struct CentringJson {
    /// `experiment`, `pooled` or `none`.
    name: &'static str,
    /// Why it is valid for the model, one sentence.
    reason: String,
}

#[derive(Debug, Serialize)]
struct Regressor {
    parameter: String,
    output: String,
    /// The regressor after expansion, e.g. `s[water.u]*u^2`.
    expression: String,
    /// The term as written, e.g. `water.u*|water.u|`.
    term: String,
    /// `phi` (expanded) or `phi2` (measured medium, evaluated pointwise in IV3).
    kind: &'static str,
}

#[derive(Debug, Default, Serialize)]
struct Nuisance {
    before: usize,
    after: usize,
    kept: Vec<Kept>,
    dropped: Vec<Dropped>,
    /// Every unreduced nuisance column, per output.
    regressors: Vec<NuisanceRegressor>,
}

#[derive(Debug, Serialize)]
struct Kept {
    name: String,
    estimates: String,
}

#[derive(Debug, Serialize)]
struct Dropped {
    name: String,
    reason: String,
}

#[derive(Debug, Serialize)]
struct NuisanceRegressor {
    name: String,
    output: String,
    expression: String,
}

#[derive(Debug, Serialize)]
struct SignArgument {
    name: String,
    /// False for arguments relative to a measured medium (evaluated pointwise).
    fixed_per_experiment: bool,
}

#[derive(Debug, Serialize)]
struct Unidentifiable {
    parameters: Vec<String>,
    combinations: Vec<String>,
    message: String,
}

#[derive(Debug, Serialize)]
struct Separation {
    parameters: Vec<String>,
    /// The experiments that separate the group, or null when none can.
    sign_patterns: Option<Vec<BTreeMap<String, String>>>,
    message: String,
}

#[derive(Debug, Serialize)]
struct Aggregate {
    parameter: String,
    estimates: String,
    absorbed: Vec<String>,
}

/// A diagnostic: stable code, severity, message, `file:line:col` of its
/// primary span (null for model-wide findings), help and notes.
#[derive(Debug, Serialize)]
pub struct JsonDiagnostic {
    code: String,
    severity: &'static str,
    message: String,
    location: Option<String>,
    file: String,
    line: Option<usize>,
    column: Option<usize>,
    end_line: Option<usize>,
    end_column: Option<usize>,
    labels: Vec<JsonLabel>,
    help: Option<String>,
    notes: Vec<String>,
}

#[derive(Debug, Serialize)]
struct JsonLabel {
    message: String,
    primary: bool,
    line: usize,
    column: usize,
    end_line: usize,
    end_column: usize,
}

fn severity(s: Severity) -> &'static str {
    match s {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Note => "note",
    }
}

/// A diagnostic in the JSON shape, its spans as lines and columns of `source`.
pub fn diagnostic(file: &str, source: &str, d: &Diagnostic) -> JsonDiagnostic {
    let at = |offset: usize| grammar::line_col(source, offset);
    let primary = d.primary_span();
    let (line, column) = primary.map(|s| at(s.start)).unzip();
    let (end_line, end_column) = primary.map(|s| at(s.end)).unzip();
    JsonDiagnostic {
        code: d.code.clone(),
        severity: severity(d.severity),
        message: d.message.clone(),
        location: line.zip(column).map(|(l, c)| format!("{file}:{l}:{c}")),
        file: file.to_string(),
        line,
        column,
        end_line,
        end_column,
        labels: d
            .labels
            .iter()
            .map(|l| {
                let ((line, column), (end_line, end_column)) = (at(l.span.start), at(l.span.end));
                JsonLabel {
                    message: l.message.clone(),
                    primary: l.primary,
                    line,
                    column,
                    end_line,
                    end_column,
                }
            })
            .collect(),
        help: d.help.clone(),
        notes: d.notes.clone(),
    }
}

/// A set of experiments as `{argument: sign}` maps: the signs the predictor
/// fixes, plus any pointwise sign some pattern of the set makes negative (as
/// the text report shows them).
fn patterns(ir: &Ir, set: &[SignPattern]) -> Vec<BTreeMap<String, String>> {
    let shown = shown_signs(set, &relevant_signs(ir, PredictorKind::Measured));
    set.iter()
        .map(|p| {
            shown
                .iter()
                .map(|&i| {
                    let sign = if p.get(i).copied().unwrap_or(1) < 0 {
                        "-"
                    } else {
                        "+"
                    };
                    (ir.sign_args[i].name.clone(), sign.to_string())
                })
                .collect()
        })
        .collect()
}

fn names(ir: &Ir, params: &[usize]) -> Vec<String> {
    params
        .iter()
        .map(|p| ir.parameters[*p].name.clone())
        .collect()
}

/// The document for a compiled (or rejected) model.
pub fn report(file: &str, source: &str, c: &Compilation, aggregate: bool) -> CheckReport {
    let mut report = full_report(file, source, c, aggregate);
    let listed = report.errors.len() + report.warnings.len() + report.notes.len();
    report.omitted = c.diagnostics.len().saturating_sub(listed);
    report
}

fn full_report(file: &str, source: &str, c: &Compilation, aggregate: bool) -> CheckReport {
    let by = |s: Severity| -> Vec<JsonDiagnostic> {
        c.diagnostics
            .iter()
            .filter(|d| d.severity == s)
            .take(grammar::MAX_RENDERED)
            .map(|d| diagnostic(file, source, d))
            .collect()
    };
    let (errors, warnings, notes) = (
        by(Severity::Error),
        by(Severity::Warning),
        by(Severity::Note),
    );
    let Some(ir) = &c.ir else {
        let model = grammar::parse(source).0.map(|m| m.name.name);
        return CheckReport {
            errors,
            warnings,
            notes,
            ..empty(model, file, aggregate)
        };
    };
    let r = &ir.report;
    let relevant = relevant_signs(ir, PredictorKind::Measured);
    let (regressors, nuisance_regressors) = regressors(ir);
    CheckReport {
        model: Some(ir.name.clone()),
        file: file.to_string(),
        outputs: ir.states.clone(),
        parameters: ir.parameters.iter().map(|p| p.name.clone()).collect(),
        identifiable: r.identifiable,
        verdict: (!c.has_errors() || c.only_unidentifiable()).then(|| r.verdict()),
        search_cut: r.search_cut.clone(),
        any_single_pattern: r.any_single_pattern,
        data_conditions: leeway_structure::render::data_conditions(ir),
        aggregate,
        centring: r.centring.map(|c| CentringJson {
            name: c.name(),
            reason: r.centring_reason.clone(),
        }),
        regressors,
        nuisance: nuisance(r, nuisance_regressors),
        sign_arguments: ir
            .sign_args
            .iter()
            .map(|s| SignArgument {
                name: s.name.clone(),
                fixed_per_experiment: !s.measured,
            })
            .collect(),
        required_sign_patterns: patterns(ir, &r.required_patterns),
        analysed_sign_patterns: patterns(ir, &r.patterns),
        unidentifiable: r
            .unidentifiable
            .iter()
            .map(|u| Unidentifiable {
                parameters: names(ir, &u.parameters),
                combinations: u.identifiable.clone(),
                message: u.message.clone(),
            })
            .collect(),
        separations: separations(ir, &r.separations, &relevant),
        aggregates: r
            .aggregates
            .iter()
            .map(|a| Aggregate {
                parameter: ir.parameters[a.parameter].name.clone(),
                estimates: a.estimates.clone(),
                absorbed: names(ir, &a.absorbed),
            })
            .collect(),
        candidates: leeway_select::summary(source, ir),
        errors,
        warnings,
        notes,
        omitted: 0,
    }
}

/// The θ regressors (with the terms written for them) and the nuisance
/// regressors of the measured predictor, output by output.
fn regressors(ir: &Ir) -> (Vec<Regressor>, Vec<NuisanceRegressor>) {
    let columns = &ir.predictors.measured;
    let mut regressors = Vec::new();
    let mut nuisance_regressors = Vec::new();
    let by_output = leeway_structure::ir::columns_by_output(columns, ir.states.len());
    let written = written_terms(ir);
    for ((out, state), mine) in ir.states.iter().enumerate().zip(by_output) {
        for col in mine {
            let expression = column_text(ir, col, out);
            match col.kind {
                ColumnKind::Theta { parameter } => {
                    let term = written.get(&(parameter, out)).cloned().unwrap_or_default();
                    regressors.push(Regressor {
                        parameter: ir.parameters[parameter].name.clone(),
                        output: state.clone(),
                        expression,
                        term,
                        kind: if ir.parameters[parameter].measured {
                            "phi2"
                        } else {
                            "phi"
                        },
                    });
                }
                _ => nuisance_regressors.push(NuisanceRegressor {
                    name: col.name.clone(),
                    output: state.clone(),
                    expression,
                }),
            }
        }
    }
    (regressors, nuisance_regressors)
}

/// The nuisance parameters kept and dropped by the analysis.
fn nuisance(r: &Report, regressors: Vec<NuisanceRegressor>) -> Nuisance {
    Nuisance {
        before: r.nuisance.before,
        after: r.nuisance.after,
        kept: r
            .nuisance
            .kept
            .iter()
            .map(|k| Kept {
                name: k.name.clone(),
                estimates: k.estimates.clone(),
            })
            .collect(),
        dropped: r
            .nuisance
            .dropped
            .iter()
            .map(|d| Dropped {
                name: d.name.clone(),
                reason: d.reason.clone(),
            })
            .collect(),
        regressors,
    }
}

/// Each separation of parameters with the sign patterns that separate them.
fn separations(ir: &Ir, separations: &[IrSeparation], relevant: &[usize]) -> Vec<Separation> {
    separations
        .iter()
        .map(|s| Separation {
            parameters: names(ir, &s.parameters),
            sign_patterns: s.patterns.as_ref().map(|set| {
                // The group's own arguments the predictor fixes, and any
                // sign made negative (the patterns hold nothing else).
                set.iter()
                    .map(|p| {
                        s.arguments
                            .iter()
                            .zip(p)
                            .filter(|(a, sign)| **sign < 0 || relevant.binary_search(a).is_ok())
                            .map(|(a, sign)| {
                                let text = if *sign < 0 { "-" } else { "+" };
                                (ir.sign_args[*a].name.clone(), text.to_string())
                            })
                            .collect()
                    })
                    .collect()
            }),
            message: s.message.clone(),
        })
        .collect()
}

/// The document for a failure before compiling (unreadable file, bad `--pattern`).
pub fn failure(file: &str, d: Diagnostic, aggregate: bool) -> CheckReport {
    let error = JsonDiagnostic {
        code: d.code,
        severity: severity(d.severity),
        message: d.message,
        location: None,
        file: file.to_string(),
        line: None,
        column: None,
        end_line: None,
        end_column: None,
        labels: Vec::new(),
        help: d.help,
        notes: d.notes,
    };
    CheckReport {
        errors: vec![error],
        ..empty(None, file, aggregate)
    }
}

fn empty(model: Option<String>, file: &str, aggregate: bool) -> CheckReport {
    CheckReport {
        model,
        file: file.to_string(),
        outputs: Vec::new(),
        parameters: Vec::new(),
        identifiable: false,
        verdict: None,
        search_cut: None,
        any_single_pattern: false,
        data_conditions: Vec::new(),
        aggregate,
        centring: None,
        regressors: Vec::new(),
        nuisance: Nuisance::default(),
        sign_arguments: Vec::new(),
        required_sign_patterns: Vec::new(),
        analysed_sign_patterns: Vec::new(),
        unidentifiable: Vec::new(),
        separations: Vec::new(),
        aggregates: Vec::new(),
        candidates: None,
        errors: Vec::new(),
        warnings: Vec::new(),
        notes: Vec::new(),
        omitted: 0,
    }
}
