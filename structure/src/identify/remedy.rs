//! What a centring the analysis did not use would identify: for constant
//! terms (`X_0`) that the centring in use annihilates, the centrings under
//! which θ is identifiable and from which experiments. One answer, worded
//! once, for `check`, `estimate` and Python.

use crate::ir::{Centring, Ir, PredictorKind, SignPattern};

use super::analysis::Analysis;
use super::pattern::patterns_text;

/// A centring under which θ is identifiable, with the smallest set of sign
/// patterns it needs (one pattern, all positive, when one experiment does).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Remedy {
    /// The centring.
    pub centring: Centring,
    /// The experiments' sign patterns it needs.
    pub patterns: Vec<SignPattern>,
}

/// Every centring other than `current` under which θ is identifiable by
/// predictor `kind` from some set of experiments, in the order none, pooled,
/// per experiment, each with the experiments it needs.
pub fn centring_remedies(ir: &Ir, kind: PredictorKind, current: Centring) -> Vec<Remedy> {
    [Centring::None, Centring::Pooled, Centring::Experiment]
        .into_iter()
        .filter(|c| *c != current)
        .filter_map(|centring| {
            let found = Analysis::with_centring(ir, kind, centring).required()?;
            Some(Remedy {
                centring,
                patterns: found.patterns,
            })
        })
        .collect()
}

/// `` `--centring none` from experiments with sign patterns {+water.u}, {−water.u} ``
/// (each remedy, joined by "or"), with why uncentred instruments are valid
/// when `none` is among them; `None` when no centring identifies θ.
pub fn remedies_text(ir: &Ir, kind: PredictorKind, remedies: &[Remedy]) -> Option<String> {
    if remedies.is_empty() {
        return None;
    }
    // Centrings that need the same experiments are named together.
    let mut groups: Vec<(Vec<&str>, &[SignPattern])> = Vec::new();
    for r in remedies {
        match groups.iter_mut().find(|(_, p)| *p == r.patterns.as_slice()) {
            Some((names, _)) => names.push(r.centring.name()),
            None => groups.push((vec![r.centring.name()], &r.patterns)),
        }
    }
    let each: Vec<String> = groups
        .iter()
        .map(|(names, patterns)| {
            let experiments = if patterns.len() > 1 {
                format!(
                    " from experiments with sign patterns {}",
                    patterns_text(ir, patterns, kind)
                )
            } else {
                String::new()
            };
            format!("`--centring {}`{experiments}", names.join("` or `"))
        })
        .collect();
    let validity = if remedies.iter().any(|r| r.centring == Centring::None) {
        format!(
            " (uncentred instruments are {})",
            Centring::None.reason(ir, kind)
        )
    } else {
        String::new()
    };
    Some(format!("{}{validity}", each.join(" or ")))
}
