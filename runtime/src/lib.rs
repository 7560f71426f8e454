//! leeway-runtime: data → estimates. The [`Model`] trait that generated and
//! interpreted models share, the IR [`Interpreter`], and (in later modules)
//! data loading, instruments, the LS/IV estimators, simulation and fit.

pub mod interp;
pub mod model;

pub use interp::Interpreter;
pub use leeway_structure as structure;
pub use model::{Model, Signals, next_heading, planar_rotation};
pub mod data;
pub mod estimate;
pub mod moments;
pub mod signs;
pub mod simulate;
pub mod study;
pub mod synth;
pub mod write;

pub use data::{DataError, Experiment, Row, Source, load_csv};
pub use write::write_csv;
pub use estimate::{
    Centring, Estimate, EstimateError, Initial, Instruments, Method, Options, estimate,
};
