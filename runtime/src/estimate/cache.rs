//! What the passes of one estimate over an in-memory record keep for its later passes: the regressor rows and targets, the headings' rotations and the last instrument simulation — values that do not change between the refinements, so later passes reuse their bits instead of computing them again.

use super::*;
use crate::moments::RegressorRows;

/// The most an estimate keeps for its later passes, over all its records
/// (bytes). A record beyond it is walked in full on every pass, as a
/// streamed one is.
pub(super) const KEEP_BUDGET: usize = 256 << 20;

/// What earlier passes over one record kept (see [`walk::Reuse`]).
#[derive(Debug, Default)]
pub(super) struct RecordCache {
    /// The regressor rows and targets of each output, and the plan they
    /// were computed for (predictor kind, block columns, held columns' bits).
    regressors: Option<(PlanKey, Vec<RegressorRows>)>,
    headings: Option<Vec<[f64; 2]>>,
    /// The states after each step of the simulation of `(θ, μ)` (their bits).
    trajectory: Option<(Vec<u64>, Vec<u64>, Vec<f64>)>,
    /// The previous trajectory's storage, reused for the next one.
    spare: Vec<f64>,
}

type PlanKey = (PredictorKind, Vec<Vec<usize>>, Vec<(usize, u64)>);

fn plan_key(plan: &PassPlan) -> PlanKey {
    (
        plan.kind,
        plan.cols.clone(),
        plan.held.iter().map(|(c, v)| (*c, v.to_bits())).collect(),
    )
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Bytes a record of `len` samples keeps for `plan` (an upper bound).
pub(super) fn keep_bytes(len: usize, plan: &PassPlan, n_out: usize) -> usize {
    let per_sample: usize = plan.cols.iter().map(|c| c.len() + 6).sum::<usize>() + 2 + 2 * n_out;
    len.saturating_mul(per_sample).saturating_mul(8)
}

impl RecordCache {
    /// Forgets regressor rows kept for another plan.
    pub(super) fn prepare(&mut self, plan: &PassPlan) {
        if self
            .regressors
            .as_ref()
            .is_some_and(|(k, _)| *k != plan_key(plan))
        {
            self.regressors = None;
        }
    }

    /// The regressor rows of each output (after [`RecordCache::prepare`]).
    pub(super) fn regressors(&self) -> Option<&[RegressorRows]> {
        self.regressors.as_ref().map(|(_, r)| r.as_slice())
    }

    /// Every sample's heading rotation.
    pub(super) fn headings(&self) -> Option<&[[f64; 2]]> {
        self.headings.as_deref()
    }

    /// The states of the simulation of exactly `(θ, μ)`, if kept.
    pub(super) fn trajectory_of(&self, theta: &[f64], mu: &[f64]) -> Option<&[f64]> {
        match &self.trajectory {
            Some((t, m, states)) if *t == bits(theta) && *m == bits(mu) => Some(states),
            _ => None,
        }
    }

    /// Storage for the next trajectory.
    pub(super) fn take_spare(&mut self) -> Vec<f64> {
        let mut v = std::mem::take(&mut self.spare);
        v.clear();
        v
    }

    /// Keeps what a completed pass computed.
    pub(super) fn keep(
        &mut self,
        plan: &PassPlan,
        regressors: Option<Vec<RegressorRows>>,
        headings: Option<Vec<[f64; 2]>>,
        trajectory: Option<(&[f64], &[f64], Vec<f64>)>,
    ) {
        if let Some(r) = regressors {
            self.regressors = Some((plan_key(plan), r));
        }
        if let Some(h) = headings {
            self.headings = Some(h);
        }
        if let Some((theta, mu, states)) = trajectory {
            if let Some((_, _, old)) = self.trajectory.replace((bits(theta), bits(mu), states)) {
                self.spare = old;
            }
        }
    }

    /// Gives back unused trajectory storage.
    pub(super) fn return_spare(&mut self, v: Vec<f64>) {
        self.spare = v;
    }
}
