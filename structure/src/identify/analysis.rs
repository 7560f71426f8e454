//! A predictor's analysis context: its parsed columns, preference order and
//! output blocks, and the rank tests on them the searches ask.

use crate::ir::{Centring, Ir, PredictorKind};
use std::collections::{BTreeMap, BTreeSet};

use super::names::Names;
use super::pattern::relevant_signs;
use super::reduce::{Patterns, Reduction, blocks, preference_order, reduce, reduce_block};
use super::structural::{Structural, odd_signs};

/// A predictor's analysis context.
pub struct Analysis<'a> {
    /// Names for messages.
    pub names: Names<'a>,
    /// Parsed structure.
    pub structural: Structural,
    /// Preference order.
    pub order: Vec<usize>,
    /// Number of sign arguments.
    pub n_signs: usize,
    /// The sign arguments this predictor fixes per experiment (IV3 evaluates
    /// measured media pointwise, so their signs are free).
    pub relevant: Vec<usize>,
    /// The predictor.
    pub kind: PredictorKind,
    /// Columns connected through shared outputs ([`blocks`]).
    pub(super) blocks: Vec<Vec<usize>>,
    /// Columns without any structural entry.
    pub(super) empty_cols: Vec<usize>,
    /// The block of each column (`None` for an empty column).
    pub(super) block_of: Vec<Option<usize>>,
    /// Columns of each parameter (θ first, then its nuisance columns).
    pub(super) param_cols: BTreeMap<usize, Vec<usize>>,
    /// The first term of each parameter (for messages).
    pub(super) first_term: BTreeMap<usize, usize>,
}

impl<'a> Analysis<'a> {
    /// Prepares the analysis of one predictor of a model, with the model's
    /// default centring ([`Centring::for_model`]).
    pub fn new(ir: &'a Ir, kind: PredictorKind) -> Analysis<'a> {
        Analysis::with_centring(ir, kind, Centring::for_model(ir, kind))
    }
    /// Prepares the analysis of one predictor with a given centring.
    pub fn with_centring(ir: &'a Ir, kind: PredictorKind, centring: Centring) -> Analysis<'a> {
        let columns = ir.predictors.get(kind);
        let measured = |p: usize| kind == PredictorKind::Measured && ir.parameters[p].measured;
        let structural = Structural::new(columns);
        let order = preference_order(columns, &measured);
        let blocks_of = blocks(&structural, &order);
        Analysis {
            names: Names {
                ir,
                columns,
                centring,
            },
            structural,
            order,
            n_signs: ir.sign_args.len(),
            relevant: relevant_signs(ir, kind),
            kind,
            block_of: {
                let mut of = vec![None; columns.len()];
                for (b, cols) in blocks_of.0.iter().enumerate() {
                    for &c in cols {
                        of[c] = Some(b);
                    }
                }
                of
            },
            param_cols: {
                let mut m: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
                for (c, col) in columns.iter().enumerate() {
                    m.entry(col.kind.parameter()).or_default().push(c);
                }
                for v in m.values_mut() {
                    v.sort_by_key(|c| columns[*c].kind.is_nuisance());
                }
                m
            },
            blocks: blocks_of.0,
            empty_cols: blocks_of.1,
            first_term: {
                let mut m = BTreeMap::new();
                for (i, t) in ir.terms.iter().enumerate() {
                    m.entry(t.parameter).or_insert(i);
                }
                m
            },
        }
    }
    /// Reduction for a pattern set.
    pub fn reduce(&self, patterns: Patterns) -> Reduction {
        reduce(&self.structural, patterns, &self.order, self.names.centring)
    }
    /// θ identifiable from these patterns.
    pub fn identifiable(&self, patterns: Patterns) -> bool {
        let red = self.reduce(patterns);
        self.names
            .columns
            .iter()
            .enumerate()
            .all(|(c, col)| col.kind.is_nuisance() || red.pivot[c])
    }
    /// Are the θ columns of `group` free of every null vector?
    pub(super) fn group_identifiable(&self, patterns: Patterns, group: &[usize]) -> bool {
        let theta = self.group_theta(group);
        if theta.iter().any(|c| self.block_of[*c].is_none()) {
            return false;
        }
        // Only the blocks holding the group's columns matter.
        let involved = self.blocks_holding(theta.iter().copied());
        self.blocks_ok(patterns, &involved, &|c| theta.contains(&c))
    }
    /// The blocks holding these columns, sorted.
    pub(super) fn blocks_holding(&self, cols: impl Iterator<Item = usize>) -> Vec<usize> {
        let set: BTreeSet<usize> = cols.filter_map(|c| self.block_of[c]).collect();
        set.into_iter().collect()
    }
    /// The θ columns of a group of parameters.
    pub(super) fn group_theta(&self, group: &[usize]) -> BTreeSet<usize> {
        group
            .iter()
            .flat_map(|p| self.param_cols.get(p).into_iter().flatten())
            .copied()
            .filter(|c| !self.names.columns[*c].kind.is_nuisance())
            .collect()
    }
    /// In these blocks, are the columns `need` selects free of every null vector?
    pub(super) fn blocks_ok(
        &self,
        patterns: Patterns,
        blocks: &[usize],
        need: &dyn Fn(usize) -> bool,
    ) -> bool {
        blocks.iter().all(|&b| {
            let cols = &self.blocks[b];
            let e = reduce_block(&self.structural, patterns, cols, self.names.centring);
            (0..cols.len()).all(|j| {
                e.pivot[j]
                    || (!need(cols[j]) && e.combination[j].iter().all(|(k, _)| !need(cols[*k])))
            })
        })
    }
    /// The sign arguments among `args` (sorted) a block's columns involve.
    pub(super) fn block_signs(&self, b: usize, args: &[usize]) -> Vec<usize> {
        let set: BTreeSet<usize> = self.blocks[b]
            .iter()
            .flat_map(|c| self.structural.signs_of(*c))
            .filter(|i| args.binary_search(i).is_ok())
            .collect();
        set.into_iter().collect()
    }
    /// True when, over the sign arguments `args`, every monomial of each
    /// column of these blocks carries the same odd sign set: flipping signs
    /// then only negates whole columns, which changes no rank.
    pub(super) fn homogeneous_over(&self, blocks: &[usize], args: &[usize]) -> bool {
        blocks.iter().all(|&b| {
            self.blocks[b].iter().all(|&c| {
                let mut sets = self.structural.cols[c]
                    .iter()
                    .map(|(_, _, vars)| odd_signs(vars, args));
                let first = sets.next().unwrap_or_default();
                sets.all(|s| s == first)
            })
        })
    }
}
