//! Everything the study produced, before it is printed and written.

use crate::reproduce::margins;
use leeway_scenarios::study;
use leeway_scenarios::study::StudyOutcomes;
use std::collections::BTreeMap;

/// Everything the study produced, before it is printed and written.
pub struct Report {
    /// The outcomes of every run.
    pub outcomes: StudyOutcomes,
    /// Per case: the summaries of the results.json contract.
    pub summaries: BTreeMap<String, study::CaseSummary>,
    /// Per case and estimator: the parameter error over every estimate.
    pub all_estimates: BTreeMap<String, BTreeMap<String, AllEstimates>>,
    /// The paper's claims, checked.
    pub claims: Vec<study::Claim>,
    /// The input design checked on the true trajectories.
    pub margins: margins::DesignCheck,
    /// Wall time of the study and the design check, seconds.
    pub seconds: f64,
    /// Worker threads used.
    pub threads: usize,
}

/// The parameter error over every estimate an estimator returned, whether
/// or not its model then diverged on the validation record. The study's
/// summaries leave diverged runs out of every mean and median, which is
/// right for the fit but flatters an estimator whose worst estimates are
/// exactly the ones that diverge (survivor bias): at small N this is where
/// LS and the IV estimators part ways.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AllEstimates {
    /// Runs that returned an estimate, per N.
    pub estimated: Vec<usize>,
    /// Median parameter error over those runs, per N.
    pub median: Vec<f64>,
}

/// Per case, the record lengths at which LS's median parameter error over
/// every estimate is below IV3's: where LS is ahead (claim (a)'s breakpoint
/// lies above the largest of them).
pub fn ls_ahead(report: &Report) -> BTreeMap<String, Vec<usize>> {
    report
        .all_estimates
        .iter()
        .map(|(case, est)| {
            let n = &report.outcomes.config.n;
            let ahead = match (est.get("LS"), est.get("IV3")) {
                (Some(ls), Some(iv3)) => n
                    .iter()
                    .zip(ls.median.iter().zip(&iv3.median))
                    .filter(|(_, (a, b))| a < b || (a.is_finite() && b.is_nan()))
                    .map(|(n, _)| *n)
                    .collect(),
                _ => Vec::new(),
            };
            (case.clone(), ahead)
        })
        .collect()
}

pub fn all_estimates(out: &StudyOutcomes) -> BTreeMap<String, BTreeMap<String, AllEstimates>> {
    let cfg = &out.config;
    let mut cases = BTreeMap::new();
    for (c, case) in cfg.cases.iter().enumerate() {
        let mut estimators = BTreeMap::new();
        for (m, name) in study::ESTIMATORS.iter().enumerate() {
            let mut a = AllEstimates::default();
            for ni in 0..cfg.n.len() {
                let errors: Vec<f64> = out.outcomes[c]
                    .iter()
                    .filter_map(|run| run.get(ni).and_then(|o| o.get(m)))
                    .filter(|o| o.theta.is_some())
                    .map(|o| o.param_error)
                    .collect();
                a.estimated.push(errors.len());
                a.median.push(study::median(errors));
            }
            estimators.insert(name.to_string(), a);
        }
        cases.insert(case.name.clone(), estimators);
    }
    cases
}
