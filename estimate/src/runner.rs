//! One experiment's part of each pass: [`PassRunner`] reads an experiment's
//! facts, and walks it for a pass's moment sums, long-run sums or free-run
//! fit, keeping what later passes over an in-memory record can reuse.

use crate::cache::{InstrumentsKey, Kept, RecordCache, Resume, SimulationKey, bits};
use crate::method::Instruments;
use crate::moments::{CrossMoments, LongRun, MomentAccumulator, PartialSums, RegressorRows};
use crate::prefix::{Checkpoint, Wanted};
use leeway_model::experiment::Source;
use leeway_model::interp::TermPlan;
use leeway_model::interrupt::Interrupt;
use leeway_model::model::{HeadingRotation, Model, Signals};
use leeway_model::signs::SignCounter;
use leeway_structure::ir::{Ir, PredictorKind, Rotation};
use nalgebra::DVector;

use crate::protocol::{
    BadValue, ExperimentFacts, FactsRequest, LongRunPass, Pass, PassPlan, PassRequest, PassSummary,
    PrefixInstruments, Summary,
};
use crate::record::{ExperimentInfo, FactsState, RecordSums, record_info};
use crate::walk::{EquationWalker, REGRESSOR_LIMIT, Reuse, Stopper};

/// The θ of one moment pass (see [`Pass::Moments`]).
struct MomentPass<'a> {
    theta_sim: &'a [f64],
    mu: &'a [f64],
    reference: Option<(&'a [f64], &'a [f64])>,
    scan: bool,
    prefix: Option<&'a PrefixInstruments>,
}

/// A model ready to run passes over experiments (its term plans built once).
pub struct PassRunner<'a> {
    model: &'a dyn Model,
    terms: Vec<TermPlan>,
    /// Asked during the data walks (see [`LocalPasses::interruptible`]).
    pub(crate) interrupt: Option<Interrupt>,
}

impl<'a> PassRunner<'a> {
    /// Passes of `model`.
    pub fn new(model: &'a dyn Model) -> PassRunner<'a> {
        PassRunner {
            model,
            terms: leeway_model::interp::term_plans(model.ir()),
            interrupt: None,
        }
    }

    /// The facts of one experiment, in one visit.
    pub fn facts(&self, e: &dyn Source, request: &FactsRequest) -> ExperimentFacts {
        self.facts_from(e, request, None).0
    }

    /// [`PassRunner::facts`], the visit going on from where it stood after
    /// the first samples (`from`, kept over a record this in-memory one
    /// begins with); and where it stands after this one's.
    pub(super) fn facts_from(
        &self,
        e: &dyn Source,
        request: &FactsRequest,
        from: Option<FactsState>,
    ) -> (ExperimentFacts, Option<FactsState>) {
        let ir = self.model.ir();
        let kind = request.method.predictor();
        let mut stands = None;
        let read = (e.len() >= leeway_model::experiment::MIN_SAMPLES).then(|| {
            // Signs and sums in one visit, one heading rotation per sample.
            let memory = e.in_memory();
            let mut state = match from {
                Some(s) if memory.is_some() && s.len <= e.len() => s,
                _ => FactsState {
                    len: 0,
                    counter: SignCounter::new(ir, kind),
                    sums: RecordSums::new(ir),
                    headings: HeadingRotation::default(),
                },
            };
            let planar = matches!(ir.rotation, Rotation::Planar { .. });
            let start = state.len;
            let FactsState {
                counter,
                sums,
                headings,
                ..
            } = &mut state;
            // Ctrl-C: the rest of the visit is skipped once asked for (the
            // driver asks too, and discards these facts).
            let mut stop = Stopper::new(self.interrupt.as_ref());
            let mut sample = |row: &leeway_model::experiment::Row| {
                if stop.now() {
                    return;
                }
                let rot = headings.next(row.heading);
                counter.sample(&Signals {
                    states: row.states,
                    inputs: row.inputs,
                    rotation: if planar { &rot } else { row.rotation },
                    disturbances: row.disturbances,
                });
                sums.sample(row, rot);
            };
            match memory {
                Some(x) => x.rows_from(start, &mut sample),
                None => e.visit(&mut sample),
            }
            state.len = e.len();
            stands = memory.is_some().then(|| state.clone());
            let signs = state.counter.finish(ir, e.name());
            let info = record_info(
                ir,
                state.sums,
                &signs,
                request.method,
                request.heading_spread,
            );
            (signs, info)
        });
        let facts = ExperimentFacts {
            name: e.name().to_string(),
            len: e.len(),
            read,
        };
        (facts, stands)
    }

    fn walker(&self, plan: &PassPlan, instruments: Option<Instruments>) -> EquationWalker<'_> {
        EquationWalker {
            model: self.model,
            ir: self.model.ir(),
            terms: &self.terms,
            kind: plan.kind,
            instruments,
            delayed_mean: plan.delayed_mean,
            n_cols: plan.n_cols,
            instrument_means: None,
            interrupt: self.interrupt.as_ref(),
        }
    }

    /// What experiment `index` (`e`) contributes to the pass.
    pub fn pass(&self, e: &dyn Source, index: usize, request: &PassRequest) -> PassSummary {
        self.pass_keeping(e, index, request, None)
    }

    /// [`PassRunner::pass`], reading and filling what earlier passes over
    /// this in-memory record kept: the same summary, sooner.
    pub(super) fn pass_keeping(
        &self,
        e: &dyn Source,
        index: usize,
        request: &PassRequest,
        cache: Option<(&mut RecordCache, &mut usize, bool)>,
    ) -> PassSummary {
        let info = &request.infos[index];
        let plan = &request.plan;
        PassSummary(match &request.pass {
            Pass::Moments {
                theta_sim,
                mu,
                reference,
                scan,
                prefix,
            } => {
                let reference = reference
                    .as_ref()
                    .map(|(t, m)| (t.as_slice(), m.as_slice()));
                self.moments(
                    e,
                    info,
                    plan,
                    MomentPass {
                        theta_sim,
                        mu,
                        reference,
                        scan: *scan,
                        prefix: prefix.get(index).and_then(Option::as_ref),
                    },
                    cache,
                )
            }
            Pass::LongRun(lr) => {
                self.long_run(e, info, plan, lr, &lr.centres[index], &lr.mean_res[index])
            }
            Pass::FreeRun { theta, means } => Summary::FreeRun(crate::free_run::FreeRunSums::of(
                self.model, theta, means, e,
            )),
        })
    }

    fn moments(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        plan: &PassPlan,
        pass: MomentPass,
        cache: Option<(&mut RecordCache, &mut usize, bool)>,
    ) -> Summary {
        let (mut cache, mut budget, keep_for_others) = match cache {
            Some((c, b, o)) => (Some(c), Some(b), o),
            None => (None, None, false),
        };
        let MomentPass {
            theta_sim,
            mu,
            reference,
            scan,
            prefix: prefix_instruments,
        } = pass;
        let ir = self.model.ir();
        // An empty θ asks for the delayed bootstrap pass of the refined IV.
        let mut walker = if theta_sim.is_empty() {
            self.walker(plan, Some(Instruments::Delayed))
        } else {
            self.walker(plan, plan.instruments)
        };
        walker.instrument_means = prefix_instruments.map(|p| p.means.as_slice());
        // The measured means the instruments take.
        let instrument_means = prefix_instruments.map_or(&info.measured_mean, |p| &p.means);
        let simulates = walker.instruments == Some(Instruments::Simulated) && !theta_sim.is_empty();
        let n = plan.n_cols;
        // What this pass keeps for later ones.
        let mut new_headings = cache
            .as_deref()
            .is_some_and(|c| c.headings().is_none())
            .then(|| Vec::with_capacity(e.len()));
        let mut new_trajectory = match cache.as_deref_mut() {
            Some(c) if simulates => Some(c.take_spare()),
            _ => None,
        };
        // Regressor rows are kept by the scanning pass of an instrumental
        // estimate (their values are then known to be finite) and read by
        // its later passes — and by other estimates' passes with the same
        // plan; least squares makes one pass, and keeps its rows only for
        // others.
        let keeps = scan && (plan.instruments.is_some() || keep_for_others);
        let instruments_key = instruments_key(ir, plan, &walker, info);
        let reads_means = reads_measured_disturbances(ir, plan.kind);
        let means_key = |m: &[f64]| if reads_means { bits(m) } else { Vec::new() };
        // What this pass takes up from the passes over a prefix of its record.
        let checkpoint = match (cache.as_deref_mut(), budget.as_deref_mut()) {
            (Some(c), Some(b)) => {
                let headings_known = c.headings().is_some_and(|h| h.len() == e.len());
                let wanted = Wanted {
                    plan,
                    info,
                    samples: e.len(),
                    n_out: ir.states.len(),
                    keeps_rows: keeps,
                    instruments: instruments_key.as_ref(),
                    headings_known,
                    simulation: prefix_instruments
                        .filter(|_| simulates && reference.is_none())
                        .map(|p| {
                            let key = SimulationKey {
                                theta: theta_sim,
                                mu,
                                means: means_key(&p.means),
                            };
                            (key, p.samples)
                        }),
                };
                Checkpoint::take(c, b, &wanted)
            }
            _ => Checkpoint::default(),
        };
        if checkpoint.resumes() {
            // The heading rotations kept so far go on too, or none are kept.
            new_headings = new_headings.and_then(|_| {
                cache
                    .as_deref_mut()
                    .and_then(|c| checkpoint.take_headings(c))
            });
        }
        let measured_known = checkpoint.measured_known();
        let resumed = checkpoint.resumed_equations();
        let from = checkpoint.into_resumption();
        if let Some(states) = from.states
            && let Some(spare) = new_trajectory.replace(states)
            && let Some(c) = cache.as_deref_mut()
        {
            c.return_spare(spare);
        }
        let reserve = cache.as_deref().map_or(0, |c| c.reserve);
        let kept = cache.as_deref();
        let kept_rows = kept.and_then(|c| c.regressors(plan, info));
        let rows = kept_rows.filter(|_| plan.instruments.is_some());
        let keep_rows = keeps && kept.is_some() && kept_rows.is_none();
        // Where this pass stands at the end, for a pass over a longer record.
        let mut history = None;
        let keeps_history = keep_rows && instruments_key.is_some();
        let mut sim_kept = None;
        let keeps_simulation = simulates && cache.is_some() && e.in_memory().is_some();
        let mut reuse = Reuse {
            headings: kept.and_then(RecordCache::headings),
            keep_headings: new_headings.as_mut(),
            skip_measured: rows.is_some(),
            reference: match (kept, reference) {
                (Some(c), Some((t, m))) => c.trajectory_of(t, m),
                _ => None,
            },
            keep_trajectory: new_trajectory.as_mut(),
            measured_known,
            resume: from.history,
            keep_history: keeps_history.then_some(&mut history),
            resume_simulation: from.simulation,
            keep_simulation: keeps_simulation.then_some(&mut sim_kept),
        };
        // The sink sees equation k = 2, 3, …: regressors at k − 1, target at k.
        let mut k = 1 + resumed;
        let mut bad = None;
        let mut acc = accumulators(plan, from.rows, from.sums, keep_rows, e.len(), reserve);
        if let (Some(sums), Some(rows)) = (from.sums_over_kept, rows) {
            for ((a, s), r) in acc.iter_mut().zip(sums).zip(rows) {
                a.resume_instruments(s, r);
            }
        }
        let walked = walker.walk(
            e,
            info,
            theta_sim,
            mu,
            reference,
            &mut reuse,
            |z: &[f64], phi: &[f64], t: &[f64]| {
                k += 1;
                if let Some(rows) = rows {
                    for ((o, a), r) in acc.iter_mut().enumerate().zip(rows) {
                        a.push_instruments(&z[o * n..(o + 1) * n], &plan.cols[o], r);
                    }
                    return;
                }
                if k - 2 < measured_known {
                    for (o, a) in acc.iter_mut().enumerate() {
                        let z = z.get(o * n..(o + 1) * n).unwrap_or(&[]);
                        a.push_over_kept_row(z, &plan.cols[o]);
                    }
                    return;
                }
                if scan && bad.is_none() {
                    bad = non_finite(ir, plan.kind, n, k, phi, t);
                }
                for (o, a) in acc.iter_mut().enumerate() {
                    let mut target = t[o];
                    for (c, v) in &plan.held {
                        target -= phi[o * n + c] * v;
                    }
                    a.push_columns(
                        &z[o * n..(o + 1) * n],
                        &phi[o * n..(o + 1) * n],
                        &plan.cols[o],
                        target,
                    );
                }
            },
        );
        let located = |bad: Option<(usize, String)>| {
            bad.map(|(sample, what)| BadValue {
                location: e.locate(sample),
                what,
            })
        };
        let Ok(change) = walked else {
            if let (Some(c), Some(v)) = (cache, new_trajectory) {
                c.return_spare(v);
            }
            // The simulation stopped the walk early: a bad value further
            // on is still a data error, not a divergence.
            if scan && bad.is_none() {
                bad = self.first_non_finite(e, info, plan);
            }
            return Summary::Diverged { bad: located(bad) };
        };
        // Where the simulation's sums stood, for a warm start's pass over a
        // longer record.
        let simulation = sim_kept
            .and_then(|walk| Some((walk, simulation_sums(&acc, rows.is_some())?)))
            .filter(|_| bad.is_none())
            .map(|(walk, sums)| {
                let key = SimulationKey {
                    theta: theta_sim,
                    mu,
                    means: means_key(instrument_means),
                };
                (key, walk, sums)
            });
        let (moments, new_rows, partial) = finish(acc, rows, keeps_history);
        if let (Some(c), Some(budget)) = (cache, budget) {
            let new_rows = new_rows.into_iter().collect::<Option<Vec<_>>>();
            c.keep(
                plan,
                info,
                Kept {
                    resume: match (instruments_key, history, partial) {
                        (Some(instruments), Some(history), Some(sums)) if bad.is_none() => {
                            Some(Resume {
                                instruments,
                                history,
                                sums,
                            })
                        }
                        _ => None,
                    },
                    regressors: new_rows.filter(|_| keep_rows && bad.is_none()),
                    headings: new_headings,
                    trajectory: new_trajectory.map(|states| (theta_sim, mu, states)),
                    simulation,
                },
                budget,
            );
        }
        Summary::Moments {
            moments,
            change,
            bad: located(bad),
        }
    }

    /// The first measured value a scanning pass would find bad
    /// ([`non_finite`]), walking the whole record without instruments.
    fn first_non_finite(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        plan: &PassPlan,
    ) -> Option<(usize, String)> {
        let ir = self.model.ir();
        let n = plan.n_cols;
        let mut bad = None;
        let mut k = 1usize;
        let _ = self.walker(plan, None).walk(
            e,
            info,
            &[],
            &[],
            None,
            &mut Reuse::default(),
            |_: &[f64], phi: &[f64], t: &[f64]| {
                k += 1;
                if bad.is_none() {
                    bad = non_finite(ir, plan.kind, n, k, phi, t);
                }
            },
        );
        bad
    }

    fn long_run(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        plan: &PassPlan,
        lr: &LongRunPass,
        centres: &[Vec<f64>],
        mean_res: &[f64],
    ) -> Summary {
        // The instruments of the reported iterate (empty θ: the delayed bootstrap).
        let walker = if lr.theta_sim.is_empty() && !lr.own {
            self.walker(plan, Some(Instruments::Delayed))
        } else {
            self.walker(plan, plan.instruments)
        };
        let n = plan.n_cols;
        let mut sums = LongRun::new(lr.dim, lr.lags);
        let mut zeta = DVector::zeros(lr.dim);
        let walked = walker.walk(
            e,
            info,
            &lr.theta_sim,
            &lr.mu,
            None,
            &mut Reuse::default(),
            |z: &[f64], phi: &[f64], t: &[f64]| {
                zeta.fill(0.0);
                for (o, rows) in lr.rows.iter().enumerate() {
                    let mut res = t[o];
                    for (c, v) in &plan.held {
                        res -= phi[o * n + c] * v;
                    }
                    for c in &plan.cols[o] {
                        res -= phi[o * n + c] * lr.values[*c];
                    }
                    res -= mean_res[o];
                    let source = if lr.own { phi } else { z };
                    for (r, c, j) in rows {
                        zeta[*r] += (source[o * n + c] - centres[o][*j]) * res;
                    }
                }
                sums.push(&zeta);
            },
        );
        let sums = walked.ok().map(|_| {
            let g = sums.sum_psd();
            // Row-major, as documented (g is symmetric).
            g.transpose().as_slice().to_vec()
        });
        Summary::LongRun { dim: lr.dim, sums }
    }
}

/// What a θ-free pass's instruments depend on besides the samples, the
/// plan and the sign pattern (`None` for simulated instruments).
fn instruments_key(
    ir: &Ir,
    plan: &PassPlan,
    walker: &EquationWalker,
    info: &ExperimentInfo,
) -> Option<InstrumentsKey> {
    (walker.instruments != Some(Instruments::Simulated)).then(|| {
        let delayed_means = walker.instruments == Some(Instruments::Delayed)
            && walker.delayed_mean
            && reads_measured_disturbances(ir, plan.kind);
        InstrumentsKey {
            instruments: walker.instruments,
            means: if delayed_means {
                bits(&info.measured_mean)
            } else {
                Vec::new()
            },
        }
    })
}

/// The accumulators of a moment pass, one per output: beginning with the
/// prefix's `rows` (going on from `sums`, where the pass over them stood),
/// or keeping every row of the record's `samples` (room for `reserve`), or
/// keeping none.
fn accumulators(
    plan: &PassPlan,
    rows: Option<Vec<RegressorRows>>,
    sums: Option<Vec<PartialSums>>,
    keep_rows: bool,
    samples: usize,
    reserve: usize,
) -> Vec<MomentAccumulator> {
    let mut prefix = rows.map(Vec::into_iter);
    let mut resume_sums = sums.map(Vec::into_iter);
    plan.cols
        .iter()
        .map(|c| {
            let mut a = MomentAccumulator::new(c.len(), c.len());
            match (
                prefix.as_mut().and_then(Iterator::next),
                resume_sums.as_mut().and_then(Iterator::next),
            ) {
                (Some(known), Some(from)) => a.keep_rows_resuming(known, from, samples),
                (Some(known), None) => a.keep_rows_after(known, samples),
                (None, _) if keep_rows => a.keep_rows(samples, reserve),
                (None, _) => {}
            }
            a
        })
        .collect()
}

/// Where the accumulators of a simulating pass stand, per output (against
/// kept rows: their instruments' sums), if every one can say.
fn simulation_sums(acc: &[MomentAccumulator], over_kept: bool) -> Option<Vec<PartialSums>> {
    if over_kept {
        Some(
            acc.iter()
                .map(MomentAccumulator::partial_instruments)
                .collect(),
        )
    } else {
        acc.iter().map(MomentAccumulator::partial).collect()
    }
}

/// The moments of each output, with the rows each accumulator kept and
/// (`keeps_history`) where the accumulation stood, for a pass that can be
/// gone on from; against `kept` rows, neither.
#[allow(clippy::type_complexity)]
fn finish(
    acc: Vec<MomentAccumulator>,
    kept: Option<&[RegressorRows]>,
    keeps_history: bool,
) -> (
    Vec<CrossMoments>,
    Vec<Option<RegressorRows>>,
    Option<Vec<PartialSums>>,
) {
    match kept {
        Some(rows) => {
            let (moments, new_rows) = acc
                .into_iter()
                .zip(rows)
                .map(|(a, r)| (a.finish_with(r), None))
                .unzip();
            (moments, new_rows, None)
        }
        None => {
            // Only a pass that can be gone on from keeps where it stood.
            let partial = if keeps_history {
                acc.iter().map(MomentAccumulator::partial).collect()
            } else {
                None
            };
            let (moments, new_rows) = acc
                .into_iter()
                .map(MomentAccumulator::finish_keeping)
                .unzip();
            (moments, new_rows, partial)
        }
    }
}

/// A measured regressor or target that is not finite, or so large that
/// its square or a sum of squares leaves f64's range ([`REGRESSOR_LIMIT`]),
/// in equation `k` (regressors at `k − 1`): `(sample, what)`.
pub(super) fn non_finite(
    ir: &Ir,
    kind: PredictorKind,
    n: usize,
    k: usize,
    phi: &[f64],
    t: &[f64],
) -> Option<(usize, String)> {
    // The common case in one branch-free sweep (NaN fails `<=` too): a
    // count of the entries out of range vectorises (compare, mask, add);
    // the rare bad value is then looked for entry by entry.
    // `!(|x| <= limit)` and not `|x| > limit`: NaN must count.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    let out_of_range = |v: &[f64]| -> u64 {
        v.iter()
            .map(|x| u64::from(!(x.abs() <= REGRESSOR_LIMIT)))
            .sum()
    };
    if out_of_range(phi) + out_of_range(t) == 0 {
        return None;
    }
    let predictors = ir.predictors.get(kind);
    let wrong = |v: f64| !v.is_finite() || v.abs() > REGRESSOR_LIMIT;
    for (o, target) in t.iter().enumerate() {
        for (c, col) in predictors.iter().enumerate().take(n) {
            let v = phi[o * n + c];
            if wrong(v) && v != 0.0 {
                return Some((
                    k - 1,
                    format!(
                        "the regressor {} of `{}` evaluates to {v:e}",
                        col.name, ir.states[o]
                    ),
                ));
            }
        }
        if wrong(*target) {
            return Some((
                k,
                format!(
                    "the difference quotient of `{}` evaluates to {target:e}",
                    ir.states[o]
                ),
            ));
        }
    }
    None
}

/// Whether `kind`'s regressors read disturbance values: only terms
/// evaluated pointwise at the measured disturbances do (`Φ2` of IV3).
fn reads_measured_disturbances(ir: &Ir, kind: PredictorKind) -> bool {
    use leeway_structure::ir::{Entry, Pointwise};
    ir.predictors.get(kind).iter().any(|c| {
        c.entries.iter().any(|e| {
            matches!(
                e,
                Entry::Term {
                    pointwise: Pointwise::Measured,
                    ..
                }
            )
        })
    })
}
