//! leeway-runtime: data → estimates. The [`Model`] trait that generated and
//! interpreted models share, the IR [`Interpreter`], and (in later modules)
//! data loading, instruments, the LS/IV estimators, simulation and fit.

pub mod interp;
pub mod model;

pub use interp::Interpreter;
pub use leeway_structure as structure;
pub use model::{Model, Signals, next_heading, planar_rotation};
