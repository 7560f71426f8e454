//! leeway-runtime: data → estimates. The [`Model`] trait that generated and
//! interpreted models share, the IR [`Interpreter`], and (in later modules)
//! data loading, instruments, the LS/IV estimators, simulation and fit.

// The estimators index several parallel per-output and per-component arrays
// in one loop, and pass sample visitors as closures over slices; clippy's
// style lints for both fire on code that predates the `-D warnings` check of
// this crate (estimate.rs, simulate.rs, synth.rs). Allowed here, crate-wide,
// until the runtime's owner rewrites or keeps those loops.

pub mod interp;
pub mod model;

pub use interp::Interpreter;
pub use leeway_structure as structure;
pub use model::{Model, Signals, next_heading, planar_rotation};
pub mod data;
pub mod design;
pub mod estimate;
pub mod input;
pub mod moments;
pub mod report;
pub mod resample;
pub mod signs;
pub mod simulate;
pub mod study;
pub mod synth;
pub mod write;
pub mod zigzag;

pub use data::{DataError, Experiment, Row, Source, load_csv};
pub use estimate::{
    Centring, Combine, Estimate, EstimateError, Initial, Instruments, Method, Options, estimate,
};
pub use write::write_csv;
