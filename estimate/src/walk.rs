//! The data pass: every equation of an experiment with its regressors, instruments (simulated, delayed or none) and target, and the instrument simulation stepped along.
//!
//! The anchored heading is rotated by small steps rather than by a `sincos`
//! a sample, and pointwise moduli take their signs sample by sample as the
//! simulation evaluates them (`scenarios/tests/scenarios/real_logs.rs`). A measured
//! regressor or target beyond [`REGRESSOR_LIMIT`] or not finite is the data
//! error `non-finite-data`, located in its source and found by the first
//! (scanning) pass, never a rank verdict.

use crate::dense::{Dense, EquationBlock};
use crate::estimator::Estimator;
use crate::method::{Instruments, Method};
use crate::moments::BLOCK;
use crate::outcome::{EstimateError, err};
use crate::protocol::{BadValue, PassPlan, SimChange};
use crate::record::{ExperimentInfo, FixedSignColumn};
use leeway_model::experiment::Source;
use leeway_model::interp::{ArgPlan, TermPlan};
use leeway_model::interrupt::Interrupt;
use leeway_model::model::{
    HeadingRotation, Model, Signals, SlotRegressors, planar_rotation, rotated,
};
use leeway_model::signs::set_pointwise_signs;
use leeway_structure::grammar::EquationKind;
use leeway_structure::ir::{Ir, PredictorKind, Rotation};
use std::sync::Arc;

/// Visits every equation of an experiment: `f(z, φ, t)` with dense buffers
/// (`n_out × n_cols`) of instruments and regressors and the targets.
pub(super) struct EquationWalker<'a> {
    pub(super) model: &'a dyn Model,
    pub(super) ir: &'a Ir,
    pub(super) terms: &'a [TermPlan],
    pub(super) kind: PredictorKind,
    pub(super) instruments: Option<Instruments>,
    /// Delayed instruments take measured disturbances at their experiment
    /// mean (bootstrap of the refined IV) instead of one sample earlier.
    pub(super) delayed_mean: bool,
    pub(super) n_cols: usize,
    /// Simulated instruments take measured disturbances at these means
    /// (a warm start's instruments: those of the shorter record it settled
    /// on) instead of the experiment's own.
    pub(super) instrument_means: Option<&'a [f64]>,
    /// Asked every [`INTERRUPT_EVERY`] samples: once it says stop, the rest
    /// of the walk is skipped (the driver, asking after the pass, then
    /// discards it).
    pub(super) interrupt: Option<&'a Interrupt>,
    /// Evaluators of only the slots the pass reads, of the measured
    /// regressors and of the instruments (`None`: every slot).
    pub(super) slots: WalkSlots,
}

/// The slots of the regressor buffers a pass reads, where the model can
/// evaluate just those ([`Model::regressor_slots`]).
#[derive(Clone, Default)]
pub(super) struct WalkSlots {
    pub(super) measured: Option<Arc<dyn SlotRegressors>>,
    pub(super) instruments: Option<Arc<dyn SlotRegressors>>,
}

/// What a walk gives each equation to: its instruments `z` and regressors
/// `phi` (dense, `n_out × n_cols`; empty where the walk skips them) and its
/// targets `t`, in the order of the record.
pub(super) trait EquationSink {
    fn equation<D: Dense>(&mut self, z: D, phi: D, t: &[f64]);
    /// Before a block's equations: `in_range()` says whether every
    /// regressor and target of the block is finite and within
    /// [`REGRESSOR_LIMIT`] (one sweep over the block, for a sink that
    /// would otherwise check each equation).
    fn block(&mut self, in_range: impl FnOnce() -> bool) {
        let _ = in_range;
    }
    /// A block's equations, in order: by default each in turn
    /// ([`EquationSink::equation`]). A sink that vectorises across the
    /// block's samples must give each equation the bits it would alone.
    #[inline(always)]
    fn equations(&mut self, block: EquationBlock) {
        for s in 0..block.n {
            let (z, phi, t) = block.equation(s);
            self.equation(z, phi, t);
        }
    }
}

/// Whether every value is finite and within [`REGRESSOR_LIMIT`]: one
/// branch-free sweep (a count of the values out of range, which
/// vectorises; NaN fails `<=` too).
pub(super) fn in_range(values: impl Iterator<Item = f64>) -> bool {
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    let out: u64 = values
        .map(|x| u64::from(!(x.abs() <= REGRESSOR_LIMIT)))
        .sum();
    out == 0
}

/// Samples between two questions to the interrupt (a few milliseconds).
pub(super) const INTERRUPT_EVERY: usize = 1 << 15;

#[derive(Debug)]
pub(super) struct Diverged;

/// Largest magnitude of a measured regressor or target: squares stay below
/// 1e290, so sums of squares over 10¹⁸ samples stay finite.
pub const REGRESSOR_LIMIT: f64 = 1e145;

/// What a walk over an in-memory record reuses from an earlier walk over it,
/// and what it keeps for later ones: values that do not depend on θ, or
/// the states of a simulation already run. Reused values are the very bits
/// the walk would compute, so a walk gives the same sums either way.
#[derive(Default)]
pub(super) struct Reuse<'a> {
    /// The rotation of each sample's measured heading (planar models).
    pub(super) headings: Option<&'a [[f64; 2]]>,
    /// Keep each sample's heading rotation here.
    pub(super) keep_headings: Option<&'a mut Vec<[f64; 2]>>,
    /// The sink takes the regressors and targets from a kept copy: skip them.
    pub(super) skip_measured: bool,
    /// The reference simulation's states after each step (`n_out` each),
    /// from the walk that simulated the reference θ: it need not run again.
    pub(super) reference: Option<&'a [f64]>,
    /// Keep the instrument simulation's states after each step here.
    pub(super) keep_trajectory: Option<&'a mut Vec<f64>>,
    /// The instrument simulation's states after each step (`n_out` each),
    /// from a walk that simulated the same `(θ, μ)`: read instead of
    /// stepping it again (the covariance pass, after the refinement that
    /// simulated its instruments).
    pub(super) instruments: Option<&'a [f64]>,
    /// The sink knows the regressors and targets of this many first
    /// equations (kept over a shorter prefix of the record): skip them there.
    pub(super) measured_known: usize,
    /// Go on from where a walk over the record's first samples stood
    /// (walks that simulate nothing): only the samples after them are walked.
    pub(super) resume: Option<History>,
    /// Keep where this walk stood after the record's samples here.
    pub(super) keep_history: Option<&'a mut Option<History>>,
    /// Go on from where a walk that simulated the same instruments over the
    /// record's first samples stood (in-memory records with kept heading
    /// rotations; the measured history is read again from the record).
    pub(super) resume_simulation: Option<SimWalk>,
    /// Keep where this walk's simulation stood after the record's samples here.
    pub(super) keep_simulation: Option<&'a mut Option<SimWalk>>,
}

/// Where a walk that simulates its instruments (and has no reference
/// simulation) stood after a record's samples: the simulation's state, the
/// anchored heading's rotation and the sums of its fit to the data. A walk
/// of the same simulation over a longer record that begins with these
/// samples goes on from here, with the same bits as one from the start.
#[derive(Clone, Debug)]
pub(super) struct SimWalk {
    /// Samples walked.
    pub(super) samples: usize,
    /// Equations given to the sink.
    pub(super) equations: usize,
    x_sim: Vec<f64>,
    rz: [f64; 2],
    err2: Vec<f64>,
    y_sum: Vec<f64>,
    y_sum2: Vec<f64>,
    y_n: usize,
}

/// Where a walk whose instruments do not depend on θ (least squares,
/// delayed instruments) stood after a record's samples: the measured
/// history one and two samples back, the heading rotation, and how many
/// samples and equations it saw. A walk over a longer record that begins
/// with these samples goes on from here, with the same bits as one from
/// the start.
#[derive(Clone, Debug)]
pub(super) struct History {
    y1: Vec<f64>,
    y2: Vec<f64>,
    u1: Vec<f64>,
    rot1: Vec<f64>,
    rot2: Vec<f64>,
    d1: Vec<f64>,
    d2: Vec<f64>,
    rh1: [f64; 2],
    rh2: [f64; 2],
    /// The heading rotation's state, if the walk advanced it over every
    /// sample (`None` when it read kept rotations: a walk that goes on
    /// from here must read them too).
    headings: Option<HeadingRotation>,
    /// Samples walked.
    pub(super) samples: usize,
    /// Equations given to the sink.
    pub(super) equations: usize,
}

impl SimWalk {
    /// Whether a walk over a record of `samples` samples and `n_out`
    /// states can go on from here (its caller sums from here too: the
    /// same check on both sides).
    pub(super) fn fits(&self, samples: usize, n_out: usize) -> bool {
        self.samples >= 3
            && self.samples <= samples
            && self.equations + 2 == self.samples
            && self.x_sim.len() == n_out
    }

    /// Entries of the simulation's states after each step over these samples.
    pub(super) fn trajectory_len(&self) -> usize {
        self.samples.saturating_sub(1) * self.x_sim.len()
    }

    /// Where a simulation of `n_out` states stood after `samples` samples
    /// and `equations` equations (states and sums zero).
    #[cfg(test)]
    pub(super) fn after(samples: usize, equations: usize, n_out: usize) -> SimWalk {
        SimWalk {
            samples,
            equations,
            x_sim: vec![0.0; n_out],
            rz: [1.0, 0.0],
            err2: vec![0.0; n_out],
            y_sum: vec![0.0; n_out],
            y_sum2: vec![0.0; n_out],
            y_n: samples.saturating_sub(1),
        }
    }
}

impl History {
    /// A walk can go on from here without kept heading rotations: it
    /// advanced the rotation itself over every sample.
    pub(super) fn continues_headings(&self) -> bool {
        self.headings.is_some()
    }

    /// Where a walk stood after `samples` samples and `equations`
    /// equations, its heading rotation's state kept or not (history zero).
    #[cfg(test)]
    pub(super) fn after(samples: usize, equations: usize, headings: bool) -> History {
        History {
            y1: Vec::new(),
            y2: Vec::new(),
            u1: Vec::new(),
            rot1: Vec::new(),
            rot2: Vec::new(),
            d1: Vec::new(),
            d2: Vec::new(),
            rh1: [1.0, 0.0],
            rh2: [1.0, 0.0],
            headings: headings.then(HeadingRotation::default),
            samples,
            equations,
        }
    }
}

impl EquationWalker<'_> {
    /// Whether a walk of `theta_sim` simulates its instruments (an empty θ
    /// simulates nothing).
    pub(super) fn simulates(&self, theta_sim: &[f64]) -> bool {
        self.instruments == Some(Instruments::Simulated) && !theta_sim.is_empty()
    }

    /// Gives each equation to `sink`: instruments, regressors
    /// (`n_out × n_cols`) and targets (both empty when the walk skips the
    /// measured side). Generic in the sink, so it is inlined into the walk.
    /// Where the model evaluates blocks and the walk evaluates every
    /// equation, equations are evaluated [`BLOCK`] at a time
    /// ([`PendingBlock`]), each with the bits it would have alone.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn walk<S: EquationSink>(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        theta_sim: &[f64],
        mu: &[f64],
        reference: Option<(&[f64], &[f64])>,
        reuse: &mut Reuse,
        sink: &mut S,
    ) -> Result<SimChange, Diverged> {
        let ir = self.ir;
        let shape = Shape::of(ir);
        let n_out = shape.n_out;
        // Only instruments of their own can leave the regressors out.
        let skip_measured = reuse.skip_measured && self.instruments.is_some();
        let measured_known = reuse.measured_known;
        // Measured states one and two samples back feed the regressors,
        // targets and delayed instruments: none of them in a walk that
        // skips the measured side and simulates its instruments.
        let keeps_states = !(skip_measured && self.instruments == Some(Instruments::Simulated));
        // A kept reference simulation is used whole (one state per step) or not at all.
        let known_reference = reuse
            .reference
            .filter(|r| r.len() == e.len().saturating_sub(1) * n_out);
        let known_headings = reuse.headings.filter(|r| r.len() == e.len());
        // Kept instrument states likewise, and only for a walk from the start.
        let known_states = reuse
            .instruments
            .filter(|r| r.len() == e.len().saturating_sub(1) * n_out);
        let h = e.step();
        let mut eq = EquationBuffers::new(self, info);
        if self.evaluates_blocks() && !skip_measured && measured_known == 0 {
            eq.block = Some(PendingBlock::new(n_out * self.n_cols, n_out));
        }
        let (resume, resume_sim) = self.resumed(e, theta_sim, reference, reuse, known_headings);
        let replay_until = resume_sim.as_ref().map_or(0, |s| s.samples);
        let start = resume
            .as_ref()
            .map_or(replay_until.saturating_sub(2), |h| h.samples);
        let mut hist = resume.unwrap_or_else(|| History::start(&shape));
        // Rotations read from a kept copy leave the running rotation behind.
        hist.headings = hist.headings.take().filter(|_| known_headings.is_none());
        let known_states = known_states.filter(|_| resume_sim.is_none());
        let simulated = (theta_sim, mu, reference, known_reference);
        let mut sims = Simulations::new(self, info, simulated, h, resume_sim, &mut hist.equations);
        sims.known_states = known_states;
        let mut k = start;
        let mut diverged = false;
        let simulates = self.simulates(theta_sim);
        let mut stop = Stopper::new(self.interrupt);
        let mut sample = |row: &leeway_model::experiment::Row| {
            if diverged || stop.now() {
                return;
            }
            if k < replay_until {
                // Walked again for the history only.
            } else if k == 0 {
                sims.begin(row);
            } else {
                if simulates {
                    sims.set_disturbances(&hist);
                }
                if k >= 2 {
                    let skip_measured = skip_measured || hist.equations < measured_known;
                    self.equation(
                        info,
                        row,
                        &hist,
                        &sims.sim,
                        (&shape, h),
                        &mut eq,
                        skip_measured,
                        sink,
                    );
                    hist.equations += 1;
                }
                // Advance the instrument simulation from k−1 to k (its
                // disturbances set at the sample's start).
                if simulates
                    && sims
                        .step(&hist, row.states, reuse.keep_trajectory.as_deref_mut())
                        .is_err()
                {
                    diverged = true;
                    return;
                }
            }
            let keep_headings = reuse.keep_headings.as_deref_mut();
            hist.shift(row, k, keeps_states, &shape, known_headings, keep_headings);
            k += 1;
        };
        // In-memory columns are walked by a loop the sample is inlined into.
        match e.in_memory() {
            Some(x) => x.rows_from(start, &mut sample),
            None => e.visit(&mut sample),
        }
        // The equations of the last block (or of the block the simulation
        // diverged in, as far as it went).
        self.flush(info, &mut eq, sink);
        if diverged {
            return Err(Diverged);
        }
        hist.samples = k;
        Ok(self.keep_where(reuse, theta_sim, hist, sims))
    }

    /// Keeps where a completed walk stood after the record's samples
    /// (`hist`, `sims`) into `reuse`, for a walk over a longer record: a
    /// θ-free walk's history, or a simulation's; its change and fit sums.
    fn keep_where(
        &self,
        reuse: &mut Reuse,
        theta_sim: &[f64],
        hist: History,
        sims: Simulations,
    ) -> SimChange {
        if let Some(kept) = reuse.keep_history.as_deref_mut()
            && self.instruments != Some(Instruments::Simulated)
        {
            *kept = Some(hist);
        } else if let Some(kept) = reuse.keep_simulation.as_deref_mut()
            && self.simulates(theta_sim)
        {
            *kept = Some(SimWalk {
                samples: hist.samples,
                equations: hist.equations,
                x_sim: sims.sim.x,
                rz: sims.sim.rz,
                err2: sims.change.err2.clone(),
                y_sum: sims.change.y_sum.clone(),
                y_sum2: sims.change.y_sum2.clone(),
                y_n: sims.change.y_n,
            });
        }
        sims.change
    }

    /// What a walk goes on from: where a θ-free walk over the record's
    /// first samples stood, or else where a simulation of the same
    /// instruments did (each only where it can: see [`Reuse`]).
    fn resumed(
        &self,
        e: &dyn Source,
        theta_sim: &[f64],
        reference: Option<(&[f64], &[f64])>,
        reuse: &mut Reuse,
        known_headings: Option<&[[f64; 2]]>,
    ) -> (Option<History>, Option<SimWalk>) {
        // A walk that simulates goes on from nothing kept (its simulation's
        // state is not part of a history), nor does a streamed record's.
        let resume = reuse.resume.take().filter(|_| {
            self.instruments != Some(Instruments::Simulated) && e.in_memory().is_some()
        });
        // A simulation goes on from its state; the two samples before it are
        // walked again for the measured history only (their heading rotations kept).
        let resume_sim = reuse.resume_simulation.take().filter(|s| {
            resume.is_none()
                && self.instruments == Some(Instruments::Simulated)
                && !theta_sim.is_empty()
                && reference.is_none()
                && e.in_memory().is_some()
                && known_headings.is_some()
                && s.fits(e.len(), self.ir.states.len())
        });
        (resume, resume_sim)
    }

    /// Whether this walk's evaluators take blocks of samples: the
    /// measured regressors' and (if any) the instruments'.
    fn evaluates_blocks(&self) -> bool {
        let blocks =
            |s: &Option<Arc<dyn SlotRegressors>>| s.as_ref().is_some_and(|s| s.evaluates_blocks());
        blocks(&self.slots.measured)
            && (self.instruments.is_none() || blocks(&self.slots.instruments))
    }

    /// Gives equation k (sample `row`) to the sink: its regressors (unless
    /// `skip_measured`) and instruments evaluated into `eq` at the history
    /// `hist` (samples k − 1 and k − 2) and the instrument simulation
    /// `sim`, and its targets (step `h`). With a pending block, the
    /// equation joins it, and the block is evaluated and given to the sink
    /// once full.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn equation<S: EquationSink>(
        &self,
        info: &ExperimentInfo,
        row: &leeway_model::experiment::Row,
        hist: &History,
        sim: &Simulation,
        (shape, h): (&Shape, f64),
        eq: &mut EquationBuffers,
        skip_measured: bool,
        sink: &mut S,
    ) {
        let planar = shape.planar.is_some();
        if let Some(block) = eq.block.as_mut() {
            set_pointwise_signs(&mut eq.signs, &info.varying, &hist.y1);
            block
                .measured
                .push(block.len, &measured_signals(hist, planar), &eq.signs);
            if let Some((sig, states)) = self.instrument_signals(info, hist, sim, planar) {
                set_pointwise_signs(&mut eq.signs, &info.varying, states);
                block.instruments.push(block.len, &sig, &eq.signs);
            }
            let n_out = block.n_out;
            let t = &mut block.t[block.len * n_out..(block.len + 1) * n_out];
            targets(self.ir, row.states, &hist.y1, h, t);
            block.len += 1;
            if block.len == BLOCK {
                self.flush(info, eq, sink);
            }
            return;
        }
        self.regressors_and_instruments(info, hist, sim, planar, eq, skip_measured);
        let empty: &[f64] = &[];
        if skip_measured {
            // Least squares has no instruments of its own.
            let z: &[f64] = if self.instruments.is_some() {
                &eq.z
            } else {
                empty
            };
            sink.equation(z, empty, empty);
        } else {
            targets(self.ir, row.states, &hist.y1, h, &mut eq.t);
            let instruments: &[f64] = if self.instruments.is_some() {
                &eq.z
            } else {
                &eq.phi
            };
            sink.equation(instruments, &eq.phi[..], &eq.t[..]);
        }
    }

    /// Evaluates the pending block's equations, slot-major, and gives them
    /// to the sink in order (nothing without a block or equations).
    fn flush<S: EquationSink>(
        &self,
        info: &ExperimentInfo,
        eq: &mut EquationBuffers,
        sink: &mut S,
    ) {
        let Some(block) = eq.block.as_mut() else {
            return;
        };
        let n = block.len;
        if n == 0 {
            return;
        }
        let slots = block.phi.len() / BLOCK;
        if n < BLOCK {
            // A shorter block lays its slots out anew: the slots no
            // evaluator writes must read zero, as in a buffer of one equation.
            block.phi.fill(0.0);
            block.z.fill(0.0);
        }
        let (phi, z) = (&mut block.phi[..slots * n], &mut block.z[..slots * n]);
        let measured: [Signals; BLOCK] = std::array::from_fn(|s| block.measured.signals(s));
        if let Some(plan) = &self.slots.measured {
            plan.update_block(
                &measured[..n],
                block.measured.signs(n),
                block.measured.n_signs(),
                phi,
            );
        }
        if self.instruments.is_some() {
            let instruments: [Signals; BLOCK] =
                std::array::from_fn(|s| block.instruments.signals(s));
            if let Some(plan) = &self.slots.instruments {
                let signs = block.instruments.signs(n);
                plan.update_block(&instruments[..n], signs, block.instruments.n_signs(), z);
            }
            if self.instruments == Some(Instruments::Simulated) {
                for (s, sig) in instruments[..n].iter().enumerate() {
                    eq.fixed.write(&info.fixed_sign_columns, sig, z, (n, s));
                }
            }
        }
        let n_out = block.n_out;
        let t = &block.t[..n * n_out];
        sink.block(|| in_range(phi.iter().copied()) && in_range(t.iter().copied()));
        sink.equations(EquationBlock {
            z: if self.instruments.is_some() { z } else { phi },
            phi,
            t,
            n,
            slots,
            n_out,
        });
        block.len = 0;
    }

    /// The measured regressors the pass reads.
    #[inline(always)]
    fn eval_measured(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        match &self.slots.measured {
            Some(slots) => slots.update(sig, signs, out),
            None => self.model.regressors_update(self.kind, sig, signs, out),
        }
    }

    /// The instruments' regressors the pass reads.
    #[inline(always)]
    fn eval_instruments(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        match &self.slots.instruments {
            Some(slots) => slots.update(sig, signs, out),
            None => self.model.regressors_update(self.kind, sig, signs, out),
        }
    }

    /// The signals the instruments are evaluated at, and the states their
    /// pointwise moduli take their signs from (`None`: least squares).
    #[inline(always)]
    fn instrument_signals<'s>(
        &'s self,
        info: &'s ExperimentInfo,
        hist: &'s History,
        sim: &'s Simulation,
        planar: bool,
    ) -> Option<(Signals<'s>, &'s [f64])> {
        match self.instruments? {
            Instruments::Simulated => {
                let means = self.instrument_means.unwrap_or(&info.measured_mean);
                let sig = Signals {
                    states: &sim.x,
                    inputs: &hist.u1,
                    rotation: if planar { &sim.rz } else { &hist.rot2 },
                    disturbances: means,
                };
                Some((sig, &sim.x))
            }
            Instruments::Delayed => {
                let dist: &[f64] = if self.delayed_mean {
                    &info.measured_mean
                } else {
                    &hist.d2
                };
                let sig = Signals {
                    states: &hist.y2,
                    inputs: &hist.u1,
                    rotation: if planar { &hist.rh2 } else { &hist.rot2 },
                    disturbances: dist,
                };
                Some((sig, &hist.y2))
            }
        }
    }

    /// Evaluates one equation's regressors (unless `skip_measured`) and
    /// instruments into `eq`, at the history `hist` (samples k − 1 and
    /// k − 2) and the instrument simulation `sim`.
    #[inline(always)]
    fn regressors_and_instruments(
        &self,
        info: &ExperimentInfo,
        hist: &History,
        sim: &Simulation,
        planar: bool,
        eq: &mut EquationBuffers,
        skip_measured: bool,
    ) {
        if !skip_measured {
            set_pointwise_signs(&mut eq.signs, &info.varying, &hist.y1);
            self.eval_measured(&measured_signals(hist, planar), &eq.signs, &mut eq.phi);
        }
        if let Some((sig, states)) = self.instrument_signals(info, hist, sim, planar) {
            set_pointwise_signs(&mut eq.signs, &info.varying, states);
            self.eval_instruments(&sig, &eq.signs, &mut eq.z);
            if self.instruments == Some(Instruments::Simulated) {
                eq.fixed
                    .write(&info.fixed_sign_columns, &sig, &mut eq.z, (1, 0));
            }
        }
    }
}

/// The signals the measured regressors are evaluated at: samples k − 1.
#[inline(always)]
fn measured_signals(hist: &History, planar: bool) -> Signals<'_> {
    Signals {
        states: &hist.y1,
        inputs: &hist.u1,
        rotation: if planar { &hist.rh1 } else { &hist.rot1 },
        disturbances: &hist.d1,
    }
}

/// Equations evaluated a block at a time: each one's signals, sign
/// patterns and targets are copied as the walk passes it, then the model's
/// block evaluators take them all at once (slot-major, docs/performance.md)
/// and the sink each in turn. Every value is the bits the equation would
/// have alone; the sink reads them through [`BlockColumn`](crate::dense::BlockColumn)s, without a copy
/// into buffers of their own.
struct PendingBlock {
    len: usize,
    measured: SignalRows,
    instruments: SignalRows,
    n_out: usize,
    /// Targets, `n_out` per equation.
    t: Vec<f64>,
    /// Regressors and instruments, slot-major (`slots × len`), zeroed once:
    /// the evaluators write only the slots the pass reads.
    phi: Vec<f64>,
    z: Vec<f64>,
}

impl PendingBlock {
    fn new(slots: usize, n_out: usize) -> PendingBlock {
        PendingBlock {
            len: 0,
            measured: SignalRows::default(),
            instruments: SignalRows::default(),
            n_out,
            t: vec![0.0; BLOCK * n_out],
            phi: vec![0.0; BLOCK * slots],
            z: vec![0.0; BLOCK * slots],
        }
    }
}

/// The signals and sign patterns of a block's equations, row after row:
/// states, inputs, rotation, disturbances and signs, each as wide as the
/// walk's (the same for every equation of a walk).
#[derive(Default)]
struct SignalRows {
    widths: [usize; 5],
    values: [Vec<f64>; 5],
}

impl SignalRows {
    /// Equation `s`'s signals and signs.
    #[inline(always)]
    fn push(&mut self, s: usize, sig: &Signals, signs: &[f64]) {
        let parts = [
            sig.states,
            sig.inputs,
            sig.rotation,
            sig.disturbances,
            signs,
        ];
        for ((w, v), part) in self.widths.iter_mut().zip(&mut self.values).zip(parts) {
            if s == 0 && v.len() < BLOCK * part.len() {
                v.resize(BLOCK * part.len(), 0.0);
            }
            *w = part.len();
            copy_few(&mut v[s * *w..(s + 1) * *w], part);
        }
    }

    /// Equation `s`'s signals (stale ones beyond the equations pushed).
    fn signals(&self, s: usize) -> Signals<'_> {
        let part = |i: usize| &self.values[i][s * self.widths[i]..(s + 1) * self.widths[i]];
        Signals {
            states: part(0),
            inputs: part(1),
            rotation: part(2),
            disturbances: part(3),
        }
    }

    /// The sign patterns of the first `n` equations.
    fn signs(&self, n: usize) -> &[f64] {
        &self.values[4][..n * self.widths[4]]
    }

    fn n_signs(&self) -> usize {
        self.widths[4]
    }
}

/// The sizes of one sample's signals.
struct Shape {
    n_out: usize,
    n_in: usize,
    /// Measured rotation columns (they travel with the data; a planar
    /// heading does not).
    n_rot: usize,
    n_comp: usize,
    /// A planar model's yaw-rate state (its heading integrates it).
    planar: Option<usize>,
}

impl Shape {
    fn of(ir: &Ir) -> Shape {
        Shape {
            n_out: ir.states.len(),
            n_in: ir.inputs.len(),
            n_rot: if matches!(ir.rotation, Rotation::Measured { .. }) {
                ir.rotation_vars.len()
            } else {
                0
            },
            n_comp: ir.components.len(),
            planar: match &ir.rotation {
                Rotation::Planar { integrates, .. } => Some(*integrates),
                _ => None,
            },
        }
    }
}

/// One equation's dense buffers (`n_out × n_cols`) of regressors and
/// instruments and its targets, with what evaluating them needs.
struct EquationBuffers<'a> {
    phi: Vec<f64>,
    z: Vec<f64>,
    t: Vec<f64>,
    /// Signs of the pointwise moduli, sample by sample where they change.
    signs: Vec<f64>,
    fixed: FixedSigns<'a>,
    /// Equations waiting to be evaluated as a block, where the walk does.
    block: Option<PendingBlock>,
}

impl<'a> EquationBuffers<'a> {
    fn new(walker: &EquationWalker<'a>, info: &ExperimentInfo) -> EquationBuffers<'a> {
        let n_out = walker.ir.states.len();
        let len = n_out * walker.n_cols;
        // Zeroed once: `regressors_update` then writes only the structurally
        // nonzero slots, sample after sample.
        EquationBuffers {
            phi: vec![0.0; len],
            z: vec![0.0; len],
            t: vec![0.0; n_out],
            signs: info.signs.clone(),
            fixed: FixedSigns::new(walker.terms, &info.fixed_sign_columns, n_out, walker.n_cols),
            block: None,
        }
    }
}

/// The fixed-sign Φ2 instruments' distinct arguments (the same few across
/// columns), each evaluated once a sample, and their buffers: nothing
/// allocated per sample.
struct FixedSigns<'a> {
    terms: &'a [TermPlan],
    /// Columns of a row of the instruments' buffer.
    n_cols: usize,
    args: Vec<&'a ArgPlan>,
    /// The argument of each factor: `slots[column][term][factor]`.
    slots: Vec<Vec<Vec<usize>>>,
    values: Vec<f64>,
    acc: Vec<f64>,
    set: Vec<bool>,
}

impl<'a> FixedSigns<'a> {
    fn new(
        terms: &'a [TermPlan],
        columns: &[FixedSignColumn],
        n_out: usize,
        n_cols: usize,
    ) -> FixedSigns<'a> {
        let mut args: Vec<&ArgPlan> = Vec::new();
        let slots: Vec<Vec<Vec<usize>>> = columns
            .iter()
            .map(|fixed| {
                fixed
                    .terms
                    .iter()
                    .map(|(term, _, _)| {
                        terms[*term]
                            .factors
                            .iter()
                            .map(|(arg, _)| match args.iter().position(|a| *a == arg) {
                                Some(slot) => slot,
                                None => {
                                    args.push(arg);
                                    args.len() - 1
                                }
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        FixedSigns {
            terms,
            n_cols,
            values: vec![0.0; args.len()],
            args,
            slots,
            acc: vec![0.0; n_out],
            set: vec![false; n_out],
        }
    }

    /// Writes the instruments of the fixed-sign `columns` at the signals
    /// `sig` into `z` (`n_out × n_cols`), or into sample `s` of a block of
    /// `n` laid out slot-major (`(n, s)`; `(1, 0)`: one equation's buffer).
    #[inline(always)]
    fn write(
        &mut self,
        columns: &[FixedSignColumn],
        sig: &Signals,
        z: &mut [f64],
        (n, s): (usize, usize),
    ) {
        for (v, arg) in self.values.iter_mut().zip(&self.args) {
            *v = arg.eval(sig, true);
        }
        for (fixed, slots) in columns.iter().zip(&self.slots) {
            self.set.fill(false);
            for ((term, o, signs), slots) in fixed.terms.iter().zip(slots) {
                let plan = &self.terms[*term];
                let mut t = plan.coefficient;
                for (((_, modulus), s), slot) in plan.factors.iter().zip(signs).zip(slots) {
                    let v = self.values[*slot];
                    t *= if *modulus { s * v } else { v };
                }
                self.acc[*o] = if self.set[*o] { self.acc[*o] + t } else { t };
                self.set[*o] = true;
            }
            for o in 0..self.acc.len() {
                if self.set[o] {
                    z[(o * self.n_cols + fixed.column) * n + s] = self.acc[o];
                }
            }
        }
    }
}

/// The simulations a walk steps: the instruments' of `θ` and `μ`, and a
/// reference one (the previous instruments), in lockstep, with the sums of
/// their change and fit.
struct Simulations<'a> {
    model: &'a dyn Model,
    theta: &'a [f64],
    mu: &'a [f64],
    /// The reference's `(θ, μ)`.
    reference: Option<(&'a [f64], &'a [f64])>,
    /// The reference's states after each step, kept by an earlier walk.
    known_reference: Option<&'a [f64]>,
    /// The instrument simulation's own states after each step, kept by an
    /// earlier walk of the same `(θ, μ)`: the same bits it would step to.
    known_states: Option<&'a [f64]>,
    /// Beyond these magnitudes a simulation has diverged.
    bound: &'a [f64],
    /// The step.
    h: f64,
    planar: Option<usize>,
    sim: Simulation,
    reference_sim: Reference,
    fbuf: Vec<f64>,
    /// Which disturbance components are measured.
    measured: Vec<bool>,
    change: SimChange,
}

/// What a walk simulates: `(θ, μ)`, the reference's `(θ, μ)`, and the
/// reference's states after each step if kept.
type Simulated<'a> = (
    &'a [f64],
    &'a [f64],
    Option<(&'a [f64], &'a [f64])>,
    Option<&'a [f64]>,
);

impl<'a> Simulations<'a> {
    /// The simulations of `walker` over an experiment (`info`, step `h`),
    /// going on from where the instrument simulation `resumed` stood (its
    /// equations then counted in `equations`).
    fn new(
        walker: &EquationWalker<'a>,
        info: &'a ExperimentInfo,
        (theta, mu, reference, known_reference): Simulated<'a>,
        h: f64,
        resumed: Option<SimWalk>,
        equations: &mut usize,
    ) -> Simulations<'a> {
        let ir = walker.ir;
        let shape = Shape::of(ir);
        Simulations {
            model: walker.model,
            theta,
            mu,
            reference,
            known_reference,
            known_states: None,
            bound: &info.bound,
            h,
            planar: shape.planar,
            sim: Simulation::start(&shape, resumed.as_ref()),
            reference_sim: Reference::start(&shape),
            fbuf: vec![0.0; shape.n_out],
            measured: ir
                .components
                .iter()
                .map(|c| ir.disturbances[c.disturbance].measured)
                .collect(),
            change: change_from(shape.n_out, resumed, equations),
        }
    }

    /// Both begin at the measured first sample.
    #[inline(always)]
    fn begin(&mut self, row: &leeway_model::experiment::Row) {
        self.sim.begin(row, self.planar);
        self.reference_sim
            .begin(row, &self.sim, self.planar.is_some());
    }

    /// The step's disturbances and rotation, written well before it reads
    /// them: values stored one by one just before they are read as a
    /// vector stall on store forwarding (measured: about 5 % of one study
    /// run).
    #[inline(always)]
    fn set_disturbances(&mut self, hist: &History) {
        simulation_disturbances(&self.measured, &hist.d1, self.mu, &mut self.sim.dist);
        self.sim.rz_step.copy_from_slice(&self.sim.rz);
        if let Some((_, mu_ref)) = self.reference
            && self.known_reference.is_none()
        {
            simulation_disturbances(
                &self.measured,
                &hist.d1,
                mu_ref,
                &mut self.reference_sim.dist,
            );
        }
    }

    /// Steps both from k − 1 to k (history `hist`, measured states `y` at
    /// k), the instrument simulation's new state kept into `keep`.
    #[inline(always)]
    fn step(
        &mut self,
        hist: &History,
        y: &[f64],
        keep: Option<&mut Vec<f64>>,
    ) -> Result<(), Diverged> {
        let (h, planar) = (self.h, self.planar);
        match self.known_states {
            Some(known) => {
                // States after step `y_n` (steps taken so far), read.
                let n_out = self.sim.x.len();
                let at = self.change.y_n * n_out;
                self.sim.next.copy_from_slice(&known[at..at + n_out]);
            }
            None => self
                .sim
                .step(self.model, self.theta, h, hist, planar, &mut self.fbuf),
        }
        if self.sim.beyond(self.bound) {
            return Err(Diverged);
        }
        self.sim.advance(h, hist, planar);
        if let Some(kept) = keep {
            extend_few(kept, &self.sim.x);
        }
        add_fit(&mut self.change, y, &self.sim.x);
        if let Some((theta_ref, _)) = self.reference {
            let n_out = self.sim.x.len();
            let stepped = self.change.y_n - 1;
            let x_ref: &[f64] = if let Some(known) = self.known_reference {
                &known[stepped * n_out..(stepped + 1) * n_out]
            } else {
                self.reference_sim
                    .step(self.model, theta_ref, h, hist, planar, &mut self.fbuf);
                &self.reference_sim.x
            };
            add_reference(&mut self.change, &self.sim.x, x_ref);
        }
        Ok(())
    }
}

/// The instrument simulation, stepped along the walk.
struct Simulation {
    /// Its state.
    x: Vec<f64>,
    next: Vec<f64>,
    /// The anchored heading's rotation `ψ_z(k) = y_ψ(k−1) + h·r_sim(k−1)`,
    /// rotated from the measured one by the small simulated step.
    rz: [f64; 2],
    /// The step's copy of `rz`, written with its disturbances.
    rz_step: Vec<f64>,
    /// The step's disturbances.
    dist: Vec<f64>,
}

impl Simulation {
    /// A simulation to begin at the first sample, or going on from `resumed`.
    fn start(shape: &Shape, resumed: Option<&SimWalk>) -> Simulation {
        let mut x = vec![0.0; shape.n_out];
        if let Some(s) = resumed {
            x.copy_from_slice(&s.x_sim);
        }
        Simulation {
            x,
            next: vec![0.0; shape.n_out],
            rz: resumed.map_or([1.0, 0.0], |s| s.rz),
            rz_step: vec![0.0; 2],
            dist: vec![0.0; shape.n_comp],
        }
    }

    /// Begins at the measured first sample.
    #[inline(always)]
    fn begin(&mut self, row: &leeway_model::experiment::Row, planar: Option<usize>) {
        self.x.copy_from_slice(row.states);
        if planar.is_some() {
            self.rz = planar_rotation(row.heading);
        }
    }

    /// Steps from k − 1 into `next` (not yet taken: see
    /// [`Simulation::advance`]), with the inputs and rotation at k − 1.
    #[inline(always)]
    fn step(
        &mut self,
        model: &dyn Model,
        theta: &[f64],
        h: f64,
        hist: &History,
        planar: Option<usize>,
        fbuf: &mut [f64],
    ) {
        let sig = Signals {
            states: &self.x,
            inputs: &hist.u1,
            rotation: if planar.is_some() {
                &self.rz_step
            } else {
                &hist.rot1
            },
            disturbances: &self.dist,
        };
        model.step(theta, h, &sig, fbuf, &mut self.next);
    }

    /// Whether the state stepped to is not finite or beyond `bound`.
    #[inline(always)]
    fn beyond(&self, bound: &[f64]) -> bool {
        self.next
            .iter()
            .zip(bound)
            .any(|(x, b)| !x.is_finite() || x.abs() > *b)
    }

    /// Takes the state stepped to, the anchored heading rotated by the step.
    #[inline(always)]
    fn advance(&mut self, h: f64, hist: &History, planar: Option<usize>) {
        if let Some(yaw) = planar {
            self.rz = rotated(hist.rh1, h * self.x[yaw]);
        }
        std::mem::swap(&mut self.x, &mut self.next);
    }
}

/// The reference simulation (the previous instruments), stepped in
/// lockstep with the instrument simulation.
struct Reference {
    x: Vec<f64>,
    next: Vec<f64>,
    rz: [f64; 2],
    dist: Vec<f64>,
}

impl Reference {
    fn start(shape: &Shape) -> Reference {
        Reference {
            x: vec![0.0; shape.n_out],
            next: vec![0.0; shape.n_out],
            rz: [1.0, 0.0],
            dist: vec![0.0; shape.n_comp],
        }
    }

    /// Begins where the instrument simulation `sim` begins.
    #[inline(always)]
    fn begin(&mut self, row: &leeway_model::experiment::Row, sim: &Simulation, planar: bool) {
        self.x.copy_from_slice(row.states);
        if planar {
            self.rz = sim.rz;
        }
    }

    /// Steps from k − 1 to k, with the inputs and rotation at k − 1.
    #[inline(always)]
    fn step(
        &mut self,
        model: &dyn Model,
        theta: &[f64],
        h: f64,
        hist: &History,
        planar: Option<usize>,
        fbuf: &mut [f64],
    ) {
        let sig = Signals {
            states: &self.x,
            inputs: &hist.u1,
            rotation: if planar.is_some() {
                &self.rz
            } else {
                &hist.rot1
            },
            disturbances: &self.dist,
        };
        model.step(theta, h, &sig, fbuf, &mut self.next);
        if let Some(yaw) = planar {
            self.rz = rotated(hist.rh1, h * self.x[yaw]);
        }
        std::mem::swap(&mut self.x, &mut self.next);
    }
}

impl History {
    /// Where a walk stands before the first sample.
    fn start(shape: &Shape) -> History {
        History {
            y1: vec![0.0; shape.n_out],
            y2: vec![0.0; shape.n_out],
            u1: vec![0.0; shape.n_in],
            rot1: vec![0.0; shape.n_rot],
            rot2: vec![0.0; shape.n_rot],
            d1: vec![0.0; shape.n_comp],
            d2: vec![0.0; shape.n_comp],
            rh1: [1.0, 0.0],
            rh2: [1.0, 0.0],
            headings: Some(HeadingRotation::default()),
            samples: 0,
            equations: 0,
        }
    }

    /// Shifts the history: (k−2) ← (k−1) ← k, sample `k` being `row` (its
    /// measured states only if the walk `keeps_states`); a planar model's
    /// heading rotation read from the `known` ones, or advanced, and kept
    /// into `keep`.
    /// (Swaps, and no copy of an empty slice: copies of a few values cost
    /// a `memcpy` call each.)
    #[inline(always)]
    fn shift(
        &mut self,
        row: &leeway_model::experiment::Row,
        k: usize,
        keeps_states: bool,
        shape: &Shape,
        known: Option<&[[f64; 2]]>,
        keep: Option<&mut Vec<[f64; 2]>>,
    ) {
        if keeps_states {
            std::mem::swap(&mut self.y2, &mut self.y1);
            copy_few(&mut self.y1, row.states);
        }
        copy_few(&mut self.u1, row.inputs);
        if shape.n_rot > 0 {
            std::mem::swap(&mut self.rot2, &mut self.rot1);
            copy_few(&mut self.rot1, row.rotation);
        }
        if shape.n_comp > 0 {
            std::mem::swap(&mut self.d2, &mut self.d1);
            copy_few(&mut self.d1, row.disturbances);
        }
        if shape.planar.is_some() {
            self.rh2 = self.rh1;
            self.rh1 = match (known, self.headings.as_mut()) {
                (Some(r), _) => r[k],
                (None, Some(h)) => h.next(row.heading),
                // A resumed walk without its rotation state is only
                // offered kept rotations (`History::continues_headings`).
                (None, None) => planar_rotation(row.heading),
            };
            if let Some(kept) = keep {
                kept.push(self.rh1);
            }
        }
    }
}

/// The simulation's change and fit sums of a walk, zero or going on from
/// where the simulation `resumed` stood (its equations then counted in
/// `equations`).
fn change_from(n_out: usize, resumed: Option<SimWalk>, equations: &mut usize) -> SimChange {
    let mut change = SimChange {
        diff2: vec![0.0; n_out],
        sum: vec![0.0; n_out],
        sum2: vec![0.0; n_out],
        n: 0,
        err2: vec![0.0; n_out],
        y_sum: vec![0.0; n_out],
        y_sum2: vec![0.0; n_out],
        y_n: 0,
    };
    if let Some(s) = resumed {
        *equations = s.equations;
        change.err2 = s.err2;
        change.y_sum = s.y_sum;
        change.y_sum2 = s.y_sum2;
        change.y_n = s.y_n;
    }
    change
}

/// Each equation's target: the difference quotient of the measured states
/// `y` from `y1` one step `h` back, or the states themselves.
#[inline(always)]
fn targets(ir: &Ir, y: &[f64], y1: &[f64], h: f64, t: &mut [f64]) {
    for (o, eq) in ir.equations.iter().enumerate() {
        t[o] = match eq.kind {
            EquationKind::Der => (y[o] - y1[o]) / h,
            EquationKind::Next => y[o],
        };
    }
}

/// Adds how the simulated `x` tracks the measured `y` to `change`.
#[inline(always)]
fn add_fit(change: &mut SimChange, y: &[f64], x: &[f64]) {
    for (o, (&y, &x)) in y.iter().zip(x).enumerate() {
        change.err2[o] += (y - x) * (y - x);
        change.y_sum[o] += y;
        change.y_sum2[o] += y * y;
    }
    change.y_n += 1;
}

/// Adds how the simulated `x` differs from the reference `x_ref` to `change`.
#[inline(always)]
fn add_reference(change: &mut SimChange, x: &[f64], x_ref: &[f64]) {
    for o in 0..x.len() {
        let d = x[o] - x_ref[o];
        change.diff2[o] += d * d;
        change.sum[o] += x_ref[o];
        change.sum2[o] += x_ref[o] * x_ref[o];
    }
    change.n += 1;
}

/// `dst.copy_from_slice(src)` for the few values of one sample: copies of
/// up to four values are inlined rather than a `memcpy` call each (a
/// call costs more than the copy, and the walk makes several a sample).
#[inline(always)]
fn copy_few(dst: &mut [f64], src: &[f64]) {
    match (dst, src) {
        ([a], [x]) => *a = *x,
        ([a, b], [x, y]) => (*a, *b) = (*x, *y),
        ([a, b, c], [x, y, z]) => (*a, *b, *c) = (*x, *y, *z),
        ([a, b, c, d], [x, y, z, w]) => (*a, *b, *c, *d) = (*x, *y, *z, *w),
        (dst, src) => dst.copy_from_slice(src),
    }
}

/// `v.extend_from_slice(src)` for the few values of one sample, inlined
/// as [`copy_few`] is.
#[inline(always)]
fn extend_few(v: &mut Vec<f64>, src: &[f64]) {
    if src.len() <= 4 {
        for x in src {
            v.push(*x);
        }
    } else {
        v.extend_from_slice(src);
    }
}

/// The disturbance values a simulation step uses: measured components as
/// recorded (one sample back), unmeasured ones at the current estimate of
/// their means.
pub(super) fn simulation_disturbances(
    measured: &[bool],
    recorded: &[f64],
    means: &[f64],
    out: &mut [f64],
) {
    for (((o, m), r), mean) in out.iter_mut().zip(measured).zip(recorded).zip(means) {
        *o = if *m { *r } else { *mean };
    }
}

impl Estimator<'_> {
    /// What a data pass needs of this estimator's plan.
    pub(super) fn pass_plan(&self) -> PassPlan {
        PassPlan {
            kind: self.kind,
            instruments: if self.options.method == Method::Ls {
                None
            } else {
                Some(self.options.instruments)
            },
            delayed_mean: self.options.instruments == Instruments::Simulated,
            n_cols: self.n_cols,
            cols: (0..self.ir.states.len())
                .map(|o| self.blocks[self.block_of_output[o]].cols.clone())
                .collect(),
            held: self.held.clone(),
        }
    }

    /// The located data error for a non-finite value found by the first pass:
    /// never a rank verdict.
    pub(super) fn non_finite_error(&self, i: usize, bad: &BadValue) -> EstimateError {
        err(
            "non-finite-data",
            format!(
                "{}: {} on this sample of experiment `{}`, beyond {REGRESSOR_LIMIT:e}: its products would overflow",
                bad.location, bad.what, self.facts[i].name
            ),
            "a value this large is a logging error or a unit mistake: repair the sample, or declare the column's unit in data { } so that values are in base units",
        )
    }
}

/// Asks an interrupt every [`INTERRUPT_EVERY`] samples of a visit and
/// remembers its yes.
pub(super) struct Stopper<'a> {
    interrupt: Option<&'a Interrupt>,
    seen: usize,
    stopped: bool,
}

impl<'a> Stopper<'a> {
    pub(super) fn new(interrupt: Option<&'a Interrupt>) -> Stopper<'a> {
        Stopper {
            interrupt,
            seen: 0,
            stopped: false,
        }
    }

    /// Whether this sample and the rest are to be skipped.
    pub(super) fn now(&mut self) -> bool {
        if !self.stopped && self.seen.is_multiple_of(INTERRUPT_EVERY) {
            self.stopped = self.interrupt.is_some_and(Interrupt::requested);
        }
        self.seen += 1;
        self.stopped
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_model::interp::Share;
    use leeway_structure::ir::Signal;

    /// `u − d`: a state less a measured medium's component.
    fn relative(state: usize) -> ArgPlan {
        ArgPlan {
            signal: Signal::State(state),
            shares: vec![(Share::One, 0)],
        }
    }

    /// The instrument of a `Φ2` modulus whose argument keeps its sign in
    /// the data is the noise-free `s·a_sim`, not `|a_sim|`: where the
    /// simulated argument crosses zero against the data's sign, the two
    /// differ in sign, and only `s·a_sim` is the smooth analogue of the
    /// regressor (docs/estimation.md, "Sign of Φ2 instruments").
    #[test]
    fn a_fixed_sign_instrument_is_the_sign_times_the_simulated_argument() {
        // Term 0: 2·|u − d|·(u − d) on output 0; term 1: 3·|v − d| on
        // output 0; term 2: 5·|v − d| on output 1. Column 1 holds terms 0
        // and 1 (summed in order), column 0 term 2.
        let terms = vec![
            TermPlan {
                coefficient: 2.0,
                factors: vec![(relative(0), true), (relative(0), false)],
                parameter: 0,
                output: 0,
            },
            TermPlan {
                coefficient: 3.0,
                factors: vec![(relative(1), true)],
                parameter: 1,
                output: 0,
            },
            TermPlan {
                coefficient: 5.0,
                factors: vec![(relative(1), true)],
                parameter: 2,
                output: 1,
            },
        ];
        let columns = vec![
            FixedSignColumn {
                column: 1,
                terms: vec![(0, 0, vec![1.0, 1.0]), (1, 0, vec![-1.0])],
            },
            FixedSignColumn {
                column: 0,
                terms: vec![(2, 1, vec![-1.0])],
            },
        ];
        let (n_out, n_cols) = (2, 2);
        let mut fixed = FixedSigns::new(&terms, &columns, n_out, n_cols);
        // The simulated u − d = 0.5 − 2 = −1.5 against the data's sign +1;
        // v − d = 1 − 2 = −1 with the data's sign −1.
        let sig = Signals {
            states: &[0.5, 1.0],
            inputs: &[],
            rotation: &[],
            disturbances: &[2.0],
        };
        // One equation's buffer: `n_out × n_cols`, row by row.
        let mut z = vec![f64::NAN; n_out * n_cols];
        fixed.write(&columns, &sig, &mut z, (1, 0));
        let column_1: f64 = 2.0 * (1.0 * -1.5) * -1.5 + 3.0 * (-1.0 * -1.0);
        assert_eq!(z[1].to_bits(), column_1.to_bits(), "{z:?}");
        assert_eq!(
            z[n_cols].to_bits(),
            (5.0f64 * (-1.0 * -1.0)).to_bits(),
            "{z:?}"
        );
        // Pointwise `|a_sim|` would give −4.5 + 3 in column 1.
        assert_ne!(z[1], 2.0 * 1.5 * -1.5 + 3.0 * 1.0);
        // Slots no fixed-sign column owns are left as they were.
        assert!(z[0].is_nan() && z[n_cols + 1].is_nan(), "{z:?}");
        // Sample 2 of a block of 3, laid out slot-major.
        let mut block = vec![f64::NAN; n_out * n_cols * 3];
        fixed.write(&columns, &sig, &mut block, (3, 2));
        assert_eq!(block[3 + 2].to_bits(), column_1.to_bits(), "{block:?}");
        assert_eq!(block[(n_cols) * 3 + 2], 5.0, "{block:?}");
        assert_eq!(block.iter().filter(|v| !v.is_nan()).count(), 2, "{block:?}");
    }
}
