//! The refinement policy: bootstrap, re-simulation with the estimate, damping, convergence, the iterate reported.
//!
//! Its decisions do not hang on round-off: fits within 10⁻⁶ points
//! (`FIT_TIE`) are a tie settled for the earlier iterate, and with the
//! runaway guard a diverging full step stops the refinement rather than
//! damping near an unstable simulation. `scenarios/tests/scenarios/robustness.rs`
//! moves every measured value by one ulp: the study's mean fits of LS, IV2
//! and IV3 stay within half their Monte Carlo standard error.

use crate::accumulate::Accumulated;
use crate::estimator::Estimator;
use crate::method::{Initial, Instruments, Method};
use crate::moments::CrossMoments;
use crate::outcome::{Estimate, EstimateError, InstrumentSimulation, err};
use crate::protocol::PrefixInstruments;
use crate::solve::BlockSolution;
use leeway_model::number::short_number;
use leeway_model::signs::ExperimentSigns;
use leeway_model::warning::Warning;
use std::collections::BTreeMap;

/// Fit points by which a refinement's simulation may fall below the best
/// earlier iterate before the refinement counts as running away.
pub(super) const RUNAWAY_FIT_DROP: f64 = 5.0;

/// Fits closer than this (fit points) are a tie, settled in favour of the
/// earlier iterate: which iterate is reported must not depend on round-off.
const FIT_TIE: f64 = 1e-6;

/// A refinement contracts when its simulation moved less than this fraction
/// of the previous one's move; the next move is then predicted as
/// `change · (change / previous change)`.
const CONTRACTION: f64 = 0.5;

/// One iterate of the refined IV.
#[derive(Clone, Debug)]
pub(super) struct Iterate {
    pub(super) theta: Vec<f64>,
    pub(super) sol: Vec<BlockSolution>,
    /// The θ (empty: delayed bootstrap) whose simulation gave the instruments.
    pub(super) theta_sim: Vec<f64>,
    pub(super) mu: Vec<f64>,
    pub(super) moments: Vec<Vec<CrossMoments>>,
    /// Fit of this iterate's own simulation to the data, once simulated.
    pub(super) fit: Option<f64>,
}

impl Estimator<'_> {
    pub(super) fn run(
        &mut self,
        sign_patterns: Vec<ExperimentSigns>,
    ) -> Result<Estimate, EstimateError> {
        let (cur, settled) = self.refine()?;
        self.report_iterate(cur, settled, sign_patterns)
    }

    /// The refined IV's iterations: the iterate to report, and how the
    /// refinement ended.
    pub(super) fn refine(&mut self) -> Result<(Iterate, Settled), EstimateError> {
        let refine =
            self.options.method != Method::Ls && self.options.instruments == Instruments::Simulated;
        let (mut theta_sim, mut mu, prefix) = self.starting_instruments(refine);
        // The current iterate: its estimate, the simulation that produced its
        // instruments, and (once simulated itself) how well it tracks the data.
        let mut cur = self.first_iterate(refine, &theta_sim, &mu, prefix)?;
        let mut refinements = 0usize;
        let mut converged = !refine;
        let mut stopped = false;
        let mut best: Option<Iterate> = None;
        // The previous full-step refinement's move of the simulation.
        let mut previous_change: Option<f64> = None;
        while refine && refinements < self.options.max_refinements {
            // A full step whose simulation diverges means the refinement is
            // not contracting here; with the runaway guard it stops rather
            // than damping: damped steps near an unstable simulation amplify
            // round-off into a different estimate (the paper's plain refined
            // IV damps, at most five times).
            let tries = if self.options.runaway_guard { 1 } else { 6 };
            let Some(Resimulated {
                theta: trial,
                mu: trial_mu,
                moments: m,
                change,
                fit,
                step,
            }) = self.resimulate(&cur, &theta_sim, &mu, tries)?
            else {
                let detail = format!(
                    "refinement stopped after {refinements}: the simulation with the refined estimate diverges{}; the iterate whose simulation fits the data best is reported",
                    if tries > 1 { " even when damped" } else { "" }
                );
                self.warnings.push(Warning::new(
                    "refinement-diverged",
                    format!("refinement stopped after {refinements}: the refined model's simulation diverges"),
                    "the best iterate is reported; try --initial nominal or longer experiments",
                    detail,
                ));
                stopped = true;
                break;
            };
            if step < 1.0 {
                self.warnings.push(Warning::plain(
                    "refinement-damped",
                    format!(
                        "refinement {} damped by {} (the simulation with the full step diverged)",
                        refinements + 1,
                        short_number(step)
                    ),
                ));
            } else {
                cur.fit = Some(fit);
                if best
                    .as_ref()
                    .is_none_or(|b| b.fit.unwrap_or(f64::NEG_INFINITY) + FIT_TIE < fit)
                {
                    best = Some(cur.clone());
                }
            }
            theta_sim = trial.clone();
            mu = trial_mu.clone();
            refinements += 1;
            let sol = self.solve(&m, false)?;
            let next = Iterate {
                theta: self.theta_of(&sol),
                sol,
                theta_sim: trial,
                mu: trial_mu,
                moments: m,
                fit: None,
            };
            if std::env::var("LEEWAY_DEBUG").is_ok() {
                eprintln!("refinement {refinements}: change {change:.3e} simulation fit {fit:.1}");
            }
            if self.settles(change, step, previous_change) {
                converged = true;
                cur = next;
                break;
            }
            previous_change = (step == 1.0).then_some(change);
            if self.runs_away(best.as_ref(), cur.fit, refinements) {
                cur = next;
                stopped = true;
                break;
            }
            cur = next;
        }
        if refine && !converged {
            cur = self.unsettled(cur, best, stopped, refinements);
        }
        let settled = Settled {
            refine,
            converged,
            stopped,
            refinements,
        };
        Ok((cur, settled))
    }

    /// The instruments a refinement begins with: the nominal model's, or a
    /// warm start's, continuing (`prefix`, per experiment) the simulation
    /// its own instruments came from over the samples it settled on.
    fn starting_instruments(
        &self,
        refine: bool,
    ) -> (Vec<f64>, Vec<f64>, Vec<Option<PrefixInstruments>>) {
        let n_comp = self.ir.components.len();
        let mut theta_sim = self.nominal.clone();
        let mut mu = vec![0.0; n_comp];
        // A warm start that carries the simulation its own instruments came
        // from begins with those instruments over the samples it settled on
        // (continued over the new ones): the same fixed point within the
        // tolerance, and the passes there need not be summed again.
        let mut prefix = Vec::new();
        if let (true, Some(start)) = (refine, &self.options.start) {
            theta_sim.clone_from(&start.theta);
            mu.clone_from(&start.means);
            if let Some(sim) = &start.instruments
                && sim.theta.len() == start.theta.len()
                && sim.means.len() == start.means.len()
                && sim.experiments.len() == self.facts.len()
            {
                theta_sim.clone_from(&sim.theta);
                mu.clone_from(&sim.means);
                prefix = sim
                    .experiments
                    .iter()
                    .zip(&self.facts)
                    .map(|((samples, means), f)| {
                        (*samples <= f.len && means.len() == n_comp).then(|| PrefixInstruments {
                            samples: *samples,
                            means: means.clone(),
                        })
                    })
                    .collect();
            }
        }
        (theta_sim, mu, prefix)
    }

    /// The first iterate: from the instruments of `(θ, μ)`, or the delayed
    /// bootstrap (refined IV from delayed instruments without a warm start).
    fn first_iterate(
        &mut self,
        refine: bool,
        theta_sim: &[f64],
        mu: &[f64],
        prefix: Vec<Option<PrefixInstruments>>,
    ) -> Result<Iterate, EstimateError> {
        let bootstrap =
            refine && self.options.start.is_none() && self.options.initial == Initial::Delayed;
        let first: Vec<f64> = if bootstrap {
            Vec::new()
        } else {
            theta_sim.to_vec()
        };
        let moments = match self.accumulate(&first, mu, None, true, prefix)? {
            Accumulated::Done(m, _, _) => m,
            Accumulated::Bad(i, bad) => return Err(self.non_finite_error(i, &bad)),
            Accumulated::Diverged => {
                return Err(err(
                    "nominal-diverges",
                    "the simulation of the nominal model diverges on the input of these experiments",
                    "give nominal values closer to the craft (nominal { } in the model, or --nominal FILE)",
                ));
            }
        };
        let sol = self.solve(&moments, !refine)?;
        Ok(Iterate {
            theta: self.theta_of(&sol),
            sol,
            theta_sim: first,
            mu: mu.to_vec(),
            moments,
            fit: None,
        })
    }

    /// Re-simulates with the estimate of `cur` (and the disturbance means it
    /// implies), damping towards the previous simulation `(θ, μ)` if it
    /// diverges, in at most `tries` steps; the new simulation is compared
    /// with the previous one in the same pass: once the instruments stop
    /// moving, so does the estimate. `None` when every step diverged.
    fn resimulate(
        &mut self,
        cur: &Iterate,
        theta_sim: &[f64],
        mu: &[f64],
        tries: usize,
    ) -> Result<Option<Resimulated>, EstimateError> {
        let new_mu = self.implied_means(cur);
        let mut step = 1.0;
        for _ in 0..tries {
            let trial: Vec<f64> = theta_sim
                .iter()
                .zip(&cur.theta)
                .map(|(a, b)| a + step * (b - a))
                .collect();
            let trial_mu: Vec<f64> = mu
                .iter()
                .zip(&new_mu)
                .map(|(a, b)| a + step * (b - a))
                .collect();
            if let Accumulated::Done(m, change, fit) =
                self.accumulate(&trial, &trial_mu, Some((theta_sim, mu)), false, Vec::new())?
            {
                return Ok(Some(Resimulated {
                    theta: trial,
                    mu: trial_mu,
                    moments: m,
                    change,
                    fit,
                    step,
                }));
            }
            step *= 0.5;
        }
        Ok(None)
    }

    /// The disturbance means the iterate `cur` implies (§6): those its
    /// re-simulation takes.
    pub(super) fn implied_means(&self, cur: &Iterate) -> Vec<f64> {
        let values: BTreeMap<usize, f64> = self.all_values(&cur.sol).into_iter().collect();
        self.mean_vector(&values, &cur.theta)
    }

    /// Whether a refinement whose simulation moved by `change` (a damped
    /// `step`, or a full one after a move of `previous_change`) settles:
    /// it moved less than the tolerance, or the refinement contracts so
    /// that the next one would: its estimate would differ from this one by
    /// less than the tolerance moves the instruments, and a pass is saved.
    fn settles(&self, change: f64, step: f64, previous_change: Option<f64>) -> bool {
        let predicted = previous_change
            .filter(|p| step == 1.0 && change < CONTRACTION * p)
            .map(|p| change * (change / p));
        change < self.options.tolerance || predicted.is_some_and(|p| p < self.options.tolerance)
    }

    /// Whether the refinement is running away (small samples; with the
    /// runaway guard): the simulation of the iterate before it (`fit`)
    /// tracks the data markedly worse than an earlier iterate (`best`).
    /// Its warning, if so.
    fn runs_away(&mut self, best: Option<&Iterate>, fit: Option<f64>, refinements: usize) -> bool {
        if let (true, Some(b), Some(f)) = (self.options.runaway_guard, best, fit)
            && b.fit.unwrap_or(f) - f > RUNAWAY_FIT_DROP
        {
            let drop = b.fit.unwrap_or(f) - f;
            self.warnings.push(Warning::new(
                "refinement-runaway",
                format!("refinement stopped after {refinements}: it tracked the data {drop:.1} fit points worse than before"),
                "the best iterate is reported; longer experiments make the refinement stable",
                format!(
                    "refinement stopped after {refinements}: the simulation of the refined estimate tracks the data {drop:.1} fit points worse than an earlier iterate (small-sample runaway); the best iterate is reported"
                ),
            ));
            return true;
        }
        false
    }

    /// The iterate reported by a refinement that did not settle (`cur`,
    /// or the `best` one), with its warning.
    fn unsettled(
        &mut self,
        cur: Iterate,
        best: Option<Iterate>,
        stopped: bool,
        refinements: usize,
    ) -> Iterate {
        let mut cur = cur;
        // Report the iterate whose own simulation tracks the data best.
        if let (true, Some(b)) = (self.options.runaway_guard, best)
            && cur.fit.is_none_or(|f| f + FIT_TIE < b.fit.unwrap_or(f))
        {
            cur = b;
        }
        if !stopped {
            self.warnings.push(Warning::new(
                "not-settled",
                format!("the refined IV did not settle within {refinements} refinements"),
                "the best iterate is reported; raise --max-refinements or record longer experiments",
                format!(
                    "the refined IV did not settle within {} refinements (instrument simulation still moving more than {} of its variation); the iterate whose simulation fits the data best is reported",
                    refinements,
                    short_number(self.options.tolerance)
                ),
            ));
        }
        cur
    }

    /// The estimate of the reported iterate `cur`: its recorded solve, its
    /// own simulation, its covariance, and (a settled refinement) the
    /// instruments a warm start continues.
    fn report_iterate(
        &mut self,
        cur: Iterate,
        settled: Settled,
        sign_patterns: Vec<ExperimentSigns>,
    ) -> Result<Estimate, EstimateError> {
        let Settled {
            refine,
            mut converged,
            stopped,
            refinements,
        } = settled;
        let theta_sim = cur.theta_sim.clone();
        let mu = cur.mu.clone();
        let moments = cur.moments;
        // Record the numeric findings of the reported solve.
        let sol = if refine {
            self.solve(&moments, true)?
        } else {
            cur.sol
        };
        let theta = self.theta_of(&sol);
        let columns = self.ir.predictors.get(self.kind);
        if !sol
            .iter()
            .flat_map(|s| &s.kept)
            .any(|c| !columns[*c].kind.is_nuisance())
        {
            return Err(err(
                "rank-deficient",
                "no physical parameter could be estimated from these data: every θ column is unexcited or held",
                "record experiments that excite the craft (varying inputs, turning), or check the data columns",
            ));
        }
        let values: BTreeMap<usize, f64> = self.all_values(&sol).into_iter().collect();
        // The reported θ simulated on its own data: an estimate that does
        // not reproduce its data is never called converged. With a
        // covariance it runs in the covariance pass (one read of the data
        // for both), which `strict` then discards with the estimate.
        let free_run = self
            .options
            .own_simulation
            .then(|| (theta.clone(), self.mean_vector(&values, &theta)));
        let (cov, own, long_runs) = if self.options.covariance {
            let pass = self.covariance(&moments, &sol, (&theta_sim, &mu), free_run)?;
            let own = pass
                .free_runs
                .map(|r| self.own_simulation_of(r))
                .transpose()?;
            (pass.cov, own, pass.long_runs)
        } else {
            let own = free_run
                .map(|(theta, means)| self.own_simulation(&theta, &means))
                .transpose()?;
            (None, own, None)
        };
        let moment_system = long_runs.and_then(|lr| self.moment_system(&moments, &sol, lr));
        if let Some(problem) = own
            .as_ref()
            .and_then(|o| self.own_simulation_problem(o, stopped))
        {
            if self.options.strict {
                return Err(problem);
            }
            self.warnings.push(
                Warning::new(
                    "own-simulation",
                    own_simulation_summary(&problem.message),
                    "compare with --method ls and validate on held-out data; --strict makes this an error",
                    problem.message,
                )
                .biasing(),
            );
            converged = false;
        } else if let Some(w) = own.as_ref().and_then(|o| self.poor_own_fit(o)) {
            self.warnings.push(w);
        }
        let mut estimate = self.finish(
            sign_patterns,
            &sol,
            values,
            theta,
            cov,
            refinements,
            converged,
        )?;
        estimate.diagnostics.own_simulation = own;
        estimate.moment_system = moment_system;
        // The instruments of a settled refinement, for a warm start that
        // continues them on longer records.
        if refine && converged && !theta_sim.is_empty() {
            estimate.instrument_simulation = Some(InstrumentSimulation {
                theta: theta_sim,
                means: mu,
                experiments: self
                    .facts
                    .iter()
                    .zip(&self.infos)
                    .map(|(f, i)| (f.len, i.measured_mean.clone()))
                    .collect(),
            });
        }
        Ok(estimate)
    }
}

/// A refinement's new simulation: its `(θ, μ)` (the estimate's, or a
/// damped `step` towards it), the moments of its instruments, how far it
/// moved from the previous one and how well it fits the data.
struct Resimulated {
    theta: Vec<f64>,
    mu: Vec<f64>,
    moments: Vec<Vec<CrossMoments>>,
    change: f64,
    fit: f64,
    step: f64,
}

/// How the refinement ended.
pub(super) struct Settled {
    /// The estimate refines at all (a refined IV).
    pub(super) refine: bool,
    pub(super) converged: bool,
    /// Stopped early (divergence, runaway).
    pub(super) stopped: bool,
    pub(super) refinements: usize,
}

/// The first clause of the own-simulation problem: what the simulation did.
fn own_simulation_summary(message: &str) -> String {
    message
        .split(", so it is not reported")
        .next()
        .unwrap_or(message)
        .to_string()
}
