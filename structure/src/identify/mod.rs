//! Passes 5–6, reduce and identify: the exact structural rank of the stacked
//! coefficient matrix over (experiment, output, monomial), for a set of sign
//! patterns or for all of them at once (signs kept symbolic: the Walsh
//! characters of distinct sign sets are independent, so "all patterns" is the
//! matrix with sign variables kept in the monomials).
//!
//! Columns are taken in a preference order — nuisance first, then θ of
//! unmeasured media, then θ of measured media — so that
//! * θ is identifiable iff every θ column is a pivot (no null vector touches θ);
//! * a dependent nuisance column is expressed through kept nuisance only;
//! * with aggregation, the later of two confounded parameters is held at its
//!   nominal value and the kept one estimates the aggregate.
//!
//! The passes, in the order [`report()`] runs them: `structural` parses the
//! columns once; `reduce` takes the exact echelon form block by block;
//! `verdict` reads θ's verdict and the nuisance reduction off it; `search`
//! (with `completion`) finds the fewest experiments; `separation` says
//! what tells each unidentifiable group apart. `analysis` holds one
//! predictor's context, `pattern` the sign patterns as text, `names` the
//! names messages use, `centring` the centring policy, and `remedy` what
//! another centring would identify.

pub(crate) mod analysis;
pub(crate) mod centring;
pub(crate) mod completion;
pub(crate) mod names;
pub(crate) mod pattern;
pub(crate) mod reduce;
pub(crate) mod remedy;
pub(crate) mod report;
pub(crate) mod search;
pub(crate) mod separation;
pub(crate) mod structural;
mod union_find;
pub(crate) mod verdict;

pub use crate::ir::Centring;
pub use analysis::Analysis;
pub use names::{Names, linear_text, linear_text_capped};
pub use pattern::{
    all_patterns, parse_pattern, pattern_spec, pattern_text, patterns_text, patterns_text_over,
    pointwise_signs, relevant_signs, shown_signs,
};
pub use reduce::{
    ExperimentStructure, Patterns, Reduction, blocks, preference_order, reduce, reduce_block,
};
pub use remedy::{Remedy, centring_remedies, remedies_text};
pub use report::{CompileOptions, constant_parameters, report};
pub use search::{Found, MAX_ENUMERATED_SIGNS, PRUNE_BUDGET, SEARCH_BUDGET};
pub use structural::Structural;
pub use verdict::{Verdict, nuisance_report, verdict};
