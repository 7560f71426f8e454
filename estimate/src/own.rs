//! The estimate's own simulation on its data: a free run of the reported θ
//! (unmeasured disturbances at the means it implies, measured ones and the
//! inputs as recorded), fitted per state as `validate` fits it. The
//! refinement's instruments are simulated with the measured disturbances at
//! their means and with the previous iterate, so a refinement may settle on
//! a θ whose own simulation diverges (an unstable model under an autopilot,
//! paper A1): this pass is what says so.
//!
//! It is one `FreeRun` pass, or part of the covariance pass when the
//! estimate has one (a streamed record is then read once for both). An estimate whose own simulation diverges or
//! fits below 0 % is never reported as converged: a warning naming the
//! likely causes, the error `own-simulation` under `strict`. The Monte Carlo
//! study, which validates its estimates itself, turns it off.

use crate::accumulate::mismatched;
use crate::estimator::Estimator;
use crate::free_run::FreeRunSums;
use crate::method::Method;
use crate::outcome::{EstimateError, OwnSimulation, StateFit, err};
use crate::protocol::{Pass, PassRequest, Summary};
use leeway_model::warning::Warning;

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
            head: None,
        };
        let summaries = self.pass(&request)?;
        let sums = summaries
            .into_iter()
            .map(|s| match s.0 {
                Summary::FreeRun(sums) => Ok(sums),
                _ => Err(mismatched()),
            })
            .collect::<Result<Vec<_>, _>>()?;
        self.own_simulation_of(sums)
    }

    /// The own simulation's fits from every experiment's free-run sums, in
    /// experiment order.
    pub(super) fn own_simulation_of(
        &self,
        sums: Vec<FreeRunSums>,
    ) -> Result<OwnSimulation, EstimateError> {
        if sums.len() != self.facts.len() {
            return Err(mismatched());
        }
        let mut diverged = Vec::new();
        let mut per_state: Vec<Vec<f64>> = vec![Vec::new(); self.ir.states.len()];
        for (sums, f) in sums.into_iter().zip(&self.facts) {
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

    /// What an estimate whose own simulation fails — it diverges, or some
    /// state fits worse than its mean — is reported with: a warning naming
    /// the likely causes (an error under `strict`).
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

    /// A warning for the states the estimate simulates poorly on its own
    /// data (a fit below `POOR_OWN_FIT` %; below 0, worse than the
    /// state's mean): per state, since the mean over states can hide one.
    /// Not a failure of the estimate (that is the mean's, above): a state
    /// that barely varies fits poorly for a good model too.
    pub(super) fn poor_own_fit(&self, own: &OwnSimulation) -> Option<Warning> {
        let poor: Vec<String> = own
            .fits
            .iter()
            .filter_map(|f| {
                f.fit
                    .filter(|fit| *fit < POOR_OWN_FIT)
                    .map(|fit| format!("`{}` {fit:.0} %", f.state))
            })
            .collect();
        let worse = worse_than_mean(own);
        let below_mean = if worse.is_empty() {
            ""
        } else {
            "; below 0 %: worse than the state's mean"
        };
        (own.diverged.is_empty() && !poor.is_empty()).then(|| {
            Warning::new(
                "poor-own-fit",
                format!(
                    "the estimate simulates its own data poorly in {} (below {POOR_OWN_FIT:.0} %{below_mean})",
                    poor.join(", ")
                ),
                "excite those states more, look for a missing term, and validate on held-out data",
                format!(
                    "the estimate's free run on the data it was estimated from fits {} (per state, normalised fit; below {POOR_OWN_FIT:.0} % a model barely simulates the state, unless the state barely varies in the record{below_mean})",
                    poor.join(", ")
                ),
            )
        })
    }
}

/// The states the own simulation fits below 0 % (worse than their mean),
/// each with its fit: `["u -3.2 %"]`.
fn worse_than_mean(own: &OwnSimulation) -> Vec<String> {
    own.fits
        .iter()
        .filter_map(|f| {
            f.fit
                .filter(|fit| *fit < 0.0)
                .map(|fit| format!("{} {fit:.1} %", f.state))
        })
        .collect()
}

/// The own-data fit (%) below which a state is said to be simulated poorly.
pub const POOR_OWN_FIT: f64 = 50.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_state_worse_than_its_mean_is_named_whatever_the_mean() {
        // The survey boat's case: a mean of 34 % hid a state below zero.
        let fit = |state: &str, fit: f64| StateFit {
            state: state.into(),
            fit: Some(fit),
        };
        let own = OwnSimulation {
            fits: vec![fit("u", -4.6), fit("v", 40.0), fit("r", 66.0)],
            mean_fit: Some(33.8),
            diverged: Vec::new(),
        };
        assert_eq!(worse_than_mean(&own), vec!["u -4.6 %".to_string()]);
        let good = OwnSimulation {
            fits: vec![fit("u", 4.6), fit("v", 40.0)],
            mean_fit: Some(22.3),
            diverged: Vec::new(),
        };
        assert!(worse_than_mean(&good).is_empty());
    }
}
