//! Text → syntax tree: the entry [`parse`]. pest types never leave this module.
//!
//! The input is refused up front by [`guards`](crate::guards) when it is too
//! large or too deep, parsed by the pest grammar of [`rules`], built into the
//! syntax tree by [`build`], and a syntax error is worded for the user by
//! [`wording`].

pub(crate) mod build;
pub(crate) mod rules;
pub(crate) mod wording;

use crate::ast::ModelSyntax;
use crate::diagnostic::data::Diagnostic;
use crate::guards::refuse;
use crate::parse::build::build_model;
use crate::parse::rules::{Rule, SomParser};
use crate::parse::wording::syntax_error;
use pest::Parser;

/// Parses a `.som` source. pest stops at the first syntax error, so a failed
/// parse returns exactly one diagnostic.
pub fn parse(source: &str) -> (Option<ModelSyntax>, Vec<Diagnostic>) {
    if let Some(d) = refuse(source) {
        return (None, vec![d]);
    }
    match SomParser::parse(Rule::file, source) {
        Ok(mut pairs) => {
            let Some(file) = pairs.next() else {
                return (None, vec![Diagnostic::error("syntax", "empty parse")]);
            };
            let model = file.into_inner().find(|p| p.as_rule() == Rule::model);
            match model {
                Some(m) => (Some(build_model(m)), Vec::new()),
                None => (None, vec![Diagnostic::error("syntax", "no model found")]),
            }
        }
        Err(e) => (None, vec![syntax_error(source, e)]),
    }
}

#[cfg(test)]
pub(crate) mod testing;
