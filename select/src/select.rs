//! Backward elimination among a model's candidate terms on the IV
//! estimator's own Wald statistics, every sub-model solved from the full
//! candidate model's moment sums, and the stopping rule (docs/selection.md).

use crate::candidates::{CandidateError, CandidateModel};
use crate::subsolve::{Solve, SubEstimate, chi2_sf, solve_sub};
use crate::suggest::{Suggestion, missing_terms};
use leeway_estimate::parallel::{in_order, threads_for};
use leeway_estimate::{
    Estimate, EstimateError, EstimateOptions, Method, MomentSystem, Start, estimate,
};
use leeway_model::experiment::{Experiment, Source};
use leeway_model::interp::Interpreter;
use leeway_model::simulate::Disturbances;
use leeway_model::validation::validate;
use leeway_structure::grammar;
use leeway_structure::ir::{ColumnKind, Ir};
use leeway_structure::{CompileOptions, compile};
use serde::Serialize;
use std::cell::Cell;
use std::collections::{BTreeMap, BTreeSet};

/// Options of a selection.
#[derive(Clone, Debug)]
pub struct SelectOptions {
    /// The estimator (an IV method) and its options.
    pub estimate: EstimateOptions,
    /// A model on the path is within reach of the best held-out criterion
    /// when its criterion `c` is at most `c*·(1 + tolerance·c*)`, `c*` the
    /// best's: the slack grows with the best's own error, since a free run
    /// that barely follows the craft measures little.
    pub tolerance: f64,
    /// Threads for the held-out free runs (0: one per core, at most one per
    /// experiment); the result is the same bits whatever the number.
    pub threads: usize,
}

impl Default for SelectOptions {
    fn default() -> SelectOptions {
        SelectOptions {
            estimate: EstimateOptions {
                method: Method::Iv3,
                ..EstimateOptions::default()
            },
            tolerance: 0.5,
            threads: 0,
        }
    }
}

/// Why a selection could not be made.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectError {
    /// Stable code.
    pub code: &'static str,
    /// What went wrong.
    pub message: String,
    /// What to do.
    pub hint: String,
}

impl From<CandidateError> for SelectError {
    fn from(e: CandidateError) -> SelectError {
        SelectError {
            code: "invalid-candidates",
            message: e.message,
            hint: e.hint,
        }
    }
}

impl From<EstimateError> for SelectError {
    fn from(e: EstimateError) -> SelectError {
        SelectError {
            code: "estimate-failed",
            message: format!("[{}] {}", e.code, e.message),
            hint: e.hint,
        }
    }
}

fn fail(code: &'static str, message: String, hint: &str) -> SelectError {
    SelectError {
        code,
        message,
        hint: hint.to_string(),
    }
}

/// One step of the path: the model after dropping one candidate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// The candidate dropped at this step (`None`: the full model), or
    /// added back (reason `added back`).
    pub dropped: Option<String>,
    /// Why: `wald` (the least significant on the path), `added back` or
    /// `dropped back` (the refinement of the path's best model),
    /// `exchangeable with X`, `not excited`.
    pub reason: String,
    /// Its Wald statistic in distance-metric form: the change of J when it
    /// is dropped (or added), its θ and nuisance columns together.
    pub wald: Option<f64>,
    /// The statistic's degrees of freedom (the columns it brings).
    pub wald_df: Option<usize>,
    /// `P(χ² > wald)`.
    pub p_value: Option<f64>,
    /// Candidates kept after the step.
    pub size: usize,
    /// Hansen's J of the model after the step (its instruments: the full model's).
    pub j: f64,
    /// J's degrees of freedom.
    pub j_df: usize,
    /// `J − d·ln N`, `d` the path's candidates not in the model: the
    /// over-identification criterion (lower is better).
    pub score: f64,
    /// The held-out free-run criterion: the mean over held-out experiments
    /// and outputs of `‖y − ŷ‖/‖y − ȳ‖` (`1 − fit/100`); `None` without held-out data.
    pub criterion: Option<f64>,
}

/// The outcome of a selection.
#[derive(Clone, Debug, Serialize)]
pub struct Selection {
    /// The candidates declared.
    pub candidates: Vec<String>,
    /// The path, from the full model.
    pub steps: Vec<Step>,
    /// The step chosen.
    pub chosen: usize,
    /// Candidates kept, in declaration order.
    pub kept: Vec<String>,
    /// Candidates dropped, in the order they were dropped.
    pub dropped: Vec<String>,
    /// Where the held-out criterion comes from.
    pub held_out: String,
    /// Equations N of the data (`ln N` is the price of a candidate kept).
    pub equations: usize,
    /// Passes over the data: the full model's estimate, the free runs of
    /// the path (one per step), the chosen model's estimate.
    pub passes: Passes,
    /// The chosen model as a `.som` source.
    #[serde(skip)]
    pub chosen_source: String,
    /// The chosen model's estimate, refined as `estimate` refines it.
    pub estimate: Estimate,
    /// What it may lack: its one-step residuals' strongest correlations
    /// with regressors it does not declare.
    pub suggestions: Vec<Suggestion>,
}

/// Passes over the data, over both rounds of the selection.
#[derive(Clone, Debug, Serialize)]
pub struct Passes {
    /// Rounds made: each one estimate of the full candidate model and one
    /// of its chosen model.
    pub rounds: usize,
    /// Refinements of the full candidate model's estimate (each one pass, plus
    /// its covariance pass).
    pub full_estimate_refinements: usize,
    /// Free-run simulations of the held-out data: one per step of the
    /// reported path, and those the first round's stopping rule read.
    pub free_runs: usize,
    /// Refinements of the chosen model's estimate.
    pub chosen_estimate_refinements: usize,
}

/// The compiled candidate model and its text.
struct Compiled {
    ir: Ir,
    text: CandidateModel,
}

fn compiled(source: &str) -> Result<Compiled, SelectError> {
    let c = compile(source, &CompileOptions::default());
    let Some(ir) = c.ir.filter(|_| {
        !c.diagnostics
            .iter()
            .any(|d| d.is_error() && d.code != "unidentifiable-combination")
    }) else {
        let errors: Vec<_> = c
            .diagnostics
            .iter()
            .filter(|d| d.is_error())
            .take(1)
            .cloned()
            .collect();
        let first = grammar::render_short(&errors, "MODEL.som", source);
        let first = first.trim_end();
        return Err(fail(
            "invalid-model",
            format!("the candidate model does not compile: {first}"),
            "run `leeway check` on it",
        ));
    };
    let (syntax, _) = grammar::parse(source);
    let Some(syntax) = syntax else {
        return Err(fail(
            "invalid-model",
            "the candidate model does not parse".into(),
            "run `leeway check` on it",
        ));
    };
    let names: BTreeSet<String> = ir.parameters.iter().map(|p| p.name.clone()).collect();
    let text = CandidateModel::read(source, &syntax, &names)?;
    Ok(Compiled { ir, text })
}

/// Candidates structurally exchangeable with an earlier term: from each
/// unidentifiable combination the first term is kept (a non-candidate
/// before any candidate, then declaration order), the other candidates
/// returned with the term they are exchangeable with.
pub fn exchangeable(ir: &Ir, candidates: &[String]) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let rank = |name: &String| match candidates.iter().position(|c| c == name) {
        Some(i) => i + 1,
        None => 0,
    };
    for combo in &ir.report.unidentifiable {
        let mut names: Vec<String> = combo
            .parameters
            .iter()
            .filter_map(|p| ir.parameters.get(*p).map(|x| x.name.clone()))
            .collect();
        names.sort_by_key(|n| (rank(n), ir.parameters.iter().position(|p| &p.name == n)));
        let Some(first) = names.first().cloned() else {
            continue;
        };
        for n in names.into_iter().skip(1) {
            if candidates.contains(&n) && !out.iter().any(|(d, _): &(String, String)| d == &n) {
                out.push((n, first.clone()));
            }
        }
    }
    out
}

/// Selects the candidate terms of `source` the data need.
/// `experiments` are the estimation data, `validation` (may be empty)
/// held-out data; without it each experiment is held out in turn.
pub fn select(
    source: &str,
    experiments: &[Experiment],
    validation: &[Experiment],
    options: &SelectOptions,
) -> Result<Selection, SelectError> {
    if options.estimate.method == Method::Ls {
        return Err(fail(
            "invalid-option",
            "selection needs an IV method: least squares has no instruments to test the dropped terms with".into(),
            "use --method iv3 (or iv1, iv2)",
        ));
    }
    let first = compiled(source)?;
    let candidates = first.text.candidates.clone();
    if candidates.is_empty() {
        return Err(fail(
            "no-candidates",
            "the model declares no candidate term".into(),
            "mark the parameters of the terms to choose among with `?`: `?Y_vv*v*|v|`",
        ));
    }
    let mut steps = Vec::new();
    let mut dropped: Vec<String> = Vec::new();
    // Structurally exchangeable candidates first: never two kept.
    let exchange = exchangeable(&first.ir, &candidates);
    let source = if exchange.is_empty() {
        source.to_string()
    } else {
        let gone: BTreeSet<String> = exchange.iter().map(|(d, _)| d.clone()).collect();
        first.text.without(&gone)?
    };
    let model = compiled(&source)?;
    for (d, with) in &exchange {
        dropped.push(d.clone());
        let size = candidates.len() - dropped.len();
        steps.push(pre_step(d, &format!("exchangeable with {with}"), size));
    }
    let round = |start: Option<Start>, round: Round| {
        run(
            &model,
            &candidates,
            &steps,
            &dropped,
            experiments,
            validation,
            options,
            start,
            round,
        )
    };
    // The first round only leads to the second: its free runs are made
    // where its stopping rule reads them, and it suggests nothing.
    let first = round(None, Round::First)?;
    // Again on instruments simulated by the first choice's estimate: the
    // full candidate model's own simulation, with every false candidate's
    // noise in its θ, makes weaker instruments (and a poorer long-run
    // covariance) than a model near the truth.
    let ir = &model.ir;
    let start = Start {
        theta: ir
            .parameters
            .iter()
            .map(|p| first.estimate.get(&p.name).unwrap_or(0.0))
            .collect(),
        means: disturbance_means(ir, &first.estimate),
        instruments: None,
    };
    // A second round that cannot be made (its instrument simulation
    // diverges) leaves the first round's choice, its path in full.
    let Ok(mut second) = round(Some(start), Round::Last) else {
        return round(None, Round::Last);
    };
    second.passes.rounds += first.passes.rounds;
    second.passes.full_estimate_refinements += first.passes.full_estimate_refinements;
    second.passes.free_runs += first.passes.free_runs;
    second.passes.chosen_estimate_refinements += first.passes.chosen_estimate_refinements;
    Ok(second)
}

/// Which round of the selection a path is.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Round {
    /// Leads to the next round only: no suggestions, and held-out
    /// criteria only where its stopping rule reads them.
    First,
    /// The round reported.
    Last,
}

/// The path and the choice from one estimate of the full candidate model
/// (its instruments simulated from `start` when given, else refined from
/// the nominal model).
#[allow(clippy::too_many_arguments)]
fn run(
    model: &Compiled,
    candidates: &[String],
    steps: &[Step],
    dropped: &[String],
    experiments: &[Experiment],
    validation: &[Experiment],
    options: &SelectOptions,
    start: Option<Start>,
    round: Round,
) -> Result<Selection, SelectError> {
    let mut steps = steps.to_vec();
    let mut dropped = dropped.to_vec();
    let candidates = candidates.to_vec();
    let ir = &model.ir;
    let interp = Interpreter::new(ir.clone());
    let sources: Vec<&dyn Source> = experiments.iter().map(|e| e as &dyn Source).collect();
    let mut est_options = options.estimate.clone();
    est_options.covariance = true;
    est_options.nominal = None;
    if let Some(start) = start {
        est_options.start = Some(start);
        est_options.max_refinements = 0;
    }
    let full = estimate(&interp, &sources, &est_options)?;
    let Some(system) = full.moment_system.clone() else {
        return Err(fail(
            "no-covariance",
            "the full candidate model's estimate has no covariance (an instrument simulation diverged)".into(),
            "check the full candidate model with `leeway estimate` first",
        ));
    };
    let kind = est_options.method.predictor();
    let columns: Vec<ColumnKind> = ir
        .predictors
        .get(kind)
        .iter()
        .map(|c| c.kind.clone())
        .collect();
    let param_index = |name: &str| ir.parameters.iter().position(|p| p.name == name);
    let cand_params: Vec<(String, usize)> = model
        .text
        .candidates
        .iter()
        .filter_map(|c| param_index(c).map(|p| (c.clone(), p)))
        .collect();
    let kept_cols: BTreeSet<usize> = system
        .blocks
        .iter()
        .flat_map(|b| b.kept.iter().copied())
        .collect();
    let is_candidate = |p: usize| cand_params.iter().any(|(_, q)| *q == p);
    // Held (not estimated) columns of non-candidates stay at the estimate's value.
    let held: BTreeMap<usize, f64> = full
        .columns
        .iter()
        .enumerate()
        .filter(|(c, _)| !kept_cols.contains(c) && !is_candidate(columns[*c].parameter()))
        .filter_map(|(c, e)| e.value.map(|v| (c, v)))
        .collect();
    let mut active: BTreeSet<usize> = BTreeSet::new();
    for (name, p) in &cand_params {
        let excited = kept_cols
            .iter()
            .any(|c| matches!(columns[*c], ColumnKind::Theta { parameter } if parameter == *p));
        if excited {
            active.insert(*p);
        } else {
            dropped.push(name.clone());
            let size = candidates.len() - dropped.len();
            steps.push(pre_step(name, "not excited", size));
        }
    }
    let means = disturbance_means(ir, &full);
    let all: Vec<usize> = (0..experiments.len()).collect();
    let n_eq = full.diagnostics.equations.max(2);
    let ln_n = (n_eq as f64).ln();
    let ctx = Context {
        system: &system,
        columns: &columns,
        held: &held,
        cand_params: &cand_params,
        theta_full: &full.theta,
        interp: &interp,
        means: &means,
        experiments,
        validation,
        threads: options.threads,
    };
    let held_out = if !validation.is_empty() {
        "the validation data".to_string()
    } else if experiments.len() >= 2 {
        "each experiment left out in turn".to_string()
    } else {
        "none (one experiment and no validation data): J alone decides".to_string()
    };
    // Candidates on the path, before any Wald drop.
    let start_size = active.len();
    let free_runs = Cell::new(0);
    let criterion_of = |active: &BTreeSet<usize>| {
        let criterion = ctx.criterion(active);
        if criterion.is_some() {
            free_runs.set(free_runs.get() + 1);
        }
        criterion
    };
    // The last round measures every step's held-out criterion as it goes;
    // the first only those its stopping rule reads, once the path is done.
    let measuring = Cell::new(round == Round::Last);
    let record =
        |dropped_now: Option<Dropping>, active: &BTreeSet<usize>, steps: &mut Vec<Step>| {
            let sub = ctx.solve(active, &all);
            let criterion = if measuring.get() {
                criterion_of(active)
            } else {
                None
            };
            let (name, reason, w) = match dropped_now {
                Some(d) => (Some(d.name), d.reason.to_string(), d.wald),
                None => (None, "full model".to_string(), None),
            };
            steps.push(Step {
                dropped: name,
                reason,
                wald: w.map(|w| w.0),
                wald_df: w.map(|w| w.1),
                p_value: w.map(|(s, df)| chi2_sf(s, df)),
                size: active.len(),
                j: sub.j,
                j_df: sub.df,
                score: sub.j - (start_size - active.len()) as f64 * ln_n,
                criterion,
            });
        };
    let first_scored = steps.len();
    record(None, &active, &mut steps);
    while !active.is_empty() {
        let sub = ctx.solve(&active, &all);
        // The candidate whose removal raises J least: its distance-metric
        // statistic, the Wald statistic of its θ and nuisance columns
        // together (ties to the later declared).
        let mut least: Option<(usize, f64, usize)> = None;
        for p in &active {
            let mut without = active.clone();
            without.remove(p);
            let w = ctx.solve(&without, &all);
            let rise = (w.j - sub.j).max(0.0);
            if least.is_none_or(|(_, r, _)| rise <= r) {
                least = Some((*p, rise, w.df.saturating_sub(sub.df).max(1)));
            }
        }
        let Some((p, rise, df)) = least else { break };
        active.remove(&p);
        let name = ir.parameters[p].name.clone();
        dropped.push(name.clone());
        let drop = Dropping {
            name: name.clone(),
            reason: "wald",
            wald: Some((rise, df)),
        };
        record(Some(drop), &active, &mut steps);
    }
    // The stopping rule. The model on the path with the lowest
    // J − d·ln N (ties: the smaller), refined by single additions and
    // removals of the path's candidates while the score falls. If its free
    // run on the held-out data is worse than c*·(1 + tolerance·c*), c* the best
    // model on the path up to it, the smallest path model within that
    // bound instead.
    let path_end = steps.len();
    let scored = &steps[first_scored..];
    let by_score = first_scored
        + scored
            .iter()
            .enumerate()
            .fold(None::<(usize, f64)>, |acc, (k, s)| match acc {
                Some((_, sc)) if sc < s.score => acc,
                _ => Some((k, s.score)),
            })
            .map_or(0, |(k, _)| k);
    let path_set: BTreeSet<usize> = cand_params
        .iter()
        .filter(|(n, _)| !dropped[..first_scored].contains(n))
        .map(|(_, p)| *p)
        .collect();
    let path_model = |k: usize| -> BTreeSet<usize> {
        cand_params
            .iter()
            .filter(|(n, _)| !dropped[..k].contains(n))
            .map(|(_, p)| *p)
            .collect()
    };
    if !measuring.get() {
        for (k, step) in steps
            .iter_mut()
            .enumerate()
            .take(by_score + 1)
            .skip(first_scored)
        {
            step.criterion = criterion_of(&path_model(k));
        }
        measuring.set(true);
    }
    let mut set: BTreeSet<usize> = path_model(by_score);
    let score = |s: &BTreeSet<usize>| ctx.solve(s, &all).j - (start_size - s.len()) as f64 * ln_n;
    let mut now = score(&set);
    loop {
        // The move that lowers the score most (ties: the first declared).
        let mut best: Option<(f64, usize, BTreeSet<usize>)> = None;
        for (_, p) in cand_params.iter().filter(|(_, p)| path_set.contains(p)) {
            let mut next = set.clone();
            if !next.remove(p) {
                next.insert(*p);
            }
            let sc = score(&next);
            if sc < now && best.as_ref().is_none_or(|(b, _, _)| sc < *b) {
                best = Some((sc, *p, next));
            }
        }
        let Some((sc, p, next)) = best else { break };
        let before = ctx.solve(&set, &all);
        let after = ctx.solve(&next, &all);
        let added = next.len() > set.len();
        let change = (after.j - before.j).abs();
        let df = after.df.abs_diff(before.df).max(1);
        now = sc;
        set = next;
        let drop = Dropping {
            name: ir.parameters[p].name.clone(),
            reason: if added { "added back" } else { "dropped back" },
            wald: Some((change, df)),
        };
        record(Some(drop), &set, &mut steps);
    }
    let refined = steps.len() - 1;
    let bound = steps[first_scored..=by_score]
        .iter()
        .chain(&steps[path_end..])
        .filter_map(|s| s.criterion)
        .fold(f64::INFINITY, f64::min);
    // The criterion's own noise grows with its level: on a craft the free
    // run follows closely (c* ≈ 0.1) a small excess is a real loss; where
    // it barely follows (c* ≥ 0.5, a current it cannot reproduce) the same
    // excess is noise.
    let bound = bound * (1.0 + options.tolerance * bound);
    let within = |k: usize| steps[k].criterion.is_none_or(|c| c <= bound);
    let chosen = if refined > by_score && refined >= path_end {
        if within(refined) { Some(refined) } else { None }
    } else {
        None
    }
    .or_else(|| (first_scored..=by_score).rev().find(|k| within(*k)))
    .unwrap_or(first_scored);
    let chosen_set: BTreeSet<usize> = if chosen == refined && refined >= path_end {
        set
    } else {
        path_model(chosen.min(path_end - 1))
    };
    let is_dropped = |name: &String| {
        cand_params
            .iter()
            .find(|(n, _)| n == name)
            .is_none_or(|(_, p)| !chosen_set.contains(p))
    };
    // In the order dropped: the pre-steps, then the path's.
    let dropped_final: Vec<String> = dropped.iter().filter(|d| is_dropped(d)).cloned().collect();
    let kept: Vec<String> = candidates
        .iter()
        .filter(|c| !dropped_final.contains(c))
        .cloned()
        .collect();
    let kept_set: BTreeSet<String> = kept.iter().cloned().collect();
    let chosen_source = model.text.chosen(&kept_set)?;
    let chosen_model = compiled(&chosen_source)?;
    let chosen_interp = Interpreter::new(chosen_model.ir.clone());
    let mut final_options = options.estimate.clone();
    final_options.nominal = None;
    let chosen_estimate = estimate(&chosen_interp, &sources, &final_options)?;
    let chosen_means = disturbance_means(&chosen_model.ir, &chosen_estimate);
    let suggestions = match round {
        Round::First => Vec::new(),
        Round::Last => missing_terms(
            &chosen_interp,
            &chosen_estimate.theta,
            &chosen_means,
            experiments,
        ),
    };
    Ok(Selection {
        candidates,
        passes: Passes {
            rounds: 1,
            full_estimate_refinements: full.diagnostics.refinements,
            free_runs: free_runs.get(),
            chosen_estimate_refinements: chosen_estimate.diagnostics.refinements,
        },
        steps,
        chosen,
        kept,
        dropped: dropped_final,
        held_out,
        equations: n_eq,
        chosen_source,
        estimate: chosen_estimate,
        suggestions,
    })
}

/// The candidate a path step drops, why, and its Wald statistic with its df.
struct Dropping {
    name: String,
    reason: &'static str,
    wald: Option<(f64, usize)>,
}

/// A step before the path: a candidate dropped for its structure or its data.
fn pre_step(name: &str, reason: &str, size: usize) -> Step {
    Step {
        dropped: Some(name.to_string()),
        reason: reason.to_string(),
        wald: None,
        wald_df: None,
        p_value: None,
        size,
        j: 0.0,
        j_df: 0,
        score: 0.0,
        criterion: None,
    }
}

/// The estimate's means of the unmeasured components, by global component.
fn disturbance_means(ir: &Ir, est: &Estimate) -> Vec<f64> {
    ir.components
        .iter()
        .map(|c| {
            let d = &ir.disturbances[c.disturbance].name;
            est.disturbances
                .iter()
                .find(|m| &m.disturbance == d && m.component == c.name)
                .map_or(0.0, |m| m.mean)
        })
        .collect()
}

/// What the path's sub-model solves and free runs share.
struct Context<'a> {
    system: &'a MomentSystem,
    columns: &'a [ColumnKind],
    held: &'a BTreeMap<usize, f64>,
    cand_params: &'a [(String, usize)],
    theta_full: &'a [f64],
    interp: &'a Interpreter,
    means: &'a [f64],
    experiments: &'a [Experiment],
    validation: &'a [Experiment],
    threads: usize,
}

impl Context<'_> {
    /// The sub-model with the candidates `active` (parameter indices) and every non-candidate.
    fn solve(&self, active: &BTreeSet<usize>, train: &[usize]) -> SubEstimate {
        let on = |c: usize| {
            let p = self.columns[c].parameter();
            active.contains(&p) || !self.cand_params.iter().any(|(_, q)| *q == p)
        };
        solve_sub(self.system, &on, self.held, train, Solve::Gmm)
    }

    /// θ of the sub-model: estimated θ columns, dropped candidates at 0,
    /// the others at the full estimate's value.
    fn theta(&self, active: &BTreeSet<usize>, sub: &SubEstimate) -> Vec<f64> {
        let mut theta = self.theta_full.to_vec();
        for (_, p) in self.cand_params {
            if !active.contains(p) {
                theta[*p] = 0.0;
            }
        }
        for (c, v) in &sub.values {
            if let ColumnKind::Theta { parameter } = self.columns[*c] {
                theta[parameter] = *v;
            }
        }
        theta
    }

    /// The held-out free-run criterion of the sub-model `active`: the
    /// experiments' free runs side by side, summed in experiment order.
    fn criterion(&self, active: &BTreeSet<usize>) -> Option<f64> {
        let all: Vec<usize> = (0..self.experiments.len()).collect();
        let threads = |n: usize| match self.threads {
            0 => threads_for(n),
            t => t.min(n).max(1),
        };
        let errors: Vec<f64> = if !self.validation.is_empty() {
            let sub = self.solve(active, &all);
            let theta = self.theta(active, &sub);
            let n = self.validation.len();
            in_order(n, threads(n), |i| self.error(&theta, &self.validation[i]))
        } else if self.experiments.len() >= 2 {
            let n = self.experiments.len();
            in_order(n, threads(n), |i| {
                let train: Vec<usize> = all.iter().copied().filter(|k| *k != i).collect();
                let sub = self.solve(active, &train);
                let theta = self.theta(active, &sub);
                self.error(&theta, &self.experiments[i])
            })
        } else {
            return None;
        };
        Some(errors.iter().sum::<f64>() / errors.len() as f64)
    }

    /// `‖y − ŷ‖/‖y − ȳ‖` averaged over the outputs of one free run
    /// (infinite when it diverges).
    fn error(&self, theta: &[f64], e: &Experiment) -> f64 {
        let v = validate(self.interp, theta, e, Disturbances::Constant(self.means));
        if v.diverged() {
            return f64::INFINITY;
        }
        // The states only: the integrated heading drifts with any error in r.
        let fits: Vec<f64> = v.fits.iter().flatten().copied().collect();
        if fits.is_empty() {
            return f64::INFINITY;
        }
        fits.iter().map(|f| 1.0 - f / 100.0).sum::<f64>() / fits.len() as f64
    }
}
