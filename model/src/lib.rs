//! leeway-model: what every later stage shares about a craft. The [`Model`]
//! trait that generated (`include_model!`) and interpreted models implement,
//! the IR [`Interpreter`], samples and experiments as estimators read them
//! ([`experiment`]) and as the equations see them, inputs' dead times
//! applied ([`delay`]), the sign patterns found in data ([`signs`]), simulation
//! and fits ([`simulate`]), validation of θ on recorded experiments — the
//! one implementation `leeway validate` and `leeway.validate` share
//! ([`validation`]) —, one-step-ahead residuals and their whiteness and
//! input-independence tests ([`residuals`], on the sample correlations of
//! [`correlation`]), values given by name ([`given`]), numbers in messages
//! ([`number`]), the [`warning`] shape every estimate-time warning takes, and the
//! [`interrupt`] flag a caller raises to stop a long computation. No IO, no
//! randomness.

pub mod correlation;
pub mod delay;
pub mod experiment;
pub mod given;
pub mod interp;
pub mod interrupt;
pub mod model;
pub mod number;
pub mod residuals;
pub mod signs;
pub mod simulate;
pub mod validation;
pub mod warning;

#[doc(inline)]
pub use experiment::{Experiment, Head, MIN_SAMPLES, Row, Source, column_name};
#[doc(inline)]
pub use interp::Interpreter;
#[doc(inline)]
pub use model::{Model, Signals, next_heading, planar_rotation};
