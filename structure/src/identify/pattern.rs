//! Sign patterns: which signs a predictor fixes, how a set of patterns is
//! written in messages, and parsing the patterns a user names
//! (`water.u:+,r:-`, [`parse_pattern`]: `leeway check --pattern` and
//! Python's `check`).

use crate::ir::{Ir, PredictorKind, SignArg, SignPattern};
use leeway_grammar::{MAX_LISTED, join_capped};
use std::collections::BTreeSet;

/// Every sign pattern of `n` arguments, all-plus first.
pub fn all_patterns(n: usize) -> Vec<SignPattern> {
    (0..(1usize << n))
        .map(|bits| {
            (0..n)
                .map(|i| if bits >> i & 1 == 1 { -1 } else { 1 })
                .collect()
        })
        .collect()
}

/// The sign arguments a predictor fixes per experiment (paper A7): those
/// relative to a medium it does not take from data. Plain states are
/// evaluated pointwise by every predictor.
pub fn relevant_signs(ir: &Ir, kind: PredictorKind) -> Vec<usize> {
    (0..ir.sign_args.len())
        .filter(|i| {
            let a = &ir.sign_args[*i];
            !a.pointwise && (kind != PredictorKind::Measured || !a.measured)
        })
        .collect()
}

/// The sign arguments a predictor evaluates pointwise (their sign may
/// change within an experiment).
pub fn pointwise_signs(ir: &Ir, kind: PredictorKind) -> Vec<usize> {
    (0..ir.sign_args.len())
        .filter(|i| {
            let a = &ir.sign_args[*i];
            a.pointwise || (kind == PredictorKind::Measured && a.measured)
        })
        .collect()
}

/// `{+water.u +water.v}, {+water.u -water.v}`: the signs the predictor fixes,
/// plus any pointwise (measured-medium) sign that some pattern of the set
/// makes negative, shown in every pattern of the set.
pub fn patterns_text(ir: &Ir, set: &[SignPattern], kind: PredictorKind) -> String {
    patterns_text_over(ir, set, &relevant_signs(ir, kind))
}

/// The sign arguments a set of patterns is shown with: `base` (sorted) and
/// every argument some pattern makes negative, in order. One scan of each
/// pattern, so showing one set costs no more than reading it.
pub fn shown_signs(set: &[SignPattern], base: &[usize]) -> Vec<usize> {
    let mut shown: BTreeSet<usize> = base.iter().copied().collect();
    for p in set {
        shown.extend(
            p.iter()
                .enumerate()
                .filter(|(_, s)| **s < 0)
                .map(|(i, _)| i),
        );
    }
    shown.into_iter().collect()
}

/// [`patterns_text`] showing the arguments `base` (sorted; e.g. those of
/// one group of parameters) and the negative ones: at most [`MAX_LISTED`]
/// signs per pattern and patterns per set, the rest counted, so a message
/// stays short whatever the number of sign arguments (the JSON report lists
/// every pattern in full).
pub fn patterns_text_over(ir: &Ir, set: &[SignPattern], base: &[usize]) -> String {
    let shown = shown_signs(set, base);
    if shown.is_empty() {
        return "{} (no modulus needs a fixed sign)".to_string();
    }
    let sign = |p: &SignPattern, i: usize| p.get(i).copied().unwrap_or(1) < 0;
    let one = |p: &SignPattern| -> String {
        let mut items: Vec<String> = shown
            .iter()
            .take(MAX_LISTED)
            .map(|i| {
                format!(
                    "{}{}",
                    if sign(p, *i) { "-" } else { "+" },
                    ir.sign_args[*i].name
                )
            })
            .collect();
        let rest = &shown[shown.len().min(MAX_LISTED)..];
        if !rest.is_empty() {
            let minus = rest.iter().filter(|i| sign(p, **i)).count();
            let plus = rest.len() - minus;
            items.push(match (plus, minus) {
                (_, 0) => format!("… and {} more, all +", rest.len()),
                (0, _) => format!("… and {} more, all -", rest.len()),
                _ => format!("… and {} more: {plus} +, {minus} -", rest.len()),
            });
        }
        format!("{{{}}}", items.join(" "))
    };
    join_capped(set.iter().map(one), ", ")
}

/// `{+water.u -water.v}`: one pattern (see [`patterns_text`]).
pub fn pattern_text(ir: &Ir, p: &SignPattern, kind: PredictorKind) -> String {
    patterns_text(ir, std::slice::from_ref(p), kind)
}

/// Parses one experiment's sign pattern written as `water.u:+,air.u:-`: each
/// named sign argument gets the given sign (`+`, `-`, `+1` or `-1`), every
/// argument not named gets `+`. Names are those of [`Ir::sign_args`].
pub fn parse_pattern(sign_args: &[SignArg], spec: &str) -> Result<SignPattern, String> {
    let mut pattern = vec![1i8; sign_args.len()];
    let mut given: Vec<&str> = Vec::new();
    let known = || {
        if sign_args.is_empty() {
            "this model has no sign argument (no modulus of a noisy state)".to_string()
        } else {
            let list: Vec<&str> = sign_args.iter().map(|s| s.name.as_str()).collect();
            format!("its sign arguments are {}", join_capped(&list, ", "))
        }
    };
    for item in spec.split(',').map(str::trim).filter(|i| !i.is_empty()) {
        let Some((name, sign)) = item.rsplit_once(':') else {
            return Err(format!(
                "expected `argument:+` or `argument:-`, found `{item}`"
            ));
        };
        let (name, sign) = (name.trim(), sign.trim());
        let value = match sign {
            "+" | "+1" | "1" => 1,
            "-" | "-1" => -1,
            _ => {
                return Err(format!(
                    "the sign of `{name}` must be `+` or `-`, found `{sign}`"
                ));
            }
        };
        let Some(index) = sign_args.iter().position(|s| s.name == name) else {
            return Err(format!(
                "`{name}` is not a sign argument of this model; {}",
                known()
            ));
        };
        if given.contains(&name) {
            return Err(format!("`{name}` is given twice in one pattern"));
        }
        given.push(name);
        pattern[index] = value;
    }
    Ok(pattern)
}

/// A pattern in the syntax [`parse_pattern`] reads: `water.u:+,water.v:-`
/// (the signs this predictor fixes).
pub fn pattern_spec(ir: &Ir, p: &SignPattern, kind: PredictorKind) -> String {
    relevant_signs(ir, kind)
        .into_iter()
        .map(|i| {
            format!(
                "{}:{}",
                ir.sign_args[i].name,
                if p.get(i).copied().unwrap_or(1) < 0 {
                    "-"
                } else {
                    "+"
                }
            )
        })
        .collect::<Vec<_>>()
        .join(",")
}
