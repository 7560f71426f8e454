//! leeway-runtime: data → estimates. The [`Model`] trait that generated and
//! interpreted models share, the IR [`Interpreter`], data loading
//! ([`data`]: experiments in memory, streamed or from CSV files), the LS and
//! IV estimators ([`estimate()`]), simulation and fit ([`simulate`]),
//! synthetic data ([`synth`]), and the paper's study ([`study`]). The
//! `leeway` crate's documentation is the guide to all of it.

// The estimators index several parallel per-output and per-component arrays
// in one loop, and pass sample visitors as closures over slices; clippy's
// style lints for both fire on code that predates the `-D warnings` check of
// this crate (estimate.rs, simulate.rs, synth.rs). Allowed here, crate-wide,
// until the runtime's owner rewrites or keeps those loops.

pub mod interp;
pub mod model;

#[doc(inline)]
pub use interp::Interpreter;
#[doc(inline)]
pub use leeway_structure as structure;
#[doc(inline)]
pub use model::{Model, Signals, next_heading, planar_rotation};
pub mod data;
pub mod design;
pub mod estimate;
pub mod input;
pub mod interrupt;
pub mod moments;
pub mod report;
pub mod resample;
pub mod signs;
pub mod simulate;
pub mod study;
pub mod synth;
pub mod write;
pub mod zigzag;

#[doc(inline)]
pub use data::{DataError, Experiment, Row, Source, load_csv};
#[doc(inline)]
pub use estimate::{
    Centring, Combine, Estimate, EstimateError, EstimateOptions, Initial, Instruments, Method,
    estimate,
};
#[doc(inline)]
pub use write::write_csv;
