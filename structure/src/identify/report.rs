//! The compile-time identifiability report: its options, the notes on
//! constant terms, and the report itself. The report names the centring it
//! assumed and, for a constant that centring annihilates, the centring that
//! keeps it.

use crate::ir::{Centring, ColumnKind, Ir, PredictorKind, Report, Separation, SignPattern};
use leeway_grammar::and_list;
use num_traits::Zero;
use std::collections::BTreeSet;

use super::analysis::Analysis;
use super::reduce::Patterns;
use super::remedy::{centring_remedies, remedies_text};
use super::verdict::{nuisance_report, verdict};

/// Options of [`compile`](crate::compile) and of the identifiability [`report`]: aggregation,
/// the experiments analysed, the centring.
#[derive(Clone, Debug, Default)]
pub struct CompileOptions {
    /// Estimate identifiable combinations when θ is not identifiable.
    pub aggregate: bool,
    /// Analyse these experiments instead of searching.
    pub patterns: Option<Vec<SignPattern>>,
    /// The centring to analyse (default: the model's, [`Centring::for_model`]).
    pub centring: Option<Centring>,
}

/// θ indices of constant terms (`X_0`): parameters all of whose terms have no factor.
pub fn constant_parameters(ir: &Ir) -> Vec<usize> {
    // One pass over the terms: (has a term, every term is constant).
    let mut seen = vec![(false, true); ir.parameters.len()];
    for t in &ir.terms {
        if let Some(s) = seen.get_mut(t.parameter) {
            s.0 = true;
            s.1 &= t.factors.is_empty();
        }
    }
    (0..ir.parameters.len())
        .filter(|p| seen[*p] == (true, true))
        .collect()
}

/// What the analysis says about constant terms: a note per constant
/// identifiable under `centring`; for a group it annihilates, the centrings
/// and experiments that identify θ ([`centring_remedies`]), with those
/// experiments as the separation's patterns. When θ is identifiable under
/// `centring` from other experiments (`identifiable_somewhere`), the sign
/// patterns are the way out and the usual separation says so.
fn constant_notes(
    ir: &Ir,
    centring: Centring,
    patterns: &[SignPattern],
    identifiable_somewhere: bool,
) -> (Vec<String>, Vec<(Vec<usize>, Separation)>) {
    let constants = constant_parameters(ir);
    if constants.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let constant_set: BTreeSet<usize> = constants.iter().copied().collect();
    let a = Analysis::with_centring(ir, PredictorKind::Measured, centring);
    let red = a.reduce(Patterns::Set(patterns));
    let theta: BTreeSet<usize> = a
        .names
        .columns
        .iter()
        .enumerate()
        .filter(|(_, col)| matches!(col.kind, ColumnKind::Theta { parameter } if constant_set.contains(&parameter)))
        .map(|(i, _)| i)
        .collect();
    let here = red
        .null_space()
        .iter()
        .all(|v| v.iter().all(|(c, q)| !theta.contains(c) || q.is_zero()));
    let names: Vec<String> = constants
        .iter()
        .map(|p| format!("`{}`", ir.parameters[*p].name))
        .collect();
    let list = quoted_join(&names);
    let (plural, them) = if constants.len() == 1 {
        ("", "it")
    } else {
        ("s", "them")
    };
    if here {
        let note = format!(
            "{list}: constant term{plural} (a constant force), identifiable with {}; least squares estimates {them} as its intercept",
            match centring {
                Centring::None => "uncentred instruments (centring none)",
                Centring::Pooled => "pooled centring (a constant's own instrument stays uncentred)",
                Centring::Experiment => "per-experiment centring",
            },
        );
        return (vec![note], Vec::new());
    }
    if identifiable_somewhere {
        return (Vec::new(), Vec::new());
    }
    let remedies = centring_remedies(ir, PredictorKind::Measured, centring);
    let separation = match remedies_text(ir, PredictorKind::Measured, &remedies) {
        Some(way) => Separation {
            parameters: constants.clone(),
            // Full patterns: over every sign argument.
            arguments: (0..remedies
                .first()
                .map_or(0, |r| r.patterns.first().map_or(0, Vec::len)))
                .collect(),
            patterns: remedies.first().map(|r| r.patterns.clone()),
            message: format!("{list}: θ is identifiable with {way}"),
        },
        None => Separation {
            parameters: constants.clone(),
            patterns: None,
            arguments: Vec::new(),
            message: format!(
                "{list}: constant term{plural} that no centring separates from the constant parts of the other columns (e.g. the nuisance moments of `cos² = 1 − sin²`) from any experiments; remove {them} or estimate the aggregate with --aggregate"
            ),
        },
    };
    (Vec::new(), vec![(constants, separation)])
}

fn quoted_join(q: &[String]) -> String {
    and_list(q)
}

/// The compile-time identifiability report (measured predictor).
pub fn report(ir: &Ir, options: &CompileOptions) -> Report {
    let centring = options
        .centring
        .unwrap_or_else(|| Centring::for_model(ir, PredictorKind::Measured));
    let a = Analysis::with_centring(ir, PredictorKind::Measured, centring);
    let baseline = vec![vec![1i8; a.n_signs]];
    let check_set = options.patterns.clone().unwrap_or_else(|| baseline.clone());
    let red_check = a.reduce(Patterns::Set(&check_set));
    let v_check = verdict(&a.names, &red_check);
    let mut search_cut = None;
    let found = if options.patterns.is_some() {
        None
    } else {
        a.required()
    };
    let required = if options.patterns.is_some() {
        if v_check.identifiable {
            check_set.clone()
        } else {
            Vec::new()
        }
    } else {
        match &found {
            Some(f) => {
                search_cut.clone_from(&f.untried);
                f.patterns.clone()
            }
            None => Vec::new(),
        }
    };
    let identifiable = !required.is_empty();
    let reduction_set = if options.patterns.is_some() || !identifiable {
        check_set.clone()
    } else {
        required.clone()
    };
    let red = a.reduce(Patterns::Set(&reduction_set));
    let v = verdict(&a.names, &red);
    let single = if options.patterns.is_some() {
        a.any_single_blocks()
    } else {
        a.any_single_pattern_given(found.as_ref())
    };
    let mut single_note = None;
    let any_single_pattern = match single {
        Some(b) => b,
        None => {
            let why = "whether one experiment of any sign pattern identifies θ was not checked: an output block holds too many interacting sign arguments to try each pattern";
            // Not part of the verdict: said with the cut search, or as a note.
            match &mut search_cut {
                Some(cut) => *cut = format!("{cut}; {why}"),
                None => single_note = Some(why.to_string()),
            }
            false
        }
    };
    let (mut notes, constant_separations) =
        constant_notes(ir, centring, &reduction_set, found.is_some());
    let separations = v_check
        .combinations
        .iter()
        .map(|c| {
            // A group of constant terms is separated by the centring, not by signs.
            match constant_separations
                .iter()
                .find(|(ps, _)| c.parameters.iter().all(|p| ps.contains(p)))
            {
                Some((_, separation)) => Separation {
                    parameters: c.parameters.clone(),
                    ..separation.clone()
                },
                None => a.separation(c),
            }
        })
        .collect();
    Report {
        centring: Some(centring),
        centring_reason: centring.reason(ir, PredictorKind::Measured),
        identifiable,
        any_single_pattern,
        required_patterns: required,
        patterns: reduction_set,
        unidentifiable: v_check.combinations,
        separations,
        nuisance: nuisance_report(&a.names, &red),
        aggregates: if options.aggregate {
            v.aggregates
        } else {
            Vec::new()
        },
        notes: {
            notes.extend(single_note);
            notes
        },
        search_cut,
    }
}
