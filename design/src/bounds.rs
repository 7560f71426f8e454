//! Every count a design derives from a user's numbers, bounded and checked
//! here before anything is allocated for it: the samples per experiment a
//! budget and a sample time buy, the pilot trials, the verification's
//! trials, and the run a `--target` would need. The CLI, the plan file and
//! Python's `leeway.design` meet the same bounds.

use crate::error::DesignError;
use leeway_model::number::short_number as num;

/// How the run length follows from the budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BudgetRule {
    /// Samples per experiment.
    Samples(usize),
    /// Total seconds, shared by the experiments.
    Time(f64),
    /// Seconds per experiment.
    Each(f64),
}

impl BudgetRule {
    /// Samples per experiment when `experiments` share the budget at
    /// sample time `h`, within [`SAMPLES`] ([`samples`]).
    pub fn samples(self, experiments: usize, h: f64) -> Result<usize, DesignError> {
        samples(self, experiments, h)
    }
}

/// Samples per experiment: at least 50, at most 10 million — the range
/// `budget.samples` allows, and the bound of every other count of samples
/// (a time budget over a step, the run a target needs).
pub const SAMPLES: (usize, usize) = (50, 10_000_000);
/// Most pilot trials calibrating the predicted standard errors.
pub const PILOT: usize = 1000;
/// Most Monte Carlo trials of a verification.
pub const TRIALS: usize = 10_000;

/// Samples per experiment when `experiments` share the budget `rule` at
/// sample time `h`, s: within [`SAMPLES`], or an error naming the plan's
/// value (`budget.time`, `step`) located by its key. Computed in floating
/// point and compared before it becomes a count, so no budget wraps or
/// saturates.
pub fn samples(rule: BudgetRule, experiments: usize, h: f64) -> Result<usize, DesignError> {
    let e = experiments.max(1);
    let (count, key, what) = match rule {
        BudgetRule::Samples(n) => (n as f64, "budget.samples", format!("budget.samples = {n}")),
        BudgetRule::Time(t) => (
            (t / h / e as f64).floor(),
            "budget.time",
            format!("budget.time = {} s at a step of {} s", num(t), num(h)),
        ),
        BudgetRule::Each(t) => (
            (t / h).floor(),
            "step",
            format!(
                "step = {} s over the default {} s per experiment",
                num(h),
                num(t)
            ),
        ),
    };
    let shared = if e == 1 {
        "one experiment".to_string()
    } else {
        format!("{e} experiments")
    };
    if count.is_nan() || count > SAMPLES.1 as f64 {
        return Err(DesignError::plan(
            format!(
                "{what} is more than {} samples per experiment ({shared}), the most leeway plans",
                SAMPLES.1
            ),
            &format!(
                "a run has at most {} samples (as budget.samples): shorten budget.time or lengthen step",
                SAMPLES.1
            ),
        )
        .key(key));
    }
    if count < SAMPLES.0 as f64 {
        return Err(DesignError::plan(
            format!(
                "{what} buys {count} samples per experiment ({shared}), fewer than {}",
                SAMPLES.0
            ),
            &format!(
                "a run needs at least {} samples: raise budget.time",
                SAMPLES.0
            ),
        )
        .key(key));
    }
    // In SAMPLES.0..=SAMPLES.1 and whole: exact as a count.
    Ok(count as usize)
}

/// The samples per experiment a run needs (`samples`, a real number, e.g.
/// from a target precision), rounded up; `None` when that is more than
/// [`SAMPLES`]`.1` (beyond what leeway plans) or not a number.
pub fn needed(samples: f64) -> Option<usize> {
    // In 0..=SAMPLES.1: exact as a count once rounded up.
    (0.0..=SAMPLES.1 as f64)
        .contains(&samples)
        .then(|| samples.ceil() as usize)
}

/// A count of samples a run needs, in words: `1200 samples`, or `more than
/// 10000000 samples (beyond what leeway plans)`.
pub fn needed_words(samples: Option<usize>) -> String {
    match samples {
        Some(n) => format!("{n} samples"),
        None => format!("more than {} samples (beyond what leeway plans)", SAMPLES.1),
    }
}

/// Pilot trials `k`, or why not (the message the front ends show).
pub fn pilot(k: usize) -> Result<usize, String> {
    if k <= PILOT {
        Ok(k)
    } else {
        Err(format!("{k} pilot trials: give 0 to {PILOT}"))
    }
}

/// Monte Carlo trials `m` of a verification, or why not.
pub fn trials(m: usize) -> Result<usize, String> {
    if (1..=TRIALS).contains(&m) {
        Ok(m)
    } else {
        Err(format!("{m} runs: give 1 to {TRIALS}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_budget_beyond_the_bound_is_an_error_naming_it() {
        for (rule, h, key) in [
            (BudgetRule::Time(1e308), 0.05, "budget.time"),
            (BudgetRule::Time(1200.0), 1e-300, "budget.time"),
            (BudgetRule::Time(1200.0), 1e-9, "budget.time"),
            (BudgetRule::Time(1e7), 0.05, "budget.time"),
            (BudgetRule::Each(600.0), 1e-300, "step"),
            (BudgetRule::Time(f64::INFINITY), 0.05, "budget.time"),
        ] {
            let e = samples(rule, 2, h).expect_err("beyond the bound");
            assert_eq!(e.key.as_deref(), Some(key), "{e:?}");
            assert!(e.message.contains("more than 10000000 samples"), "{e:?}");
            assert!(e.hint.contains("budget.time"), "{e:?}");
        }
        assert_eq!(samples(BudgetRule::Time(1200.0), 2, 0.05), Ok(12_000));
        assert_eq!(samples(BudgetRule::Time(2e6), 2, 0.1), Ok(SAMPLES.1));
        assert!(samples(BudgetRule::Time(2e6 + 1.0), 2, 0.1).is_err());
        let e = samples(BudgetRule::Time(4.0), 2, 0.05).expect_err("too few");
        assert!(e.message.contains("40 samples"), "{e:?}");
    }

    #[test]
    fn a_run_beyond_the_bound_is_said_so() {
        assert_eq!(needed(1200.2), Some(1201));
        assert_eq!(needed(1e7), Some(SAMPLES.1));
        assert_eq!(needed(1e7 + 1.0), None);
        assert_eq!(needed(f64::INFINITY), None);
        assert_eq!(needed(f64::NAN), None);
        assert_eq!(
            needed_words(None),
            "more than 10000000 samples (beyond what leeway plans)"
        );
    }
}
