//! The sample time and the rotation: a planar heading or a measured `R`,
//! declared once.

use crate::exact::{Q, decimal};
use leeway_grammar::{Diagnostic, Ident, Item, ModelSyntax, Number, RotationRow, Span};
use num_traits::Zero;
use std::collections::BTreeMap;

use super::decl::{Resolved, RotationDecl, Symbol};
use super::symbols::{declare, duplicate, invalid_number, not_a_state, state_of};

/// The step and the rotation (a heading or a measured `rotation`), in the
/// order written; returns the span of the first heading or rotation.
pub(super) fn resolve_step_and_rotation(
    r: &mut Resolved,
    model: &ModelSyntax,
    diags: &mut Vec<Diagnostic>,
) -> Option<Span> {
    let mut rotation_span: Option<Span> = None;
    let mut step_span: Option<Span> = None;
    for item in &model.items {
        match item {
            Item::Step { value, span } => {
                if let Some(first) = step_span {
                    diags.push(
                        Diagnostic::error("duplicate-declaration", "`step` is declared twice")
                            .with_primary(*span, "second step")
                            .with_secondary(first, "first declared here")
                            .with_help("a model has one sample time"),
                    );
                    continue;
                }
                step_span = Some(*span);
                resolve_step(r, value, diags);
            }
            Item::Heading {
                name,
                integrates,
                axes,
                span,
            } => {
                if let Some(first) = rotation_span {
                    diags.push(rotation_conflict(*span, first));
                    continue;
                }
                rotation_span = Some(*span);
                resolve_heading(r, name, integrates, axes.as_ref(), *span, diags);
            }
            Item::Rotation { rows, span } => {
                if let Some(first) = rotation_span {
                    diags.push(rotation_conflict(*span, first));
                    continue;
                }
                rotation_span = Some(*span);
                resolve_rotation(r, rows, diags);
            }
            _ => {}
        }
    }
    rotation_span
}

/// `step h`: a positive decimal.
fn resolve_step(r: &mut Resolved, value: &Number, diags: &mut Vec<Diagnostic>) {
    match decimal(&value.text) {
        Ok(q) if q > Q::zero() => r.step = Some((q, value.span)),
        Err(why) => diags.push(invalid_number(why, value.span)),
        Ok(_) => diags.push(
            Diagnostic::error(
                "invalid-step",
                format!(
                    "the sample time must be positive, found `{}`",
                    crate::exact::shown(&value.text)
                ),
            )
            .with_primary(value.span, "not a positive number")
            .with_help("write the sample time in seconds, e.g. `step 0.1`"),
        ),
    }
}

/// `heading psi integrates r axes(u, v)`: a planar rotation.
fn resolve_heading(
    r: &mut Resolved,
    name: &Ident,
    integrates: &Ident,
    axes: Option<&(Ident, Ident)>,
    span: Span,
    diags: &mut Vec<Diagnostic>,
) {
    declare(r, diags, name, Symbol::Heading, "the heading");
    let Some(yaw) = state_of(r, integrates) else {
        diags.push(not_a_state(r, integrates, "the integrated yaw rate"));
        return;
    };
    if let Some(axes) = heading_axes(r, axes, span, diags) {
        r.rotation = RotationDecl::Planar {
            heading: name.clone(),
            integrates: yaw,
            axes,
        };
    }
}

/// The two states a heading rotates: those named, else the first two.
fn heading_axes(
    r: &Resolved,
    axes: Option<&(Ident, Ident)>,
    span: Span,
    diags: &mut Vec<Diagnostic>,
) -> Option<[usize; 2]> {
    match axes {
        Some((a, b)) => match (state_of(r, a), state_of(r, b)) {
            (Some(i), Some(j)) if i != j => Some([i, j]),
            (Some(_), Some(_)) => {
                diags.push(
                    Diagnostic::error(
                        "heading-axes",
                        "the two heading axes must be different states",
                    )
                    .with_primary(b.span, "same as the first axis")
                    .with_help("name the surge and sway states, e.g. `axes(u, v)`"),
                );
                None
            }
            (None, _) => {
                diags.push(not_a_state(r, a, "a heading axis"));
                None
            }
            (_, None) => {
                diags.push(not_a_state(r, b, "a heading axis"));
                None
            }
        },
        None if r.states.len() >= 2 => Some([0, 1]),
        None => {
            diags.push(
                Diagnostic::error(
                    "heading-axes",
                    "a planar heading rotates two states, but fewer are declared",
                )
                .with_primary(span, "needs two body axes")
                .with_help("declare surge and sway states, or name them with `axes(u, v)`"),
            );
            None
        }
    }
}

/// `rotation { state: [col, ..], .. }`: a measured rotation, its columns
/// declared in the order they first appear.
fn resolve_rotation(r: &mut Resolved, rows: &[RotationRow], diags: &mut Vec<Diagnostic>) {
    let mut columns: Vec<Ident> = Vec::new();
    let mut table = vec![Vec::new(); r.states.len()];
    let mut width: Option<usize> = None;
    let mut seen_rows: BTreeMap<usize, Span> = BTreeMap::new();
    for row in rows {
        let Some(si) = state_of(r, &row.state) else {
            diags.push(not_a_state(r, &row.state, "a rotation row"));
            continue;
        };
        if let Some(first) = seen_rows.insert(si, row.state.span) {
            diags.push(duplicate(&row.state, first, "a rotation row"));
            continue;
        }
        match width {
            None => width = Some(row.entries.len()),
            Some(w) if w != row.entries.len() => diags.push(
                Diagnostic::error(
                    "rotation-shape",
                    format!(
                        "this rotation row has {} entries, the first had {w}",
                        row.entries.len()
                    ),
                )
                .with_primary(row.span, "different length")
                .with_help("every row of R has one entry per earth-frame disturbance component"),
            ),
            Some(_) => {}
        }
        let mut entries = Vec::new();
        for e in &row.entries {
            entries.push(e.as_ref().map(
                |id| match columns.iter().position(|c| c.name == id.name) {
                    Some(k) => k,
                    None => {
                        columns.push(id.clone());
                        columns.len() - 1
                    }
                },
            ));
        }
        table[si] = entries;
    }
    for (k, c) in columns.iter().enumerate() {
        declare(r, diags, c, Symbol::RotationColumn(k), "a rotation column");
    }
    let width = width.unwrap_or(0);
    for row in table.iter_mut() {
        row.resize(width, None);
    }
    r.rotation = RotationDecl::Measured {
        columns,
        rows: table,
        width,
    };
}

/// A second heading or rotation.
fn rotation_conflict(span: Span, first: Span) -> Diagnostic {
    Diagnostic::error("rotation-conflict", "the model declares R twice")
        .with_primary(span, "second heading/rotation")
        .with_secondary(first, "first declared here")
        .with_help("use either `heading .. integrates ..` (planar) or `rotation { .. }` (measured R), once")
}
