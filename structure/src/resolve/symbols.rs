//! The symbol table: declaring each name once (states and inputs first, as
//! the other declarations refer to them), looking states up, and the
//! diagnostics that name what is declared.

use leeway_grammar::{Diagnostic, Ident, Item, ModelSyntax, Span};

use super::decl::{Resolved, Symbol};

/// A name declared a second time.
pub(super) fn duplicate(name: &Ident, first: Span, what: &str) -> Diagnostic {
    Diagnostic::error("duplicate-declaration", format!("`{}` is declared twice", name.name))
        .with_primary(name.span, format!("second declaration of {what}"))
        .with_secondary(first, "first declared here")
        .with_help("every state, input, heading, disturbance, component and relative velocity needs its own name")
}

/// Enters a name in the table, or reports it declared twice (`false`).
pub(super) fn declare(
    r: &mut Resolved,
    diags: &mut Vec<Diagnostic>,
    id: &Ident,
    sym: Symbol,
    what: &str,
) -> bool {
    if let Some((_, first)) = r.symbols.get(&id.name) {
        diags.push(duplicate(id, *first, what));
        false
    } else {
        r.symbols.insert(id.name.clone(), (sym, id.span));
        true
    }
}

/// The state a name refers to, if it is one.
pub(super) fn state_of(r: &Resolved, id: &Ident) -> Option<usize> {
    match r.symbols.get(&id.name) {
        Some((Symbol::State(i), _)) => Some(*i),
        _ => None,
    }
}

/// A name where `role` needs a state.
pub(super) fn not_a_state(r: &Resolved, id: &Ident, role: &str) -> Diagnostic {
    let what = match r.symbols.get(&id.name) {
        Some((Symbol::Input(_), _)) => "an input",
        Some(_) => "not a state",
        None => "not declared",
    };
    Diagnostic::error(
        "unknown-name",
        format!("`{}` is {what}; {role} must be a state", id.name),
    )
    .with_primary(id.span, "expected a state")
    .with_help(format!("declared states: {}", names(&r.states)))
}

/// The states and inputs, and an error when there is no state.
pub(super) fn declare_states_and_inputs(
    r: &mut Resolved,
    model: &ModelSyntax,
    diags: &mut Vec<Diagnostic>,
) {
    for item in &model.items {
        match item {
            Item::States(ids) => {
                for id in ids {
                    let k = r.states.len();
                    if declare(r, diags, id, Symbol::State(k), "a state") {
                        r.states.push(id.clone());
                    }
                }
            }
            Item::Inputs(ids) => {
                for id in ids {
                    let k = r.inputs.len();
                    if declare(r, diags, id, Symbol::Input(k), "an input") {
                        r.inputs.push(id.clone());
                    }
                }
            }
            _ => {}
        }
    }
    if r.states.is_empty() {
        diags.push(
            Diagnostic::error(
                "no-states",
                format!("model `{}` declares no state", model.name.name),
            )
            .with_primary(model.name.span, "this model")
            .with_help(
                "declare the measured states, e.g. `state u, v, r`, and give each an equation",
            ),
        );
    }
}

/// `a, b, c` or `none` (at most `MAX_LISTED` names, then a count).
pub fn names(ids: &[Ident]) -> String {
    if ids.is_empty() {
        "none".to_string()
    } else {
        leeway_grammar::join_capped(ids.iter().map(|i| i.name.as_str()), ", ")
    }
}

/// A literal refused by [`decimal`], with the limits in the help.
pub(crate) fn invalid_number(why: String, span: Span) -> Diagnostic {
    Diagnostic::error("invalid-number", why)
        .with_primary(span, "here")
        .with_help(format!(
            "write a decimal of at most {} significant digits between 1e-{} and 1e{} in magnitude, such as -0.15 or 1.5e-4",
            crate::exact::MAX_SIGNIFICANT_DIGITS,
            crate::exact::MAX_DECIMAL_EXPONENT,
            crate::exact::MAX_DECIMAL_EXPONENT + 1
        ))
}
