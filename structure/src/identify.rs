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

use crate::exact::{Echelon, Q, echelon, fmt_q, parse_q};
use crate::ir::{
    Aggregate, Column, ColumnKind, Combination, DroppedNuisance, Ir, KeptNuisance, NuisanceReport,
    PredictorKind, Report, Separation, SignArg, SignPattern, StructVar,
};
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
        let list = match media.as_slice() {
            [one] => one.clone(),
            [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
            [] => String::new(),
        };
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
    /// These experiments.
    Set(&'a [SignPattern]),
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

/// Exact reduction of the columns for the given patterns, in `order`, with
/// the constants the centring annihilates removed.
pub fn reduce(
    s: &Structural,
    patterns: Patterns,
    order: &[usize],
    centring: Centring,
) -> Reduction {
    let n = s.len();
    // Blocks: columns connected through shared outputs.
    let mut parent: BTreeMap<usize, usize> = BTreeMap::new();
    fn find(p: &mut BTreeMap<usize, usize>, x: usize) -> usize {
        let mut r = x;
        while let Some(&q) = p.get(&r) {
            if q == r {
                break;
            }
            r = q;
        }
        p.insert(x, r);
        r
    }
    for col in &s.cols {
        let outs: BTreeSet<usize> = col.iter().map(|(o, _, _)| *o).collect();
        let mut it = outs.into_iter();
        if let Some(first) = it.next() {
            parent.entry(first).or_insert(first);
            for o in it {
                parent.entry(o).or_insert(o);
                let (a, b) = (find(&mut parent, first), find(&mut parent, o));
                if a != b {
                    parent.insert(b, a);
                }
            }
        }
    }
    let mut blocks: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    let mut empty_cols = Vec::new();
    for &c in order {
        match s.cols[c].first() {
            Some((o, _, _)) => {
                let root = find(&mut parent, *o);
                blocks.entry(root).or_default().push(c);
            }
            None => empty_cols.push(c),
        }
    }
    let mut pivot = vec![false; n];
    let mut combination = vec![Vec::new(); n];
    for cols in blocks.values() {
        let mut rows: BTreeMap<RowKey, Vec<Q>> = BTreeMap::new();
        let width = cols.len();
        for (j, &c) in cols.iter().enumerate() {
            for (o, q, vars) in &s.cols[c] {
                match patterns {
                    Patterns::All => {
                        // Signs stay symbolic: only a monomial without any
                        // variable is the same constant in every experiment.
                        let constant = vars.iter().all(|(v, _)| matches!(v, StructVar::Sign(_)));
                        let kept = match centring {
                            Centring::Experiment => !constant,
                            Centring::Pooled => !vars.is_empty() || s.intercepts.contains(o),
                            Centring::None => true,
                        };
                        if kept {
                            let key = (0, *o, vars.clone());
                            rows.entry(key).or_insert_with(|| vec![Q::zero(); width])[j] += q;
                        }
                    }
                    Patterns::Set(set) => {
                        for (pi, pat) in set.iter().enumerate() {
                            let ctx = RowContext {
                                pattern: pat,
                                frozen: None,
                                varying: &[],
                                keep_constants: centring != Centring::Experiment,
                            };
                            add_row(&mut rows, pi, *o, q, vars, &ctx, j, width);
                        }
                    }
                    Patterns::Experiments(list) => {
                        for (pi, e) in list.iter().enumerate() {
                            let ctx = RowContext {
                                pattern: &e.pattern,
                                frozen: e.frozen_rotation.as_deref(),
                                varying: &e.varying,
                                keep_constants: centring != Centring::Experiment,
                            };
                            add_row(&mut rows, pi, *o, q, vars, &ctx, j, width);
                        }
                    }
                }
            }
        }
        if centring == Centring::Pooled && !matches!(patterns, Patterns::All) {
            pool_constants(&mut rows, &s.intercepts);
        }
        let matrix: Vec<Vec<Q>> = rows
            .into_values()
            .filter(|r| r.iter().any(|q| !q.is_zero()))
            .collect();
        let e: Echelon = echelon(&matrix, width);
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

/// Pooled centring removes, per output, the constant common to every
/// experiment: the constant rows `(experiment, output, 1)` become their
/// differences from the first experiment's (the same rank as the projection
/// onto the complement of the common constant). Outputs with a constant θ
/// column keep their constants: that column's own instrument is uncentred.
fn pool_constants(rows: &mut BTreeMap<RowKey, Vec<Q>>, intercepts: &BTreeSet<usize>) {
    let constant: Vec<RowKey> = rows
        .keys()
        .filter(|(_, o, vars)| vars.is_empty() && !intercepts.contains(o))
        .cloned()
        .collect();
    let mut base: BTreeMap<usize, Vec<Q>> = BTreeMap::new();
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
                let diff: Vec<Q> = row.iter().zip(b).map(|(a, c)| a - c).collect();
                rows.insert(key.clone(), diff);
            }
        }
    }
    // An experiment without a constant row has the constant 0 there.
    let experiments: BTreeSet<usize> = rows.keys().map(|(e, _, _)| *e).collect();
    for (o, b) in base {
        for &e in &experiments {
            let key = (e, o, Vec::new());
            if !constant.contains(&key) {
                let neg: Vec<Q> = b.iter().map(|q| -q.clone()).collect();
                rows.insert(key, neg);
            }
        }
    }
}

/// How one experiment evaluates structural monomials.
struct RowContext<'a> {
    pattern: &'a [i8],
    frozen: Option<&'a [Q]>,
    varying: &'a [usize],
    /// Constants within the experiment stay rows (no per-experiment centring).
    keep_constants: bool,
}

/// Adds one structural monomial of column `j` to the rows of experiment `pi`:
/// fixed signs evaluated, varying ones kept symbolic, frozen rotation
/// variables multiplied into the coefficient.
#[allow(clippy::too_many_arguments)]
fn add_row(
    rows: &mut BTreeMap<RowKey, Vec<Q>>,
    pi: usize,
    output: usize,
    q: &Q,
    vars: &[(StructVar, u32)],
    experiment: &RowContext,
    j: usize,
    width: usize,
) {
    let mut coef = q.clone();
    let mut rest = Vec::with_capacity(vars.len());
    for (v, e) in vars {
        match v {
            StructVar::Sign(i) if experiment.varying.contains(i) => rest.push((*v, *e)),
            StructVar::Sign(i) => {
                if e % 2 == 1 && experiment.pattern.get(*i).copied().unwrap_or(1) < 0 {
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
    let slot = &mut rows
        .entry((pi, output, rest))
        .or_insert_with(|| vec![Q::zero(); width])[j];
    *slot += coef;
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
                constant_terms.join(", "),
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
                    empty.join(", "),
                    if empty.len() == 1 { "is" } else { "are" }
                )
            } else {
                format!("{list} cannot be told apart from nuisance terms")
            }
        } else {
            format!("{list} enter only as {}", idents.join(", "))
        };
        if !nuisance.is_empty() {
            let ns: Vec<String> = nuisance.iter().map(|k| cols[*k].name.clone()).collect();
            message.push_str(&format!(" (together with {})", ns.join(", ")));
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
    let q: Vec<String> = items.iter().map(|s| format!("`{s}`")).collect();
    match q.len() {
        0 => String::new(),
        1 => q[0].clone(),
        n => format!("{} and {}", q[..n - 1].join(", "), q[n - 1]),
    }
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
        Analysis {
            names: Names {
                ir,
                columns,
                centring,
            },
            structural: Structural::new(columns),
            order: preference_order(columns, &measured),
            n_signs: ir.sign_args.len(),
            relevant: relevant_signs(ir, kind),
            kind,
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
        let red = self.reduce(patterns);
        let theta: BTreeSet<usize> = self
            .names
            .columns
            .iter()
            .enumerate()
            .filter(|(_, c)| matches!(c.kind, ColumnKind::Theta { parameter } if group.contains(&parameter)))
            .map(|(i, _)| i)
            .collect();
        red.null_space()
            .iter()
            .all(|v| v.iter().all(|(c, q)| !theta.contains(c) || q.is_zero()))
    }
    /// True when flipping any set of signs only negates whole columns.
    fn homogeneous(&self) -> bool {
        (0..self.structural.len()).all(|c| self.structural.homogeneous_signs(c).is_some())
    }
    /// The smallest set of sign patterns, over the given arguments (others +1),
    /// for which `ok` holds; `None` if none within the budget.
    fn search(
        &self,
        args: &[usize],
        ok: &dyn Fn(&[SignPattern]) -> bool,
    ) -> Option<Vec<SignPattern>> {
        let m = args.len().min(MAX_ENUMERATED_SIGNS);
        let candidates = self.expand_patterns(&args[..m]);
        let mut spent = 0usize;
        for single in &candidates {
            spent += 1;
            if ok(std::slice::from_ref(single)) {
                return Some(vec![single.clone()]);
            }
        }
        // Under sign flips columns only change sign when homogeneous, so one
        // experiment may be taken all-plus without loss of generality.
        let fix_first = self.homogeneous();
        for size in 2..=4usize.min(candidates.len()) {
            let mut idx: Vec<usize> = (0..size).collect();
            loop {
                if fix_first && idx[0] != 0 {
                    break;
                }
                spent += 1;
                if spent > SEARCH_BUDGET {
                    return None;
                }
                let set: Vec<SignPattern> = idx.iter().map(|i| candidates[*i].clone()).collect();
                if ok(&set) {
                    return Some(set);
                }
                if !next_combination(&mut idx, candidates.len()) {
                    break;
                }
            }
        }
        None
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
    /// The smallest set of sign patterns identifying θ (if θ is identifiable from any).
    pub fn required_patterns(&self) -> Option<Vec<SignPattern>> {
        if !self.identifiable(Patterns::All) {
            return None;
        }
        self.search(&self.relevant, &|set| self.identifiable(Patterns::Set(set)))
            .or_else(|| {
                // Pointwise moduli of measured media may change sign too (within an
                // experiment or between experiments): search over them as well.
                let all: Vec<usize> = (0..self.n_signs).collect();
                (all.len() > self.relevant.len())
                    .then(|| self.search(&all, &|set| self.identifiable(Patterns::Set(set))))
                    .flatten()
            })
    }
    /// Whether one experiment of any sign pattern identifies θ.
    pub fn any_single_pattern(&self) -> Option<bool> {
        if self.relevant.len() > MAX_ENUMERATED_SIGNS {
            return None;
        }
        Some(
            self.expand_patterns(&self.relevant)
                .iter()
                .all(|p| self.identifiable(Patterns::Set(std::slice::from_ref(p)))),
        )
    }
    /// What separates an unidentifiable group.
    pub fn separation(&self, combination: &Combination) -> Separation {
        let group = &combination.parameters;
        let cols = self.names.columns;
        let member_cols: Vec<usize> = (0..cols.len())
            .filter(|c| group.contains(&cols[*c].kind.parameter()))
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
                    many.join(", ")
                ),
            }
        };
        let theta_signs: Vec<Option<BTreeSet<usize>>> = group
            .iter()
            .filter_map(|p| {
                cols.iter()
                    .position(|c| c.kind == ColumnKind::Theta { parameter: *p })
            })
            .map(|c| self.structural.homogeneous_signs(c))
            .collect();
        if !self.group_identifiable(Patterns::All, group) {
            let texts: Vec<String> = group.iter().map(|p| self.names.term_text(*p)).collect();
            let why = match theta_signs.first() {
                Some(Some(s))
                    if theta_signs.iter().all(|t| t.as_ref() == Some(s)) && s.is_empty() =>
                {
                    format!(
                        "{} carry no modulus, so no sign pattern tells them apart",
                        texts.join(" and ")
                    )
                }
                Some(Some(s)) if theta_signs.iter().all(|t| t.as_ref() == Some(s)) => format!(
                    "{} carry the same sign factor ({}), so every experiment scales them alike",
                    texts.join(" and "),
                    s.iter().map(sign_name).collect::<Vec<_>>().join("·")
                ),
                _ => "their regressors coincide in every sign pattern".to_string(),
            };
            return Separation {
                parameters: group.clone(),
                patterns: None,
                message: format!("no experiment separates {list}: {why}"),
            };
        }
        let found = self.search(&args, &|set| {
            self.group_identifiable(Patterns::Set(set), group)
        });
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
                        patterns_text(self.names.ir, found.as_deref().unwrap_or(&[]), self.kind)
                    ),
                }
            }
            (Some(set), _) => format!(
                "{list} are separated by the sign patterns {}",
                patterns_text(self.names.ir, set, self.kind)
            ),
            (None, _) => {
                format!("{list}: no set of up to four sign patterns separates them (search budget)")
            }
        };
        Separation {
            parameters: group.clone(),
            patterns: found,
            message,
        }
    }
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
    let relevant = relevant_signs(ir, kind);
    let shown: Vec<usize> = (0..ir.sign_args.len())
        .filter(|i| relevant.contains(i) || set.iter().any(|p| p.get(*i).copied().unwrap_or(1) < 0))
        .collect();
    if shown.is_empty() {
        return "{} (no modulus needs a fixed sign)".to_string();
    }
    set.iter()
        .map(|p| {
            let items: Vec<String> = shown
                .iter()
                .map(|i| {
                    format!(
                        "{}{}",
                        if p.get(*i).copied().unwrap_or(1) < 0 {
                            "-"
                        } else {
                            "+"
                        },
                        ir.sign_args[*i].name
                    )
                })
                .collect();
            format!("{{{}}}", items.join(" "))
        })
        .collect::<Vec<_>>()
        .join(", ")
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
            format!("its sign arguments are {}", list.join(", "))
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

/// Options of the compile-time analysis.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Estimate identifiable combinations when θ is not identifiable.
    pub aggregate: bool,
    /// Analyse these experiments instead of searching.
    pub patterns: Option<Vec<SignPattern>>,
    /// The centring to analyse (default: the model's, [`Centring::for_model`]).
    pub centring: Option<Centring>,
}

/// θ indices of constant terms (`X_0`): parameters all of whose terms have no factor.
pub fn constant_parameters(ir: &Ir) -> Vec<usize> {
    (0..ir.parameters.len())
        .filter(|p| {
            let mut terms = ir.terms.iter().filter(|t| t.parameter == *p).peekable();
            terms.peek().is_some() && terms.all(|t| t.factors.is_empty())
        })
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
    let identifiable_under = |c: Centring| {
        let a = Analysis::with_centring(ir, PredictorKind::Measured, c);
        let red = a.reduce(Patterns::Set(patterns));
        let theta: Vec<usize> = a
            .names
            .columns
            .iter()
            .enumerate()
            .filter(|(_, col)| matches!(col.kind, ColumnKind::Theta { parameter } if constants.contains(&parameter)))
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
    match q.len() {
        0 => String::new(),
        1 => q[0].clone(),
        n => format!("{} and {}", q[..n - 1].join(", "), q[n - 1]),
    }
}

/// The compile-time identifiability report (measured predictor).
pub fn report(ir: &Ir, options: &Options) -> Report {
    let centring = options
        .centring
        .unwrap_or_else(|| Centring::for_model(ir, PredictorKind::Measured));
    let a = Analysis::with_centring(ir, PredictorKind::Measured, centring);
    let baseline = vec![vec![1i8; a.n_signs]];
    let check_set = options.patterns.clone().unwrap_or_else(|| baseline.clone());
    let red_check = a.reduce(Patterns::Set(&check_set));
    let v_check = verdict(&a.names, &red_check);
    let required = if options.patterns.is_some() {
        if v_check.identifiable {
            check_set.clone()
        } else {
            Vec::new()
        }
    } else {
        a.required_patterns().unwrap_or_default()
    };
    let identifiable = !required.is_empty();
    let reduction_set = if options.patterns.is_some() || !identifiable {
        check_set.clone()
    } else {
        required.clone()
    };
    let red = a.reduce(Patterns::Set(&reduction_set));
    let v = verdict(&a.names, &red);
    let (notes, constant_separations) = constant_notes(ir, centring, &reduction_set);
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
        any_single_pattern: a.any_single_pattern().unwrap_or(v_check.identifiable),
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
        notes,
    }
}
