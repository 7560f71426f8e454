//! leeway-estimate: the estimators of the paper, `ls`, `iv1`, `iv2`, `iv3`.
//!
//! Each experiment is visited in order; per pass the regressors `Φ(k−1)`
//! (from data), the instruments `Z(k−1)` and the target (`(y(k) − y(k−1))/h`
//! for `der`, `y(k)` for `next`) feed shifted moment sums per output, so
//! memory is `O(n_ϑ²)` whatever N. Columns split into blocks of outputs that
//! share no parameter (usually one block per output), each solved on its own.
//!
//! Instruments (paper §V-B, SPEC §5): the nominal model is simulated with the
//! known input; its noise-free regressors are the instruments, centred per
//! experiment (default), pooled, or not. Rotation entries come from a heading
//! anchored to the previous measurement, `ψ_z(k) = y_ψ(k−1) + h·r_sim(k−1)`
//! (with a measured `R`: the measurement one sample earlier); measured
//! disturbances enter as their experiment mean. The estimate is refined by
//! re-simulating with it (Young's refined IV) until it settles. Equations
//! start at k = 2 so no instrument uses a same-sample measurement.
//!
//! One module per phase: per-experiment facts, the structural plan, the
//! data walk and its moment sums, the solve, the refinement, covariance,
//! disturbance means, the estimate's own simulation, the report; passes over
//! the data go through a byte-exact protocol, run here or on workers.
//!
//! Estimators never panic on data: errors are [`EstimateError`] values with
//! a stable code and a hint. Every sum runs in a fixed order (experiments in
//! order, samples in order), so results are bit-identical across runs,
//! CPUs and whoever runs the passes. An estimate on a streamed source keeps
//! `O(n_ϑ²)` memory whatever N — samples are visited, never collected — and
//! at most [`TRAJECTORY_BUDGET`] of kept instrument simulations more; on
//! in-memory records at most the keeping budget of [`LocalPasses`] more.

mod accumulate;
mod cache;
mod checked_facts;
mod covariance;
pub mod dense;
mod disturbances;
mod estimator;
pub mod feedback;
mod free_run;
mod local;
mod method;
pub mod moments;
mod options;
mod outcome;
mod own;
pub mod parallel;
mod plan;
mod prefix;
mod protocol;
mod record;
mod refine;
mod report;
mod run;
mod runner;
mod scan;
mod slots;
mod solve;
mod subsample;
mod system;
mod walk;
mod zeta;

pub use cache::{KeptSimulations, TRAJECTORY_BUDGET};
pub use leeway_structure::identify::Centring;
pub use local::{LocalPasses, PrefixRows};
pub use method::{Choice, Combine, Initial, Instruments, Method, Named, UnknownName};
pub use options::{EstimateOptions, Interrupt, MAX_LAGS, MAX_REFINEMENTS, OutOfRange, Start};
pub use outcome::{
    ColumnEstimate, Diagnostics, DisturbanceMoment, DroppedAtStart, Estimate, EstimateError,
    InstrumentSimulation, MomentBlock, MomentSystem, OwnSimulation, StateFit, SubsampleRefinement,
};
pub use plan::{PlanKey, StructuralPlan};
pub use protocol::{
    ExperimentFacts, FactsRequest, PassRequest, PassSummary, Passes, decode, encode, head_samples,
};
pub use run::{NOMINAL_LIMIT, estimate, estimate_with};
pub use runner::PassRunner;
pub use scan::{
    Bound, DelayRange, DelayScan, MAX_SCAN_CANDIDATES, ScanBy, ScanPoint, scan_delay, scan_delays,
    with_dead_time,
};
pub use walk::REGRESSOR_LIMIT;
