//! The estimate's own simulation on its data: a free run of the reported θ
//! (unmeasured disturbances at the means it implies, measured ones and the
//! inputs as recorded), fitted per state as `validate` fits it. The
//! refinement's instruments are simulated with the measured disturbances at
//! their means and with the previous iterate, so a refinement may settle on
//! a θ whose own simulation diverges (an unstable model under an autopilot,
//! paper A1): this pass is what says so.

use super::*;
use leeway_model::simulate::{Disturbances, simulate_each};
use serde::{Deserialize, Serialize};

/// What one experiment's free run contributes, per state: the sum of the
/// squared simulation errors, and the sums of the measurement and of its
/// square, shifted by its first value (so the spread keeps its digits).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct FreeRunSums {
    diverged: bool,
    n: usize,
    err2: Vec<f64>,
    sum: Vec<f64>,
    sum2: Vec<f64>,
}

impl FreeRunSums {
    /// The free run of `theta` on `e`, unmeasured disturbances at `means`.
    pub(super) fn of(model: &dyn Model, theta: &[f64], means: &[f64], e: &dyn Source) -> Self {
        let n_out = model.ir().states.len();
        let mut sums = FreeRunSums {
            diverged: false,
            n: 0,
            err2: vec![0.0; n_out],
            sum: vec![0.0; n_out],
            sum2: vec![0.0; n_out],
        };
        let mut first: Option<Vec<f64>> = None;
        let constant = Disturbances::Constant(means);
        sums.diverged = simulate_each(model, theta, e, constant, &mut |row, x, _| {
            let y0 = first.get_or_insert_with(|| row.states.to_vec());
            for o in 0..n_out {
                let (y, d) = (row.states[o] - y0[o], row.states[o] - x[o]);
                sums.err2[o] += d * d;
                sums.sum[o] += y;
                sums.sum2[o] += y * y;
            }
            sums.n += 1;
        });
        sums
    }

    /// The fit per state, `100·(1 − ‖y − ŷ‖/‖y − ȳ‖)`; `None` where the
    /// measurement is constant or the simulation diverged.
    fn fits(&self) -> Vec<Option<f64>> {
        let n = self.n.max(1) as f64;
        (0..self.err2.len())
            .map(|o| {
                let spread = self.sum2[o] - self.sum[o] * self.sum[o] / n;
                (!self.diverged && spread > 0.0 && self.err2[o].is_finite())
                    .then(|| 100.0 * (1.0 - (self.err2[o] / spread).sqrt()))
            })
            .collect()
    }
}

impl Estimator<'_> {
    /// Simulates the reported θ on every experiment (one pass) and fits it.
    pub(super) fn own_simulation(
        &self,
        theta: &[f64],
        means: &[f64],
    ) -> Result<OwnSimulation, EstimateError> {
        let request = PassRequest {
            plan: self.pass_plan(),
            pass: Pass::FreeRun {
                theta: theta.to_vec(),
                means: means.to_vec(),
            },
            infos: self.infos.clone(),
        };
        let summaries = self.pass(&request)?;
        if summaries.len() != self.facts.len() {
            return Err(mismatched());
        }
        let mut diverged = Vec::new();
        let mut per_state: Vec<Vec<f64>> = vec![Vec::new(); self.ir.states.len()];
        for (s, f) in summaries.into_iter().zip(&self.facts) {
            let Summary::FreeRun(sums) = s.0 else {
                return Err(mismatched());
            };
            if sums.diverged {
                diverged.push(f.name.clone());
            }
            for (all, fit) in per_state.iter_mut().zip(sums.fits()) {
                all.extend(fit);
            }
        }
        // As `validate`'s mean: over the experiments that define a fit, and
        // none at all when one diverged (a mean would flatter the model).
        let fits: Vec<StateFit> = self
            .ir
            .states
            .iter()
            .zip(&per_state)
            .map(|(state, all)| StateFit {
                state: state.clone(),
                fit: (diverged.is_empty() && !all.is_empty())
                    .then(|| all.iter().sum::<f64>() / all.len() as f64),
            })
            .collect();
        let defined: Vec<f64> = fits.iter().filter_map(|f| f.fit).collect();
        let mean_fit =
            (!defined.is_empty()).then(|| defined.iter().sum::<f64>() / defined.len() as f64);
        Ok(OwnSimulation {
            fits,
            mean_fit,
            diverged,
        })
    }

    /// What an estimate whose own simulation fails is reported with: a
    /// warning naming the likely causes (an error under `strict`).
    pub(super) fn own_simulation_problem(
        &self,
        own: &OwnSimulation,
        ran_away: bool,
    ) -> Option<EstimateError> {
        let what = if !own.diverged.is_empty() {
            format!(
                "diverges on {} (the model is unstable on these inputs)",
                leeway_structure::grammar::and_list(own.diverged.iter().map(|e| format!("`{e}`")))
            )
        } else {
            match own.mean_fit {
                Some(fit) if fit < 0.0 => format!(
                    "fits the data worse than their mean (mean fit of the states {fit:.1} %)"
                ),
                _ => return None,
            }
        };
        let mut causes = vec![
            "the input depends on the measurements (a closed loop such as an autopilot or dynamic positioning: the estimators assume open loop, paper A1)".to_string(),
        ];
        if self.options.method == Method::Ls {
            causes.push("least squares' bias where the measurements are noisy or disturbed (the instrumental-variable methods, --method iv3, are consistent there)".into());
        }
        if !self.unexcited.is_empty() {
            causes.push("columns the data hardly excite (see the warnings on excitation)".into());
        }
        if ran_away {
            causes.push("a refinement that ran away".into());
        }
        if own.diverged.is_empty() {
            causes.push("states that barely vary in the record (a small steady offset then fits worse than their mean)".into());
        }
        Some(err(
            "own-simulation",
            format!(
                "the estimate does not reproduce its own data: its simulation {what}, so it is not reported as converged; likely causes: {}",
                causes.join("; ")
            ),
            "compare with --method ls, record open-loop experiments (or those parts of the log), and validate on held-out data before using this model",
        ))
    }
}
