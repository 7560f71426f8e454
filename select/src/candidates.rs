//! The candidates a model declares (`?name`) and the chosen model written
//! back as source: kept candidates lose their `?`, dropped ones their terms.

use leeway_structure::grammar::{self, BinOp, Expr, Item, ModelSyntax, Span, line_col};
use std::collections::BTreeSet;

/// A problem with a candidate model's text, located in it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CandidateError {
    /// What is wrong, with the line and column.
    pub message: String,
    /// What to do.
    pub hint: String,
}

/// One summand of an equation's right-hand side as written.
#[derive(Clone, Debug)]
struct Summand {
    /// Written after a `-` (or with a leading `-`).
    negative: bool,
    span: Span,
    /// The parameters named in it (candidates or not).
    parameters: BTreeSet<String>,
}

/// A candidate model's text: which parameters are candidates, and the
/// equations' summands to write a chosen model from.
#[derive(Clone, Debug)]
pub struct CandidateModel {
    source: String,
    /// Candidate parameters, in order of first appearance.
    pub candidates: Vec<String>,
    /// The spans of every `?` (one byte each).
    marks: Vec<(String, usize)>,
    /// Per equation: the right-hand side's span and its summands.
    equations: Vec<(String, Span, Vec<Summand>)>,
    /// `nominal { }` entries: name and the span to delete (the entry and its comma).
    nominal: Vec<(String, Span)>,
}

impl CandidateModel {
    /// Reads the candidates of `source`, whose syntax tree is `syntax`
    /// (`parameters`: the compiled model's parameter names).
    /// A candidate must sit in a summand of its equation with no other
    /// parameter, so that dropping it removes exactly its terms.
    pub fn read(
        source: &str,
        syntax: &ModelSyntax,
        parameters: &BTreeSet<String>,
    ) -> Result<CandidateModel, CandidateError> {
        let mut candidates = Vec::new();
        let mut marks = Vec::new();
        let mut equations = Vec::new();
        let mut nominal = Vec::new();
        let known = parameters;
        for item in &syntax.items {
            match item {
                Item::Equation { state, rhs, .. } => {
                    let mut summands = Vec::new();
                    split_sum(rhs, false, &mut summands);
                    let mut out = Vec::new();
                    for (negative, e) in summands {
                        let mut parameters = BTreeSet::new();
                        let mut marked = Vec::new();
                        names(e, known, &mut parameters, &mut marked);
                        for (name, at) in &marked {
                            if !candidates.contains(name) {
                                candidates.push(name.clone());
                            }
                            marks.push((name.clone(), *at));
                        }
                        out.push(Summand {
                            negative,
                            span: e.span(),
                            parameters,
                        });
                    }
                    equations.push((state.name.clone(), rhs.span(), out));
                }
                Item::Nominal { entries, span } => {
                    for (name, value) in entries {
                        // Delete the entry and a comma after it.
                        let mut end = value.span.end;
                        let rest = &source[end..span.end];
                        let trimmed = rest.trim_start();
                        if trimmed.starts_with(',') {
                            end += rest.len() - trimmed.len() + 1;
                        }
                        nominal.push((name.name.clone(), Span::new(name.span.start, end)));
                    }
                }
                _ => {}
            }
        }
        let model = CandidateModel {
            source: source.to_string(),
            candidates,
            marks,
            equations,
            nominal,
        };
        model.check_summands()?;
        Ok(model)
    }

    /// Every summand holding a candidate holds no other parameter.
    fn check_summands(&self) -> Result<(), CandidateError> {
        for (state, _, summands) in &self.equations {
            for s in summands {
                let cands: Vec<&String> = s
                    .parameters
                    .iter()
                    .filter(|p| self.candidates.contains(p))
                    .collect();
                if !cands.is_empty() && s.parameters.len() > 1 {
                    let (line, col) = line_col(&self.source, s.span.start);
                    let others: Vec<&String> = s.parameters.iter().collect();
                    return Err(CandidateError {
                        message: format!(
                            "{line}:{col}: a term of `{state}` with candidate `{}` also holds {}: a candidate's term must have no other parameter",
                            cands[0],
                            grammar::and_list(others.iter().map(|p| format!("`{p}`")).collect::<Vec<_>>())
                        ),
                        hint: "write the candidate's terms as their own summands: `X*u + ?X_v*v`, not `X*(u + ?X_v*v)`".to_string(),
                    });
                }
            }
        }
        Ok(())
    }

    /// The model with the candidates in `kept` kept (their `?` removed) and
    /// every other candidate's terms and nominal entries removed.
    pub fn chosen(&self, kept: &BTreeSet<String>) -> Result<String, CandidateError> {
        let gone: BTreeSet<String> = self
            .candidates
            .iter()
            .filter(|c| !kept.contains(*c))
            .cloned()
            .collect();
        self.write(&gone, false)
    }

    /// The model without the candidates `gone` (their terms and nominal
    /// entries removed), the other candidates still marked.
    pub fn without(&self, gone: &BTreeSet<String>) -> Result<String, CandidateError> {
        self.write(gone, true)
    }

    fn write(&self, gone: &BTreeSet<String>, marked: bool) -> Result<String, CandidateError> {
        let dropped = |p: &String| gone.contains(p);
        let kept: BTreeSet<String> = if marked {
            BTreeSet::new()
        } else {
            self.candidates
                .iter()
                .filter(|c| !gone.contains(*c))
                .cloned()
                .collect()
        };
        // Edits as (span, replacement), applied back to front.
        let mut edits: Vec<(Span, String)> = Vec::new();
        for (state, rhs_span, summands) in &self.equations {
            if !summands.iter().any(|s| s.parameters.iter().any(dropped)) {
                continue;
            }
            let mut text = String::new();
            for s in summands
                .iter()
                .filter(|s| !s.parameters.iter().any(dropped))
            {
                let term = if marked {
                    self.source[s.span.start..s.span.end].to_string()
                } else {
                    self.without_marks(s.span)
                };
                match (text.is_empty(), s.negative) {
                    (true, false) => {}
                    (true, true) => text.push('-'),
                    (false, false) => text.push_str(" + "),
                    (false, true) => text.push_str(" - "),
                }
                text.push_str(&term);
            }
            if text.is_empty() {
                let (line, col) = line_col(&self.source, rhs_span.start);
                return Err(CandidateError {
                    message: format!(
                        "{line}:{col}: every term of `{state}` would be dropped: the chosen model needs at least one"
                    ),
                    hint: "declare the equation's essential terms without `?`".to_string(),
                });
            }
            edits.push((*rhs_span, text));
        }
        let rewritten: Vec<Span> = edits.iter().map(|(s, _)| *s).collect();
        let inside = |at: usize| rewritten.iter().any(|s| s.start <= at && at < s.end);
        for (name, at) in &self.marks {
            if kept.contains(name) && !inside(*at) {
                edits.push((Span::new(*at, at + 1), String::new()));
            }
        }
        for (name, span) in &self.nominal {
            if dropped(name) {
                edits.push((*span, String::new()));
            }
        }
        edits.sort_by_key(|(s, _)| std::cmp::Reverse(s.start));
        let mut out = self.source.clone();
        for (span, text) in edits {
            out.replace_range(span.start..span.end, &text);
        }
        Ok(out)
    }

    /// The source text of `span` with its `?` marks removed.
    fn without_marks(&self, span: Span) -> String {
        let mut text = String::new();
        let mut from = span.start;
        let mut at: Vec<usize> = self
            .marks
            .iter()
            .map(|(_, a)| *a)
            .filter(|a| span.start <= *a && *a < span.end)
            .collect();
        at.sort_unstable();
        for a in at {
            text.push_str(&self.source[from..a]);
            from = a + 1;
        }
        text.push_str(&self.source[from..span.end]);
        text
    }
}

/// The summands of a sum as written, each with its sign.
fn split_sum<'a>(e: &'a Expr, negative: bool, out: &mut Vec<(bool, &'a Expr)>) {
    match e {
        Expr::Binary {
            op: op @ (BinOp::Add | BinOp::Sub),
            lhs,
            rhs,
            ..
        } => {
            split_sum(lhs, negative, out);
            split_sum(rhs, negative ^ (*op == BinOp::Sub), out);
        }
        _ => out.push((negative, e)),
    }
}

/// The parameters named in `e` (among `known`), and where a `?` marks one.
fn names(
    e: &Expr,
    known: &BTreeSet<String>,
    params: &mut BTreeSet<String>,
    marked: &mut Vec<(String, usize)>,
) {
    match e {
        Expr::Number(_) => {}
        Expr::Path(p) => {
            if p.field.is_none() && known.contains(&p.base.name) {
                params.insert(p.base.name.clone());
                if p.candidate {
                    marked.push((p.base.name.clone(), p.span.start));
                }
            }
        }
        Expr::Abs(i, _) | Expr::Neg(i, _) | Expr::Paren(i, _) => names(i, known, params, marked),
        Expr::Binary { lhs, rhs, .. } => {
            names(lhs, known, params, marked);
            names(rhs, known, params, marked);
        }
    }
}
