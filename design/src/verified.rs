//! A design judged by its verification (`design --verify M`, Python's
//! `leeway.design(verify=M)`): when the verified models of the design fall
//! short of the verdict, the other runs the design tried
//! (`Design::runs_tried`) are designed and verified in turn and the first
//! that passes is the design. Every caller gets the same design, the same
//! verdicts and the same record of what was tried.

use crate::design::{DesignOptions, design};
use crate::error::DesignError;
use crate::plan::Conditions;
use crate::report::{Design, DifferBy, RunsOption};
use crate::verify::{RunsVerified, Verification, verify};
use leeway_model::model::Model;
use leeway_structure::identify::Centring;

/// A design and, when asked for and the design keeps its signs, its
/// verification (whose `runs_verified` lists every runs option verified).
pub struct Verified {
    /// The design taken: the first whose verified models pass, else the
    /// search's own.
    pub design: Design,
    /// Its verification.
    pub verification: Option<Verification>,
}

/// Designs the trial for `model` under `c` and, with `trials`, verifies it
/// by that many Monte Carlo trials (seeded by `options.seed`); a verdict
/// that fails makes the other runs the design tried be designed and
/// verified in turn. `progress` is called after each trial.
pub fn design_verified(
    model: &dyn Model,
    c: &Conditions,
    options: &DesignOptions,
    trials: Option<usize>,
    progress: &(dyn Fn() + Sync),
) -> Result<Verified, DesignError> {
    let first = design(model, c, options)?;
    let Some(m) = trials.filter(|_| first.feasible) else {
        return Ok(Verified {
            design: first,
            verification: None,
        });
    };
    let Some(v) = verify(model, &first, m, options.seed, progress) else {
        return Ok(Verified {
            design: first,
            verification: None,
        });
    };
    let mut record = vec![RunsVerified::of(&first, Some(&v))];
    let mut outcome = (first, v);
    if !outcome.1.verdict.passed {
        for runs in untried(&outcome.0) {
            let alt = DesignOptions {
                runs: Some(runs),
                ..options.clone()
            };
            // An option the search tried once designs again; one that no
            // longer does is recorded as not verified.
            let Ok(d) = design(model, c, &alt) else {
                continue;
            };
            let v = d
                .feasible
                .then(|| verify(model, &d, m, options.seed, progress))
                .flatten();
            record.push(RunsVerified::of(&d, v.as_ref()));
            if let Some(v) = v.filter(|v| v.verdict.passed) {
                outcome = (d, v);
                break;
            }
        }
    }
    let (design, mut verification) = outcome;
    let taken = (design.runs_tried.iter())
        .find(|o| o.chosen)
        .map(|o| (o.runs, o.centring.clone(), o.differ_by.clone()));
    for r in &mut record {
        r.taken = taken == Some((r.runs, r.centring.clone(), r.differ_by.clone()));
    }
    // Only the design verified: nothing else to record.
    if record.len() > 1 {
        verification.runs_verified = record;
    }
    Ok(Verified {
        design,
        verification: Some(verification),
    })
}

/// The runs the design tried and did not take, as `DesignOptions::runs`.
fn untried(design: &Design) -> Vec<(usize, Centring, DifferBy)> {
    design
        .runs_tried
        .iter()
        .filter(|o| !o.chosen && o.worst_relative.is_some())
        .filter_map(RunsOption::key)
        .collect()
}
