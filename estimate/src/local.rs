//! Passes on this machine: every experiment in order, with what earlier
//! passes over an in-memory record keep for later ones.

use crate::cache::{Continued, KEEP_BUDGET, KeptSimulations, RecordCache, TRAJECTORY_BUDGET};
use crate::outcome::EstimateError;
use crate::parallel::{in_order, threads_for};
use crate::plan::{PlanKey, StructuralPlan};
use crate::protocol::{
    ExperimentFacts, FactsRequest, Pass, PassRequest, PassSummary, Passes, Summary,
};
use crate::record::FactsState;
use crate::runner::PassRunner;
use leeway_model::experiment::{Experiment, Source};
use leeway_model::interrupt::Interrupt;
use leeway_model::model::Model;
use leeway_structure::ir::PredictorKind;

/// The experiments of this machine, visited in order. What passes over its
/// in-memory experiments compute that later passes need again is kept (at
/// most 512 MiB), for the later passes of an estimate and for other
/// estimates run through the same `LocalPasses` (other methods on the same
/// records): their facts, regressor rows and targets, heading rotations and
/// last instrument simulation. Every summary is what [`PassRunner`] computes,
/// bit for bit, only sooner.
pub struct LocalPasses<'a> {
    runner: PassRunner<'a>,
    experiments: &'a [&'a dyn Source],
    kept: std::sync::Mutex<KeptPasses>,
    /// What each streamed experiment keeps: its last instrument simulation,
    /// where [`TRAJECTORY_BUDGET`] leaves room for it (`None`: nothing).
    streamed: Vec<std::sync::Mutex<Option<KeptSimulations>>>,
    /// Threads a pass over streamed experiments uses (in-memory ones are
    /// passed over in order, on one, for what they keep).
    threads: usize,
}

/// The caches of streamed `experiments` of a model with `n_out` states:
/// in experiment order, each whose two trajectories (the one kept and the
/// one a pass writes beside it) fit in what is left of `total` bytes gets
/// them reserved; the others keep nothing.
fn streamed_caches(
    experiments: &[&dyn Source],
    n_out: usize,
    total: usize,
) -> Vec<std::sync::Mutex<Option<KeptSimulations>>> {
    let mut left = total;
    experiments
        .iter()
        .map(|e| {
            let bytes = KeptSimulations::bytes(e.len(), n_out);
            let fits = e.in_memory().is_none() && bytes <= left;
            if fits {
                left -= bytes;
            }
            std::sync::Mutex::new(fits.then(|| KeptSimulations::new(bytes)))
        })
        .collect()
}

/// What [`LocalPasses`] kept of each in-memory record — its regressor rows
/// and where its facts visits stood — with a copy of the record, for the
/// passes over longer records that begin with it ([`LocalPasses::continuing`]).
pub struct PrefixRows {
    records: Vec<Option<(Experiment, Continued)>>,
    plans: KeptPlans,
}

/// What [`LocalPasses`] keeps: facts per request, each experiment's cache
/// (none for a streamed one), and the bytes it may still keep.
struct KeptPasses {
    facts: Vec<((PredictorKind, u64), Vec<ExperimentFacts>)>,
    records: Vec<Option<RecordCache>>,
    /// The structural plans of the estimates made (their sign patterns
    /// are those of records that may be continued: the key says them).
    plans: KeptPlans,
    budget: usize,
    /// Serving several estimates: least squares keeps its rows too.
    for_others: bool,
}

impl<'a> LocalPasses<'a> {
    /// These passes, their data walks asking `interrupt` every few thousand
    /// samples and skipping the rest of a pass once it says stop: for one
    /// estimate only ([`estimate`] makes them), whose driver then stops with
    /// `interrupted` — what a stopped pass kept must not serve another.
    pub(super) fn interruptible(mut self, interrupt: Option<Interrupt>) -> LocalPasses<'a> {
        self.runner.interrupt = interrupt;
        self
    }

    /// Passes of `model` over `experiments`.
    pub fn new(model: &'a dyn Model, experiments: &'a [&'a dyn Source]) -> LocalPasses<'a> {
        LocalPasses {
            runner: PassRunner::new(model),
            experiments,
            kept: std::sync::Mutex::new(KeptPasses {
                facts: Vec::new(),
                records: experiments
                    .iter()
                    .map(|e| e.in_memory().is_some().then(RecordCache::default))
                    .collect(),
                plans: Vec::new(),
                budget: KEEP_BUDGET,
                for_others: false,
            }),
            streamed: streamed_caches(experiments, model.ir().states.len(), TRAJECTORY_BUDGET),
            threads: threads_for(experiments.len()),
        }
    }

    /// Passes over streamed experiments on at most `threads` threads (the
    /// default: the machine's cores). The summaries are the same whatever
    /// the number.
    pub fn with_threads(self, threads: usize) -> LocalPasses<'a> {
        LocalPasses {
            threads: threads.max(1),
            ..self
        }
    }

    /// The threads a pass uses: one when any experiment is held in memory
    /// (its cache is kept in experiment order, against one budget).
    fn pass_threads(&self) -> usize {
        if self.experiments.iter().any(|e| e.in_memory().is_some()) {
            1
        } else {
            self.threads
        }
    }

    /// Keeps at most `bytes` for later passes (0: nothing; every pass then
    /// computes everything). The default is 512 MiB for in-memory records
    /// and [`TRAJECTORY_BUDGET`] for streamed ones, whose instrument
    /// simulations get at most `bytes` too.
    pub fn with_budget(mut self, bytes: usize) -> LocalPasses<'a> {
        let n_out = self.runner.n_out();
        self.streamed = streamed_caches(self.experiments, n_out, bytes.min(TRAJECTORY_BUDGET));
        self.adjusted(|k| k.budget = bytes)
    }

    /// These passes will serve several estimates on the same records (the
    /// study's four methods): a least-squares pass then keeps its regressor
    /// rows for the instrumental estimates with the same plan.
    pub fn for_several_estimates(self) -> LocalPasses<'a> {
        self.adjusted(|k| k.for_others = true)
    }

    fn adjusted(self, f: impl FnOnce(&mut KeptPasses)) -> LocalPasses<'a> {
        let mut kept = self.kept.into_inner().unwrap_or_else(|p| p.into_inner());
        f(&mut kept);
        LocalPasses {
            runner: self.runner,
            experiments: self.experiments,
            kept: std::sync::Mutex::new(kept),
            streamed: self.streamed,
            threads: self.threads,
        }
    }

    /// The regressor rows and facts visits these passes kept of each
    /// in-memory record, to begin the passes over longer records that start
    /// with the same samples ([`LocalPasses::continuing`]).
    pub fn into_prefix_rows(self) -> PrefixRows {
        let kept = self.kept.into_inner().unwrap_or_else(|p| p.into_inner());
        PrefixRows {
            records: self
                .experiments
                .iter()
                .zip(kept.records)
                .map(|(e, cache)| match (e.in_memory(), cache) {
                    (Some(x), Some(c)) => Some((x.clone(), c.into_continued())),
                    _ => None,
                })
                .collect(),
            plans: kept.plans,
        }
    }

    /// These passes begin with what `prefix` kept over shorter records:
    /// where an experiment starts with the samples of the one `prefix` was
    /// kept over (checked bit for bit), a scanning pass evaluates only the
    /// regressors of the samples after them, and a facts visit reads only
    /// those samples (the study, which estimates on longer and longer
    /// prefixes of one record). The same summaries, sooner.
    pub fn continuing(self, prefix: PrefixRows) -> LocalPasses<'a> {
        let experiments = self.experiments;
        self.adjusted(|k| {
            k.plans = prefix.plans;
            for ((e, cache), known) in experiments
                .iter()
                .zip(k.records.iter_mut())
                .zip(prefix.records)
            {
                if let (Some(x), Some((before, rows))) = (e.in_memory(), known)
                    && cache.is_some()
                    && x.begins_with(&before)
                {
                    *cache = Some(RecordCache::with_prefix(rows, &mut k.budget));
                }
            }
        })
    }

    /// The records passed over will be continued to at most `samples`
    /// samples ([`LocalPasses::continuing`]): room for the longest record's
    /// regressor rows is reserved at once, so that no pass copies them.
    pub fn reserving(self, samples: usize) -> LocalPasses<'a> {
        self.adjusted(|k| {
            for c in k.records.iter_mut().flatten() {
                c.reserve = samples;
            }
        })
    }

    /// Streamed experiment `i`'s cache. A poisoned lock (a pass over it
    /// panicked) leaves it keeping nothing.
    fn streamed_slot(&self, i: usize) -> std::sync::MutexGuard<'_, Option<KeptSimulations>> {
        self.streamed[i].lock().unwrap_or_else(|poisoned| {
            let mut slot = poisoned.into_inner();
            *slot = None;
            slot
        })
    }

    fn kept(&self) -> std::sync::MutexGuard<'_, KeptPasses> {
        // A poisoned lock only means an earlier pass panicked: what it kept
        // is then dropped, not trusted.
        self.kept.lock().unwrap_or_else(|poisoned| {
            let mut k = poisoned.into_inner();
            k.facts.clear();
            k.records.iter_mut().for_each(|r| {
                if r.is_some() {
                    *r = Some(RecordCache::default());
                }
            });
            k
        })
    }
}

impl Passes for LocalPasses<'_> {
    fn facts(&self, request: &FactsRequest) -> Result<Vec<ExperimentFacts>, EstimateError> {
        if request.head.is_some() {
            // A subsample's facts: of the heads, so nothing kept serves them.
            return Ok(in_order(self.experiments.len(), self.pass_threads(), |i| {
                self.runner.facts(self.experiments[i], request)
            }));
        }
        // Facts depend on the request only through the predictor kind and the spread.
        let key = (request.method.predictor(), request.heading_spread.to_bits());
        if let Some((_, f)) = self.kept().facts.iter().find(|(k, _)| *k == key) {
            return Ok(f.clone());
        }
        // An in-memory record's visit goes on from where the last one over
        // it (or over a record it begins with) stood.
        let kind = request.method.predictor();
        let from: Vec<Option<FactsState>> = self
            .kept()
            .records
            .iter()
            .map(|c| c.as_ref().and_then(|c| c.facts_state(kind)).cloned())
            .collect();
        let (facts, stands): (Vec<ExperimentFacts>, Vec<Option<FactsState>>) =
            in_order(self.experiments.len(), self.pass_threads(), |i| {
                self.runner
                    .facts_from(self.experiments[i], request, from[i].clone())
            })
            .into_iter()
            .unzip();
        for (cache, stands) in self.kept().records.iter_mut().zip(stands) {
            if let (Some(c), Some(s)) = (cache, stands) {
                c.keep_facts_state(kind, s);
            }
        }
        if self.experiments.iter().all(|e| e.in_memory().is_some()) {
            self.kept().facts.push((key, facts.clone()));
        }
        Ok(facts)
    }

    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        let stop_early = matches!(request.pass, Pass::Moments { scan: false, .. });
        let threads = self.pass_threads();
        // A subsample's pass reads the heads: nothing kept of the whole
        // records serves it, and it keeps nothing.
        if threads > 1 || request.head.is_some() {
            // Streamed experiments, each walked on its own, keep their
            // instrument simulations only (not a subsample's).
            let mut out = in_order(self.experiments.len(), threads, |i| {
                let mut slot = self.streamed_slot(i);
                self.runner
                    .pass_with_kept(self.experiments[i], i, request, slot.as_mut())
            });
            if stop_early
                && let Some(k) = out
                    .iter()
                    .position(|s| matches!(s.0, Summary::Diverged { .. }))
            {
                out.truncate(k + 1);
            }
            return Ok(out);
        }
        let mut kept = self.kept();
        let KeptPasses {
            records,
            budget,
            for_others,
            ..
        } = &mut *kept;
        let mut out = Vec::with_capacity(self.experiments.len());
        for (i, (e, cache)) in self.experiments.iter().zip(records.iter_mut()).enumerate() {
            let mut slot = self.streamed_slot(i);
            let cache = match cache {
                Some(c) => Some((c, &mut *budget, *for_others)),
                None => slot.as_mut().map(|s| (&mut s.cache, &mut s.budget, false)),
            };
            let s = self.runner.pass_keeping(*e, i, request, cache);
            let diverged = matches!(s.0, Summary::Diverged { .. });
            out.push(s);
            if diverged && stop_early {
                break;
            }
        }
        Ok(out)
    }

    fn known_plan(&self, key: &PlanKey) -> Option<std::sync::Arc<StructuralPlan>> {
        let kept = self.kept();
        kept.plans
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, p)| p.clone())
    }

    fn keep_plan(&self, key: PlanKey, plan: std::sync::Arc<StructuralPlan>) {
        let mut kept = self.kept();
        if !kept.plans.iter().any(|(k, _)| *k == key) {
            kept.plans.push((key, plan));
        }
    }
}

/// Structural plans by their keys, kept for later estimates.
type KeptPlans = Vec<(PlanKey, std::sync::Arc<StructuralPlan>)>;
