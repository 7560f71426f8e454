//! What `leeway check` says about a candidate model before any data: its
//! candidates, the identifiability of the full set, and which candidates are
//! structurally exchangeable (one can stand for another).

use crate::candidates::CandidateModel;
use crate::select::exchangeable;
use leeway_structure::grammar;
use leeway_structure::ir::Ir;
use std::collections::BTreeSet;

/// The candidate section of `check`'s text (`None`: no candidate, or a
/// candidate model whose text `select` refuses, said in one line).
pub fn describe(source: &str, ir: &Ir) -> Option<String> {
    let (syntax, _) = grammar::parse(source);
    let syntax = syntax?;
    let names: BTreeSet<String> = ir.parameters.iter().map(|p| p.name.clone()).collect();
    let model = match CandidateModel::read(source, &syntax, &names) {
        Ok(m) => m,
        Err(e) => return Some(format!("candidates: {} ({})\n", e.message, e.hint)),
    };
    if model.candidates.is_empty() {
        return None;
    }
    let mut text = format!(
        "candidates: {} ({})\n  the full candidate set: {}\n",
        model.candidates.len(),
        model.candidates.join(", "),
        ir.report.verdict()
    );
    let pairs = exchangeable(ir, &model.candidates);
    if pairs.is_empty() {
        text.push_str("  exchangeable candidates: none\n");
    } else {
        for (dropped, with) in pairs {
            text.push_str(&format!(
                "  exchangeable: `{dropped}` can stand for `{with}` (select keeps `{with}`)\n"
            ));
        }
    }
    Some(text)
}
