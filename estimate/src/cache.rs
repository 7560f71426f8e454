//! What passes over an in-memory record keep for later passes over it (of the same estimate, or of other estimates on the same record): its facts, its regressor rows and targets, its headings' rotations and its last instrument simulation (the next refinement's reference) — values later passes would compute again bit for bit.
//!
//! At most 512 MiB (`KEEP_BUDGET`) over all records, or what
//! `LocalPasses::with_budget` says. A streamed record keeps its last
//! instrument simulations only (`RecordCache::trajectories_only`), within
//! `TRAJECTORY_BUDGET` over all streamed records, so their memory stays
//! flat whatever their length (a covariance pass reads the instruments
//! kept by the refinement that simulated them, streamed or not). Keeping
//! changes no estimate: `scenarios/tests/scenarios/distributed.rs` checks every
//! method, in any order, with warm starts, under any budget and continued
//! from prefixes (rows kept over other records must go unused), against
//! workers that keep nothing.

use crate::method::Instruments;
use crate::moments::{PartialSums, RegressorRows};
use crate::protocol::PassPlan;
use crate::record::{ExperimentInfo, FactsState, FixedSignColumn};
use crate::walk::{History, SimWalk};
use leeway_structure::ir::PredictorKind;

/// The most one [`LocalPasses`] keeps for later passes, over all its
/// records (bytes). What does not fit is computed again on every pass, as
/// for a streamed record.
pub(super) const KEEP_BUDGET: usize = 512 << 20;

/// The most one [`LocalPasses`](crate::LocalPasses) (or one worker's datasets) keeps of its
/// streamed records' instrument simulations (bytes): two trajectories a
/// record (the kept one, and the one a pass writes while it reads the
/// other), reserved in record order — 48 MB for a record of 10⁶ samples of
/// three states, so a single such file keeps them and a campaign's first
/// record only; the others simulate again, their memory flat. (Measured:
/// a record's refinement passes and covariance pass about 5–15 % faster;
/// at a budget of 256 MiB, five of ten files of 10⁶ samples kept theirs,
/// 190 MiB more for no time saved that the host's spread shows.)
pub const TRAJECTORY_BUDGET: usize = 64 << 20;

/// What earlier passes over one record kept (see [`walk::Reuse`]).
#[derive(Debug, Default)]
pub(super) struct RecordCache {
    /// The regressor rows and targets of each output, per plan (predictor
    /// kind, block columns, held columns' bits) and sign pattern, kept by
    /// scanning passes: their values are known to be finite.
    regressors: KeptRows,
    /// Rows kept over a shorter prefix of this record
    /// ([`LocalPasses::continuing`]): the first rows of a scanning pass
    /// with the same plan and sign pattern.
    prefix: KeptRows,
    /// The prefix's heading rotations, for a pass that goes on from it.
    prefix_headings: Option<Vec<[f64; 2]>>,
    headings: Option<Vec<[f64; 2]>>,
    /// The states after each step of the simulation of `(θ, μ)` (their
    /// bits), the last one of each plan's passes.
    trajectories: Vec<KeptTrajectory>,
    /// Where the last pass of each plan that simulated its instruments stood.
    simulations: Vec<SimResume>,
    /// The same, kept over a shorter prefix of this record with the
    /// simulation's states: for a warm start's first pass, which continues
    /// those instruments.
    prefix_simulations: Vec<(SimResume, Vec<f64>)>,
    /// The previous trajectory's storage, reused for the next one.
    spare: Vec<f64>,
    /// Samples of the longest record that will begin with this one: room
    /// for their regressor rows is reserved at once.
    pub(super) reserve: usize,
    /// Where the facts visit of each predictor kind stood after this
    /// record's samples (or a prefix's), to go on from.
    facts: Vec<(PredictorKind, FactsState)>,
    /// A streamed record's cache: it keeps its last instrument simulations
    /// only (see [`RecordCache::trajectories_only`]).
    only_trajectories: bool,
}

/// The states after each step of one plan's last simulation, with the
/// bits of the `(θ, μ)` simulated.
type KeptTrajectory = (RowsKey, Vec<u64>, Vec<u64>, Vec<f64>);

/// What one record keeps between the passes of an estimate whose passes
/// are run elsewhere than [`LocalPasses`] (a worker's, holding the record
/// across passes): the states of its last instrument simulations, in the
/// bytes reserved for them ([`KeptSimulations::bytes`], against
/// [`TRAJECTORY_BUDGET`] over all the records of a process). Read by a
/// refinement's next pass as its reference and by the covariance pass as
/// its instruments, they are the very states stepping would give.
///
/// [`LocalPasses`]: crate::LocalPasses
pub struct KeptSimulations {
    pub(super) cache: RecordCache,
    pub(super) budget: usize,
}

impl KeptSimulations {
    /// Bytes a record of `samples` samples of a model with `n_out` states
    /// reserves: two trajectories (the one kept and the one a pass writes
    /// while it reads the other).
    pub fn bytes(samples: usize, n_out: usize) -> usize {
        samples
            .saturating_mul(n_out)
            .saturating_mul(2 * std::mem::size_of::<f64>())
    }

    /// Room for a record's simulations of at most `bytes`.
    pub fn new(bytes: usize) -> KeptSimulations {
        KeptSimulations {
            cache: RecordCache::trajectories_only(),
            budget: bytes,
        }
    }
}

/// What a record's cache hands to the passes over a longer record that
/// begins with it: its regressor rows and where its facts visits stood.
pub(super) struct Continued {
    rows: KeptRows,
    headings: Option<Vec<[f64; 2]>>,
    facts: Vec<(PredictorKind, FactsState)>,
    simulations: Vec<(SimResume, Vec<f64>)>,
}

/// Where a pass that simulated its instruments stood after a record's
/// samples, before its last partial block: a pass over a longer record
/// that begins with these samples, with the same plan, sign pattern,
/// simulation and instruments, goes on from here.
#[derive(Clone, Debug)]
pub(super) struct SimResume {
    key: RowsKey,
    fixed: Vec<FixedSignColumn>,
    theta: Vec<u64>,
    mu: Vec<u64>,
    /// The measured disturbance means its instruments took (empty for a
    /// predictor that reads none).
    means: Vec<u64>,
    pub(super) walk: SimWalk,
    /// Per output.
    pub(super) sums: Vec<PartialSums>,
}

/// What a pass's simulated instruments are: its θ and μ, and the measured
/// means they take (empty where the predictor reads none).
pub(super) struct SimulationKey<'a> {
    pub(super) theta: &'a [f64],
    pub(super) mu: &'a [f64],
    pub(super) means: Vec<u64>,
}

/// Where the scanning pass that kept a plan's rows stood after them, if
/// its instruments do not depend on θ (least squares, delayed
/// instruments): the scanning pass over a longer record that begins with
/// the same samples goes on from here instead of summing them again.
#[derive(Clone, Debug)]
pub(super) struct Resume {
    pub(super) instruments: InstrumentsKey,
    pub(super) history: History,
    /// Per output.
    pub(super) sums: Vec<PartialSums>,
}

/// What a θ-free pass's instruments depend on besides the samples, the
/// plan and the sign pattern: their kind, and the measured means where
/// they are read (delayed instruments of a predictor that reads measured
/// disturbances take them at their experiment mean, which a longer record
/// changes).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct InstrumentsKey {
    pub(super) instruments: Option<Instruments>,
    pub(super) means: Vec<u64>,
}

/// What a record's regressor rows depend on besides its samples: the plan
/// (predictor kind, block columns, held columns' bits) and the sign
/// pattern (the signs' bits and the pointwise ones).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct RowsKey {
    kind: PredictorKind,
    cols: Vec<Vec<usize>>,
    held: Vec<(usize, u64)>,
    signs: Vec<u64>,
    varying: Vec<(usize, usize)>,
}

/// Regressor rows of each output, per plan and sign pattern, and where the
/// pass that kept them stood, if it can be gone on from.
pub(super) type KeptRows = Vec<(RowsKey, Vec<RegressorRows>, Option<Resume>)>;

fn rows_key(plan: &PassPlan, info: &ExperimentInfo) -> RowsKey {
    RowsKey {
        kind: plan.kind,
        cols: plan.cols.clone(),
        held: plan.held.iter().map(|(c, v)| (*c, v.to_bits())).collect(),
        signs: bits(&info.signs),
        varying: info.varying.clone(),
    }
}

pub(super) fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// What a completed pass offers to keep.
pub(super) struct Kept<'a> {
    pub(super) regressors: Option<Vec<RegressorRows>>,
    /// Where the pass that kept the regressors stood, if θ-free.
    pub(super) resume: Option<Resume>,
    pub(super) headings: Option<Vec<[f64; 2]>>,
    /// The simulated `(θ, μ)` and its states after each step.
    pub(super) trajectory: Option<(&'a [f64], &'a [f64], Vec<f64>)>,
    /// Where a pass that simulated its instruments stood.
    pub(super) simulation: Option<(SimulationKey<'a>, SimWalk, Vec<PartialSums>)>,
}

impl RecordCache {
    /// The cache of a streamed record: only the states of its last
    /// instrument simulation are kept — a refinement's next pass reads them
    /// as its reference, the covariance pass as its instruments, instead of
    /// simulating them again. Its rows, headings and facts are read again
    /// from the file on every pass, as before.
    pub(super) fn trajectories_only() -> RecordCache {
        RecordCache {
            only_trajectories: true,
            ..RecordCache::default()
        }
    }

    /// Whether this cache keeps instrument simulations only (a streamed record's).
    pub(super) fn keeps_trajectories_only(&self) -> bool {
        self.only_trajectories
    }

    /// The regressor rows of each output kept for `plan` and `info`'s signs.
    pub(super) fn regressors(
        &self,
        plan: &PassPlan,
        info: &ExperimentInfo,
    ) -> Option<&[RegressorRows]> {
        let key = rows_key(plan, info);
        self.regressors
            .iter()
            .find(|(k, _, _)| *k == key)
            .map(|(_, r, _)| r.as_slice())
    }

    /// The rows of a shorter prefix of this record kept for `plan` and
    /// `info`'s signs (taken: the pass that extends them keeps the whole),
    /// and where the pass that kept them stood.
    pub(super) fn take_prefix(
        &mut self,
        plan: &PassPlan,
        info: &ExperimentInfo,
        budget: &mut usize,
    ) -> Option<(Vec<RegressorRows>, Option<Resume>)> {
        let key = rows_key(plan, info);
        let at = self.prefix.iter().position(|(k, _, _)| *k == key)?;
        let (_, rows, resume) = self.prefix.swap_remove(at);
        *budget += rows.iter().map(RegressorRows::bytes).sum::<usize>();
        Some((rows, resume))
    }

    /// The prefix's heading rotations (taken), for a pass that goes on
    /// from the prefix's samples.
    pub(super) fn take_prefix_headings(&mut self) -> Option<Vec<[f64; 2]>> {
        self.prefix_headings.take()
    }

    /// Where a pass over the prefix stood that simulated `key`'s
    /// instruments over its `samples` samples with `plan` and `info`'s sign
    /// pattern, and that simulation's states (taken).
    pub(super) fn take_prefix_simulation(
        &mut self,
        plan: &PassPlan,
        info: &ExperimentInfo,
        key: &SimulationKey,
        samples: usize,
        budget: &mut usize,
    ) -> Option<(SimResume, Vec<f64>)> {
        let rows = rows_key(plan, info);
        let (theta, mu) = (bits(key.theta), bits(key.mu));
        let at = self.prefix_simulations.iter().position(|(s, _)| {
            s.key == rows
                && s.fixed == info.fixed_sign_columns
                && s.theta == theta
                && s.mu == mu
                && s.means == key.means
                && s.walk.samples == samples
        })?;
        let (resume, states) = self.prefix_simulations.swap_remove(at);
        *budget += std::mem::size_of_val(states.as_slice());
        Some((resume, states))
    }

    /// Every regressor row kept, where the facts visits and the last
    /// simulated pass of each plan stood, to begin the cache of a longer
    /// record.
    pub(super) fn into_continued(self) -> Continued {
        let mut trajectories = self.trajectories;
        let simulations = self
            .simulations
            .into_iter()
            .filter_map(|s| {
                let at = trajectories.iter().position(|(_, t, m, x)| {
                    *t == s.theta && *m == s.mu && x.len() == s.walk.trajectory_len()
                })?;
                Some((s, trajectories.swap_remove(at).3))
            })
            .collect();
        Continued {
            rows: self.regressors,
            headings: self.headings,
            facts: self.facts,
            simulations,
        }
    }

    /// Where the facts visit of `kind` stood, if kept.
    pub(super) fn facts_state(&self, kind: PredictorKind) -> Option<&FactsState> {
        self.facts.iter().find(|(k, _)| *k == kind).map(|(_, s)| s)
    }

    /// Keeps where the facts visit of `kind` stands.
    pub(super) fn keep_facts_state(&mut self, kind: PredictorKind, state: FactsState) {
        self.facts.retain(|(k, _)| *k != kind);
        self.facts.push((kind, state));
    }

    /// A cache that knows `rows`, kept over a prefix of its record, as far
    /// as `budget` allows.
    pub(super) fn with_prefix(known: Continued, budget: &mut usize) -> Self {
        let mut prefix = Vec::new();
        for (key, r, resume) in known.rows {
            let bytes: usize = r.iter().map(RegressorRows::bytes).sum();
            if bytes <= *budget {
                *budget -= bytes;
                prefix.push((key, r, resume));
            }
        }
        let mut prefix_simulations = Vec::new();
        for (s, states) in known.simulations {
            let bytes = std::mem::size_of_val(states.as_slice());
            if bytes <= *budget {
                *budget -= bytes;
                prefix_simulations.push((s, states));
            }
        }
        RecordCache {
            prefix,
            prefix_headings: known.headings,
            facts: known.facts,
            prefix_simulations,
            ..RecordCache::default()
        }
    }

    /// Every sample's heading rotation.
    pub(super) fn headings(&self) -> Option<&[[f64; 2]]> {
        self.headings.as_deref()
    }

    /// The states of the simulation of exactly `(θ, μ)`, if kept.
    pub(super) fn trajectory_of(&self, theta: &[f64], mu: &[f64]) -> Option<&[f64]> {
        let (theta, mu) = (bits(theta), bits(mu));
        self.trajectories
            .iter()
            .find(|(_, t, m, _)| *t == theta && *m == mu)
            .map(|(_, _, _, states)| states.as_slice())
    }

    /// Storage for the next trajectory.
    pub(super) fn take_spare(&mut self) -> Vec<f64> {
        let mut v = std::mem::take(&mut self.spare);
        v.clear();
        v
    }

    /// Gives back trajectory storage that was not kept.
    pub(super) fn return_spare(&mut self, v: Vec<f64>) {
        self.spare = v;
    }

    /// Keeps what a completed pass with `plan` computed, as far as
    /// `budget` (bytes left) allows; what is kept is taken off it.
    pub(super) fn keep(
        &mut self,
        plan: &PassPlan,
        info: &ExperimentInfo,
        kept: Kept,
        budget: &mut usize,
    ) {
        let mut fits = |bytes: usize| {
            let ok = bytes <= *budget;
            if ok {
                *budget -= bytes;
            }
            ok
        };
        let kept = if self.only_trajectories {
            Kept {
                regressors: None,
                headings: None,
                simulation: None,
                ..kept
            }
        } else {
            kept
        };
        if let Some(r) = kept.regressors {
            let bytes = r.iter().map(RegressorRows::bytes).sum();
            if fits(bytes) {
                self.regressors.push((rows_key(plan, info), r, kept.resume));
            }
        }
        if let Some(h) = kept.headings
            && fits(std::mem::size_of_val(h.as_slice()))
        {
            self.headings = Some(h);
        }
        let key = rows_key(plan, info);
        if let Some((theta, mu, states)) = kept.trajectory {
            // The plan's kept trajectory is replaced: only the new one's growth counts.
            let at = self.trajectories.iter().position(|(k, ..)| *k == key);
            let old = at.map_or(0, |i| {
                std::mem::size_of_val(self.trajectories[i].3.as_slice())
            });
            let new = std::mem::size_of_val(states.as_slice());
            if new <= old || fits(new - old) {
                *budget += old.saturating_sub(new);
                let entry = (key.clone(), bits(theta), bits(mu), states);
                match at {
                    Some(i) => self.spare = std::mem::replace(&mut self.trajectories[i], entry).3,
                    None => self.trajectories.push(entry),
                }
            } else {
                self.spare = states;
            }
        }
        if let Some((sim, walk, sums)) = kept.simulation {
            self.simulations.retain(|s| s.key != key);
            self.simulations.push(SimResume {
                key,
                fixed: info.fixed_sign_columns.clone(),
                theta: bits(sim.theta),
                mu: bits(sim.mu),
                means: sim.means,
                walk,
                sums,
            });
        }
    }
}
