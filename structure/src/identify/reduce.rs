//! Reduction: the exact echelon form of a predictor's columns, in preference
//! order, block by block, over the rows a set of sign patterns gives.

use crate::exact::{Echelon, Q, SparseRow, echelon_sparse};
use crate::ir::{Centring, Column, ColumnKind, SignPattern, StructVar};
use num_traits::{One, Zero};
use std::collections::{BTreeMap, BTreeSet};

use super::structural::Structural;
use super::union_find::UnionFind;

/// Which sign patterns the analysis covers.
#[derive(Clone, Copy, Debug)]
pub enum Patterns<'a> {
    /// Every pattern at once (signs symbolic).
    All,
    /// Every pattern of the listed sign arguments (sorted), the others +1:
    /// those signs symbolic, exactly as [`Patterns::All`] over them.
    Symbolic(&'a [usize]),
    /// These experiments.
    Set(&'a [SignPattern]),
    /// These experiments, each pattern over `args` only (`set[e][k]` is the
    /// sign of `args[k]`, sorted; every other sign `+`): the search over a
    /// few arguments of a large model never builds full patterns.
    Local {
        /// The sign arguments the patterns give (sorted).
        args: &'a [usize],
        /// The patterns.
        set: &'a [SignPattern],
    },
    /// Experiments as recorded: each with its sign pattern and, when its
    /// rotation barely varied, the constant values of the rotation variables
    /// (paper Remark 2: with `R` constant the rotation no longer separates
    /// the disturbance terms from the others).
    Experiments(&'a [ExperimentStructure]),
}

/// One recorded experiment, for the run-time structural analysis.
#[derive(Clone, Debug, PartialEq)]
pub struct ExperimentStructure {
    /// Its sign pattern.
    pub pattern: SignPattern,
    /// Constant rotation variables (exact values), if `R` did not vary.
    pub frozen_rotation: Option<Vec<Q>>,
    /// Sign arguments evaluated pointwise (plain states; measured media in
    /// IV3) whose sign changes within the experiment: kept symbolic, as if
    /// every sign occurred.
    pub varying: Vec<usize>,
}

/// The exact reduction of a predictor's columns.
#[derive(Clone, Debug, PartialEq)]
pub struct Reduction {
    /// The preference order used.
    pub order: Vec<usize>,
    /// `pivot[c]`: column `c` is kept.
    pub pivot: Vec<bool>,
    /// For a dropped column `c`: `col_c = Σ q · col_k` over kept `k`.
    pub combination: Vec<Vec<(usize, Q)>>,
}

impl Reduction {
    /// Kept columns in column order.
    pub fn kept(&self) -> Vec<usize> {
        (0..self.pivot.len()).filter(|c| self.pivot[*c]).collect()
    }
    /// The null space as sparse vectors over column indices.
    pub fn null_space(&self) -> Vec<Vec<(usize, Q)>> {
        (0..self.pivot.len())
            .filter(|c| !self.pivot[*c])
            .map(|c| {
                let mut v = vec![(c, Q::one())];
                v.extend(self.combination[c].iter().map(|(k, q)| (*k, -q.clone())));
                v
            })
            .collect()
    }
}

/// Preference order: nuisance (in column order), θ of unmeasured media, θ of measured media.
pub fn preference_order(
    columns: &[Column],
    measured_parameter: &dyn Fn(usize) -> bool,
) -> Vec<usize> {
    let mut order: Vec<usize> = (0..columns.len())
        .filter(|c| columns[*c].kind.is_nuisance())
        .collect();
    order.extend((0..columns.len()).filter(|c| matches!(columns[*c].kind, ColumnKind::Theta { parameter } if !measured_parameter(parameter))));
    order.extend((0..columns.len()).filter(|c| matches!(columns[*c].kind, ColumnKind::Theta { parameter } if measured_parameter(parameter))));
    order
}

type RowKey = (usize, usize, Vec<(StructVar, u32)>);

/// The columns connected through shared outputs (each block in `order`),
/// and the columns without any structural entry. Blocks are independent:
/// the stacked matrix is block diagonal over them, whatever the patterns.
pub fn blocks(s: &Structural, order: &[usize]) -> (Vec<Vec<usize>>, Vec<usize>) {
    let n_out = s
        .cols
        .iter()
        .flat_map(|c| c.iter().map(|(o, _, _)| *o + 1))
        .max()
        .unwrap_or(0);
    let mut linked = UnionFind::new(n_out);
    for col in &s.cols {
        if let Some((first, _, _)) = col.first() {
            for (o, _, _) in &col[1..] {
                linked.union(*first, *o);
            }
        }
    }
    let mut index: Vec<Option<usize>> = vec![None; n_out];
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut empty_cols = Vec::new();
    for &c in order {
        match s.cols[c].first() {
            Some((o, _, _)) => {
                let root = linked.find(*o);
                let b = *index[root].get_or_insert_with(|| {
                    out.push(Vec::new());
                    out.len() - 1
                });
                out[b].push(c);
            }
            None => empty_cols.push(c),
        }
    }
    (out, empty_cols)
}

/// Exact reduction of the columns for the given patterns, in `order`, with
/// the constants the centring annihilates removed.
pub fn reduce(
    s: &Structural,
    patterns: Patterns,
    order: &[usize],
    centring: Centring,
) -> Reduction {
    let n = s.len();
    let (blocks, empty_cols) = blocks(s, order);
    let mut pivot = vec![false; n];
    let mut combination = vec![Vec::new(); n];
    for cols in &blocks {
        let e = reduce_block(s, patterns, cols, centring);
        for (j, &c) in cols.iter().enumerate() {
            pivot[c] = e.pivot[j];
            combination[c] = e.combination[j]
                .iter()
                .map(|(k, q)| (cols[*k], q.clone()))
                .collect();
        }
    }
    for c in empty_cols {
        pivot[c] = false;
    }
    Reduction {
        order: order.to_vec(),
        pivot,
        combination,
    }
}

/// The echelon form of one block's columns (`cols`, in preference order)
/// over the rows the patterns give.
pub fn reduce_block(
    s: &Structural,
    patterns: Patterns,
    cols: &[usize],
    centring: Centring,
) -> Echelon {
    // Sparse rows: entries are added column by column, so each row's
    // columns come in increasing order (a block may have hundreds of columns
    // and rows, most entries zero).
    let mut rows: BTreeMap<RowKey, SparseRow> = BTreeMap::new();
    let width = cols.len();
    for (j, &c) in cols.iter().enumerate() {
        for (o, q, vars) in &s.cols[c] {
            match patterns {
                Patterns::All | Patterns::Symbolic(_) => {
                    // Signs stay symbolic (those not listed are +1): only a
                    // monomial without any other variable is the same
                    // constant in every experiment.
                    let vars: Vec<(StructVar, u32)> = match patterns {
                        Patterns::Symbolic(args) => vars
                            .iter()
                            .filter(|(v, _)| match v {
                                StructVar::Sign(i) => args.binary_search(i).is_ok(),
                                _ => true,
                            })
                            .copied()
                            .collect(),
                        _ => vars.clone(),
                    };
                    let constant = vars.iter().all(|(v, _)| matches!(v, StructVar::Sign(_)));
                    let kept = match centring {
                        Centring::Experiment => !constant,
                        Centring::Pooled => !vars.is_empty() || s.intercepts.contains(o),
                        Centring::None => true,
                    };
                    if kept {
                        push_entry(rows.entry((0, *o, vars)).or_default(), j, q.clone());
                    }
                }
                Patterns::Set(set) => {
                    for (pi, pat) in set.iter().enumerate() {
                        let ctx = RowContext {
                            pattern: pat,
                            local: None,
                            frozen: None,
                            varying: &[],
                            keep_constants: centring != Centring::Experiment,
                        };
                        add_row(&mut rows, pi, *o, q, vars, &ctx, j);
                    }
                }
                Patterns::Local { args, set } => {
                    for (pi, pat) in set.iter().enumerate() {
                        let ctx = RowContext {
                            pattern: pat,
                            local: Some(args),
                            frozen: None,
                            varying: &[],
                            keep_constants: centring != Centring::Experiment,
                        };
                        add_row(&mut rows, pi, *o, q, vars, &ctx, j);
                    }
                }
                Patterns::Experiments(list) => {
                    for (pi, e) in list.iter().enumerate() {
                        let ctx = RowContext {
                            pattern: &e.pattern,
                            local: None,
                            frozen: e.frozen_rotation.as_deref(),
                            varying: &e.varying,
                            keep_constants: centring != Centring::Experiment,
                        };
                        add_row(&mut rows, pi, *o, q, vars, &ctx, j);
                    }
                }
            }
        }
    }
    if centring == Centring::Pooled && !matches!(patterns, Patterns::All | Patterns::Symbolic(_)) {
        pool_constants(&mut rows, &s.intercepts);
    }
    let matrix: Vec<SparseRow> = rows
        .into_values()
        .map(|mut r| {
            r.retain(|(_, q)| !q.is_zero());
            r
        })
        .filter(|r| !r.is_empty())
        .collect();
    echelon_sparse(&matrix, width)
}

/// Adds `q` at column `j` of a sparse row whose last column is at most `j`.
fn push_entry(row: &mut SparseRow, j: usize, q: Q) {
    match row.last_mut() {
        Some((last, v)) if *last == j => *v += q,
        _ => row.push((j, q)),
    }
}

/// `a − b` for sparse rows (columns increasing).
fn sparse_diff(a: &SparseRow, b: &SparseRow) -> SparseRow {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut k) = (0, 0);
    while i < a.len() || k < b.len() {
        let ca = a.get(i).map_or(usize::MAX, |e| e.0);
        let cb = b.get(k).map_or(usize::MAX, |e| e.0);
        if ca < cb {
            out.push(a[i].clone());
            i += 1;
        } else if cb < ca {
            out.push((cb, -b[k].1.clone()));
            k += 1;
        } else {
            out.push((ca, &a[i].1 - &b[k].1));
            i += 1;
            k += 1;
        }
    }
    out
}

/// Pooled centring removes, per output, the constant common to every
/// experiment: the constant rows `(experiment, output, 1)` become their
/// differences from the first experiment's (the same rank as the projection
/// onto the complement of the common constant). Outputs with a constant θ
/// column keep their constants: that column's own instrument is uncentred.
fn pool_constants(rows: &mut BTreeMap<RowKey, SparseRow>, intercepts: &BTreeSet<usize>) {
    let constant: BTreeSet<RowKey> = rows
        .keys()
        .filter(|(_, o, vars)| vars.is_empty() && !intercepts.contains(o))
        .cloned()
        .collect();
    let mut base: BTreeMap<usize, SparseRow> = BTreeMap::new();
    for key in &constant {
        let Some(row) = rows.remove(key) else {
            continue;
        };
        match base.get(&key.1) {
            // The first experiment with this output's constant is the reference.
            None => {
                base.insert(key.1, row);
            }
            Some(b) => {
                rows.insert(key.clone(), sparse_diff(&row, b));
            }
        }
    }
    // An experiment without a constant row has the constant 0 there.
    let experiments: BTreeSet<usize> = rows.keys().map(|(e, _, _)| *e).collect();
    for (o, b) in base {
        for &e in &experiments {
            let key = (e, o, Vec::new());
            if !constant.contains(&key) {
                let neg: SparseRow = b.iter().map(|(j, q)| (*j, -q.clone())).collect();
                rows.insert(key, neg);
            }
        }
    }
}

/// How one experiment evaluates structural monomials.
struct RowContext<'a> {
    pattern: &'a [i8],
    /// The sign arguments `pattern` gives, when not all ([`Patterns::Local`]).
    local: Option<&'a [usize]>,
    frozen: Option<&'a [Q]>,
    varying: &'a [usize],
    /// Constants within the experiment stay rows (no per-experiment centring).
    keep_constants: bool,
}

/// Adds one structural monomial of column `j` to the rows of experiment `pi`:
/// fixed signs evaluated, varying ones kept symbolic, frozen rotation
/// variables multiplied into the coefficient.
fn add_row(
    rows: &mut BTreeMap<RowKey, SparseRow>,
    pi: usize,
    output: usize,
    q: &Q,
    vars: &[(StructVar, u32)],
    experiment: &RowContext,
    j: usize,
) {
    let mut coef = q.clone();
    let mut rest = Vec::with_capacity(vars.len());
    for (v, e) in vars {
        match v {
            StructVar::Sign(i) if experiment.varying.contains(i) => rest.push((*v, *e)),
            StructVar::Sign(i) => {
                let at = match experiment.local {
                    Some(args) => args.binary_search(i).ok(),
                    None => Some(*i),
                };
                let sign = at
                    .and_then(|k| experiment.pattern.get(k))
                    .copied()
                    .unwrap_or(1);
                if e % 2 == 1 && sign < 0 {
                    coef = -coef;
                }
            }
            StructVar::Rot(i) if experiment.frozen.is_some() => {
                let value = experiment
                    .frozen
                    .and_then(|f| f.get(*i))
                    .cloned()
                    .unwrap_or_else(Q::zero);
                for _ in 0..*e {
                    coef *= &value;
                }
            }
            _ => rest.push((*v, *e)),
        }
    }
    // A monomial that became constant is annihilated by zero-mean instruments.
    if rest.is_empty() && !experiment.keep_constants {
        return;
    }
    push_entry(rows.entry((pi, output, rest)).or_default(), j, coef);
}
