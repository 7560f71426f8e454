//! leeway-select: which of a model's candidate terms (`?name`) the data need.
//!
//! One IV estimate of the full candidate model keeps its moment sums
//! ([`leeway_estimate::MomentSystem`]); every sub-model on the path is then
//! solved from sub-blocks of them ([`subsolve`]), with the full model's
//! instruments, so a sub-model is over-identified and Hansen's J tests the
//! terms it dropped. The path drops, one at a time, the candidate whose
//! removal raises J least (its Wald statistic in distance-metric form); the
//! path's model with the lowest `J − d·ln N` (`d` the candidates dropped),
//! refined by single additions and removals, is chosen unless its held-out
//! free-run error is out of reach of the best; all of it twice, the second
//! time on instruments simulated by the first choice
//! ([`select()`]). The chosen model is written back as source
//! ([`candidates`]) and estimated as `estimate` does.

pub mod candidates;
pub mod describe;
pub mod select;
pub mod subsolve;
pub mod suggest;

pub use candidates::{CandidateError, CandidateModel};
pub use describe::{CandidateSummary, Exchangeable, describe, summary};
pub use select::{Passes, SelectError, SelectOptions, Selection, Step, exchangeable, select};
pub use suggest::{Suggestion, missing_terms};
