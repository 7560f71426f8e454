//! Pass 7, lower: resolved declarations, terms and columns → the IR.

use crate::exact::{fmt_q, to_f64};
use crate::ir::{self, Ir, Predictors, Report, SignArg};
use crate::resolve::decl::{Resolved, RotationDecl};
use crate::terms::{ParamDecl, TermDecl, arg_medium, factors_text};
use leeway_grammar::{Diagnostic, EquationKind};
use std::collections::{BTreeMap, BTreeSet};

/// Builds the IR (without the report, which `identify::report` fills).
pub fn lower(
    r: &Resolved,
    params: &[ParamDecl],
    terms: &[TermDecl],
    sign_args: Vec<SignArg>,
    predictors: Predictors,
    diags: &mut Vec<Diagnostic>,
) -> Ir {
    let (rotation, rotation_vars) = lower_rotation(&r.rotation);
    let nominal = nominal_values(r, params, diags);
    let parameters = lower_parameters(r, params, terms, &nominal);
    let ir_terms = terms
        .iter()
        .map(|t| ir::Term {
            output: t.output,
            coefficient: to_f64(&t.coefficient),
            coefficient_exact: fmt_q(&t.coefficient),
            parameter: t.parameter,
            factors: t.factors.clone(),
            text: factors_text(r, &t.factors),
            span: t.span,
        })
        .collect();
    Ir {
        name: r.name.name.clone(),
        step: r.step.as_ref().map(|(q, _)| to_f64(q)),
        states: r.states.iter().map(|s| s.name.clone()).collect(),
        inputs: r.inputs.iter().map(|s| s.name.clone()).collect(),
        rotation,
        rotation_vars,
        disturbances: r
            .disturbances
            .iter()
            .map(|d| ir::Disturbance {
                name: d.name.name.clone(),
                measured: d.measured,
                earth: d.earth,
                components: d.components.clone(),
            })
            .collect(),
        components: r
            .components
            .iter()
            .map(|c| ir::Component {
                name: c.name.name.clone(),
                disturbance: c.disturbance,
                state: c.state,
            })
            .collect(),
        relatives: r
            .relatives
            .iter()
            .map(|(n, d)| ir::Relative {
                name: n.name.clone(),
                disturbance: *d,
            })
            .collect(),
        equations: r
            .equations
            .iter()
            .enumerate()
            .map(|(i, e)| ir::Equation {
                state: i,
                kind: e.as_ref().map_or(EquationKind::Der, |e| e.kind),
            })
            .collect(),
        parameters,
        terms: ir_terms,
        sign_args,
        predictors,
        data_columns: r
            .data
            .iter()
            .map(|(id, col, _)| (id.name.clone(), col.clone()))
            .collect(),
        data_units: r
            .units
            .iter()
            .map(|(id, unit, _)| (id.name.clone(), unit.clone()))
            .collect(),
        delays: r
            .delays
            .iter()
            .map(|(input, lag, _)| ir::Delay {
                input: *input,
                lag: *lag,
            })
            .collect(),
        report: Report::default(),
    }
}

/// The rotation and the names of its variables.
fn lower_rotation(rotation: &RotationDecl) -> (ir::Rotation, Vec<String>) {
    match rotation {
        RotationDecl::None => (ir::Rotation::None, Vec::new()),
        RotationDecl::Planar {
            heading,
            integrates,
            axes,
        } => (
            ir::Rotation::Planar {
                heading: heading.name.clone(),
                integrates: *integrates,
                axes: *axes,
            },
            vec![
                format!("cos({})", heading.name),
                format!("sin({})", heading.name),
            ],
        ),
        RotationDecl::Measured { columns, rows, .. } => (
            ir::Rotation::Measured { rows: rows.clone() },
            columns.iter().map(|c| c.name.clone()).collect(),
        ),
    }
}

/// The nominal values by parameter name; an error for a name no term uses.
fn nominal_values<'a>(
    r: &'a Resolved,
    params: &[ParamDecl],
    diags: &mut Vec<Diagnostic>,
) -> BTreeMap<&'a str, f64> {
    let names: BTreeSet<&str> = params.iter().map(|p| p.name.as_str()).collect();
    let mut nominal: BTreeMap<&str, f64> = BTreeMap::new();
    for (id, q, span) in &r.nominal {
        if names.contains(id.name.as_str()) {
            nominal.insert(&id.name, to_f64(q));
        } else {
            diags.push(
                Diagnostic::error(
                    "unknown-parameter",
                    format!("`{}` is not a parameter of this model", id.name),
                )
                .with_primary(*span, "no term uses it")
                .with_help(format!(
                    "parameters: {}",
                    leeway_grammar::join_capped(params.iter().map(|p| p.name.as_str()), ", ")
                )),
            );
        }
    }
    nominal
}

/// Each parameter with its nominal value, medium, whether that medium is
/// measured, and the outputs it enters.
fn lower_parameters(
    r: &Resolved,
    params: &[ParamDecl],
    terms: &[TermDecl],
    nominal: &BTreeMap<&str, f64>,
) -> Vec<ir::Parameter> {
    // The terms of each parameter, in one pass (a model may have 10⁴ parameters).
    let mut by_parameter: Vec<Vec<&TermDecl>> = vec![Vec::new(); params.len()];
    for t in terms {
        if let Some(mine) = by_parameter.get_mut(t.parameter) {
            mine.push(t);
        }
    }
    params
        .iter()
        .zip(by_parameter)
        .map(|(p, mine)| {
            let media: Vec<usize> = {
                let mut m: Vec<usize> = mine
                    .iter()
                    .filter_map(|t| t.factors.iter().find_map(|f| arg_medium(r, &f.arg)))
                    .collect();
                m.sort_unstable();
                m.dedup();
                m
            };
            let medium = if media.len() == 1 {
                Some(media[0])
            } else {
                None
            };
            let measured = !mine.is_empty()
                && mine.iter().all(|t| {
                    t.factors
                        .iter()
                        .find_map(|f| arg_medium(r, &f.arg))
                        .is_some_and(|d| r.disturbances[d].measured)
                });
            let mut outputs: Vec<usize> = mine.iter().map(|t| t.output).collect();
            outputs.sort_unstable();
            outputs.dedup();
            ir::Parameter {
                name: p.name.clone(),
                nominal: nominal.get(p.name.as_str()).copied().unwrap_or(0.0),
                medium,
                measured,
                outputs,
            }
        })
        .collect()
}
