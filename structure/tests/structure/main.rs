//! The integration tests of this crate, one binary (each module was a test
//! binary of its own: one link instead of many keeps the test build lean).

mod broken;
mod delay;
mod echelon;
mod identifiability;
mod limits;
mod models;
mod never_panics;
mod nuisance_basis;
mod search;
