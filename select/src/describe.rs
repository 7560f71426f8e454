//! What `leeway check` says about a candidate model before any data: its
//! candidates, the identifiability of the full set, and which candidates are
//! structurally exchangeable (one can stand for another) — as text and as
//! the `candidates` field of `check --json`.

use crate::candidates::CandidateModel;
use crate::select::exchangeable;
use leeway_structure::grammar;
use leeway_structure::ir::Ir;
use serde::Serialize;
use std::collections::BTreeSet;

/// The candidates of a model as `check` reports them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CandidateSummary {
    /// The candidates in declaration order (empty when `refused`).
    pub candidates: Vec<String>,
    /// `check`'s verdict on the full candidate set (`identifiable`,
    /// `not-identifiable`, `undecided`).
    pub full_set: &'static str,
    /// Candidates one can stand for another: `select` keeps `stands_for`
    /// and drops `candidate`.
    pub exchangeable: Vec<Exchangeable>,
    /// Why `select` refuses the candidates as written (with what to do);
    /// null when it accepts them.
    pub refused: Option<String>,
}

/// A candidate structurally exchangeable with an earlier term.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Exchangeable {
    /// The candidate `select` drops.
    pub candidate: String,
    /// The term it can stand for, which `select` keeps.
    pub stands_for: String,
}

/// The candidates of `source` compiled as `ir` (`None`: no candidate, or
/// a text that does not parse).
pub fn summary(source: &str, ir: &Ir) -> Option<CandidateSummary> {
    let (syntax, _) = grammar::parse(source);
    let syntax = syntax?;
    let names: BTreeSet<String> = ir.parameters.iter().map(|p| p.name.clone()).collect();
    let model = match CandidateModel::read(source, &syntax, &names) {
        Ok(m) => m,
        Err(e) => {
            return Some(CandidateSummary {
                candidates: Vec::new(),
                full_set: ir.report.verdict(),
                exchangeable: Vec::new(),
                refused: Some(format!("{} ({})", e.message, e.hint)),
            });
        }
    };
    if model.candidates.is_empty() {
        return None;
    }
    let exchangeable = exchangeable(ir, &model.candidates)
        .into_iter()
        .map(|(candidate, stands_for)| Exchangeable {
            candidate,
            stands_for,
        })
        .collect();
    Some(CandidateSummary {
        candidates: model.candidates,
        full_set: ir.report.verdict(),
        exchangeable,
        refused: None,
    })
}

/// The candidate section of `check`'s text (`None`: no candidate, or a
/// candidate model whose text `select` refuses, said in one line).
pub fn describe(source: &str, ir: &Ir) -> Option<String> {
    let s = summary(source, ir)?;
    if let Some(refused) = s.refused {
        return Some(format!("candidates: {refused}\n"));
    }
    let mut text = format!(
        "candidates: {} ({})\n  the full candidate set: {}\n",
        s.candidates.len(),
        s.candidates.join(", "),
        s.full_set
    );
    if s.exchangeable.is_empty() {
        text.push_str("  exchangeable candidates: none\n");
    } else {
        for e in s.exchangeable {
            text.push_str(&format!(
                "  exchangeable: `{}` can stand for `{}` (select keeps `{}`)\n",
                e.candidate, e.stands_for, e.stands_for
            ));
        }
    }
    Some(text)
}
