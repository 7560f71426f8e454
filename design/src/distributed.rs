//! `--verify` past one machine: each Monte Carlo run of a design's
//! verification on its own ([`trial`]: a pure function of the model, the
//! design, the seed and the run's index, answered as bytes a cluster can
//! ship), and the verification from every run's bytes ([`summarise`]) —
//! the same, bit for bit, as [`verify`](crate::verify::verify) with as many
//! runs, however the runs were spread. A worker may recompute the design
//! from the model, the plan and the options rather than receive it: a
//! design is deterministic.

use crate::report::Design;
use crate::verify::{Bench, RunResult, Verification};
use leeway_estimate::{EstimateError, decode, encode};
use leeway_model::model::Model;

/// Whether `design` can be verified: it keeps its signs and has the noise,
/// the validation run and the method a verification needs (what `leeway
/// design --verify` checks before it runs).
pub fn verifiable(model: &dyn Model, design: &Design) -> bool {
    design.feasible && Bench::new(model, design).is_some()
}

/// Run `index` (from 0) of the verification of `design` seeded by `seed`,
/// as bytes (every float bit for bit); `None` when the design has nothing
/// to verify.
pub fn trial(model: &dyn Model, design: &Design, seed: u64, index: usize) -> Option<Vec<u8>> {
    let bench = Bench::new(model, design)?;
    Some(encode(&bench.run(model, design, seed, index)))
}

/// The verification of `design` from the bytes of its runs 0, 1, … in
/// order; `None` when the design has nothing to verify, an error when a
/// run's bytes cannot be read (another version of leeway wrote them).
pub fn summarise(
    model: &dyn Model,
    design: &Design,
    seed: u64,
    trials: &[Vec<u8>],
) -> Result<Option<Verification>, EstimateError> {
    let Some(bench) = Bench::new(model, design) else {
        return Ok(None);
    };
    let results: Vec<RunResult> = trials.iter().map(|b| decode(b)).collect::<Result<_, _>>()?;
    Ok(Some(bench.summarise(model, design, seed, &results)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{DesignOptions, design};
    use crate::document::json;
    use crate::plan::parse;
    use crate::verify::verify;
    use leeway_model::Interpreter;

    #[test]
    fn runs_made_apart_summarise_to_the_local_verification() {
        let source = include_str!("../../examples/models/rov.som");
        let ir = leeway_structure::compile(source, &Default::default())
            .ir
            .expect("the ROV compiles");
        let model = Interpreter::new(ir);
        let plan = parse(include_str!("../../examples/plans/rov.toml"), false).expect("a plan");
        let conditions = plan.conditions(model.ir()).expect("conditions");
        let options = DesignOptions {
            pilot: 0,
            seed: 3,
            ..Default::default()
        };
        let d = design(&model, &conditions, &options).expect("a design");
        assert!(verifiable(&model, &d));
        let local = verify(&model, &d, 3, 3, &|| ());
        // Out of order, as a cluster may finish them; summarised in order.
        let mut trials: Vec<(usize, Vec<u8>)> = [2, 0, 1]
            .into_iter()
            .map(|r| (r, trial(&model, &d, 3, r).expect("a trial")))
            .collect();
        trials.sort_by_key(|t| t.0);
        let bytes: Vec<Vec<u8>> = trials.into_iter().map(|t| t.1).collect();
        let apart = summarise(&model, &d, 3, &bytes).expect("readable");
        assert!(local.is_some());
        assert_eq!(json(&d, apart.as_ref()), json(&d, local.as_ref()));
        assert!(summarise(&model, &d, 3, &[vec![1, 2, 3]]).is_err());
    }
}
