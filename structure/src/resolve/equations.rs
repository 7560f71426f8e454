//! Equations, nominal values and the data mapping (columns and units), and
//! the states left without an equation.

use crate::exact::decimal;
use leeway_grammar::{DataEntry, Diagnostic, EquationKind, Expr, Ident, Item, ModelSyntax, Span};
use std::collections::BTreeMap;

use super::decl::{EquationDecl, Resolved, RotationDecl, SPECIAL_COLUMNS, Symbol};
use super::symbols::{duplicate, invalid_number, not_a_state};

/// Equations, nominal values and the data mapping, in the order written.
pub(super) fn resolve_equations_and_data(
    r: &mut Resolved,
    model: &ModelSyntax,
    diags: &mut Vec<Diagnostic>,
) {
    r.equations = vec![None; r.states.len()];
    let mut nominal_seen: BTreeMap<String, Span> = BTreeMap::new();
    let mut data_seen: BTreeMap<String, Span> = BTreeMap::new();
    for item in &model.items {
        match item {
            Item::Equation {
                kind,
                state,
                rhs,
                span,
            } => resolve_equation(r, *kind, state, rhs, *span, diags),
            Item::Nominal { entries, .. } => {
                for (id, num) in entries {
                    if let Some(first) = nominal_seen.insert(id.name.clone(), id.span) {
                        diags.push(duplicate(id, first, "a nominal value"));
                        continue;
                    }
                    match decimal(&num.text) {
                        Ok(q) => r.nominal.push((id.clone(), q, id.span)),
                        Err(why) => diags.push(invalid_number(why, num.span)),
                    }
                }
            }
            Item::Data { entries, .. } => {
                for entry in entries {
                    let id = &entry.signal;
                    if let Some(first) = data_seen.insert(id.name.clone(), id.span) {
                        diags.push(duplicate(id, first, "a data column mapping"));
                        continue;
                    }
                    resolve_data_entry(r, entry, diags);
                }
            }
            _ => {}
        }
    }
}

/// `der x = ...` / `next x = ...`: one per state.
fn resolve_equation(
    r: &mut Resolved,
    kind: EquationKind,
    state: &Ident,
    rhs: &Expr,
    span: Span,
    diags: &mut Vec<Diagnostic>,
) {
    match r.symbols.get(&state.name) {
        Some((Symbol::State(i), _)) => {
            let i = *i;
            if let Some(first) = &r.equations[i] {
                diags.push(
                    Diagnostic::error(
                        "duplicate-equation",
                        format!("state `{}` has two equations", state.name),
                    )
                    .with_primary(state.span, "second equation")
                    .with_secondary(first.span, "first equation")
                    .with_help("write all terms of a state in one equation, joined with `+`"),
                );
            } else {
                r.equations[i] = Some(EquationDecl {
                    kind,
                    state: i,
                    rhs: rhs.clone(),
                    span,
                });
            }
        }
        Some((Symbol::Heading, _)) => diags.push(
            Diagnostic::error(
                "heading-equation",
                format!(
                    "`{}` is the heading; it has no equation of its own",
                    state.name
                ),
            )
            .with_primary(state.span, "the heading integrates its yaw rate")
            .with_help(
                "remove this equation: `heading psi integrates r` already gives psi+ = psi + h r",
            ),
        ),
        _ => diags.push(not_a_state(r, state, "the left-hand side of an equation")),
    }
}

/// One entry of `data { signal = "column" in unit }` (not seen before).
fn resolve_data_entry(r: &mut Resolved, entry: &DataEntry, diags: &mut Vec<Diagnostic>) {
    let id = &entry.signal;
    let ok = SPECIAL_COLUMNS.contains(&id.name.as_str())
        || match r.symbols.get(&id.name) {
            Some((
                Symbol::State(_) | Symbol::Input(_) | Symbol::Heading | Symbol::RotationColumn(_),
                _,
            )) => true,
            Some((Symbol::Component(c), _)) => {
                r.disturbances[r.components[*c].disturbance].measured
            }
            _ => false,
        };
    if !ok {
        diags.push(
            Diagnostic::error("unknown-name", format!("`{}` is not a signal read from data", id.name))
                .with_primary(id.span, "cannot map a column to this")
                .with_help("map states, inputs, the heading, rotation columns, measured disturbance components, `time` or `experiment`"),
        );
        return;
    }
    if let Some((column, cspan)) = &entry.column {
        if column.trim().is_empty() {
            diags.push(
                Diagnostic::error(
                    "empty-column-name",
                    format!("the column name for `{}` is empty", id.name),
                )
                .with_primary(*cspan, "empty")
                .with_help("write the CSV header's name between the quotes"),
            );
        } else {
            r.data.push((id.clone(), column.clone(), *cspan));
        }
    }
    if let Some((unit, uspan)) = &entry.unit {
        match unit_problem(r, &id.name, unit) {
            Some((message, help)) => diags.push(
                Diagnostic::error("unknown-unit", message)
                    .with_primary(*uspan, "not a unit for this column")
                    .with_help(help),
            ),
            None => r.units.push((id.clone(), unit.clone(), *uspan)),
        }
    }
}

/// An error per state without an equation.
pub(super) fn missing_equations(r: &Resolved, diags: &mut Vec<Diagnostic>) {
    for (i, eq) in r.equations.iter().enumerate() {
        if eq.is_none() {
            let s = &r.states[i];
            diags.push(
                Diagnostic::error(
                    "missing-equation",
                    format!("state `{}` has no equation", s.name),
                )
                .with_primary(s.span, "declared here")
                .with_help(format!(
                    "add `der {0} = ...` (continuous time) or `next {0} = ...` (discrete time)",
                    s.name
                )),
            );
        }
    }
}

/// What is wrong with `signal in unit`, as (message, help), or `None` when the
/// unit is known and of a kind the signal can have. The kinds follow from the
/// signal's role where the model fixes it (the heading is an angle, the rate it
/// integrates an angular rate, its axes speeds, `time` a time); a state, input
/// or measured component may be any physical quantity except a time.
fn unit_problem(r: &Resolved, signal: &str, unit: &str) -> Option<(String, String)> {
    use crate::units::{Kind, names_of};
    let every = [
        Kind::Angle,
        Kind::AngularRate,
        Kind::Speed,
        Kind::RotationRate,
    ];
    let (allowed, role): (&[Kind], &str) = match (signal, r.symbols.get(signal)) {
        ("time", _) => (&[Kind::Time], "the time stamps"),
        ("experiment", _) => (&[], "the experiment names"),
        (_, Some((Symbol::Heading, _))) => (&[Kind::Angle], "the heading"),
        (_, Some((Symbol::RotationColumn(_), _))) => (&[], "an entry of a measured rotation"),
        (_, Some((Symbol::State(i), _))) => match &r.rotation {
            RotationDecl::Planar { integrates, .. } if integrates == i => {
                (&[Kind::AngularRate], "the yaw rate the heading integrates")
            }
            RotationDecl::Planar { axes, .. } if axes.contains(i) => {
                (&[Kind::Speed], "a velocity the heading rotates")
            }
            _ => (&every, "a state"),
        },
        _ => (&every, "a signal"),
    };
    let kind = crate::units::unit(unit).map(|(k, _)| k);
    if kind.is_some_and(|k| allowed.contains(&k)) {
        return None;
    }
    if allowed.is_empty() {
        return Some((
            format!("`{signal}` takes no unit: it is {role}"),
            format!("remove `in {unit}`"),
        ));
    }
    let message = match kind {
        Some(k) => format!("`{unit}` is {}, but `{signal}` is {role}", k.name()),
        None => format!("unknown unit `{unit}` for `{signal}`"),
    };
    Some((message, format!("units for {role}: {}", names_of(allowed))))
}
