//! One experiment's part of each pass: [`PassRunner`] reads an experiment's
//! facts, and walks it for a pass's moment sums, long-run sums or free-run
//! fit, keeping what later passes over an in-memory record can reuse.

use crate::cache::{
    InstrumentsKey, Kept, KeptSimulations, RecordCache, Resume, SimulationKey, bits,
};
use crate::dense::{Dense, EquationBlock, SlotRows};
use crate::method::Instruments;
use crate::moments::{
    CrossMoments, LongRun, MomentAccumulator, PartialSums, RegressorRows, kept_rows_bytes,
};
use crate::prefix::{Checkpoint, Wanted};
use leeway_model::delay::delayed;
use leeway_model::experiment::{Head, Source};
use leeway_model::interp::TermPlan;
use leeway_model::interrupt::Interrupt;
use leeway_model::model::{HeadingRotation, Model, Signals};
use leeway_model::number::short_number;
use leeway_model::signs::SignCounter;
use leeway_structure::ir::{Ir, PredictorKind, Rotation};

use crate::free_run::{AlongsideFreeRun, FreeRunSums};
use crate::protocol::{
    BadValue, ExperimentFacts, FactsRequest, LongRunPass, Pass, PassPlan, PassRequest, PassSummary,
    PrefixInstruments, Summary, head_samples,
};
use crate::record::{ExperimentInfo, FactsState, RecordSums, record_info};
use crate::slots::{SlotPlans, read_slots};
use crate::walk::{
    EquationSink, EquationWalker, History, REGRESSOR_LIMIT, Reuse, SimWalk, Stopper, WalkSlots,
    in_range,
};
use crate::zeta::ZetaPlan;

/// The θ of one moment pass (see [`Pass::Moments`]).
struct MomentPass<'a> {
    theta_sim: &'a [f64],
    mu: &'a [f64],
    reference: Option<(&'a [f64], &'a [f64])>,
    scan: bool,
    prefix: Option<&'a PrefixInstruments>,
}

/// The sink of a moment pass's walk: each equation's instruments,
/// regressors and targets into the accumulators of its outputs.
struct MomentSink<'a> {
    ir: &'a Ir,
    plan: &'a PassPlan,
    /// Look for non-finite measured values.
    scan: bool,
    /// The record's kept regressor rows, per output: the walk gives the
    /// instruments only.
    rows: Option<&'a [RegressorRows]>,
    /// The first equations whose rows the accumulators begin with.
    measured_known: usize,
    /// The equation given last (equation k = 2, 3, …: regressors at
    /// k − 1, target at k).
    k: usize,
    acc: Vec<MomentAccumulator>,
    /// The first bad measured value (scanning passes).
    bad: Option<(usize, String)>,
    /// Every regressor and target of the current block is in range: its
    /// equations need no check of their own.
    block_in_range: bool,
    /// An output's targets over a block.
    targets: Vec<f64>,
}

impl<'a> MomentSink<'a> {
    /// The sink of a pass with `plan` (that `scan`s for bad values) into
    /// `acc`, which know the `rows` of the whole record or the regressors
    /// of its first `measured_known` equations, and go on after the first
    /// `resumed` equations.
    fn new(
        ir: &'a Ir,
        plan: &'a PassPlan,
        scan: bool,
        rows: Option<&'a [RegressorRows]>,
        measured_known: usize,
        resumed: usize,
        acc: Vec<MomentAccumulator>,
    ) -> MomentSink<'a> {
        MomentSink {
            ir,
            plan,
            scan,
            rows,
            measured_known,
            k: 1 + resumed,
            acc,
            bad: None,
            block_in_range: false,
            targets: Vec::new(),
        }
    }

    /// Adds equation `k + 1`: instruments `z`, regressors `phi`
    /// (`n_out × n_cols` each) and targets `t`.
    #[inline(always)]
    fn push<D: Dense>(&mut self, z: D, phi: D, t: &[f64]) {
        let plan = self.plan;
        let n = plan.n_cols;
        self.k += 1;
        let k = self.k;
        if let Some(rows) = self.rows {
            for ((o, a), r) in self.acc.iter_mut().enumerate().zip(rows) {
                a.push_instruments(z.part(o * n, n), &plan.cols[o], r);
            }
            return;
        }
        if k - 2 < self.measured_known {
            for (o, a) in self.acc.iter_mut().enumerate() {
                a.push_over_kept_row(z.part(o * n, n), &plan.cols[o]);
            }
            return;
        }
        if self.scan && self.bad.is_none() && !self.block_in_range {
            self.bad = non_finite(self.ir, plan.kind, n, k, phi, t);
        }
        for (o, a) in self.acc.iter_mut().enumerate() {
            let mut target = t[o];
            for (c, v) in &plan.held {
                target -= phi.at(o * n + c) * v;
            }
            a.push_columns(z.part(o * n, n), phi.part(o * n, n), &plan.cols[o], target);
        }
    }
}

/// What a moment pass over an in-memory record keeps for later passes
/// over it: filled by its walk, offered to the record's cache when the
/// pass completes.
#[derive(Default)]
struct Keeping {
    /// Every sample's heading rotation (when none are kept yet).
    headings: Option<Vec<[f64; 2]>>,
    /// The instrument simulation's states after each step.
    trajectory: Option<Vec<f64>>,
    /// The record's regressor rows (a scanning pass, none kept yet).
    rows: bool,
    /// Where a θ-free walk stood at the end.
    wants_history: bool,
    history: Option<History>,
    /// Where a simulating walk stood at the end.
    wants_simulation: bool,
    simulation: Option<SimWalk>,
}

/// A completed moment pass, as what it keeps is offered.
struct Completed<'a> {
    /// The `(θ, μ)` simulated.
    theta: &'a [f64],
    mu: &'a [f64],
    /// What its instruments are, if they do not depend on θ.
    instruments: Option<InstrumentsKey>,
    /// What its simulated instruments are, if it kept where its simulation stood.
    simulated: Option<SimulationKey<'a>>,
    /// No bad value met: its sums may be gone on from.
    clean: bool,
}

impl Keeping {
    /// What a pass that `simulates` `n_out` states over a record of
    /// `samples` samples keeps, with `cache` (nothing without one).
    fn new(
        cache: Option<&mut RecordCache>,
        simulates: bool,
        (samples, n_out): (usize, usize),
    ) -> Keeping {
        let Some(c) = cache else {
            return Keeping::default();
        };
        let keeps_headings = c.headings().is_none() && !c.keeps_trajectories_only();
        Keeping {
            headings: keeps_headings.then(|| Vec::with_capacity(samples)),
            // Room for the whole trajectory at once: grown by doubling, it
            // would be copied and its pages cleared several times over.
            trajectory: simulates.then(|| {
                let mut v = c.take_spare();
                v.reserve_exact(samples.saturating_sub(1).saturating_mul(n_out));
                v
            }),
            ..Keeping::default()
        }
    }

    /// The [`Checkpoint`] a pass `wanted` goes on from (nothing without a
    /// cache); the simulation's states and heading rotations it goes on
    /// with become the ones this pass keeps.
    fn take_checkpoint(
        &mut self,
        cache: Option<&mut RecordCache>,
        budget: Option<&mut usize>,
        wanted: &Wanted,
    ) -> Checkpoint {
        let (Some(c), Some(b)) = (cache, budget) else {
            return Checkpoint::default();
        };
        let mut checkpoint = Checkpoint::take(c, b, wanted);
        if let Some(states) = checkpoint.take_states()
            && let Some(spare) = self.trajectory.replace(states)
        {
            c.return_spare(spare);
        }
        if checkpoint.resumes() {
            // The heading rotations kept so far go on too, or none are kept.
            self.headings = self
                .headings
                .take()
                .and_then(|_| checkpoint.take_headings(c));
        }
        checkpoint
    }

    /// `reuse` with the places this pass keeps into.
    fn reuse<'k>(&'k mut self, reuse: Reuse<'k>) -> Reuse<'k> {
        Reuse {
            keep_headings: self.headings.as_mut(),
            keep_trajectory: self.trajectory.as_mut(),
            keep_history: self.wants_history.then_some(&mut self.history),
            keep_simulation: self.wants_simulation.then_some(&mut self.simulation),
            ..reuse
        }
    }

    /// The moments of a completed pass from its accumulators (against the
    /// record's `kept` rows, if any), and what the pass offers to keep.
    fn finish<'a>(
        mut self,
        acc: Vec<MomentAccumulator>,
        kept: Option<&[RegressorRows]>,
        pass: Completed<'a>,
    ) -> (Vec<CrossMoments>, Kept<'a>) {
        // Where the simulation's sums stood, for a warm start's pass over a
        // longer record.
        let simulation = self
            .simulation
            .take()
            .and_then(|walk| Some((walk, simulation_sums(&acc, kept.is_some())?)))
            .filter(|_| pass.clean)
            .and_then(|(walk, sums)| Some((pass.simulated?, walk, sums)));
        let (moments, new_rows, partial) = finish(acc, kept, self.wants_history);
        let clean = pass.clean;
        let offered = Kept {
            resume: match (pass.instruments, self.history, partial) {
                (Some(instruments), Some(history), Some(sums)) if clean => Some(Resume {
                    instruments,
                    history,
                    sums,
                }),
                _ => None,
            },
            regressors: new_rows
                .into_iter()
                .collect::<Option<Vec<_>>>()
                .filter(|_| self.rows && clean),
            headings: self.headings,
            trajectory: self.trajectory.map(|states| (pass.theta, pass.mu, states)),
            simulation,
        };
        (moments, offered)
    }
}

/// What a moment pass begins with.
struct Begun {
    /// What it will keep.
    keeping: Keeping,
    /// What it takes up from the passes over a prefix of its record.
    checkpoint: Checkpoint,
    /// It keeps its regressor rows (a scanning pass of an instrumental
    /// estimate, or one serving others).
    keeps: bool,
    /// What its instruments are, if they do not depend on θ.
    instruments_key: Option<InstrumentsKey>,
    /// Its regressors read the measured disturbances.
    reads_means: bool,
}

impl<'a> MomentPass<'a> {
    /// How this pass, walked by `walker` over `e`, begins: what it takes
    /// from `cache` (with the bytes it may still keep) and what it will
    /// keep there.
    fn begin(
        &self,
        walker: &EquationWalker,
        e: &dyn Source,
        info: &ExperimentInfo,
        plan: &PassPlan,
        cache: Option<(&mut RecordCache, &mut usize)>,
        keep_for_others: bool,
    ) -> Begun {
        let ir = walker.ir;
        let simulates = walker.simulates(self.theta_sim);
        // Regressor rows are kept by the scanning pass of an instrumental
        // estimate (their values are then known to be finite) and read by
        // its later passes — and by other estimates' passes with the same
        // plan; least squares makes one pass, and keeps its rows only for
        // others.
        // Rows the cache could not take are not kept at all: a record whose
        // rows exceed what is left of the budget would otherwise allocate and
        // zero them on every pass, only to drop them.
        // A streamed record's cache keeps no rows.
        let fits = cache.as_ref().is_some_and(|(c, left)| {
            if c.keeps_trajectories_only() {
                return false;
            }
            let bytes = plan
                .cols
                .iter()
                .map(|c| kept_rows_bytes(c.len(), e.len()))
                .fold(0usize, usize::saturating_add);
            bytes <= **left
        });
        let keeps = self.scan && fits && (plan.instruments.is_some() || keep_for_others);
        let instruments_key = instruments_key(ir, plan, walker, info);
        let reads_means = reads_measured_disturbances(ir, plan.kind);
        let (cache, budget) = cache.unzip();
        // What this pass takes up from the passes over a prefix of its record.
        let wanted = Wanted {
            plan,
            info,
            samples: e.len(),
            n_out: ir.states.len(),
            keeps_rows: keeps,
            instruments: instruments_key.as_ref(),
            headings_known: cache
                .as_deref()
                .and_then(RecordCache::headings)
                .is_some_and(|h| h.len() == e.len()),
            simulation: self.continued_simulation(simulates, reads_means),
        };
        let mut cache = cache;
        let mut keeping = Keeping::new(cache.as_deref_mut(), simulates, (e.len(), ir.states.len()));
        let checkpoint = keeping.take_checkpoint(cache, budget, &wanted);
        Begun {
            keeping,
            checkpoint,
            keeps,
            instruments_key,
            reads_means,
        }
    }

    /// The simulation a warm start's first pass continues: the one of its
    /// instruments (when it `simulates` them, without a reference) over the
    /// samples of the shorter record it settled on.
    fn continued_simulation(
        &self,
        simulates: bool,
        reads_means: bool,
    ) -> Option<(SimulationKey<'a>, usize)> {
        let p = self
            .prefix
            .filter(|_| simulates && self.reference.is_none())?;
        let key = SimulationKey {
            theta: self.theta_sim,
            mu: self.mu,
            means: means_key(reads_means, &p.means),
        };
        Some((key, p.samples))
    }
}

impl<'a> MomentPass<'a> {
    /// This pass completed (`clean`: no bad value met), with its
    /// `instruments`; `simulated`, the predictor reading measured means or
    /// not (`Some(true)` or `Some(false)`), if it kept where its simulation
    /// stood.
    fn completed(
        &self,
        info: &'a ExperimentInfo,
        instruments: Option<InstrumentsKey>,
        simulated: Option<bool>,
        clean: bool,
    ) -> Completed<'a> {
        // The measured means the instruments take.
        let instrument_means = self.prefix.map_or(&info.measured_mean, |p| &p.means);
        Completed {
            theta: self.theta_sim,
            mu: self.mu,
            instruments,
            simulated: simulated.map(|reads_means| SimulationKey {
                theta: self.theta_sim,
                mu: self.mu,
                means: means_key(reads_means, instrument_means),
            }),
            clean,
        }
    }
}

/// What simulated instruments' measured `means` are, as kept: their bits,
/// or nothing where the predictor `reads_means` not.
fn means_key(reads_means: bool, means: &[f64]) -> Vec<u64> {
    if reads_means { bits(means) } else { Vec::new() }
}

/// A bad value's `what`, at its `sample` of `e`.
fn located(e: &dyn Source, sample: usize, what: String) -> BadValue {
    BadValue {
        location: e.locate(sample),
        what,
    }
}

/// The head of `e` a request asks for (its fraction), if any.
fn head_of(e: &dyn Source, fraction: Option<f64>) -> Option<Head<'_>> {
    fraction.map(|f| Head::new(e, head_samples(e.len(), f)))
}

/// A model ready to run passes over experiments (its term plans built once).
pub struct PassRunner<'a> {
    model: &'a dyn Model,
    terms: Vec<TermPlan>,
    /// The model's evaluators of some slots, by predictor and slots
    /// wanted, made once for all the passes of an estimate.
    slot_plans: SlotPlans,
    /// Asked during the data walks (see [`LocalPasses::interruptible`]).
    pub(crate) interrupt: Option<Interrupt>,
}

impl<'a> PassRunner<'a> {
    /// Passes of `model`.
    pub fn new(model: &'a dyn Model) -> PassRunner<'a> {
        PassRunner {
            model,
            terms: leeway_model::interp::term_plans(model.ir()),
            slot_plans: SlotPlans::default(),
            interrupt: None,
        }
    }

    /// The states of its model (each simulation step's width).
    pub(super) fn n_out(&self) -> usize {
        self.model.ir().states.len()
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
        let head = head_of(e, request.head);
        let e: &dyn Source = head.as_ref().map_or(e, |h| h);
        let view = match delayed(ir, e) {
            Ok(view) => view,
            Err(error) => {
                let facts = ExperimentFacts {
                    name: e.name().to_string(),
                    len: e.len(),
                    read: None,
                    dead_time: 0,
                    delay_error: Some(error.to_string()),
                };
                return (facts, None);
            }
        };
        let e: &dyn Source = &view;
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
            dead_time: view.dropped(),
            delay_error: None,
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
            slots: WalkSlots::default(),
        }
    }

    /// The evaluators of only the slots a pass with `plan` reads, where
    /// the model has them: the instruments' estimated columns, and the
    /// measured regressors' estimated and held columns — or every slot,
    /// where the pass `scan`s every regressor for bad values (an evaluator
    /// still, so that the walk can evaluate blocks).
    fn walk_slots(&self, plan: &PassPlan, scan: bool) -> WalkSlots {
        let n_out = self.model.ir().states.len();
        let measured = if scan {
            vec![true; n_out * plan.n_cols]
        } else {
            read_slots(plan, n_out, true)
        };
        WalkSlots {
            measured: self.slot_plans.get(self.model, plan.kind, measured),
            instruments: self
                .slot_plans
                .get(self.model, plan.kind, read_slots(plan, n_out, false)),
        }
    }

    /// The walker of a pass with the plan's instruments, or (`bootstrap`)
    /// the delayed ones of the refined IV's bootstrap pass.
    fn pass_walker(&self, plan: &PassPlan, bootstrap: bool) -> EquationWalker<'_> {
        let instruments = if bootstrap {
            Some(Instruments::Delayed)
        } else {
            plan.instruments
        };
        self.walker(plan, instruments)
    }

    /// What experiment `index` (`e`) contributes to the pass.
    pub fn pass(&self, e: &dyn Source, index: usize, request: &PassRequest) -> PassSummary {
        self.pass_keeping(e, index, request, None)
    }

    /// [`PassRunner::pass`], reading and filling the instrument simulations
    /// `kept` of this record by its earlier passes (a worker's, which holds
    /// the record across passes): the same summary, sooner. A subsample's
    /// pass neither reads nor keeps them.
    pub fn pass_with_kept(
        &self,
        e: &dyn Source,
        index: usize,
        request: &PassRequest,
        kept: Option<&mut KeptSimulations>,
    ) -> PassSummary {
        let kept = kept
            .filter(|_| request.head.is_none())
            .map(|k| (&mut k.cache, &mut k.budget, false));
        self.pass_keeping(e, index, request, kept)
    }

    /// [`PassRunner::pass`], reading and filling what earlier passes over
    /// this record kept: the same summary, sooner.
    pub(super) fn pass_keeping(
        &self,
        e: &dyn Source,
        index: usize,
        request: &PassRequest,
        cache: Option<(&mut RecordCache, &mut usize, bool)>,
    ) -> PassSummary {
        let head = head_of(e, request.head);
        let e: &dyn Source = head.as_ref().map_or(e, |h| h);
        // The facts pass reported a dead time that is no whole number of
        // samples, and the driver stopped: no pass gets here with one.
        let Ok(view) = delayed(self.model.ir(), e) else {
            return PassSummary(Summary::Diverged { bad: None });
        };
        let e: &dyn Source = &view;
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
                // The instruments' simulation, if the refinement that
                // simulated them kept it.
                let states = cache.and_then(|(c, ..)| c.trajectory_of(&lr.theta_sim, &lr.mu));
                let row = (&lr.centres[index][..], &lr.mean_res[index][..]);
                self.long_run(e, info, plan, lr, row, states)
            }
            Pass::FreeRun { theta, means } => {
                Summary::FreeRun(FreeRunSums::of(self.model, theta, means, e))
            }
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
        let ir = self.model.ir();
        // An empty θ asks for the delayed bootstrap pass of the refined IV.
        let mut walker = self.pass_walker(plan, pass.theta_sim.is_empty());
        walker.instrument_means = pass.prefix.map(|p| p.means.as_slice());
        walker.slots = self.walk_slots(plan, pass.scan);
        let simulates = walker.simulates(pass.theta_sim);
        let Begun {
            mut keeping,
            checkpoint,
            keeps,
            instruments_key,
            reads_means,
        } = pass.begin(
            &walker,
            e,
            info,
            plan,
            cache.as_deref_mut().zip(budget.as_deref_mut()),
            keep_for_others,
        );
        let kept = cache.as_deref();
        let kept_rows = kept.and_then(|c| c.regressors(plan, info));
        let rows = kept_rows.filter(|_| plan.instruments.is_some());
        keeping.rows = keeps && kept.is_some() && kept_rows.is_none();
        // Where this pass stands at the end, for a pass over a longer record.
        keeping.wants_history = keeping.rows && instruments_key.is_some();
        keeping.wants_simulation = simulates
            && kept.is_some_and(|c| !c.keeps_trajectories_only())
            && e.in_memory().is_some();
        let (measured_known, resumed) =
            (checkpoint.measured_known(), checkpoint.resumed_equations());
        let from = checkpoint.into_resumption();
        let reserve = kept.map_or(0, |c| c.reserve);
        let acc = accumulators(
            plan,
            (from.rows, from.sums),
            from.sums_over_kept.zip(rows),
            keeping.rows,
            e.len(),
            reserve,
        );
        let mut reuse = keeping.reuse(Reuse {
            headings: kept.and_then(RecordCache::headings),
            skip_measured: rows.is_some(),
            reference: kept
                .zip(pass.reference)
                .and_then(|(c, (t, m))| c.trajectory_of(t, m)),
            measured_known,
            resume: from.history,
            resume_simulation: from.simulation,
            ..Reuse::default()
        });
        let mut sink = MomentSink::new(ir, plan, pass.scan, rows, measured_known, resumed, acc);
        let (theta_sim, mu) = (pass.theta_sim, pass.mu);
        let walked = walker.walk(
            e,
            info,
            theta_sim,
            mu,
            pass.reference,
            &mut reuse,
            &mut sink,
        );
        drop(reuse);
        let MomentSink { acc, bad, .. } = sink;
        let Ok(change) = walked else {
            if let (Some(c), Some(v)) = (cache, keeping.trajectory) {
                c.return_spare(v);
            }
            return self.diverged(e, info, plan, pass.scan, bad);
        };
        let simulated = keeping.simulation.is_some();
        let completed = pass.completed(
            info,
            instruments_key,
            simulated.then_some(reads_means),
            bad.is_none(),
        );
        let (moments, offered) = keeping.finish(acc, rows, completed);
        if let (Some(c), Some(budget)) = (cache, budget) {
            c.keep(plan, info, offered, budget);
        }
        Summary::Moments {
            moments,
            change,
            bad: bad.map(|(sample, what)| located(e, sample, what)),
        }
    }

    /// The summary of a pass whose simulation diverged, with the `bad`
    /// value a scanning pass met: the simulation stopped the walk early,
    /// and a bad value further on is still a data error, not a divergence.
    fn diverged(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        plan: &PassPlan,
        scan: bool,
        mut bad: Option<(usize, String)>,
    ) -> Summary {
        if scan && bad.is_none() {
            bad = self.first_non_finite(e, info, plan);
        }
        Summary::Diverged {
            bad: bad.map(|(sample, what)| located(e, sample, what)),
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
        let mut first = FirstBad {
            ir: self.model.ir(),
            kind: plan.kind,
            n: plan.n_cols,
            k: 1,
            bad: None,
        };
        let _ = self.walker(plan, None).walk(
            e,
            info,
            &[],
            &[],
            None,
            &mut Reuse::default(),
            &mut first,
        );
        first.bad
    }

    fn long_run(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        plan: &PassPlan,
        lr: &LongRunPass,
        (centres, mean_res): (&[Vec<f64>], &[f64]),
        states: Option<&[f64]>,
    ) -> Summary {
        let sums_over =
            |e: &dyn Source| self.long_run_sums(e, (info, plan, lr), (centres, mean_res), states);
        let Some((theta, means)) = &lr.free_run else {
            return Summary::LongRun {
                dim: lr.dim,
                sums: sums_over(e),
                free_run: None,
            };
        };
        // A streamed record is read once for both; an in-memory one's
        // columns are walked directly, and the free run visits them after.
        let (sums, free_run) = if e.in_memory().is_some() {
            let sums = sums_over(e);
            (sums, FreeRunSums::of(self.model, theta, means, e))
        } else {
            let alongside = AlongsideFreeRun::new(self.model, theta, means, e);
            (sums_over(&alongside), alongside.finish())
        };
        Summary::LongRun {
            dim: lr.dim,
            sums,
            free_run: Some(free_run),
        }
    }

    /// `ζ`'s long-run sum over `e`, row-major (`None`: the instrument
    /// simulation diverged), its centres and mean residuals given, and the
    /// instrument simulation's `states` if kept.
    fn long_run_sums(
        &self,
        e: &dyn Source,
        (info, plan, lr): (&ExperimentInfo, &PassPlan, &LongRunPass),
        (centres, mean_res): (&[Vec<f64>], &[f64]),
        states: Option<&[f64]>,
    ) -> Option<Vec<f64>> {
        // The instruments of the reported iterate (empty θ: the delayed bootstrap).
        let mut walker = self.pass_walker(plan, lr.theta_sim.is_empty() && !lr.own);
        walker.slots = self.walk_slots(plan, false);
        let zeta = ZetaPlan::new(plan, lr, centres, mean_res);
        let mut sums = LongRun::new(lr.dim, lr.lags);
        let walked = walker.walk(
            e,
            info,
            &lr.theta_sim,
            &lr.mu,
            None,
            &mut Reuse {
                instruments: states,
                ..Reuse::default()
            },
            &mut ZetaSums {
                zeta: &zeta,
                sums: &mut sums,
                res: Vec::new(),
            },
        );
        walked.ok().map(|_| {
            let g = sums.sum_psd();
            // Row-major, as documented (g is symmetric).
            g.transpose().as_slice().to_vec()
        })
    }
}

impl EquationSink for MomentSink<'_> {
    #[inline(always)]
    fn equation<D: Dense>(&mut self, z: D, phi: D, t: &[f64]) {
        self.push(z, phi, t);
    }
    fn equations(&mut self, block: EquationBlock) {
        // Across the block when every equation would take the plain path
        // of `push`: no kept rows, none of its regressors known, nothing to
        // look for.
        let plain = self.rows.is_none()
            && self.k > self.measured_known
            && !(self.scan && self.bad.is_none() && !self.block_in_range);
        if !plain {
            for s in 0..block.n {
                let (z, phi, t) = block.equation(s);
                self.push(z, phi, t);
            }
            return;
        }
        let (plan, n, nb) = (self.plan, self.plan.n_cols, block.n);
        self.k += nb;
        self.targets.resize(nb.max(self.targets.len()), 0.0);
        for (o, a) in self.acc.iter_mut().enumerate() {
            // Each equation's target less its held columns, in `push`'s
            // order, across the block.
            let target = &mut self.targets[..nb];
            for (s, v) in target.iter_mut().enumerate() {
                *v = block.t[s * block.n_out + o];
            }
            for (c, v) in &plan.held {
                let phi = &block.phi[(o * n + c) * nb..][..nb];
                for (x, p) in target.iter_mut().zip(phi) {
                    *x -= p * v;
                }
            }
            a.push_block(
                SlotRows::new(block.z, nb, (o * n, n)),
                SlotRows::new(block.phi, nb, (o * n, n)),
                &plan.cols[o],
                target,
            );
        }
    }
    fn block(&mut self, in_range: impl FnOnce() -> bool) {
        self.block_in_range = self.scan && self.bad.is_none() && in_range();
    }
}

/// The first bad measured value of a walk ([`non_finite`]), equation `k`
/// being the last one seen.
struct FirstBad<'a> {
    ir: &'a Ir,
    kind: PredictorKind,
    n: usize,
    k: usize,
    bad: Option<(usize, String)>,
}

impl EquationSink for FirstBad<'_> {
    fn equation<D: Dense>(&mut self, _z: D, phi: D, t: &[f64]) {
        self.k += 1;
        if self.bad.is_none() {
            self.bad = non_finite(self.ir, self.kind, self.n, self.k, phi, t);
        }
    }
}

/// `ζ_k` of each equation into the long-run sums.
struct ZetaSums<'a> {
    zeta: &'a ZetaPlan,
    sums: &'a mut LongRun,
    /// Each output's residuals over a block.
    res: Vec<f64>,
}

impl EquationSink for ZetaSums<'_> {
    #[inline(always)]
    fn equation<D: Dense>(&mut self, z: D, phi: D, t: &[f64]) {
        self.sums.push_with(|row| self.zeta.add(z, phi, t, row));
    }
    fn equations(&mut self, block: EquationBlock) {
        self.zeta.add_block(block, &mut self.res, self.sums);
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
/// keeping none; going on from the instruments' `sums` `over_kept` rows of
/// the whole record.
#[allow(clippy::type_complexity)]
fn accumulators(
    plan: &PassPlan,
    (rows, sums): (Option<Vec<RegressorRows>>, Option<Vec<PartialSums>>),
    over_kept: Option<(Vec<PartialSums>, &[RegressorRows])>,
    keep_rows: bool,
    samples: usize,
    reserve: usize,
) -> Vec<MomentAccumulator> {
    let mut prefix = rows.map(Vec::into_iter);
    let mut resume_sums = sums.map(Vec::into_iter);
    let mut acc: Vec<MomentAccumulator> = plan
        .cols
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
        .collect();
    if let Some((sums, rows)) = over_kept {
        for ((a, s), r) in acc.iter_mut().zip(sums).zip(rows) {
            a.resume_instruments(s, r);
        }
    }
    acc
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
pub(super) fn non_finite<D: Dense>(
    ir: &Ir,
    kind: PredictorKind,
    n: usize,
    k: usize,
    phi: D,
    t: &[f64],
) -> Option<(usize, String)> {
    // The common case in one branch-free sweep; the rare bad value is
    // then looked for entry by entry.
    if in_range((0..phi.len()).map(|i| phi.at(i))) && in_range(t.iter().copied()) {
        return None;
    }
    let predictors = ir.predictors.get(kind);
    let wrong = |v: f64| !v.is_finite() || v.abs() > REGRESSOR_LIMIT;
    for (o, target) in t.iter().enumerate() {
        for (c, col) in predictors.iter().enumerate().take(n) {
            let v = phi.at(o * n + c);
            if wrong(v) && v != 0.0 {
                return Some((
                    k - 1,
                    format!(
                        "the regressor {} of `{}` evaluates to {}",
                        col.name,
                        ir.states[o],
                        short_number(v)
                    ),
                ));
            }
        }
        if wrong(*target) {
            return Some((
                k,
                format!(
                    "the difference quotient of `{}` evaluates to {}",
                    ir.states[o],
                    short_number(*target)
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
