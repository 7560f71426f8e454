//! The verdict of a reduction in words: the unidentifiable groups of θ, the
//! aggregates, and what each nuisance column estimates.

use crate::exact::Q;
use crate::ir::{
    Aggregate, Centring, ColumnKind, Combination, DroppedNuisance, KeptNuisance, NuisanceReport,
};
use leeway_grammar::join_capped;
use num_traits::One;
use std::collections::{BTreeMap, BTreeSet};

use super::names::{Names, linear_text, linear_text_capped, quoted_list};
use super::reduce::Reduction;

/// The θ-level verdict of a reduction.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// No null vector touches θ.
    pub identifiable: bool,
    /// Unidentifiable groups.
    pub combinations: Vec<Combination>,
    /// Aggregates (kept θ absorbing dropped θ).
    pub aggregates: Vec<Aggregate>,
}

/// Reads the θ verdict off a reduction.
pub fn verdict(names: &Names, red: &Reduction) -> Verdict {
    let dropped: Vec<usize> = (0..names.columns.len())
        .filter(|c| !red.pivot[*c] && theta_param(names, *c).is_some())
        .collect();
    let mut combinations = Vec::new();
    let mut aggregates = Vec::new();
    for g in theta_groups(names, red, &dropped) {
        combinations.push(group_combination(names, red, &g, &mut aggregates));
    }
    Verdict {
        identifiable: dropped.is_empty(),
        combinations,
        aggregates,
    }
}

/// The parameter of a θ column (`None` for a nuisance column).
fn theta_param(names: &Names, c: usize) -> Option<usize> {
    match names.columns[c].kind {
        ColumnKind::Theta { parameter } => Some(parameter),
        _ => None,
    }
}

/// The θ columns linked by the combinations of the dropped ones, as groups
/// (in the order their first dropped column comes), none empty.
fn theta_groups(names: &Names, red: &Reduction, dropped: &[usize]) -> Vec<BTreeSet<usize>> {
    let mut group_of: BTreeMap<usize, usize> = BTreeMap::new();
    let mut groups: Vec<BTreeSet<usize>> = Vec::new();
    for &d in dropped {
        let mut members: BTreeSet<usize> = BTreeSet::new();
        members.insert(d);
        for (k, _) in &red.combination[d] {
            if theta_param(names, *k).is_some() {
                members.insert(*k);
            }
        }
        let existing: BTreeSet<usize> = members
            .iter()
            .filter_map(|m| group_of.get(m).copied())
            .collect();
        let target = match existing.iter().next() {
            Some(&g) => g,
            None => {
                groups.push(BTreeSet::new());
                groups.len() - 1
            }
        };
        for &g in existing.iter().skip(1) {
            let moved: Vec<usize> = std::mem::take(&mut groups[g]).into_iter().collect();
            for m in moved {
                group_of.insert(m, target);
                groups[target].insert(m);
            }
        }
        for m in members {
            group_of.insert(m, target);
            groups[target].insert(m);
        }
    }
    groups.into_iter().filter(|g| !g.is_empty()).collect()
}

/// One group's combination; the aggregates of its kept columns are added.
fn group_combination(
    names: &Names,
    red: &Reduction,
    g: &BTreeSet<usize>,
    aggregates: &mut Vec<Aggregate>,
) -> Combination {
    let kept: Vec<usize> = g.iter().copied().filter(|c| red.pivot[*c]).collect();
    let lost: Vec<usize> = g.iter().copied().filter(|c| !red.pivot[*c]).collect();
    let (idents, idents_short) = identifiable_combinations(names, red, &kept, &lost, aggregates);
    let nuisance: BTreeSet<usize> = lost
        .iter()
        .flat_map(|d| red.combination[*d].iter().map(|(k, _)| *k))
        .filter(|k| theta_param(names, *k).is_none())
        .collect();
    let mut params: Vec<usize> = g.iter().filter_map(|c| theta_param(names, *c)).collect();
    params.sort_unstable();
    let mut message = group_message(names, red, &params, &lost, &idents_short, &nuisance);
    if !nuisance.is_empty() {
        let ns: Vec<String> = nuisance
            .iter()
            .map(|k| names.columns[*k].name.clone())
            .collect();
        message.push_str(&format!(" (together with {})", join_capped(&ns, ", ")));
    }
    Combination {
        parameters: params,
        identifiable: idents,
        message,
    }
}

/// What each kept column of a group estimates (in full, and capped for a
/// message), with its aggregate.
fn identifiable_combinations(
    names: &Names,
    red: &Reduction,
    kept: &[usize],
    lost: &[usize],
    aggregates: &mut Vec<Aggregate>,
) -> (Vec<String>, Vec<String>) {
    let mut idents = Vec::new();
    let mut idents_short = Vec::new();
    for &k in kept {
        let Some(pk) = theta_param(names, k) else {
            continue;
        };
        let mut items = vec![(names.param(pk).to_string(), Q::one())];
        let mut absorbed = Vec::new();
        for &d in lost {
            if let Some((_, q)) = red.combination[d].iter().find(|(c, _)| *c == k)
                && let Some(pd) = theta_param(names, d)
            {
                items.push((names.param(pd).to_string(), q.clone()));
                absorbed.push(pd);
            }
        }
        let text = linear_text(&items);
        idents_short.push(linear_text_capped(&items));
        aggregates.push(Aggregate {
            parameter: pk,
            estimates: text.clone(),
            absorbed,
        });
        idents.push(text);
    }
    (idents, idents_short)
}

/// Why a group is not identifiable, without its nuisance columns.
fn group_message(
    names: &Names,
    red: &Reduction,
    params: &[usize],
    lost: &[usize],
    idents_short: &[String],
    nuisance: &BTreeSet<usize>,
) -> String {
    let list = quoted_list(
        &params
            .iter()
            .map(|p| names.param(*p).to_string())
            .collect::<Vec<_>>(),
    );
    let constant_terms: Vec<String> = lost
        .iter()
        .filter(|d| red.combination[**d].is_empty() && is_constant_term(names, **d))
        .filter_map(|d| theta_param(names, *d))
        .map(|p| format!("`{}`", names.param(p)))
        .collect();
    if idents_short.is_empty() && !constant_terms.is_empty() {
        format!(
            "{} {} a constant term, annihilated by {} (zero-mean instruments remove every constant)",
            join_capped(&constant_terms, ", "),
            if constant_terms.len() == 1 {
                "is"
            } else {
                "are"
            },
            match names.centring {
                Centring::Experiment => "per-experiment centring",
                _ => "pooled centring",
            }
        )
    } else if idents_short.is_empty() {
        let empty: Vec<String> = lost
            .iter()
            .filter(|d| red.combination[**d].is_empty())
            .filter_map(|d| theta_param(names, *d))
            .map(|p| format!("`{}`", names.param(p)))
            .collect();
        if !empty.is_empty() && nuisance.is_empty() {
            format!(
                "{} {} not excited: the regressor vanishes or is constant within an experiment (zero-mean instruments annihilate constants)",
                join_capped(&empty, ", "),
                if empty.len() == 1 { "is" } else { "are" }
            )
        } else {
            format!("{list} cannot be told apart from nuisance terms")
        }
    } else {
        format!("{list} enter only as {}", join_capped(idents_short, ", "))
    }
}

/// True for a θ column whose terms are all constants (`X_0`).
fn is_constant_term(names: &Names, col: usize) -> bool {
    let c = &names.columns[col];
    !c.kind.is_nuisance()
        && !c.structural.is_empty()
        && c.structural.iter().all(|e| e.vars.is_empty())
}

/// The nuisance reduction: kept columns and what each estimates; dropped ones and why.
pub fn nuisance_report(names: &Names, red: &Reduction) -> NuisanceReport {
    let cols = names.columns;
    let nuisance: Vec<usize> = (0..cols.len())
        .filter(|c| cols[*c].kind.is_nuisance())
        .collect();
    let mut kept = Vec::new();
    let mut dropped = Vec::new();
    for &c in &nuisance {
        if red.pivot[c] {
            let mut items = vec![(names.moment(c), Q::one())];
            for d in 0..cols.len() {
                if !red.pivot[d]
                    && let Some((_, q)) = red.combination[d].iter().find(|(k, _)| *k == c)
                {
                    items.push((names.moment(d), q.clone()));
                }
            }
            kept.push(KeptNuisance {
                column: c,
                name: cols[c].name.clone(),
                estimates: linear_text(&items),
            });
        } else {
            let reason = if red.combination[c].is_empty() {
                "constant within an experiment (annihilated by zero-mean instruments)".to_string()
            } else {
                let items: Vec<(String, Q)> = red.combination[c]
                    .iter()
                    .map(|(k, q)| (cols[*k].name.clone(), q.clone()))
                    .collect();
                format!("= {}", linear_text(&items))
            };
            dropped.push(DroppedNuisance {
                column: c,
                name: cols[c].name.clone(),
                reason,
            });
        }
    }
    NuisanceReport {
        before: nuisance.len(),
        after: kept.len(),
        kept,
        dropped,
    }
}
