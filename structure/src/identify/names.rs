//! Message context: the names of parameters, columns and components, and
//! linear combinations written as text.

use crate::exact::{Q, fmt_q};
use crate::ir::{Centring, Column, ColumnKind, Ir};
use leeway_grammar::{MAX_LISTED, and_list};
use num_traits::{One, Signed};

/// Context for messages: names of parameters, columns and components.
pub struct Names<'a> {
    /// The IR.
    pub ir: &'a Ir,
    /// The predictor's columns.
    pub columns: &'a [Column],
    /// The centring the analysis assumes (messages name the alternatives).
    pub centring: Centring,
}

impl Names<'_> {
    pub(super) fn param(&self, p: usize) -> &str {
        &self.ir.parameters[p].name
    }
    /// What a column's coefficient is, in moments: `E[north]*X_u`.
    pub fn moment(&self, c: usize) -> String {
        let comp = |i: usize| self.ir.components[i].name.clone();
        match &self.columns[c].kind {
            ColumnKind::Theta { parameter } => self.param(*parameter).to_string(),
            ColumnKind::Rho {
                component,
                parameter,
            } => format!("E[{}]*{}", comp(*component), self.param(*parameter)),
            ColumnKind::Lambda {
                components: [a, b],
                parameter,
            } if a == b => format!("E[{}^2]*{}", comp(*a), self.param(*parameter)),
            ColumnKind::Lambda {
                components: [a, b],
                parameter,
            } => format!("E[{}*{}]*{}", comp(*a), comp(*b), self.param(*parameter)),
        }
    }
    /// The regressor text of a parameter's first term.
    pub fn term_text(&self, p: usize) -> String {
        self.ir
            .terms
            .iter()
            .find(|t| t.parameter == p)
            .map(|t| t.text.clone())
            .unwrap_or_default()
    }
}

/// `a + 2*b - 1/2*c`.
pub fn linear_text(items: &[(String, Q)]) -> String {
    let mut out = String::new();
    for (i, (name, q)) in items.iter().enumerate() {
        let neg = q.is_negative();
        let mag = q.abs();
        if i == 0 {
            if neg {
                out.push('-');
            }
        } else {
            out.push_str(if neg { " - " } else { " + " });
        }
        if mag.is_one() {
            out.push_str(name);
        } else {
            out.push_str(&format!("{}*{}", fmt_q(&mag), name));
        }
    }
    out
}

/// [`linear_text`] for a message: at most [`MAX_LISTED`] terms, then the
/// count of the others (`a + b + … (491 more terms)`).
pub fn linear_text_capped(items: &[(String, Q)]) -> String {
    if items.len() <= MAX_LISTED {
        return linear_text(items);
    }
    format!(
        "{} + … ({} more terms)",
        linear_text(&items[..MAX_LISTED]),
        items.len() - MAX_LISTED
    )
}

/// `` `a`, `b` and `c` ``.
pub(super) fn quoted_list(items: &[String]) -> String {
    and_list(items.iter().map(|s| format!("`{s}`")))
}
