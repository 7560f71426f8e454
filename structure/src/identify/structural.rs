//! The parsed structural polynomials of a predictor's columns, read once for
//! every reduction.

use crate::exact::{Q, parse_q};
use crate::ir::{Column, StructVar};
use num_traits::Zero;
use std::collections::BTreeSet;

/// One parsed structural monomial: (output, coefficient, variables with powers).
pub(super) type StructMonomial = (usize, Q, Vec<(StructVar, u32)>);

/// Parsed structural polynomials of a predictor's columns.
#[derive(Clone, Debug)]
pub struct Structural {
    pub(super) cols: Vec<Vec<StructMonomial>>,
    /// Outputs with a constant θ column (a term like `X_0`): under pooled
    /// centring its instrument is the constant itself, so constants are kept.
    pub(super) intercepts: BTreeSet<usize>,
}

impl Structural {
    /// Parses the columns' structural entries once.
    pub fn new(columns: &[Column]) -> Structural {
        let cols: Vec<Vec<StructMonomial>> = columns
            .iter()
            .map(|c| {
                c.structural
                    .iter()
                    .map(|e| {
                        (
                            e.output,
                            parse_q(&e.coefficient).unwrap_or_else(Q::zero),
                            e.vars.clone(),
                        )
                    })
                    .collect()
            })
            .collect();
        let intercepts = columns
            .iter()
            .zip(&cols)
            .filter(|(c, m)| !c.kind.is_nuisance() && is_constant_column(m))
            .flat_map(|(_, m)| m.iter().map(|(o, _, _)| *o))
            .collect();
        Structural { cols, intercepts }
    }
    /// True when column `col` is a constant (every monomial without variables).
    pub fn is_constant(&self, col: usize) -> bool {
        is_constant_column(&self.cols[col])
    }
    /// Number of columns.
    pub fn len(&self) -> usize {
        self.cols.len()
    }
    /// True when there are no columns.
    pub fn is_empty(&self) -> bool {
        self.cols.is_empty()
    }
    /// The sign arguments a column's structural polynomial involves.
    pub fn signs_of(&self, col: usize) -> BTreeSet<usize> {
        self.cols[col]
            .iter()
            .flat_map(|(_, _, vars)| {
                vars.iter().filter_map(|(v, _)| {
                    if let StructVar::Sign(i) = v {
                        Some(*i)
                    } else {
                        None
                    }
                })
            })
            .collect()
    }
    /// Sign sets per monomial, if every monomial of the column has the same one.
    pub(super) fn homogeneous_signs(&self, col: usize) -> Option<BTreeSet<usize>> {
        let mut sets = self.cols[col].iter().map(|(_, _, vars)| {
            vars.iter()
                .filter_map(|(v, _)| {
                    if let StructVar::Sign(i) = v {
                        Some(*i)
                    } else {
                        None
                    }
                })
                .collect::<BTreeSet<_>>()
        });
        let first = sets.next().unwrap_or_default();
        sets.all(|s| s == first).then_some(first)
    }
}

fn is_constant_column(monomials: &[StructMonomial]) -> bool {
    !monomials.is_empty() && monomials.iter().all(|(_, _, vars)| vars.is_empty())
}

/// The sign arguments among `args` (sorted) that occur with an odd power.
pub(super) fn odd_signs(vars: &[(StructVar, u32)], args: &[usize]) -> Vec<usize> {
    let mut out: Vec<usize> = vars
        .iter()
        .filter_map(|(v, e)| match v {
            StructVar::Sign(i) if e % 2 == 1 && args.binary_search(i).is_ok() => Some(*i),
            _ => None,
        })
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// A row family: an output and a monomial without its sign variables.
pub(super) type FamilyKey = (usize, Vec<(StructVar, u32)>);
