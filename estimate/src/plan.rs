//! What is estimated before any data pass: the structural analysis for the experiments' sign patterns, held columns, blocks of outputs, the meaning of each kept column.
//!
//! The analysis is exact (`leeway_structure::identify`, under the centring
//! used) and the single source of identifiability verdicts; the solve's
//! numeric rank only adds what the data failed to excite. Its result depends
//! only on a [`PlanKey`], so passes serving several estimates keep each
//! [`StructuralPlan`] and an estimate with the same key skips the analysis.

use crate::options::EstimateOptions;
use crate::outcome::{EstimateError, err};
use crate::record::ExperimentInfo;
use leeway_model::signs::ExperimentSigns;
use leeway_structure::exact::Q;
use leeway_structure::identify::Centring;
use leeway_structure::identify::{
    Analysis, ExperimentStructure, Patterns, Reduction, Verdict, centring_remedies,
    constant_parameters, linear_text, patterns_text, remedies_text, verdict,
};
use leeway_structure::ir::{ColumnKind, Ir, PredictorKind};
use std::collections::BTreeMap;

/// What an estimate's structural analysis depends on: the predictor, the
/// centring, whether unidentifiable parameters are aggregated (and the
/// nominal values they are then held at), and each experiment's sign
/// pattern, sign-changing arguments and frozen rotation.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanKey {
    pub(crate) kind: PredictorKind,
    pub(crate) centring: Centring,
    pub(crate) aggregate: bool,
    pub(crate) nominal: Vec<u64>,
    pub(crate) experiments: Vec<ExperimentStructure>,
}

/// What the structural analysis fixed for an estimate (see [`PlanKey`]):
/// the blocks of outputs and their structurally kept columns, the columns
/// held and what the kept ones estimate. The same key gives the same plan,
/// so runners that serve several estimates keep it
/// ([`Passes::known_plan`](crate::protocol::Passes::known_plan)).
#[derive(Clone, Debug)]
pub struct StructuralPlan {
    pub(crate) constant_cols: Vec<bool>,
    pub(crate) blocks: Vec<Block>,
    pub(crate) block_of_output: Vec<usize>,
    pub(crate) held: Vec<(usize, f64)>,
    pub(crate) preference: Vec<usize>,
    pub(crate) meaning: BTreeMap<usize, Vec<(usize, f64)>>,
    /// What each predictor column estimates, as the report states it.
    pub(crate) column_texts: std::sync::Arc<[String]>,
    pub(crate) aggregates: Vec<String>,
}

/// Fewest equations per column of the largest block (a bare minimum for the
/// moment matrices to have full rank with some margin).
pub(super) const MIN_EQUATIONS_PER_COLUMN: usize = 3;

impl StructuralPlan {
    /// Runs the structural analysis for `key` (see [`PlanKey`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        ir: &Ir,
        options: &EstimateOptions,
        kind: PredictorKind,
        centring: Centring,
        nominal: &[f64],
        infos: &[ExperimentInfo],
        signs: &[ExperimentSigns],
        key: &PlanKey,
    ) -> Result<StructuralPlan, EstimateError> {
        let columns = ir.predictors.get(kind);
        let n_cols = columns.len();
        let analysis = Analysis::with_centring(ir, kind, centring);
        let constant_cols: Vec<bool> = (0..n_cols)
            .map(|c| !columns[c].kind.is_nuisance() && analysis.structural.is_constant(c))
            .collect();
        let red = analysis.reduce(Patterns::Experiments(&key.experiments));
        let v = verdict(&analysis.names, &red);
        let mut held = Vec::new();
        let mut aggregates = Vec::new();
        if !v.identifiable {
            if !options.aggregate {
                return Err(unidentifiable(
                    ir, &analysis, &v, kind, centring, infos, signs,
                ));
            }
            for a in &v.aggregates {
                aggregates.push(format!(
                    "{} estimates {} (absorbed parameters held at their nominal values)",
                    ir.parameters[a.parameter].name, a.estimates
                ));
            }
            for (c, col) in columns.iter().enumerate() {
                if let ColumnKind::Theta { parameter } = col.kind
                    && !red.pivot[c]
                {
                    held.push((c, nominal[parameter]));
                }
            }
        }
        let meaning = meaning(&red, n_cols);
        let (blocks, block_of_output) = output_blocks(ir, columns, &red);
        let mut preference = vec![0; n_cols];
        for (rank, c) in analysis.order.iter().enumerate() {
            preference[*c] = rank;
        }
        let column_texts = column_texts(ir, columns, centring, &meaning);
        Ok(StructuralPlan {
            constant_cols,
            blocks,
            block_of_output,
            held,
            preference,
            meaning,
            column_texts,
            aggregates,
        })
    }
}

/// The error for a predictor that does not identify θ from these
/// experiments (verdict `v`), with a hint of what would.
fn unidentifiable(
    ir: &Ir,
    analysis: &Analysis,
    v: &Verdict,
    kind: PredictorKind,
    centring: Centring,
    infos: &[ExperimentInfo],
    signs: &[ExperimentSigns],
) -> EstimateError {
    let distinct: Vec<Vec<i8>> = {
        let mut p: Vec<Vec<i8>> = signs.iter().map(|s| s.pattern.clone()).collect();
        p.sort();
        p.dedup();
        p
    };
    let combos: Vec<String> = v.combinations.iter().map(|c| c.message.clone()).collect();
    let remark2 = infos.iter().any(|i| i.frozen.is_some());
    let constants = constant_parameters(ir);
    let only_constants = v
        .combinations
        .iter()
        .all(|c| c.parameters.iter().all(|p| constants.contains(p)));
    let required = analysis.required_patterns();
    let hint = match (&required, remark2) {
                    (None, _) if only_constants => {
                        match remedies_text(ir, kind, &centring_remedies(ir, kind, centring)) {
                            Some(way) => format!("θ is identifiable with {way}; or remove the constant term"),
                            None => "no centring identifies the constant term from any experiments: remove it, or estimate the identifiable combinations with --aggregate".to_string(),
                        }
                    }
                    (_, true) => "the heading barely varied: run experiments that turn the craft (paper Remark 2), or estimate the identifiable combinations with --aggregate".to_string(),
                    (Some(r), false) if !r.is_empty() => format!(
                        "θ needs experiments with sign patterns {}; or estimate the identifiable combinations with --aggregate",
                        patterns_text(ir, r, kind)
                    ),
                    _ => "no set of experiments identifies θ with this predictor; estimate the identifiable combinations with --aggregate".to_string(),
                };
    err(
        "unidentifiable",
        format!(
            "θ is not identifiable from these experiments (sign patterns {}): {}",
            patterns_text(ir, &distinct, kind),
            combos.join("; ")
        ),
        hint,
    )
}

/// What each kept column estimates: itself plus the structurally dropped
/// columns expressed through it.
fn meaning(red: &Reduction, n_cols: usize) -> BTreeMap<usize, Vec<(usize, f64)>> {
    let mut meaning: BTreeMap<usize, Vec<(usize, f64)>> = BTreeMap::new();
    for c in 0..n_cols {
        if red.pivot[c] {
            meaning.entry(c).or_default().push((c, 1.0));
        }
    }
    for d in 0..n_cols {
        if !red.pivot[d] {
            for (k, q) in &red.combination[d] {
                meaning
                    .entry(*k)
                    .or_default()
                    .push((d, leeway_structure::exact::to_f64(q)));
            }
        }
    }
    meaning
}

/// Blocks: outputs connected through shared columns, each with its
/// structurally kept columns; and the block of each output.
fn output_blocks(
    ir: &Ir,
    columns: &[leeway_structure::ir::Column],
    red: &Reduction,
) -> (Vec<Block>, Vec<usize>) {
    let n_out = ir.states.len();
    let mut parent: Vec<usize> = (0..n_out).collect();
    fn find(p: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while p[r] != r {
            r = p[r];
        }
        p[x] = r;
        r
    }
    for col in columns {
        let outs = col.outputs();
        for w in outs.windows(2) {
            let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
            parent[b] = a;
        }
    }
    let mut blocks: Vec<Block> = Vec::new();
    let mut block_of_output = vec![0; n_out];
    for (o, slot) in block_of_output.iter_mut().enumerate() {
        let root = find(&mut parent, o);
        let b = match blocks
            .iter()
            .position(|b| find(&mut parent, b.outputs[0]) == root)
        {
            Some(b) => b,
            None => {
                blocks.push(Block {
                    outputs: Vec::new(),
                    cols: Vec::new(),
                });
                blocks.len() - 1
            }
        };
        blocks[b].outputs.push(o);
        *slot = b;
    }
    for (c, col) in columns.iter().enumerate() {
        if red.pivot[c]
            && let Some(o) = col.outputs().first()
        {
            blocks[block_of_output[*o]].cols.push(c);
        }
    }
    (blocks, block_of_output)
}

/// What each column estimates, as the report states it: a kept column's
/// combination of moments, any other column's own moment. Exact rationals
/// formatted per column: worth doing once per plan, not per estimate.
fn column_texts(
    ir: &Ir,
    columns: &[leeway_structure::ir::Column],
    centring: Centring,
    meaning: &BTreeMap<usize, Vec<(usize, f64)>>,
) -> std::sync::Arc<[String]> {
    let names = leeway_structure::identify::Names {
        ir,
        columns,
        centring,
    };
    (0..columns.len())
        .map(|c| match meaning.get(&c) {
            Some(items) => {
                let q: Vec<(String, Q)> = items
                    .iter()
                    .map(|(d, v)| (names.moment(*d), Q::from_float(*v).unwrap_or_default()))
                    .collect();
                linear_text(&q)
            }
            None => names.moment(c),
        })
        .collect()
}

#[derive(Clone, Debug)]
pub(crate) struct Block {
    pub(crate) outputs: Vec<usize>,
    /// Structurally kept predictor columns of the block, in column order.
    pub(crate) cols: Vec<usize>,
}
