//! The data pass: every equation of an experiment with its regressors, instruments (simulated, delayed or none) and target, and the instrument simulation stepped along.

use crate::estimator::Estimator;
use crate::method::{Instruments, Method};
use crate::outcome::{EstimateError, err};
use crate::protocol::{BadValue, PassPlan, SimChange};
use crate::record::ExperimentInfo;
use leeway_model::experiment::Source;
use leeway_model::interrupt::Interrupt;
use leeway_model::model::{HeadingRotation, Model, Signals, planar_rotation, rotated};
use leeway_model::signs::set_pointwise_signs;
use leeway_structure::grammar::EquationKind;
use leeway_structure::ir::{Ir, PredictorKind, Rotation};

/// Visits every equation of an experiment: `f(z, φ, t)` with dense buffers
/// (`n_out × n_cols`) of instruments and regressors and the targets.
pub(super) struct EquationWalker<'a> {
    pub(super) model: &'a dyn Model,
    pub(super) ir: &'a Ir,
    pub(super) terms: &'a [leeway_model::interp::TermPlan],
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

    /// Calls `f(z, φ, t)` on each equation: instruments, regressors
    /// (`n_out × n_cols`) and targets (both empty when the walk skips the
    /// measured side). Generic in `f`, so the sink is inlined into the walk.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn walk<F: FnMut(&[f64], &[f64], &[f64])>(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        theta_sim: &[f64],
        mu: &[f64],
        reference: Option<(&[f64], &[f64])>,
        reuse: &mut Reuse,
        mut f: F,
    ) -> Result<SimChange, Diverged> {
        let ir = self.ir;
        // Only instruments of their own can leave the regressors out.
        let skip_measured = reuse.skip_measured && self.instruments.is_some();
        let measured_known = reuse.measured_known;
        // Measured states one and two samples back feed the regressors,
        // targets and delayed instruments: none of them in a walk that
        // skips the measured side and simulates its instruments.
        let keeps_states = !(skip_measured && self.instruments == Some(Instruments::Simulated));
        let n_out = ir.states.len();
        // A kept reference simulation is used whole (one state per step) or not at all.
        let known_reference = reuse
            .reference
            .filter(|r| r.len() == e.len().saturating_sub(1) * n_out);
        let known_headings = reuse.headings.filter(|r| r.len() == e.len());
        let n_in = ir.inputs.len();
        // Measured rotation columns travel with the data; a planar heading does not.
        let n_rot = if matches!(ir.rotation, Rotation::Measured { .. }) {
            ir.rotation_vars.len()
        } else {
            0
        };
        let n_comp = ir.components.len();
        let planar = match &ir.rotation {
            Rotation::Planar { integrates, .. } => Some(*integrates),
            _ => None,
        };
        let h = e.step();
        let len = n_out * self.n_cols;
        // Zeroed once: `regressors_update` then writes only the structurally
        // nonzero slots, sample after sample.
        let mut phi = vec![0.0; len];
        let mut z = vec![0.0; len];
        let mut t = vec![0.0; n_out];
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
                && s.fits(e.len(), n_out)
        });
        let replay_until = resume_sim.as_ref().map_or(0, |s| s.samples);
        let start = resume
            .as_ref()
            .map_or(replay_until.saturating_sub(2), |h| h.samples);
        let History {
            mut y1,
            mut y2,
            mut u1,
            mut rot1,
            mut rot2,
            mut d1,
            mut d2,
            mut rh1,
            mut rh2,
            headings,
            samples: _,
            mut equations,
        } = resume.unwrap_or_else(|| History {
            y1: vec![0.0; n_out],
            y2: vec![0.0; n_out],
            u1: vec![0.0; n_in],
            rot1: vec![0.0; n_rot],
            rot2: vec![0.0; n_rot],
            d1: vec![0.0; n_comp],
            d2: vec![0.0; n_comp],
            rh1: [1.0, 0.0],
            rh2: [1.0, 0.0],
            headings: Some(HeadingRotation::default()),
            samples: 0,
            equations: 0,
        });
        // Rotations read from a kept copy leave the running rotation behind.
        let mut headings = headings.filter(|_| known_headings.is_none());
        let mut x_sim = vec![0.0; n_out];
        let mut x_next = vec![0.0; n_out];
        if let Some(s) = &resume_sim {
            x_sim.copy_from_slice(&s.x_sim);
            equations = s.equations;
        }
        let mut fbuf = vec![0.0; n_out];
        // The anchored heading's rotation `ψ_z(k) = y_ψ(k−1) + h·r_sim(k−1)`,
        // rotated from the measured one by the small simulated step.
        let mut rz = resume_sim.as_ref().map_or([1.0, 0.0], |s| s.rz);
        let mut sim_dist = vec![0.0; n_comp];
        // The step's copy of `rz`, written with its disturbances.
        let mut rz_step = vec![0.0; 2];
        let measured: Vec<bool> = ir
            .components
            .iter()
            .map(|c| ir.disturbances[c.disturbance].measured)
            .collect();
        let mut k = start;
        let mut diverged = false;
        // The reference simulation (previous instruments), stepped in lockstep.
        let mut x_ref = vec![0.0; n_out];
        let mut x_ref_next = vec![0.0; n_out];
        let mut rref = [1.0, 0.0];
        let mut ref_dist = vec![0.0; n_comp];
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
        if let Some(s) = resume_sim {
            change.err2 = s.err2;
            change.y_sum = s.y_sum;
            change.y_sum2 = s.y_sum2;
            change.y_n = s.y_n;
        }
        // Buffers for the fixed-sign Φ2 instruments: nothing allocated per sample.
        let mut fix_acc = vec![0.0; n_out];
        let mut fix_set = vec![false; n_out];
        // Their distinct arguments (the same few across columns), each
        // evaluated once a sample: `fixed_slots[column][term][factor]`.
        let mut fixed_args: Vec<&leeway_model::interp::ArgPlan> = Vec::new();
        let fixed_slots: Vec<Vec<Vec<usize>>> = info
            .fixed_sign_columns
            .iter()
            .map(|fixed| {
                fixed
                    .terms
                    .iter()
                    .map(|(term, _, _)| {
                        self.terms[*term]
                            .factors
                            .iter()
                            .map(|(arg, _)| match fixed_args.iter().position(|a| *a == arg) {
                                Some(slot) => slot,
                                None => {
                                    fixed_args.push(arg);
                                    fixed_args.len() - 1
                                }
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        let mut arg_values = vec![0.0; fixed_args.len()];
        // Signs of the pointwise moduli, sample by sample where they change.
        let mut signs = info.signs.clone();
        let simulates = self.instruments == Some(Instruments::Simulated) && !theta_sim.is_empty();
        let mut stop = Stopper::new(self.interrupt);
        let mut sample = |row: &leeway_model::experiment::Row| {
            if diverged || stop.now() {
                return;
            }
            if k < replay_until {
                // Walked again for the history only.
            } else if k == 0 {
                x_sim.copy_from_slice(row.states);
                x_ref.copy_from_slice(row.states);
                if planar.is_some() {
                    rz = planar_rotation(row.heading);
                    rref = rz;
                }
            } else {
                if simulates {
                    // The step's disturbances and rotation, written well
                    // before it reads them: values stored one by one just
                    // before they are read as a vector stall on store
                    // forwarding (measured: about 5 % of one study run).
                    simulation_disturbances(&measured, &d1, mu, &mut sim_dist);
                    rz_step.copy_from_slice(&rz);
                    if let Some((_, mu_ref)) = reference
                        && known_reference.is_none()
                    {
                        simulation_disturbances(&measured, &d1, mu_ref, &mut ref_dist);
                    }
                }
                if k >= 2 {
                    let skip_measured = skip_measured || equations < measured_known;
                    if !skip_measured {
                        let sig = Signals {
                            states: &y1,
                            inputs: &u1,
                            rotation: if planar.is_some() { &rh1 } else { &rot1 },
                            disturbances: &d1,
                        };
                        set_pointwise_signs(&mut signs, &info.varying, &y1);
                        self.model
                            .regressors_update(self.kind, &sig, &signs, &mut phi);
                    }
                    match self.instruments {
                        // Least squares: the regressors are their own instruments.
                        None => {}
                        Some(Instruments::Simulated) => {
                            let means = self.instrument_means.unwrap_or(&info.measured_mean);
                            let sig = Signals {
                                states: &x_sim,
                                inputs: &u1,
                                rotation: if planar.is_some() { &rz } else { &rot2 },
                                disturbances: means,
                            };
                            set_pointwise_signs(&mut signs, &info.varying, &x_sim);
                            self.model
                                .regressors_update(self.kind, &sig, &signs, &mut z);
                            for (v, arg) in arg_values.iter_mut().zip(&fixed_args) {
                                *v = arg.eval(&sig, true);
                            }
                            for (fixed, slots) in info.fixed_sign_columns.iter().zip(&fixed_slots) {
                                fix_set.fill(false);
                                for ((term, o, signs), slots) in fixed.terms.iter().zip(slots) {
                                    let plan = &self.terms[*term];
                                    let mut t = plan.coefficient;
                                    for (((_, modulus), s), slot) in
                                        plan.factors.iter().zip(signs).zip(slots)
                                    {
                                        let v = arg_values[*slot];
                                        t *= if *modulus { s * v } else { v };
                                    }
                                    fix_acc[*o] = if fix_set[*o] { fix_acc[*o] + t } else { t };
                                    fix_set[*o] = true;
                                }
                                for o in 0..n_out {
                                    if fix_set[o] {
                                        z[o * self.n_cols + fixed.column] = fix_acc[o];
                                    }
                                }
                            }
                        }
                        Some(Instruments::Delayed) => {
                            let dist: &[f64] = if self.delayed_mean {
                                &info.measured_mean
                            } else {
                                &d2
                            };
                            let sig = Signals {
                                states: &y2,
                                inputs: &u1,
                                rotation: if planar.is_some() { &rh2 } else { &rot2 },
                                disturbances: dist,
                            };
                            set_pointwise_signs(&mut signs, &info.varying, &y2);
                            self.model
                                .regressors_update(self.kind, &sig, &signs, &mut z);
                        }
                    }
                    if skip_measured {
                        // Least squares has no instruments of its own.
                        f(if self.instruments.is_some() { &z } else { &[] }, &[], &[]);
                    } else {
                        for (o, eq) in ir.equations.iter().enumerate() {
                            t[o] = match eq.kind {
                                EquationKind::Der => (row.states[o] - y1[o]) / h,
                                EquationKind::Next => row.states[o],
                            };
                        }
                        let instruments = if self.instruments.is_some() { &z } else { &phi };
                        f(instruments, &phi, &t);
                    }
                    equations += 1;
                }
                if simulates {
                    // Advance the instrument simulation from k−1 to k
                    // (its disturbances set at the sample's start).
                    let sig = Signals {
                        states: &x_sim,
                        inputs: &u1,
                        rotation: if planar.is_some() { &rz_step } else { &rot1 },
                        disturbances: &sim_dist,
                    };
                    self.model.step(theta_sim, h, &sig, &mut fbuf, &mut x_next);
                    if x_next
                        .iter()
                        .zip(&info.bound)
                        .any(|(x, b)| !x.is_finite() || x.abs() > *b)
                    {
                        diverged = true;
                        return;
                    }
                    if let Some(yaw) = planar {
                        rz = rotated(rh1, h * x_sim[yaw]);
                    }
                    std::mem::swap(&mut x_sim, &mut x_next);
                    if let Some(kept) = reuse.keep_trajectory.as_deref_mut() {
                        extend_few(kept, &x_sim);
                    }
                    for (o, (&y, &x)) in row.states.iter().zip(&x_sim).enumerate() {
                        change.err2[o] += (y - x) * (y - x);
                        change.y_sum[o] += y;
                        change.y_sum2[o] += y * y;
                    }
                    change.y_n += 1;
                    if let Some((theta_ref, _)) = reference {
                        let stepped = change.y_n - 1;
                        let x_ref: &[f64] = if let Some(known) = known_reference {
                            &known[stepped * n_out..(stepped + 1) * n_out]
                        } else {
                            let sig = Signals {
                                states: &x_ref,
                                inputs: &u1,
                                rotation: if planar.is_some() { &rref } else { &rot1 },
                                disturbances: &ref_dist,
                            };
                            self.model
                                .step(theta_ref, h, &sig, &mut fbuf, &mut x_ref_next);
                            if let Some(yaw) = planar {
                                rref = rotated(rh1, h * x_ref[yaw]);
                            }
                            std::mem::swap(&mut x_ref, &mut x_ref_next);
                            &x_ref
                        };
                        for o in 0..n_out {
                            let d = x_sim[o] - x_ref[o];
                            change.diff2[o] += d * d;
                            change.sum[o] += x_ref[o];
                            change.sum2[o] += x_ref[o] * x_ref[o];
                        }
                        change.n += 1;
                    }
                }
            }
            // Shift the history: (k−2) ← (k−1) ← k.
            // (Swaps, and no copy of an empty slice: copies of a few values
            // cost a `memcpy` call each.)
            if keeps_states {
                std::mem::swap(&mut y2, &mut y1);
                copy_few(&mut y1, row.states);
            }
            copy_few(&mut u1, row.inputs);
            if n_rot > 0 {
                std::mem::swap(&mut rot2, &mut rot1);
                copy_few(&mut rot1, row.rotation);
            }
            if n_comp > 0 {
                std::mem::swap(&mut d2, &mut d1);
                copy_few(&mut d1, row.disturbances);
            }
            if planar.is_some() {
                rh2 = rh1;
                rh1 = match (known_headings, headings.as_mut()) {
                    (Some(r), _) => r[k],
                    (None, Some(h)) => h.next(row.heading),
                    // A resumed walk without its rotation state is only
                    // offered kept rotations (`History::continues_headings`).
                    (None, None) => planar_rotation(row.heading),
                };
                if let Some(kept) = reuse.keep_headings.as_deref_mut() {
                    kept.push(rh1);
                }
            }
            k += 1;
        };
        // In-memory columns are walked by a loop the sample is inlined into.
        match e.in_memory() {
            Some(x) => x.rows_from(start, &mut sample),
            None => e.visit(&mut sample),
        }
        if let Some(kept) = reuse.keep_history.as_deref_mut()
            && !diverged
            && self.instruments != Some(Instruments::Simulated)
        {
            *kept = Some(History {
                y1,
                y2,
                u1,
                rot1,
                rot2,
                d1,
                d2,
                rh1,
                rh2,
                headings,
                samples: k,
                equations,
            });
        } else if let Some(kept) = reuse.keep_simulation.as_deref_mut()
            && !diverged
            && self.instruments == Some(Instruments::Simulated)
            && !theta_sim.is_empty()
        {
            *kept = Some(SimWalk {
                samples: k,
                equations,
                x_sim,
                rz,
                err2: change.err2.clone(),
                y_sum: change.y_sum.clone(),
                y_sum2: change.y_sum2.clone(),
                y_n: change.y_n,
            });
        }
        if diverged { Err(Diverged) } else { Ok(change) }
    }
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
