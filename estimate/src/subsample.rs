//! The refinement on a subsample (`EstimateOptions::refine_subsample`):
//! the bootstrap and the refinement run on the head of every experiment,
//! and their settled iterate begins the refinement over all samples.
//!
//! The subsample's settled estimate is a warm start
//! ([`Start`](crate::Start)): it replaces the bootstrap over all samples,
//! and the refinement there goes on as any refinement does, settling when
//! two of its own simulations over all samples differ by less than the
//! tolerance. At scale that saves the bootstrap pass over all samples, and
//! the refinements the bootstrap's distance to the fixed point costs.
//!
//! Settling on the first pass over all samples, by comparing the
//! subsample's last two simulations there, was tried and not kept: those
//! are iterates of the subsample's refinement, and the estimate it gave lay
//! up to 0.15 standard errors from the fixed point over all samples (the
//! refinement from the bootstrap lands within 0.001) — a record's first
//! fifth does not have the whole record's disturbance means.

use crate::checked_facts::read_facts;
use crate::estimator::Estimator;
use crate::options::{EstimateOptions, Start};
use crate::outcome::{EstimateError, SubsampleRefinement};
use crate::plan::{PlanKey, StructuralPlan};
use crate::protocol::{ExperimentFacts, FactsRequest, PassRequest, PassSummary, Passes};
use leeway_model::model::Model;
use std::sync::Arc;

/// The passes of `passes`, each reading only the head of every experiment.
struct HeadPasses<'a> {
    passes: &'a dyn Passes,
    fraction: f64,
}

impl Passes for HeadPasses<'_> {
    fn facts(&self, request: &FactsRequest) -> Result<Vec<ExperimentFacts>, EstimateError> {
        self.passes.facts(&FactsRequest {
            head: Some(self.fraction),
            ..request.clone()
        })
    }

    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        self.passes.pass(&PassRequest {
            head: Some(self.fraction),
            ..request.clone()
        })
    }

    // A plan depends on the sign patterns and the options, which its key
    // says, not on the records' lengths: the two stages may share it.
    fn known_plan(&self, key: &PlanKey) -> Option<Arc<StructuralPlan>> {
        self.passes.known_plan(key)
    }

    fn keep_plan(&self, key: PlanKey, plan: Arc<StructuralPlan>) {
        self.passes.keep_plan(key, plan);
    }
}

/// What the refinement on the subsample gives the one over all samples:
/// the warm start of its settled estimate, if it settled, and what to
/// report of it.
pub(crate) struct HeadStage {
    pub(crate) start: Option<Start>,
    pub(crate) report: SubsampleRefinement,
}

/// Refines on the first `fraction` of every experiment's samples
/// ([`head_samples`](crate::protocol::head_samples)), with the options of
/// the estimate over all samples but no covariance and no own simulation
/// (what the subsample's estimate is not reported for). Any error there,
/// or a refinement that does not settle, only means the refinement over
/// all samples begins from the bootstrap, as without a subsample; an
/// interrupt stops the estimate.
pub(crate) fn refine_on_head(
    model: &dyn Model,
    passes: &dyn Passes,
    options: &EstimateOptions,
    nominal: &[f64],
    fraction: f64,
) -> Result<HeadStage, EstimateError> {
    let head_options = EstimateOptions {
        covariance: false,
        own_simulation: false,
        refine_subsample: None,
        ..options.clone()
    };
    let head = HeadPasses { passes, fraction };
    let mut report = SubsampleRefinement {
        fraction,
        samples: 0,
        refinements: 0,
        used: false,
        why_not: None,
    };
    let start = match settled_start(model, &head, &head_options, nominal, &mut report) {
        Ok(start) => start,
        Err(e) if e.code == "interrupted" => return Err(e),
        Err(e) => {
            report.why_not = Some(format!("on the subsample: {}", e.message));
            None
        }
    };
    report.used = start.is_some();
    Ok(HeadStage { start, report })
}

/// The warm start of the subsample's settled estimate: its θ and the
/// disturbance means it implies (`None`, and why in `report`, when it did
/// not settle).
fn settled_start(
    model: &dyn Model,
    head: &HeadPasses<'_>,
    options: &EstimateOptions,
    nominal: &[f64],
    report: &mut SubsampleRefinement,
) -> Result<Option<Start>, EstimateError> {
    let read = read_facts(model.ir(), head, options)?;
    report.samples = read.facts.iter().map(|f| f.len).sum();
    let mut est = Estimator::new(
        model,
        options,
        options.method.predictor(),
        nominal.to_vec(),
        read.infos,
        &read.sign_patterns,
        read.warnings,
        head,
        read.facts,
    )?;
    est.check_length()?;
    let (cur, settled) = est.refine()?;
    report.refinements = settled.refinements;
    if !settled.converged || settled.stopped {
        report.why_not = Some(format!(
            "the refinement on the subsample did not settle within {} refinements",
            settled.refinements
        ));
        return Ok(None);
    }
    Ok(Some(Start {
        means: est.implied_means(&cur),
        theta: cur.theta,
        instruments: None,
    }))
}

#[cfg(test)]
mod tests {
    use crate::protocol::head_samples as samples_of;

    #[test]
    fn a_head_is_the_fraction_rounded_up_and_never_below_the_least_record() {
        assert_eq!(samples_of(1000, 0.1), 100);
        assert_eq!(samples_of(1001, 0.1), 101);
        assert_eq!(samples_of(1000, 1.0), 1000);
        assert_eq!(samples_of(50, 0.01), 10);
        assert_eq!(samples_of(7, 0.5), 7);
        assert_eq!(samples_of(0, 0.5), 0);
    }
}
