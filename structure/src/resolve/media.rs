//! The media: disturbances with their earth- or body-frame components, and
//! the relative velocities through which they act on the craft.

use leeway_grammar::{BodyComponent, Diagnostic, Frame, Ident, Measurement, Span};
use std::collections::BTreeMap;

use super::decl::{ComponentDecl, DisturbanceDecl, Resolved, RotationDecl, Symbol};
use super::symbols::{declare, duplicate, names, not_a_state, state_of};

/// A disturbance and its components (earth or body frame).
pub(super) fn resolve_disturbance(
    r: &mut Resolved,
    name: &Ident,
    measurement: Measurement,
    frame: &Frame,
    span: Span,
    rotation_span: Option<Span>,
    diags: &mut Vec<Diagnostic>,
) {
    let di = r.disturbances.len();
    if !declare(r, diags, name, Symbol::Disturbance(di), "a disturbance") {
        return;
    }
    let earth = matches!(frame, Frame::Earth(_));
    let comps = match frame {
        Frame::Earth(ids) => {
            check_earth_shape(r, name, ids.len(), span, rotation_span, diags);
            earth_components(r, di, ids, diags)
        }
        Frame::Body(list) => body_components(r, di, list, diags),
    };
    r.disturbances.push(DisturbanceDecl {
        name: name.clone(),
        measured: measurement == Measurement::Measured,
        earth,
        components: comps,
    });
}

/// An earth-frame disturbance needs a rotation with as many columns as it has
/// components.
fn check_earth_shape(
    r: &Resolved,
    name: &Ident,
    n_components: usize,
    span: Span,
    rotation_span: Option<Span>,
    diags: &mut Vec<Diagnostic>,
) {
    let expected = match &r.rotation {
        RotationDecl::Planar { .. } => Some(2),
        RotationDecl::Measured { width, .. } => Some(*width),
        RotationDecl::None => None,
    };
    match expected {
        // A heading or rotation was declared but is invalid: already reported.
        None if rotation_span.is_some() => {}
        None => diags.push(
            Diagnostic::error(
                "missing-rotation",
                format!("`{}` is given in the earth frame, but the model has no heading or rotation", name.name),
            )
            .with_primary(span, "needs R to reach the body frame")
            .with_help("declare `heading psi integrates r` (planar) or `rotation { .. }` (measured R), or give the disturbance in `body(state: component, ..)`"),
        ),
        Some(n) if n != n_components => diags.push(
            Diagnostic::error(
                "earth-components",
                format!("`{}` has {} earth-frame components, R expects {n}", name.name, n_components),
            )
            .with_primary(span, format!("expected {n} components"))
            .with_help(if matches!(r.rotation, RotationDecl::Planar { .. }) {
                "a planar heading rotates (north, east): write `earth(north, east)`".to_string()
            } else {
                "write one component per column of the rotation rows".to_string()
            }),
        ),
        Some(_) => {}
    }
}

/// The components of an earth-frame disturbance `di`; their global indices.
fn earth_components(
    r: &mut Resolved,
    di: usize,
    ids: &[Ident],
    diags: &mut Vec<Diagnostic>,
) -> Vec<usize> {
    let mut comps = Vec::new();
    for id in ids {
        let ci = r.components.len();
        if declare(
            r,
            diags,
            id,
            Symbol::Component(ci),
            "a disturbance component",
        ) {
            r.components.push(ComponentDecl {
                name: id.clone(),
                disturbance: di,
                state: None,
            });
            comps.push(ci);
        }
    }
    comps
}

/// The components of a body-frame disturbance `di`, each on its own state;
/// their global indices.
fn body_components(
    r: &mut Resolved,
    di: usize,
    list: &[BodyComponent],
    diags: &mut Vec<Diagnostic>,
) -> Vec<usize> {
    let mut comps = Vec::new();
    let mut seen: BTreeMap<usize, Span> = BTreeMap::new();
    for bc in list {
        let Some(si) = state_of(r, &bc.state) else {
            diags.push(not_a_state(r, &bc.state, "a body-frame component's axis"));
            continue;
        };
        if let Some(first) = seen.insert(si, bc.state.span) {
            diags.push(duplicate(&bc.state, first, "a body-frame axis"));
            continue;
        }
        let ci = r.components.len();
        if declare(
            r,
            diags,
            &bc.component,
            Symbol::Component(ci),
            "a disturbance component",
        ) {
            r.components.push(ComponentDecl {
                name: bc.component.clone(),
                disturbance: di,
                state: Some(si),
            });
            comps.push(ci);
        }
    }
    comps
}

/// `rel = relative(disturbance)`.
pub(super) fn resolve_relative(
    r: &mut Resolved,
    name: &Ident,
    disturbance: &Ident,
    diags: &mut Vec<Diagnostic>,
) {
    match r.symbols.get(&disturbance.name) {
        Some((Symbol::Disturbance(d), _)) => {
            let d = *d;
            let k = r.relatives.len();
            if declare(r, diags, name, Symbol::Relative(k), "a relative velocity") {
                r.relatives.push((name.clone(), d));
            }
        }
        _ => diags.push(
            Diagnostic::error(
                "unknown-name",
                format!("`{}` is not a declared disturbance", disturbance.name),
            )
            .with_primary(disturbance.span, "expected a disturbance")
            .with_help(format!(
                "declared disturbances: {}",
                names(
                    &r.disturbances
                        .iter()
                        .map(|d| d.name.clone())
                        .collect::<Vec<_>>()
                )
            )),
        ),
    }
}
