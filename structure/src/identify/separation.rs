//! What separates an unidentifiable group of parameters: the experiments
//! that would tell them apart, or why none does.

use crate::ir::{ColumnKind, Combination, PredictorKind, Separation, SignPattern};
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
        let args = self.group_args(group);
        let list = quoted_list(
            &group
                .iter()
                .map(|p| self.names.param(*p).to_string())
                .collect::<Vec<_>>(),
        );
        let theta_signs = self.theta_signs(group);
        if !self.group_identifiable(Patterns::All, group) {
            return self.inseparable(group, &list, &theta_signs);
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
        let message = self.separating_message(&list, found.as_deref(), &theta_signs, &shown_base);
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

    /// The sign arguments the columns of a group of parameters involve, sorted.
    fn group_args(&self, group: &[usize]) -> Vec<usize> {
        let member_cols: Vec<usize> = group
            .iter()
            .flat_map(|p| self.param_cols.get(p).into_iter().flatten())
            .copied()
            .collect();
        member_cols
            .iter()
            .flat_map(|c| self.structural.signs_of(*c))
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect()
    }

    /// The sign set of each parameter's θ column, when every monomial of it
    /// has the same one.
    fn theta_signs(&self, group: &[usize]) -> Vec<Option<BTreeSet<usize>>> {
        let cols = self.names.columns;
        group
            .iter()
            .filter_map(|p| {
                self.param_cols
                    .get(p)
                    .and_then(|cs| cs.first())
                    .filter(|c| cols[**c].kind == ColumnKind::Theta { parameter: *p })
            })
            .map(|c| self.structural.homogeneous_signs(*c))
            .collect()
    }

    /// The name of a sign argument.
    fn sign_name(&self, i: &usize) -> String {
        self.names.ir.sign_args[*i].name.clone()
    }

    /// Arguments evaluated pointwise need no separate experiments: a sign
    /// change within one suffices. Said once, after the sentence.
    fn pointwise_note(&self, args: &[usize]) -> String {
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
    }

    /// A group no experiment separates, and why.
    fn inseparable(
        &self,
        group: &[usize],
        list: &str,
        theta_signs: &[Option<BTreeSet<usize>>],
    ) -> Separation {
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
            Some(Some(s)) if theta_signs.iter().all(|t| t.as_ref() == Some(s)) && s.is_empty() => {
                format!(
                    "{} {carry} no modulus, so no sign pattern tells them apart",
                    and_list(&texts)
                )
            }
            Some(Some(s)) if theta_signs.iter().all(|t| t.as_ref() == Some(s)) => format!(
                "{} {carry} the same sign factor ({}), so every experiment scales them alike",
                and_list(&texts),
                join_capped(s.iter().map(|i| self.sign_name(i)), "·")
            ),
            _ => "their regressors coincide in every sign pattern".to_string(),
        };
        Separation {
            parameters: group.to_vec(),
            patterns: None,
            arguments: Vec::new(),
            message: format!("no experiment separates {list}: {why}"),
        }
    }

    /// The sentence naming the experiments that separate a group (`found`).
    fn separating_message(
        &self,
        list: &str,
        found: Option<&[SignPattern]>,
        theta_signs: &[Option<BTreeSet<usize>>],
        shown_base: &[usize],
    ) -> String {
        match (found, theta_signs) {
            (Some(_), [Some(a), Some(b)]) => {
                let diff: Vec<usize> = a.symmetric_difference(b).copied().collect();
                match diff.as_slice() {
                    [x] => format!(
                        "{list} are separated by experiments with both signs of {}{}",
                        self.sign_name(x),
                        self.pointwise_note(&[*x])
                    ),
                    [x, y] => format!(
                        "{list} are separated by an experiment where sign({}) ≠ sign({}) together with one where they agree{}",
                        self.sign_name(x),
                        self.sign_name(y),
                        self.pointwise_note(&[*x, *y])
                    ),
                    _ => format!(
                        "{list} are separated by the sign patterns {}",
                        patterns_text_over(self.names.ir, found.unwrap_or(&[]), shown_base)
                    ),
                }
            }
            (Some(set), _) => format!(
                "{list} are separated by the sign patterns {}",
                patterns_text_over(self.names.ir, set, shown_base)
            ),
            (None, _) => format!("{list}: no set of sign patterns separates them"),
        }
    }
}
