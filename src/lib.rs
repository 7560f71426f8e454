//! leeway identifies grey-box models of vessels — ships, underwater vehicles,
//! hovercraft, aircraft, blimps — from measured data while wind and current
//! push the craft around. You write the equations of motion in a small
//! language (`.som`, a *second-order modulus model*); leeway expands them
//! into regressors, proves exactly whether the physical parameters θ are
//! identifiable and from which experiments, and estimates θ with
//! instrumental-variable estimators that stay consistent under unmeasured
//! disturbances (Ljungberg & Enqvist, *Consistent Estimators for Nonlinear
//! Vessel Models*). The same model simulates and validates.
//!
//! This facade is the crate users depend on. The command-line tool
//! (`leeway check | estimate | simulate | validate`) and the Python package
//! run the same library code. This page is a guide, in the order of the work:
//!
//! 1. [The `.som` language](#the-som-language): a complete model, line by line;
//! 2. [Models in Rust](#models-in-rust): compiled into typed code at build time;
//! 3. [Models at run time and the identifiability report](#models-at-run-time-and-the-identifiability-report);
//! 4. [Data](#data): experiments in memory or from CSV files;
//! 5. [Estimating](#estimating): θ, standard errors, nuisance, disturbances, diagnostics;
//! 6. [Simulating and validating](#simulating-and-validating);
//! 7. [Where things are](#where-things-are).
//!
//! # The `.som` language
//!
//! A `.som` file holds one craft's equations of motion. This is the paper's
//! ship (`examples/models/ship.som`, the model every example below uses):
//!
//! ```text
#![doc = include_str!("../examples/models/ship.som")]
//! ```
//!
//! Line by line:
//!
//! * `model Ship { … }` — one model per file; the name becomes the Rust type
//!   `Ship` (and `ShipParams`) in [`include_model!`].
//! * `step 1.0` — the sample time `h` in seconds (without it, taken from the
//!   data). `der x = f` means `x(k+1) = x(k) + h·f`; `next x = f` means
//!   `x(k+1) = f`.
//! * `state u, v, r` — the measured states, one equation each; `input …` —
//!   known actuator signals.
//! * `heading psi integrates r` — a measured heading `ψ`, integrated from the
//!   yaw rate in simulation; it defines the rotation `R = Rz(ψ)ᵀ` that takes
//!   earth-frame disturbances into the body frame.
//! * `disturbance current unmeasured earth(north, east)` — a medium moving
//!   with an unknown disturbance (its mean is estimated); `measured` — one a
//!   sensor records (an anemometer), read from the data.
//! * `water = relative(current)` — the velocity relative to the medium,
//!   `(u, v, r) − R·(north, east, 0)`; `water.u` is its surge component.
//! * `der u = X_u*water.u + … + X_uu*water.u*|water.u| + …` — each term is
//!   one parameter (any name not declared as a signal) times `a`, `|a|`,
//!   `a·b` or `a·|b|` of states, inputs or relative components: the model
//!   class. Anything else is a located error. What stands under a modulus
//!   (`water.u`) is a *sign argument*: which parameters an experiment
//!   identifies depends on the signs it holds there (its sign pattern).
//! * `nominal { … }` — prior values (unlisted: 0): the value of a parameter
//!   the estimator holds (not identifiable, or not excited by the data), and
//!   the θ of the first instrument simulation with [`Initial::Nominal`].
//!
//! The full reference — every construct, what leeway derives from a model,
//! and every diagnostic with its cause and fix — is the [`language`] module
//! (`docs/language.md` in the repository); the estimators and their
//! assumptions are described in `docs/estimation.md`.
//!
//! # Models in Rust
//!
//! `include_model!("models/ship.som")` runs leeway's structure compiler while
//! `cargo build` runs — parsing, expansion into regressors, the exact
//! identifiability proof — and emits, for `model Ship { … }`:
//!
//! * `pub struct Ship;` implementing [`Model`] with straight-line regressor
//!   code for each predictor (basic, augmented with a sign pattern, augmented
//!   with a measured disturbance), the right-hand side and a simulation step:
//!   no tree walk and no allocation per sample, and the same bits as the
//!   [`Interpreter`] of the same model;
//! * `pub struct ShipParams` with one `f64` field per parameter, named as in
//!   the model, `ShipParams::NAMES`, `nominal()`, and conversions to and from
//!   the θ slices the trait takes;
//! * constants `Ship::STATES`, `INPUTS`, `SIGN_ARGS`, `BASIC_COLUMNS`,
//!   `BASIC_LEN`, … and the identifiability report as data
//!   ([`Model::report`], [`Model::ir`]).
//!
//! The path is relative to the invoking file, like `include_str!` (falling
//! back to `CARGO_MANIFEST_DIR` where the compiler names no source file);
//! absolute paths are rejected so the crate builds anywhere.
//! Editing the `.som` file rebuilds the crate. Every error of the model —
//! syntax, unknown names, terms beyond second order, parameters that are not
//! identifiable, … — is a compile error on the path literal that shows the
//! model file's `path:line:col`, the source line, a caret and a hint.
//! Warnings and notes never fail the build; they appear in the generated
//! struct's documentation.
//!
//! ```
//! use leeway::{Model, Signals, planar_rotation};
//!
//! // Relative to this file (src/lib.rs), like `include_str!`.
//! leeway::include_model!("../examples/models/ship.som");
//!
//! let theta = ShipParams::nominal();
//! let rotation = planar_rotation(0.3);
//! let sig = Signals {
//!     states: &[1.0, 0.1, 0.01],
//!     inputs: &[20.0, 0.0, 0.0],
//!     rotation: &rotation,
//!     disturbances: &[0.2, 0.2, 1.0, 1.0],
//! };
//! let mut phi = [0.0; Ship::BASIC_LEN];
//! Ship.basic(&sig, &mut phi);
//! assert_eq!(phi[0], 1.0); // X_u's regressor in `der u`: u
//!
//! let (mut f, mut next) = ([0.0; 3], [0.0; 3]);
//! Ship.step(&theta.to_array(), 1.0, &sig, &mut f, &mut next);
//! assert!(Ship.report().identifiable);
//! ```
//!
//! Small models can be written inline, in a string literal (so comments and
//! layout survive and diagnostics point at `<inline>:line:col`):
//!
//! ```
//! leeway::inline_model!(r#"
//!     model Drift {
//!         state u
//!         input f
//!         der u = X_u*u + X_uu*u*|u| + X_f*f   // |u| of a noisy state: a sign argument
//!     }
//! "#);
//! assert_eq!(Drift::SIGN_ARGS, ["u"]);
//! assert_eq!(DriftParams::NAMES, ["X_u", "X_uu", "X_f"]);
//! ```
//!
//! When θ is not identifiable from any experiment, the macro fails unless
//! asked for the identifiable combinations: `include_model!("ship_iv2.som",
//! aggregate)`, like `leeway check --aggregate`.
//!
//! Generated code refers to this crate as `::leeway`: depend on it under that
//! name.
//!
//! # Models at run time and the identifiability report
//!
//! A model known only at run time (read from a file, written by a tool) is
//! compiled by [`compile`] — the same structure compiler, the same
//! diagnostics — and evaluated by the [`Interpreter`], which implements
//! [`Model`] bit for bit like generated code. [`CompileOptions`] asks for the
//! identifiable combinations (`aggregate`), analyses planned experiments
//! (`patterns`) or another instrument centring. The identifiability report
//! ([`ir::Report`], also [`Model::report`]) is data: the verdict, the
//! smallest set of sign patterns (experiments) that identifies θ, the
//! combinations that are not identifiable and what would separate them.
//! Diagnostics are data too, rendered like rustc's by [`diagnostics::render`].
//!
//! ```
//! use leeway::diagnostics::{RenderStyle, render};
//! use leeway::{CompileOptions, Interpreter, Model, compile};
//!
//! // The ship with the wind unmeasured (the paper's IV2 setting).
//! let source = include_str!("../examples/models/ship_iv2.som");
//! let c = compile(source, &CompileOptions::default());
//! // A valid model whose θ is not identifiable: the IR comes with the error.
//! assert!(c.only_unidentifiable());
//! let report = &c.ir.as_ref().expect("a valid model").report;
//! assert_eq!(report.verdict(), "not-identifiable");
//! let messages: Vec<&str> = report.unidentifiable.iter().map(|u| u.message.as_str()).collect();
//! assert!(messages.contains(&"`N_uv` and `W_uv` enter only as N_uv + W_uv"));
//! let text = render(&c.diagnostics, "ship_iv2.som", source, RenderStyle::Plain);
//! assert!(text.contains("error[unidentifiable-combination]"));
//!
//! // Estimate the identifiable combinations instead (`--aggregate`): the
//! // verdict on θ stands, and the report says what each kept parameter estimates.
//! let c = compile(source, &CompileOptions { aggregate: true, ..Default::default() });
//! let model = Interpreter::new(c.ir.expect("a valid model"));
//! let aggregates: Vec<&str> =
//!     model.report().aggregates.iter().map(|a| a.estimates.as_str()).collect();
//! assert_eq!(aggregates, ["X_uu + W_uu", "Y_vv + W_vv", "N_uv + W_uv"]);
//! ```
//!
//! # Data
//!
//! An experiment is a [`Source`]: samples visited in order, each a [`Row`]
//! of states, inputs, heading (or measured rotation) and measured
//! disturbance components, in the model's order and base units. An
//! [`Experiment`] holds one in memory, column by column — build it with
//! [`Experiment::new`] and [`Experiment::push`], or load it: [`load_csv`]
//! ([`LoadOptions`]) reads a CSV file whose header names the model's signals (or the columns
//! mapped in its `data { }` block), with an optional `time` column and an
//! `experiment` column that splits one file into several; every problem is
//! a [`DataError`] located at `file:row:column`. [`data::open_csv`]
//! streams a file too large to hold ([`data::open_file`] a CSV or, with
//! this crate's `parquet` feature, a Parquet file), and `leeway_scenarios::synth` simulates a
//! seeded "true system" to make test data, as here — the paper's ship under
//! a 0.2 m/s current (unmeasured) and a 10 m/s wind (measured):
//!
//! ```
//! use leeway_scenarios::study;
//! use leeway_scenarios::study::InputDesign;
//! use leeway::{LoadOptions, Model, load_csv, write_csv};
//!
//! leeway::include_model!("../examples/models/ship.som");
//!
//! // 600 samples of the true system (θ0, noises, disturbances; seed 7).
//! let (data, _truth) = study::estimation_experiment(&Ship, &InputDesign::default(), 10.0, 600, 7);
//! assert_eq!(data.states.len(), 3); // u, v, r
//!
//! // Logged as CSV and read back, bit for bit.
//! let path = std::env::temp_dir().join(format!("leeway-doc-{}.csv", std::process::id()));
//! let mut file = std::fs::File::create(&path)?;
//! write_csv(Ship.ir(), &[&data], 0.0, &mut file)?;
//! let header = std::fs::read_to_string(&path)?.lines().next().unwrap_or_default().to_string();
//! assert_eq!(header, "time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e");
//! let loaded = load_csv(&path, Ship.ir(), &LoadOptions::default())?;
//! std::fs::remove_file(&path)?;
//! assert_eq!(loaded[0].states, data.states);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Estimating
//!
//! [`estimate()`] takes a model, the experiments (`&[&dyn Source]`: held,
//! streamed or generated, in any mix) and [`EstimateOptions`] — by default the
//! refined IV3 ([`Method::Iv3`]) with simulated instruments, experiments'
//! moment equations summed, standard errors computed. It returns an
//! [`Estimate`], or an [`EstimateError`] with a stable code and a hint
//! (`unidentifiable`, `rank-deficient`, `sign-violation`, …). The estimate
//! holds θ in the model's parameter order with standard errors, every
//! column of the predictor (θ and the nuisance parameters `rho`, `lambda`:
//! moments of the disturbances) with what it estimates, the means of the
//! unmeasured disturbances (paper Corollary 1) and the diagnostics.
//!
//! ```
//! use leeway_scenarios::study;
//! use leeway_scenarios::study::InputDesign;
//! use leeway::{EstimateOptions, Method, Source, estimate};
//!
//! leeway::include_model!("../examples/models/ship.som");
//!
//! let (data, _truth) = study::estimation_experiment(&Ship, &InputDesign::default(), 10.0, 5000, 200);
//! let options = EstimateOptions { method: Method::Iv3, ..EstimateOptions::default() };
//! let est = estimate(&Ship, &[&data as &dyn Source], &options)?;
//!
//! // θ: in the model's order, by name, or typed.
//! let theta = ShipParams::from_slice(&est.theta)?;
//! assert_eq!(est.get("X_tau"), Some(theta.X_tau));
//! // Every estimated parameter within 4 standard errors of the true θ0.
//! for ((name, value), (se, truth)) in
//!     est.parameters.iter().zip(&est.theta).zip(est.std_errors.iter().zip(study::THETA0))
//! {
//!     let Some(se) = se else { continue }; // held: see the diagnostics below
//!     assert!((value - truth).abs() < 4.0 * se, "{name} = {value} ± {se}, true {truth}");
//! }
//!
//! // The nuisance parameters: moments of the current, with what each estimates.
//! let nuisance: Vec<_> = est.columns.iter().filter(|c| c.kind != "theta").collect();
//! assert!(!nuisance.is_empty());
//! for c in &nuisance {
//!     assert!(!c.estimates.is_empty(), "{} {}", c.name, c.status);
//! }
//!
//! // The current's mean (north, east), true 0.2 m/s each.
//! for d in &est.disturbances {
//!     let se = d.std_error.expect("computed");
//!     assert!((d.mean - 0.2).abs() < 3.0 * se, "{}.{} = {} ± {se}", d.disturbance, d.component, d.mean);
//! }
//!
//! // How it was computed and how well the data support it.
//! let diag = &est.diagnostics;
//! assert!(diag.converged);
//! assert_eq!(diag.equations, 5000 - 2);
//! assert!(diag.condition_number.is_finite());
//! // A parameter these data do not excite is held at its nominal value, has
//! // no standard error, and is named in the diagnostics (and the warnings).
//! for (name, se) in est.parameters.iter().zip(&est.std_errors) {
//!     if se.is_none() {
//!         assert!(diag.unexcited.iter().any(|u| u.starts_with(name.as_str())));
//!     }
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Simulating and validating
//!
//! [`simulate`] runs a model with a θ from an experiment's first sample,
//! driven by its inputs (and measured disturbances), with the unmeasured
//! disturbances zero or constant ([`Disturbances`]), and returns the
//! [`Trajectory`]. Validation, as `leeway validate` does it, compares the
//! simulation with the measurement on data not used for estimation: [`fits`]
//! gives the normalised fit `100·(1 − ‖y − ŷ‖/‖y − ȳ‖)` % of every state
//! (MATLAB's `compare`), [`heading_fit`] that of the integrated heading.
//!
//! ```
//! use leeway_scenarios::study;
//! use leeway_scenarios::study::InputDesign;
//! use leeway::{Disturbances, EstimateOptions, Source, estimate, fits, heading_fit, simulate};
//!
//! leeway::include_model!("../examples/models/ship.som");
//!
//! let (data, _) = study::estimation_experiment(&Ship, &InputDesign::default(), 10.0, 5000, 200);
//! let est = estimate(&Ship, &[&data as &dyn Source], &EstimateOptions::default())?;
//!
//! // A zigzag the estimate has not seen: undisturbed, noise-free, 600 s.
//! let validation = study::validation_experiment(&Ship, 600);
//! let sim = simulate(&Ship, &est.theta, &validation, Disturbances::None);
//! assert!(!sim.diverged);
//! let fit = fits(&validation, &sim); // surge, sway, yaw rate, in %
//! assert!(fit.iter().all(|f| *f > 90.0), "{fit:?}");
//! assert!(heading_fit(&validation, &sim) > 90.0);
//!
//! // The nominal model, for comparison, fits markedly worse.
//! let nominal = simulate(&Ship, &ShipParams::nominal().to_array(), &validation, Disturbances::None);
//! assert!(fits(&validation, &nominal)[0] < fit[0]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Where things are
//!
//! The items above are re-exported here; the rest lives in the crates they
//! come from, re-exported as modules: [`model`] (the [`Model`] trait, the
//! interpreter, experiments as estimators read them, sign detection,
//! simulation), [`data`] (loading and streaming CSV, Parquet and columns,
//! resampling, writing), [`mod@estimate`] (the estimators, one module per
//! phase), [`report`] (the JSON documents of `check --json` and `estimate
//! --json`) and [`structure`] — the structure compiler behind [`compile`],
//! with its grammar and diagnostics. Synthetic data (seeded true systems,
//! the paper's Monte Carlo study, a tanker zigzag campaign, input-design
//! checks) is the separate crate `leeway-scenarios`, the one with random
//! numbers and threads, so that a model compiled with [`include_model!`]
//! builds neither.
//!
//! Each section of this guide is a doc test on data it simulates itself
//! (the paper's ship through `leeway_scenarios::study`, a dev-dependency),
//! asserting what the section claims. No two public types in these docs
//! share a name: the compiler's options are [`CompileOptions`], the
//! estimator's [`EstimateOptions`]; the syntax tree is
//! `structure::grammar::ModelSyntax`, the trait [`Model`]. The macros' ui
//! tests live with `leeway-macros`, whose dev-dependencies are this crate
//! and trybuild alone, since trybuild compiles them all; benchmarks live in
//! the unpublished `leeway-bench` (`bench/`; how to run, compare and profile
//! them: `docs/performance.md`).
//!
//! Past one machine, the estimator's passes over the data are its map half:
//! [`estimate::PassRunner`] computes what one experiment
//! contributes to a pass (a small summary that serialises exactly,
//! [`estimate::encode`]), and [`estimate::estimate_with`]
//! drives an estimate whose passes a [`estimate::Passes`]
//! implementation runs wherever the data are, combining the summaries in
//! experiment order: the same bits as [`estimate()`]. The Python package's
//! `leeway.dask` is this on Dask (`docs/distributed.md`).

pub use leeway_macros::{include_model, inline_model};

// Models: compile-time, run-time, and what both share.
pub use leeway_model::{Interpreter, Model, Signals, next_heading, planar_rotation};
pub use leeway_structure::ir;
pub use leeway_structure::{Compilation, CompileOptions, compile};

// Data.
pub use leeway_data::{DataError, LoadOptions, load_csv, write_csv};
pub use leeway_model::{Experiment, Row, Source};

// Estimating.
pub use leeway_estimate::{
    Centring, ColumnEstimate, Combine, Diagnostics, DisturbanceMoment, Estimate, EstimateError,
    EstimateOptions, Initial, Instruments, Method, Start, estimate,
};

// Simulating and validating.
pub use leeway_model::simulate::{
    Disturbances, Trajectory, fit, fits, heading_fit, simulate, unwrap_heading,
};

// The crates behind the items above, each documented by its own crate docs.
#[doc(inline)]
pub use leeway_data as data;
#[doc(inline)]
pub use leeway_estimate as estimate;
#[doc(inline)]
pub use leeway_model as model;
#[doc(inline)]
pub use leeway_report as report;
#[doc(inline)]
pub use leeway_structure as structure;

/// Diagnostics as data — code, severity, message, labelled spans, help —
/// and their one renderer (rustc-like, plain or coloured), as
/// [`Compilation::diagnostics`] holds them.
pub mod diagnostics {
    pub use leeway_structure::grammar::{Diagnostic, Label, RenderStyle, Severity, render};
}

/// The `.som` language reference (`docs/language.md`), included whole, so
/// its code fences are marked `text`.
pub mod language {
    #![doc = include_str!("../docs/language.md")]
}

/// What code generated by [`include_model!`] refers to. Not a public API.
#[doc(hidden)]
pub mod __private {
    pub use core::array::TryFromSliceError;
    pub use leeway_model::Model;
    pub use leeway_model::Signals;
    pub use leeway_structure::ir::{Ir, PredictorKind};
    pub use std::sync::LazyLock;

    /// Reads the IR a generated model embeds. The macro serialized it with
    /// the same `Ir` type of the same build and checked that it reads back to
    /// exactly the same value, so this cannot fail unless the build mixes
    /// versions of leeway's crates.
    pub fn ir_from_json(json: &str) -> Ir {
        match serde_json::from_str(json) {
            Ok(ir) => ir,
            Err(e) => panic!(
                "leeway: a model embedded by include_model! does not match this version of leeway ({e})"
            ),
        }
    }
}
