//! What separates an unidentifiable group of parameters: the experiments
//! that would tell them apart, or why none does.

use crate::ir::{ColumnKind, Combination, PredictorKind, Separation};
use leeway_grammar::{and_list, join_capped};
use std::collections::BTreeSet;

use super::analysis::Analysis;
use super::names::quoted_list;
use super::pattern::{patterns_text_over, shown_signs};
use super::reduce::Patterns;

impl Analysis<'_> {
    /// What separates an unidentifiable group.
    pub fn separation(&self, combination: &Combination) -> Separation {
        let group = &combination.parameters;
        let cols = self.names.columns;
        let member_cols: Vec<usize> = group
            .iter()
            .flat_map(|p| self.param_cols.get(p).into_iter().flatten())
            .copied()
            .collect();
        let args: Vec<usize> = member_cols
            .iter()
            .flat_map(|c| self.structural.signs_of(*c))
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let list = quoted_list(
            &group
                .iter()
                .map(|p| self.names.param(*p).to_string())
                .collect::<Vec<_>>(),
        );
        let sign_name = |i: &usize| self.names.ir.sign_args[*i].name.clone();
        // Arguments evaluated pointwise need no separate experiments: a sign
        // change within one suffices. Said once, after the sentence.
        let pointwise_note = |args: &[usize]| -> String {
            let pw: Vec<String> = args
                .iter()
                .filter(|i| {
                    let a = &self.names.ir.sign_args[**i];
                    a.pointwise || (a.measured && self.kind == PredictorKind::Measured)
                })
                .map(|i| self.names.ir.sign_args[*i].name.clone())
                .collect();
            match pw.as_slice() {
                [] => String::new(),
                [one] => format!(
                    " ({one} is evaluated pointwise: a sign change within one experiment suffices)"
                ),
                many => format!(
                    " ({} are evaluated pointwise: a sign change within one experiment suffices)",
                    join_capped(many, ", ")
                ),
            }
        };
        let theta_signs: Vec<Option<BTreeSet<usize>>> = group
            .iter()
            .filter_map(|p| {
                self.param_cols
                    .get(p)
                    .and_then(|cs| cs.first())
                    .filter(|c| cols[**c].kind == ColumnKind::Theta { parameter: *p })
            })
            .map(|c| self.structural.homogeneous_signs(*c))
            .collect();
        if !self.group_identifiable(Patterns::All, group) {
            // Each distinct regressor once (499 parameters of `u` say `u` once).
            let mut texts: Vec<String> = Vec::new();
            let mut seen: BTreeSet<String> = BTreeSet::new();
            for p in group {
                let text = self
                    .first_term
                    .get(p)
                    .map(|t| self.names.ir.terms[*t].text.clone())
                    .unwrap_or_default();
                if seen.insert(text.clone()) {
                    texts.push(text);
                }
            }
            let carry = if texts.len() == 1 { "carries" } else { "carry" };
            let why = match theta_signs.first() {
                Some(Some(s))
                    if theta_signs.iter().all(|t| t.as_ref() == Some(s)) && s.is_empty() =>
                {
                    format!(
                        "{} {carry} no modulus, so no sign pattern tells them apart",
                        and_list(&texts)
                    )
                }
                Some(Some(s)) if theta_signs.iter().all(|t| t.as_ref() == Some(s)) => format!(
                    "{} {carry} the same sign factor ({}), so every experiment scales them alike",
                    and_list(&texts),
                    join_capped(s.iter().map(sign_name), "·")
                ),
                _ => "their regressors coincide in every sign pattern".to_string(),
            };
            return Separation {
                parameters: group.clone(),
                patterns: None,
                arguments: Vec::new(),
                message: format!("no experiment separates {list}: {why}"),
            };
        }
        let group_theta = self.group_theta(group);
        // Over the group's own arguments (every other sign +), else over all.
        let mut over_all = false;
        let searched = self.smallest(&args, &group_theta).or_else(|| {
            over_all = true;
            let every: Vec<usize> = (0..self.n_signs).collect();
            self.smallest(&every, &group_theta)
        });
        // The group's own signs the predictor fixes (and any made negative).
        let shown_base: Vec<usize> = args
            .iter()
            .copied()
            .filter(|i| self.relevant.binary_search(i).is_ok())
            .collect();
        let cut = searched.as_ref().and_then(|f| f.untried.clone());
        let found = searched.map(|f| f.patterns);
        let message = match (&found, theta_signs.as_slice()) {
            (Some(_), [Some(a), Some(b)]) => {
                let diff: Vec<usize> = a.symmetric_difference(b).copied().collect();
                match diff.as_slice() {
                    [x] => format!(
                        "{list} are separated by experiments with both signs of {}{}",
                        sign_name(x),
                        pointwise_note(&[*x])
                    ),
                    [x, y] => format!(
                        "{list} are separated by an experiment where sign({}) ≠ sign({}) together with one where they agree{}",
                        sign_name(x),
                        sign_name(y),
                        pointwise_note(&[*x, *y])
                    ),
                    _ => format!(
                        "{list} are separated by the sign patterns {}",
                        patterns_text_over(
                            self.names.ir,
                            found.as_deref().unwrap_or(&[]),
                            &shown_base
                        )
                    ),
                }
            }
            (Some(set), _) => format!(
                "{list} are separated by the sign patterns {}",
                patterns_text_over(self.names.ir, set, &shown_base)
            ),
            (None, _) => format!("{list}: no set of sign patterns separates them"),
        };
        let message = match cut {
            Some(cut) => format!("{message} (not proven the fewest: {cut})"),
            None => message,
        };
        // Stored over the group's arguments and any sign made negative: one
        // full pattern per group would make the report quadratic in size.
        let arguments = found
            .as_deref()
            .map(|set| {
                if over_all {
                    shown_signs(set, &args)
                } else {
                    args.clone()
                }
            })
            .unwrap_or_default();
        let patterns = found.map(|set| {
            set.iter()
                .map(|p| {
                    arguments
                        .iter()
                        .map(|a| p.get(*a).copied().unwrap_or(1))
                        .collect()
                })
                .collect()
        });
        Separation {
            parameters: group.clone(),
            patterns,
            arguments,
            message,
        }
    }
}
