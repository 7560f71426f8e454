//! Passes 5–6, reduce and identify: the exact structural rank of the stacked
//! coefficient matrix over (experiment, output, monomial), for a set of sign
//! patterns or for all of them at once (signs kept symbolic: the Walsh
//! characters of distinct sign sets are independent, so "all patterns" is the
//! matrix with sign variables kept in the monomials).
//!
//! Columns are taken in a preference order — nuisance first, then θ of
//! unmeasured media, then θ of measured media — so that
//! * θ is identifiable iff every θ column is a pivot (no null vector touches θ);
//! * a dependent nuisance column is expressed through kept nuisance only;
//! * with aggregation, the later of two confounded parameters is held at its
//!   nominal value and the kept one estimates the aggregate.

use crate::exact::{
    Echelon, Q, Small, SparseRow, echelon_sparse, field_row, fmt_q, insert_row, parse_q, small_to_q,
};
use crate::ir::{
    Aggregate, Column, ColumnKind, Combination, DroppedNuisance, Ir, KeptNuisance, NuisanceReport,
    PredictorKind, Report, Separation, SignArg, SignPattern, StructVar,
};
use leeway_grammar::{MAX_LISTED, and_list, join_capped};
use num_traits::{One, Signed, Zero};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};

/// How the instruments are centred, which decides which constants they
/// annihilate (paper A9): a monomial that is constant within an experiment
/// (the `1` of `cos² = 1 − sin²`, a constant term `X_0`, a sign alone).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Centring {
    /// Zero mean per experiment: every constant within an experiment is
    /// annihilated, and with it the means of the disturbances.
    Experiment,
    /// Zero mean over all experiments pooled: a constant common to every
    /// experiment is annihilated unless the model has a constant term in that
    /// output (whose own instrument, the constant, is kept: it spans the same
    /// instruments as no centring); constants that differ between
    /// experiments are kept.
    Pooled,
    /// No centring: constants are columns like any other.
    None,
}

impl Centring {
    /// `experiment`, `pooled`, `none`.
    pub fn name(self) -> &'static str {
        match self {
            Centring::Experiment => "experiment",
            Centring::Pooled => "pooled",
            Centring::None => "none",
        }
    }

    /// The default for a predictor of a model: per experiment when the model
    /// has a disturbance the predictor does not take from data (its mean must
    /// be annihilated), none when it has none (uncentred instruments are then
    /// consistent and keep the between-experiment information).
    pub fn for_model(ir: &Ir, kind: PredictorKind) -> Centring {
        if unmeasured_media(ir, kind).is_empty() {
            Centring::None
        } else {
            Centring::Experiment
        }
    }

    /// Why this centring is valid for the model, one sentence.
    pub fn reason(self, ir: &Ir, kind: PredictorKind) -> String {
        let media = unmeasured_media(ir, kind);
        let list = and_list(&media);
        let (is, its) = if media.len() == 1 {
            ("is", "its mean")
        } else {
            ("are", "their means")
        };
        match (self, media.is_empty()) {
            (Centring::Experiment, false) => format!(
                "the {list} {is} not taken from data by this predictor: zero-mean instruments per experiment annihilate {its} and every constant (paper A9)"
            ),
            (Centring::Experiment, true) => "zero-mean instruments per experiment annihilate every constant within an experiment (and any mean of the process disturbance)".to_string(),
            (Centring::Pooled, false) => format!(
                "valid when the means of the {list} and of the process disturbance are the same in every experiment: pooled centring keeps the between-experiment information"
            ),
            (Centring::Pooled, true) => "valid when the process disturbance has the same mean in every experiment: pooled centring keeps the between-experiment information".to_string(),
            (Centring::None, false) => format!(
                "valid only when the {list} and the process disturbance have zero mean, or their means are modelled (constant terms, nuisance columns)"
            ),
            (Centring::None, true) => "the model has no disturbance this predictor does not take from data, so uncentred instruments are consistent and keep the between-experiment information".to_string(),
        }
    }
}

/// Names of the media a predictor does not evaluate from data.
fn unmeasured_media(ir: &Ir, kind: PredictorKind) -> Vec<String> {
    ir.disturbances
        .iter()
        .filter(|d| !(d.measured && kind == PredictorKind::Measured))
        .map(|d| d.name.clone())
        .collect()
}

/// Largest number of sign arguments for which every single pattern is checked.
pub const MAX_ENUMERATED_SIGNS: usize = 8;
/// Largest number of rank evaluations one experiment search may spend.
pub const SEARCH_BUDGET: usize = 4000;

/// Of these, the most spent on dropping patterns from the constructed set
/// before the enumeration (see `Analysis::component_search`).
pub const PRUNE_BUDGET: usize = 16;

/// One parsed structural monomial: (output, coefficient, variables with powers).
type StructMonomial = (usize, Q, Vec<(StructVar, u32)>);

/// Parsed structural polynomials of a predictor's columns.
#[derive(Clone, Debug)]
pub struct Structural {
    cols: Vec<Vec<StructMonomial>>,
    /// Outputs with a constant θ column (a term like `X_0`): under pooled
    /// centring its instrument is the constant itself, so constants are kept.
    intercepts: BTreeSet<usize>,
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
    fn homogeneous_signs(&self, col: usize) -> Option<BTreeSet<usize>> {
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
    let mut parent: Vec<usize> = (0..n_out).collect();
    fn find(p: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while p[r] != r {
            r = p[r];
        }
        let mut y = x;
        while p[y] != r {
            let next = p[y];
            p[y] = r;
            y = next;
        }
        r
    }
    for col in &s.cols {
        if let Some((first, _, _)) = col.first() {
            for (o, _, _) in &col[1..] {
                let (a, b) = (find(&mut parent, *first), find(&mut parent, *o));
                if a != b {
                    parent[b] = a;
                }
            }
        }
    }
    let mut index: Vec<Option<usize>> = vec![None; n_out];
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut empty_cols = Vec::new();
    for &c in order {
        match s.cols[c].first() {
            Some((o, _, _)) => {
                let root = find(&mut parent, *o);
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

/// Context for messages: names of parameters, columns and components.
pub struct Names<'a> {
    /// The IR.
    pub ir: &'a Ir,
    /// The predictor's columns.
    pub columns: &'a [Column],
    /// The centring the analysis assumes (messages name the alternatives).
    pub centring: Centring,
}

impl Names<'_> {
    fn param(&self, p: usize) -> &str {
        &self.ir.parameters[p].name
    }
    /// What a column's coefficient is, in moments: `E[north]*X_u`.
    pub fn moment(&self, c: usize) -> String {
        let comp = |i: usize| self.ir.components[i].name.clone();
        match &self.columns[c].kind {
            ColumnKind::Theta { parameter } => self.param(*parameter).to_string(),
            ColumnKind::Rho {
                component,
                parameter,
            } => format!("E[{}]*{}", comp(*component), self.param(*parameter)),
            ColumnKind::Lambda {
                components: [a, b],
                parameter,
            } if a == b => format!("E[{}^2]*{}", comp(*a), self.param(*parameter)),
            ColumnKind::Lambda {
                components: [a, b],
                parameter,
            } => format!("E[{}*{}]*{}", comp(*a), comp(*b), self.param(*parameter)),
        }
    }
    /// The regressor text of a parameter's first term.
    pub fn term_text(&self, p: usize) -> String {
        self.ir
            .terms
            .iter()
            .find(|t| t.parameter == p)
            .map(|t| t.text.clone())
            .unwrap_or_default()
    }
}

/// `a + 2*b - 1/2*c`.
pub fn linear_text(items: &[(String, Q)]) -> String {
    let mut out = String::new();
    for (i, (name, q)) in items.iter().enumerate() {
        let neg = q.is_negative();
        let mag = q.abs();
        if i == 0 {
            if neg {
                out.push('-');
            }
        } else {
            out.push_str(if neg { " - " } else { " + " });
        }
        if mag.is_one() {
            out.push_str(name);
        } else {
            out.push_str(&format!("{}*{}", fmt_q(&mag), name));
        }
    }
    out
}

/// [`linear_text`] for a message: at most [`MAX_LISTED`] terms, then the
/// count of the others (`a + b + … (491 more terms)`).
pub fn linear_text_capped(items: &[(String, Q)]) -> String {
    if items.len() <= MAX_LISTED {
        return linear_text(items);
    }
    format!(
        "{} + … ({} more terms)",
        linear_text(&items[..MAX_LISTED]),
        items.len() - MAX_LISTED
    )
}

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
    let cols = names.columns;
    let param_of = |c: usize| match cols[c].kind {
        ColumnKind::Theta { parameter } => Some(parameter),
        _ => None,
    };
    let dropped: Vec<usize> = (0..cols.len())
        .filter(|c| !red.pivot[*c] && param_of(*c).is_some())
        .collect();
    // Union-find over θ columns linked by combinations.
    let mut group_of: BTreeMap<usize, usize> = BTreeMap::new();
    let mut groups: Vec<BTreeSet<usize>> = Vec::new();
    for &d in &dropped {
        let mut members: BTreeSet<usize> = BTreeSet::new();
        members.insert(d);
        for (k, _) in &red.combination[d] {
            if param_of(*k).is_some() {
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
    let mut combinations = Vec::new();
    let mut aggregates = Vec::new();
    for g in groups.into_iter().filter(|g| !g.is_empty()) {
        let kept: Vec<usize> = g.iter().copied().filter(|c| red.pivot[*c]).collect();
        let lost: Vec<usize> = g.iter().copied().filter(|c| !red.pivot[*c]).collect();
        let mut idents = Vec::new();
        let mut idents_short = Vec::new();
        for &k in &kept {
            let Some(pk) = param_of(k) else { continue };
            let mut items = vec![(names.param(pk).to_string(), Q::one())];
            let mut absorbed = Vec::new();
            for &d in &lost {
                if let Some((_, q)) = red.combination[d].iter().find(|(c, _)| *c == k)
                    && let Some(pd) = param_of(d)
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
        let nuisance: BTreeSet<usize> = lost
            .iter()
            .flat_map(|d| red.combination[*d].iter().map(|(k, _)| *k))
            .filter(|k| param_of(*k).is_none())
            .collect();
        let mut params: Vec<usize> = g.iter().filter_map(|c| param_of(*c)).collect();
        params.sort_unstable();
        let list = quoted_list(
            &params
                .iter()
                .map(|p| names.param(*p).to_string())
                .collect::<Vec<_>>(),
        );
        let constant_terms: Vec<String> = lost
            .iter()
            .filter(|d| red.combination[**d].is_empty() && is_constant_term(names, **d))
            .filter_map(|d| param_of(*d))
            .map(|p| format!("`{}`", names.param(p)))
            .collect();
        let mut message = if idents.is_empty() && !constant_terms.is_empty() {
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
        } else if idents.is_empty() {
            let empty: Vec<String> = lost
                .iter()
                .filter(|d| red.combination[**d].is_empty())
                .filter_map(|d| param_of(*d))
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
            format!("{list} enter only as {}", join_capped(&idents_short, ", "))
        };
        if !nuisance.is_empty() {
            let ns: Vec<String> = nuisance.iter().map(|k| cols[*k].name.clone()).collect();
            message.push_str(&format!(" (together with {})", join_capped(&ns, ", ")));
        }
        combinations.push(Combination {
            parameters: params,
            identifiable: idents,
            message,
        });
    }
    Verdict {
        identifiable: dropped.is_empty(),
        combinations,
        aggregates,
    }
}

/// True for a θ column whose terms are all constants (`X_0`).
fn is_constant_term(names: &Names, col: usize) -> bool {
    let c = &names.columns[col];
    !c.kind.is_nuisance()
        && !c.structural.is_empty()
        && c.structural.iter().all(|e| e.vars.is_empty())
}

fn quoted_list(items: &[String]) -> String {
    and_list(items.iter().map(|s| format!("`{s}`")))
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
    blocks: Vec<Vec<usize>>,
    /// Columns without any structural entry.
    empty_cols: Vec<usize>,
    /// The block of each column (`None` for an empty column).
    block_of: Vec<Option<usize>>,
    /// Columns of each parameter (θ first, then its nuisance columns).
    param_cols: BTreeMap<usize, Vec<usize>>,
    /// The first term of each parameter (for messages).
    first_term: BTreeMap<usize, usize>,
}

/// A set of sign patterns found by [`Analysis::smallest`].
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    /// The patterns (all-plus first where that is no loss).
    pub patterns: Vec<SignPattern>,
    /// `None` when no smaller set exists (proven); otherwise what the
    /// search did not try before its budget ran out (the set still works).
    pub untried: Option<String>,
}

/// One component's set: its patterns (over the component's arguments only),
/// and when the budget cut the search, the size from which sets were not all
/// tried.
struct ComponentSet {
    patterns: Vec<SignPattern>,
    exhausted_below: Option<usize>,
}

/// The sign arguments among `args` (sorted) that occur with an odd power.
fn odd_signs(vars: &[(StructVar, u32)], args: &[usize]) -> Vec<usize> {
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

/// One family of rows for [`Analysis::completion`]: its sign characters and
/// the reduced row echelon form of its evaluation matrix so far, in `i128`
/// fractions while they fit (the matrix holds ±1), else exactly in big
/// rationals, rebuilt from the rows added.
struct Family {
    chars: Vec<Vec<usize>>,
    /// The evaluation rows added so far (±1 per character).
    rows: Vec<Vec<i8>>,
    basis: Basis,
}

/// A reduced basis: pivot column and row.
enum Basis {
    Small(Vec<(usize, Vec<Small>)>),
    Big(Vec<(usize, Vec<Q>)>),
}

impl Basis {
    fn len(&self) -> usize {
        match self {
            Basis::Small(b) => b.len(),
            Basis::Big(b) => b.len(),
        }
    }
}

impl Family {
    fn new(chars: Vec<Vec<usize>>) -> Family {
        Family {
            chars,
            rows: Vec::new(),
            basis: Basis::Small(Vec::new()),
        }
    }
    /// Adds the row of pattern `p`.
    fn add(&mut self, p: &SignPattern) {
        if self.basis.len() == self.chars.len() {
            return;
        }
        let signs: Vec<i8> = self
            .chars
            .iter()
            .map(|ch| {
                if ch.iter().filter(|i| p[**i] < 0).count() % 2 == 1 {
                    -1
                } else {
                    1
                }
            })
            .collect();
        self.rows.push(signs);
        let added = match &mut self.basis {
            Basis::Small(b) => field_row::<Small>(&self.rows[self.rows.len() - 1])
                .and_then(|row| insert_row(b, row)),
            Basis::Big(b) => {
                field_row::<Q>(&self.rows[self.rows.len() - 1]).and_then(|row| insert_row(b, row))
            }
        };
        if added.is_none() {
            // Overflow: redo every row exactly (cannot overflow).
            let mut big = Vec::new();
            for r in &self.rows {
                if let Some(row) = field_row::<Q>(r) {
                    let _ = insert_row(&mut big, row);
                }
            }
            self.basis = Basis::Big(big);
        }
    }
    /// `Σ c_S χ_S` for a null vector `c` of the evaluation matrix, if it is
    /// rank deficient: a free column `j`, minus its pivot rows' entries.
    fn null_poly(&self) -> Option<BTreeMap<Vec<usize>, Q>> {
        let pivots: BTreeSet<usize> = match &self.basis {
            Basis::Small(b) => b.iter().map(|(pc, _)| *pc).collect(),
            Basis::Big(b) => b.iter().map(|(pc, _)| *pc).collect(),
        };
        let j = (0..self.chars.len()).find(|j| !pivots.contains(j))?;
        let mut poly = BTreeMap::new();
        poly.insert(self.chars[j].clone(), Q::one());
        // Column `j` of each basis row only (the rest is never needed).
        let entries: Vec<(usize, Q)> = match &self.basis {
            Basis::Small(b) => b
                .iter()
                .map(|(pc, row)| (*pc, small_to_q(&row[j])))
                .collect(),
            Basis::Big(b) => b.iter().map(|(pc, row)| (*pc, row[j].clone())).collect(),
        };
        for (pc, x) in entries {
            if !x.is_zero() {
                poly.insert(self.chars[pc].clone(), -x);
            }
        }
        Some(poly)
    }
}

/// A point of {±1}ⁿ (over `args`, the rest +1) where the first of these
/// nonzero multilinear polynomials `Σ c_S χ_S` does not vanish, and as many
/// of the others as the choices allow: variable by variable, write each
/// `g + s·h`; if `h ≠ 0` one of `g + h`, `g − h` is nonzero (they differ by
/// `2h`), so a polynomial forbids at most one sign; the first one alive is
/// obeyed, the others by majority. The first stays nonzero to the end, a
/// nonzero constant.
fn nonzero_point(polys: Vec<BTreeMap<Vec<usize>, Q>>, args: &[usize], n: usize) -> SignPattern {
    let mut p = vec![1i8; n];
    let mut alive = polys;
    for &i in args {
        // For each polynomial: (g + h, g − h), or None when s_i is absent.
        let split: Vec<Option<(Poly, Poly)>> = alive
            .iter()
            .map(|poly| {
                if !poly.keys().any(|set| set.binary_search(&i).is_ok()) {
                    return None;
                }
                let mut plus: Poly = BTreeMap::new();
                let mut minus: Poly = BTreeMap::new();
                for (set, c) in poly {
                    match set.binary_search(&i) {
                        Ok(k) => {
                            let mut rest = set.clone();
                            rest.remove(k);
                            *plus.entry(rest.clone()).or_insert_with(Q::zero) += c;
                            *minus.entry(rest).or_insert_with(Q::zero) -= c;
                        }
                        Err(_) => {
                            *plus.entry(set.clone()).or_insert_with(Q::zero) += c;
                            *minus.entry(set.clone()).or_insert_with(Q::zero) += c;
                        }
                    }
                }
                plus.retain(|_, c| !c.is_zero());
                minus.retain(|_, c| !c.is_zero());
                Some((plus, minus))
            })
            .collect();
        let first_forbids_plus = matches!(&split[0], Some((plus, _)) if plus.is_empty());
        let first_forbids_minus = matches!(&split[0], Some((_, minus)) if minus.is_empty());
        let sign = if first_forbids_plus {
            -1
        } else if first_forbids_minus {
            1
        } else {
            let kills = |minus_side: bool| {
                split
                    .iter()
                    .filter(|s| match s {
                        Some((plus, minus)) => {
                            if minus_side {
                                minus.is_empty()
                            } else {
                                plus.is_empty()
                            }
                        }
                        None => false,
                    })
                    .count()
            };
            if kills(true) < kills(false) { -1 } else { 1 }
        };
        p[i] = sign;
        alive = alive
            .into_iter()
            .zip(split)
            .filter_map(|(poly, s)| match s {
                None => Some(poly),
                Some((plus, minus)) => {
                    let next = if sign > 0 { plus } else { minus };
                    (!next.is_empty()).then_some(next)
                }
            })
            .collect();
    }
    p
}

/// A row family: an output and a monomial without its sign variables.
type FamilyKey = (usize, Vec<(StructVar, u32)>);

/// A multilinear polynomial in sign variables: odd sign set → coefficient.
type Poly = BTreeMap<Vec<usize>, Q>;

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
    fn group_identifiable(&self, patterns: Patterns, group: &[usize]) -> bool {
        let theta = self.group_theta(group);
        if theta.iter().any(|c| self.block_of[*c].is_none()) {
            return false;
        }
        // Only the blocks holding the group's columns matter.
        let involved = self.blocks_holding(theta.iter().copied());
        self.blocks_ok(patterns, &involved, &|c| theta.contains(&c))
    }
    /// The blocks holding these columns, sorted.
    fn blocks_holding(&self, cols: impl Iterator<Item = usize>) -> Vec<usize> {
        let set: BTreeSet<usize> = cols.filter_map(|c| self.block_of[c]).collect();
        set.into_iter().collect()
    }
    /// The θ columns of a group of parameters.
    fn group_theta(&self, group: &[usize]) -> BTreeSet<usize> {
        group
            .iter()
            .flat_map(|p| self.param_cols.get(p).into_iter().flatten())
            .copied()
            .filter(|c| !self.names.columns[*c].kind.is_nuisance())
            .collect()
    }
    /// In these blocks, are the columns `need` selects free of every null vector?
    fn blocks_ok(
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
    fn block_signs(&self, b: usize, args: &[usize]) -> Vec<usize> {
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
    fn homogeneous_over(&self, blocks: &[usize], args: &[usize]) -> bool {
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
    /// The smallest set of sign patterns over `args` (sorted; the other
    /// signs +1) for which the columns `need` selects are free of every null
    /// vector; `None` when no set of patterns over `args` achieves it.
    ///
    /// Exact for any number of arguments, by two facts. (1) With the signs
    /// symbolic the Walsh characters of distinct sign sets are linearly
    /// independent functions on {±1}ⁿ, so some set of patterns achieves it
    /// iff [`Patterns::Symbolic`] does, and a set does iff its evaluation
    /// matrix over the characters the columns hold has the rank the symbolic
    /// rows need; one pattern per character suffices, found deterministically
    /// (`Analysis::completion`). (2) The stacked matrix is block diagonal
    /// over output blocks and a block sees only its own signs, so the sign
    /// arguments fall into components (arguments shared by a block) whose
    /// pattern sets can be chosen independently; a set of k patterns works
    /// iff its projection on every component works, so the smallest size is
    /// the largest of the components' smallest sizes, and the components'
    /// sets, padded by repeating a pattern, combine into one set of that
    /// size. Only a component whose own patterns are too many to enumerate
    /// within [`SEARCH_BUDGET`] leaves minimality undecided (never the verdict).
    pub fn smallest(&self, args: &[usize], needed: &BTreeSet<usize>) -> Option<Found> {
        let need = &|c: usize| needed.contains(&c);
        if needed.iter().any(|c| self.block_of[*c].is_none()) {
            return None;
        }
        let involved = self.blocks_holding(needed.iter().copied());
        if !self.blocks_ok(Patterns::Symbolic(args), &involved, need) {
            return None;
        }
        // Components: blocks that share a sign argument.
        let mut parent: Vec<usize> = (0..args.len()).collect();
        fn find(p: &mut [usize], x: usize) -> usize {
            let mut r = x;
            while p[r] != r {
                r = p[r];
            }
            p[x] = r;
            r
        }
        let sigs: Vec<(usize, Vec<usize>)> = involved
            .iter()
            .map(|b| {
                let sig: Vec<usize> = self
                    .block_signs(*b, args)
                    .iter()
                    .filter_map(|i| args.binary_search(i).ok())
                    .collect();
                (*b, sig)
            })
            .filter(|(_, sig)| !sig.is_empty())
            .collect();
        for (_, sig) in &sigs {
            for w in sig.windows(2) {
                let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
                if a != b {
                    parent[b] = a;
                }
            }
        }
        let mut components: BTreeMap<usize, (BTreeSet<usize>, Vec<usize>)> = BTreeMap::new();
        for (b, sig) in &sigs {
            let root = find(&mut parent, sig[0]);
            let entry = components.entry(root).or_default();
            entry.0.extend(sig.iter().map(|k| args[*k]));
            entry.1.push(*b);
        }
        let mut sets: Vec<(Vec<usize>, Vec<SignPattern>)> = Vec::new();
        let mut untried: Vec<String> = Vec::new();
        for (comp_args, comp_blocks) in components.into_values() {
            let comp_args: Vec<usize> = comp_args.into_iter().collect();
            let c = self.component_search(&comp_args, &comp_blocks, need)?;
            if let Some(below) = c.exhausted_below {
                let names: Vec<String> = comp_args
                    .iter()
                    .map(|i| self.names.ir.sign_args[*i].name.clone())
                    .collect();
                let top = c.patterns.len() - 1;
                let sizes = if below == top {
                    format!(
                        "sets of {below} pattern{}",
                        if below == 1 { "" } else { "s" }
                    )
                } else {
                    format!("sets of {below} to {top} patterns")
                };
                untried.push(format!(
                    "{sizes} of the {} interacting sign arguments {}",
                    comp_args.len(),
                    join_capped(&names, ", ")
                ));
            }
            // Over the component's own arguments: a full pattern per
            // component would be quadratic in the number of sign arguments.
            sets.push((comp_args, c.patterns));
        }
        let k = sets.iter().map(|(_, s)| s.len()).max().unwrap_or(1);
        let patterns: Vec<SignPattern> = (0..k)
            .map(|j| {
                let mut p = vec![1i8; self.n_signs];
                for (comp_args, set) in &sets {
                    let w = &set[j.min(set.len() - 1)];
                    for (k, &a) in comp_args.iter().enumerate() {
                        p[a] = w[k];
                    }
                }
                p
            })
            .collect();
        debug_assert!(self.blocks_ok(Patterns::Set(&patterns), &involved, need));
        Some(Found {
            patterns,
            untried: (!untried.is_empty()).then(|| {
                format!(
                    "the search for a smaller set was cut at its budget of {SEARCH_BUDGET} rank evaluations per component before trying {}",
                    untried.join("; ")
                )
            }),
        })
    }
    /// The smallest set of patterns over one component's arguments (see
    /// [`Analysis::smallest`]).
    fn component_search(
        &self,
        args: &[usize],
        blocks: &[usize],
        need: &dyn Fn(usize) -> bool,
    ) -> Option<ComponentSet> {
        // Patterns over `args` only (see `Patterns::Local`).
        let ok = |set: &[SignPattern]| self.blocks_ok(Patterns::Local { args, set }, blocks, need);
        let upper = self.completion(args, blocks);
        if !ok(&upper) {
            return None;
        }
        let u = upper.len();
        let done = |patterns: Vec<SignPattern>, exhausted_below: Option<usize>| {
            Some(ComponentSet {
                patterns,
                exhausted_below,
            })
        };
        // Each pattern gives one row per family (output, monomial without
        // its signs), so the θ columns living in one family alone, which must
        // be independent, need at least as many patterns.
        let mut per_family: BTreeMap<FamilyKey, usize> = BTreeMap::new();
        for &b in blocks {
            for &c in self.blocks[b].iter().filter(|c| need(**c)) {
                let mut families = self.structural.cols[c].iter().map(|(o, _, vars)| {
                    let rest: Vec<(StructVar, u32)> = vars
                        .iter()
                        .filter(|(v, _)| !matches!(v, StructVar::Sign(_)))
                        .copied()
                        .collect();
                    (*o, rest)
                });
                if let Some(first) = families.next()
                    && !first.1.is_empty()
                    && families.all(|f| f == first)
                {
                    *per_family.entry(first).or_default() += 1;
                }
            }
        }
        let lower = per_family.values().copied().max().unwrap_or(1).max(1);
        // The completion asks full rank of every family, which is more than
        // θ may need (a measured medium's constant character, say): drop
        // patterns one at a time while the rest still identify, a few rank
        // evaluations that often bring the upper bound down to the lower one.
        let (mut upper, mut u) = (upper, u);
        let mut spent = 0usize;
        'prune: while lower < u {
            // The latest first: the all-plus pattern keeps the rows sparse.
            for drop in (0..u).rev() {
                if spent >= PRUNE_BUDGET {
                    break 'prune;
                }
                spent += 1;
                let fewer: Vec<SignPattern> = upper
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| *k != drop)
                    .map(|(_, p)| p.clone())
                    .collect();
                if ok(&fewer) {
                    upper = fewer;
                    u -= 1;
                    continue 'prune;
                }
            }
            break;
        }
        if lower >= u {
            return done(upper, None);
        }
        // Candidates by index: bit k of the index is the sign of args[k].
        let bits = args.len().min(60);
        let n_cand = 1usize << bits;
        let candidate = |index: usize| -> SignPattern {
            let mut p = vec![1i8; args.len()];
            for (k, slot) in p.iter_mut().enumerate().take(bits) {
                if index >> k & 1 == 1 {
                    *slot = -1;
                }
            }
            p
        };
        // With homogeneous columns a common flip of every pattern changes no
        // rank, so one experiment may be taken all-plus.
        let fix_first = self.homogeneous_over(blocks, args);
        for size in lower..=u {
            // The sets of this size to try; when more than the budget left,
            // the size cannot be exhausted (the found set is minimal anyway
            // once every smaller size was).
            let count = if fix_first {
                binomial(n_cand - 1, size - 1)
            } else {
                binomial(n_cand, size)
            };
            if (bits < args.len() && !(fix_first && size == 1)) || count > SEARCH_BUDGET - spent {
                return done(upper, (size < u).then_some(size));
            }
            if size > n_cand {
                break;
            }
            let mut idx: Vec<usize> = (0..size).collect();
            loop {
                if fix_first && idx[0] != 0 {
                    break;
                }
                spent += 1;
                let set: Vec<SignPattern> = idx.iter().map(|i| candidate(*i)).collect();
                if ok(&set) {
                    return done(set, None);
                }
                if !next_combination(&mut idx, n_cand) {
                    break;
                }
            }
        }
        done(upper, None)
    }
    /// A set of patterns over `args` that identifies whatever the symbolic
    /// signs identify in these blocks, all-plus first. Rows of one family
    /// (output, monomial without its signs) are `Σ_S χ_S(p)·b_S` over the
    /// sign characters `S` the family holds, so a set whose evaluation
    /// matrix `[χ_S(p)]` has full column rank in every family has the
    /// symbolic null space. While a family is rank deficient, a null vector
    /// `c` of its matrix gives the nonzero multilinear polynomial `Σ c_S χ_S`;
    /// a point where it does not vanish (found variable by variable, keeping
    /// as many other deficient families' polynomials nonzero as possible)
    /// raises that family's rank. At most one pattern per character.
    /// The patterns are over `args` only (see [`Patterns::Local`]).
    fn completion(&self, args: &[usize], blocks: &[usize]) -> Vec<SignPattern> {
        // Characters by position in `args`.
        let local = |vars: &[(StructVar, u32)]| -> Vec<usize> {
            odd_signs(vars, args)
                .iter()
                .filter_map(|i| args.binary_search(i).ok())
                .collect()
        };
        let mut by_family: BTreeMap<FamilyKey, BTreeSet<Vec<usize>>> = BTreeMap::new();
        for &b in blocks {
            for &c in &self.blocks[b] {
                for (o, _, vars) in &self.structural.cols[c] {
                    let rest: Vec<(StructVar, u32)> = vars
                        .iter()
                        .filter(|(v, _)| !matches!(v, StructVar::Sign(_)))
                        .copied()
                        .collect();
                    // A monomial constant within an experiment gives no row
                    // under per-experiment centring (symbolic or not), so its
                    // family needs no pattern of its own.
                    if rest.is_empty() && self.names.centring == Centring::Experiment {
                        continue;
                    }
                    let entry = by_family.entry((*o, rest.clone())).or_default();
                    entry.insert(local(vars));
                    if rest.is_empty() {
                        entry.insert(Vec::new());
                    }
                }
            }
        }
        let mut families: Vec<Family> = by_family
            .into_values()
            .filter(|chars| chars.len() > 1)
            .map(|chars| Family::new(chars.into_iter().collect()))
            .collect();
        let positions: Vec<usize> = (0..args.len()).collect();
        let mut set = vec![vec![1i8; args.len()]];
        for f in &mut families {
            f.add(&set[0]);
        }
        loop {
            let polys: Vec<BTreeMap<Vec<usize>, Q>> =
                families.iter().filter_map(Family::null_poly).collect();
            if polys.is_empty() {
                break;
            }
            let p = nonzero_point(polys, &positions, args.len());
            for f in &mut families {
                f.add(&p);
            }
            set.push(p);
        }
        set
    }
    /// Every pattern over `args`, the other signs +1, all-plus first.
    pub fn expand_patterns(&self, args: &[usize]) -> Vec<SignPattern> {
        all_patterns(args.len())
            .into_iter()
            .map(|small| {
                let mut p = vec![1i8; self.n_signs];
                for (k, a) in args.iter().enumerate() {
                    p[*a] = small[k];
                }
                p
            })
            .collect()
    }
    /// The smallest set of sign patterns identifying θ, if any identifies it:
    /// first over the signs the predictor fixes per experiment (pointwise ones
    /// +1), else over every sign argument (pointwise moduli may change sign
    /// within an experiment or between experiments).
    pub fn required(&self) -> Option<Found> {
        let theta: BTreeSet<usize> = (0..self.names.columns.len())
            .filter(|c| !self.names.columns[*c].kind.is_nuisance())
            .collect();
        self.smallest(&self.relevant, &theta).or_else(|| {
            let all: Vec<usize> = (0..self.n_signs).collect();
            (all.len() > self.relevant.len())
                .then(|| self.smallest(&all, &theta))
                .flatten()
        })
    }
    /// The smallest set of sign patterns identifying θ (if θ is identifiable
    /// from any; see [`Analysis::required`] for whether it is proven smallest).
    pub fn required_patterns(&self) -> Option<Vec<SignPattern>> {
        self.required().map(|f| f.patterns)
    }
    /// Whether one experiment of any sign pattern (over the signs the
    /// predictor fixes) identifies θ; `None` when a block holds too many
    /// interacting sign arguments to check every pattern within the budget.
    pub fn any_single_pattern(&self) -> Option<bool> {
        self.any_single_pattern_given(self.required().as_ref())
    }
    /// [`Analysis::any_single_pattern`] with the required set known.
    pub fn any_single_pattern_given(&self, required: Option<&Found>) -> Option<bool> {
        match required {
            None => return Some(false),
            Some(f) if f.untried.is_none() && f.patterns.len() > 1 => return Some(false),
            _ => {}
        }
        self.any_single_blocks()
    }
    /// [`Analysis::any_single_pattern`] block by block: each block sees only
    /// its own signs, so every pattern of those is tried (one when the block
    /// is homogeneous).
    pub fn any_single_blocks(&self) -> Option<bool> {
        let theta = |c: usize| !self.names.columns[c].kind.is_nuisance();
        if self.empty_cols.iter().any(|c| theta(*c)) {
            return Some(false);
        }
        // Blocks are independent and each sees only its own signs.
        for b in 0..self.blocks.len() {
            if !self.blocks[b].iter().any(|c| theta(*c)) {
                continue;
            }
            let sig = self.block_signs(b, &self.relevant);
            let candidates = if self.homogeneous_over(&[b], &sig) {
                vec![vec![1i8; self.n_signs]]
            } else if sig.len() < usize::BITS as usize - 1 && (1usize << sig.len()) <= SEARCH_BUDGET
            {
                self.expand_patterns(&sig)
            } else {
                return None;
            };
            for p in &candidates {
                if !self.blocks_ok(Patterns::Set(std::slice::from_ref(p)), &[b], &theta) {
                    return Some(false);
                }
            }
        }
        Some(true)
    }
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

/// `C(n, k)`, saturating at `usize::MAX`.
fn binomial(n: usize, k: usize) -> usize {
    if k > n {
        return 0;
    }
    let k = k.min(n - k);
    let mut out: u128 = 1;
    for i in 0..k {
        out = out * (n - i) as u128 / (i + 1) as u128;
        if out > usize::MAX as u128 {
            return usize::MAX;
        }
    }
    out as usize
}

/// Advances `idx` (strictly increasing, below `n`) to the next combination.
fn next_combination(idx: &mut [usize], n: usize) -> bool {
    let k = idx.len();
    let mut i = k;
    while i > 0 {
        i -= 1;
        if idx[i] < n - k + i {
            idx[i] += 1;
            for j in i + 1..k {
                idx[j] = idx[j - 1] + 1;
            }
            return true;
        }
    }
    false
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

/// What the analysis says about constant terms under each centring: a note
/// per constant, and for a group of constants that the centring annihilates,
/// the option that makes them estimable.
fn constant_notes(
    ir: &Ir,
    centring: Centring,
    patterns: &[SignPattern],
) -> (Vec<String>, Vec<(Vec<usize>, String)>) {
    let constants = constant_parameters(ir);
    if constants.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let constant_set: BTreeSet<usize> = constants.iter().copied().collect();
    let identifiable_under = |c: Centring| {
        let a = Analysis::with_centring(ir, PredictorKind::Measured, c);
        let red = a.reduce(Patterns::Set(patterns));
        let theta: BTreeSet<usize> = a
            .names
            .columns
            .iter()
            .enumerate()
            .filter(|(_, col)| matches!(col.kind, ColumnKind::Theta { parameter } if constant_set.contains(&parameter)))
            .map(|(i, _)| i)
            .collect();
        red.null_space()
            .iter()
            .all(|v| v.iter().all(|(c, q)| !theta.contains(c) || q.is_zero()))
    };
    let names: Vec<String> = constants
        .iter()
        .map(|p| format!("`{}`", ir.parameters[*p].name))
        .collect();
    let list = quoted_join(&names);
    let here = identifiable_under(centring);
    let none = identifiable_under(Centring::None);
    let pooled = identifiable_under(Centring::Pooled);
    let mut notes = Vec::new();
    let mut separations = Vec::new();
    let alternatives: Vec<&str> = [(Centring::None, none), (Centring::Pooled, pooled)]
        .iter()
        .filter(|(c, ok)| *ok && *c != centring)
        .map(|(c, _)| match c {
            Centring::None => "`--centring none` (uncentred instruments)",
            _ => "`--centring pooled`",
        })
        .collect();
    if here {
        notes.push(format!(
            "{list}: constant term{} (a constant force), identifiable with {}; least squares estimates {} as its intercept",
            if constants.len() == 1 { "" } else { "s" },
            match centring {
                Centring::None => "uncentred instruments (centring none)",
                Centring::Pooled => "pooled centring (a constant's own instrument stays uncentred)",
                Centring::Experiment => "per-experiment centring",
            },
            if constants.len() == 1 { "it" } else { "them" }
        ));
    } else {
        let message = if alternatives.is_empty() {
            format!(
                "{list}: constant term{} that no centring separates from the constant parts of the other columns (e.g. the nuisance moments of `cos² = 1 − sin²`); remove {} or estimate the aggregate with --aggregate",
                if constants.len() == 1 { "" } else { "s" },
                if constants.len() == 1 { "it" } else { "them" }
            )
        } else {
            format!(
                "{list} {} estimable with {}: {} centring annihilates every constant ({})",
                if constants.len() == 1 { "is" } else { "are" },
                alternatives.join(" or "),
                centring.name(),
                Centring::None.reason(ir, PredictorKind::Measured)
            )
        };
        separations.push((constants.clone(), message));
    }
    (notes, separations)
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
    let (mut notes, constant_separations) = constant_notes(ir, centring, &reduction_set);
    let separations = v_check
        .combinations
        .iter()
        .map(|c| {
            // A group of constant terms is separated by the centring, not by signs.
            match constant_separations
                .iter()
                .find(|(ps, _)| c.parameters.iter().all(|p| ps.contains(p)))
            {
                Some((_, message)) => Separation {
                    parameters: c.parameters.clone(),
                    patterns: None,
                    arguments: Vec::new(),
                    message: message.clone(),
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
