//! The estimators of the paper: `ls`, `iv1`, `iv2`, `iv3`.
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

use crate::data::Source;
use crate::model::{Model, Signals, planar_rotation};
use crate::moments::{CrossMoments, LongRun};
use crate::signs::{ExperimentSigns, detect, plain_sign_args, set_pointwise_signs};
use leeway_structure::exact::Q;
use leeway_structure::grammar::EquationKind;
pub use leeway_structure::identify::Centring;
use leeway_structure::identify::{
    Analysis, ExperimentStructure, Patterns, constant_parameters, linear_text, patterns_text,
    verdict,
};
use leeway_structure::ir::{ColumnKind, Ir, PredictorKind, Rotation};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::collections::BTreeMap;

/// Which estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Least squares on IV3's predictor, with an intercept per output and experiment.
    Ls,
    /// IV on the basic predictor `Φ(y, u)`.
    Iv1,
    /// IV on the augmented predictor, every medium unmeasured.
    Iv2,
    /// IV on the augmented predictor plus `Φ2(y + y_aux)` for measured media.
    Iv3,
}

impl Method {
    /// The predictor the method uses.
    pub fn predictor(self) -> PredictorKind {
        match self {
            Method::Iv1 => PredictorKind::Basic,
            Method::Iv2 => PredictorKind::Augmented,
            Method::Ls | Method::Iv3 => PredictorKind::Measured,
        }
    }
    /// `ls`, `iv1`, ...
    pub fn name(self) -> &'static str {
        match self {
            Method::Ls => "ls",
            Method::Iv1 => "iv1",
            Method::Iv2 => "iv2",
            Method::Iv3 => "iv3",
        }
    }
    /// All four, in the paper's order.
    pub const ALL: [Method; 4] = [Method::Ls, Method::Iv1, Method::Iv2, Method::Iv3];
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Method, String> {
        match s.to_ascii_lowercase().as_str() {
            "ls" => Ok(Method::Ls),
            "iv1" => Ok(Method::Iv1),
            "iv2" => Ok(Method::Iv2),
            "iv3" => Ok(Method::Iv3),
            other => Err(format!("unknown method `{other}`: use ls, iv1, iv2 or iv3")),
        }
    }
}

/// Where instruments come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Instruments {
    /// Simulated nominal model, refined (default).
    Simulated,
    /// Regressors of the measurement one sample earlier.
    Delayed,
}

/// Where the refined IV's first instrument simulation gets its θ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Initial {
    /// The nominal model (`nominal { }` or `--nominal`).
    Nominal,
    /// An estimate with delayed-measurement instruments (measured disturbances
    /// at their experiment mean): consistent, and close enough to the craft
    /// that the first simulation gives strong instruments.
    Delayed,
}

/// How the experiments' moment equations are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    /// `(Σᵢ Hᵢ) ϑ = Σᵢ gᵢ`: the pooled IV estimator (default). With model
    /// error every run's equations have their own solution; summing weighs
    /// runs by their length and keeps one consistent system.
    Summed,
    /// `[H₁/n₁; …; H_E/n_E] ϑ = [g₁/n₁; …]` solved by least squares: the
    /// paper's eq. (IV_problem) as written.
    Stacked,
}

impl Combine {
    /// `summed`, `stacked`.
    pub fn name(self) -> &'static str {
        match self {
            Combine::Summed => "summed",
            Combine::Stacked => "stacked",
        }
    }
}

/// Estimation options.
#[derive(Clone, Debug)]
pub struct Options {
    /// The estimator.
    pub method: Method,
    /// Instrument kind.
    pub instruments: Instruments,
    /// The θ the first instrument simulation uses (simulated instruments).
    pub initial: Initial,
    /// Instrument centring (`None`: the model's default,
    /// [`Centring::for_model`]: per experiment when the model has a
    /// disturbance the predictor does not take from data, none otherwise).
    pub centring: Option<Centring>,
    /// How the experiments' moment equations are combined.
    pub combine: Combine,
    /// θ of the nominal model (default: the model's `nominal { }`).
    pub nominal: Option<Vec<f64>>,
    /// Most re-simulations of the refined IV.
    pub max_refinements: usize,
    /// The refinement has settled when a new instrument simulation moves less
    /// than this fraction of the simulated states' variation (RMS).
    pub tolerance: f64,
    /// Estimate identifiable combinations when θ is not identifiable.
    pub aggregate: bool,
    /// A7 violations (wrong signs) are errors instead of warnings.
    pub strict: bool,
    /// Lags of the long-run covariance (≥ 1: the Euler residual is MA(1)).
    pub lags: usize,
    /// Relative residual below which a column is numerically dependent.
    pub rank_tolerance: f64,
    /// Heading spread (circular std, rad) below which `R` counts as constant.
    pub heading_spread: f64,
    /// Compute standard errors and disturbance moments (one more pass).
    pub covariance: bool,
    /// Stop a refinement whose simulation tracks the data markedly worse than
    /// an earlier iterate, and report the best iterate (small-sample runaway
    /// guard). `false` gives the plain refined IV of the paper.
    pub runaway_guard: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            method: Method::Iv3,
            instruments: Instruments::Simulated,
            initial: Initial::Delayed,
            centring: None,
            combine: Combine::Summed,
            nominal: None,
            max_refinements: 8,
            tolerance: 1e-3,
            aggregate: false,
            strict: false,
            lags: 1,
            rank_tolerance: 1e-9,
            heading_spread: 0.05,
            covariance: true,
            runaway_guard: true,
        }
    }
}

/// One column's estimate (θ or nuisance).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ColumnEstimate {
    /// Column name.
    pub name: String,
    /// `theta`, `rho` or `lambda`.
    pub kind: &'static str,
    /// The estimate (held value for held columns, `None` when dropped).
    pub value: Option<f64>,
    /// Standard error (estimated columns only).
    pub std_error: Option<f64>,
    /// `estimated`, `held at nominal`, `held at 0`, `dropped`.
    pub status: String,
    /// What the value estimates, in moments and parameter names.
    pub estimates: String,
}

/// The mean of an unmeasured disturbance component (paper Corollary 1).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DisturbanceMoment {
    /// The disturbance.
    pub disturbance: String,
    /// The component.
    pub component: String,
    /// Estimated mean.
    pub mean: f64,
    /// Its standard error (delta method).
    pub std_error: Option<f64>,
}

/// How the estimate was computed and how well the data support it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Diagnostics {
    /// `basic`, `augmented`, `measured`.
    pub predictor: String,
    /// Experiments.
    pub experiments: usize,
    /// Equations used (samples − 2 per experiment).
    pub equations: usize,
    /// Columns of the predictor (unreduced).
    pub columns: usize,
    /// Columns estimated after structural and numeric reduction.
    pub estimated: usize,
    /// Numerical rank of the stacked moment matrix over the structurally kept columns.
    pub rank: usize,
    /// Condition number of the column-equilibrated stacked matrix (largest block).
    pub condition_number: f64,
    /// Refinements (re-simulations with an estimate).
    pub refinements: usize,
    /// The refined estimate settled within the tolerance.
    pub converged: bool,
    /// Instruments used.
    pub instruments: String,
    /// Centring used, and why it is valid.
    pub centring: String,
    /// `summed` or `stacked`: how the experiments' equations were combined.
    pub combine: String,
    /// Lags of the long-run covariance.
    pub lags: usize,
    /// Combinations the data did not excite, in the model's names.
    pub unexcited: Vec<String>,
    /// What kept parameters estimate when others were held.
    pub aggregates: Vec<String>,
}

/// The result of an estimation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// The method.
    pub method: Method,
    /// θ names.
    pub parameters: Vec<String>,
    /// θ (held parameters at their nominal values).
    pub theta: Vec<f64>,
    /// Standard errors of θ (`None` for held parameters).
    pub std_errors: Vec<Option<f64>>,
    /// Every column of the predictor.
    pub columns: Vec<ColumnEstimate>,
    /// Means of the unmeasured disturbances.
    pub disturbances: Vec<DisturbanceMoment>,
    /// Sign pattern per experiment.
    pub sign_patterns: Vec<ExperimentSigns>,
    /// Diagnostics.
    pub diagnostics: Diagnostics,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Notes: facts about the data worth knowing that need no action (e.g.
    /// where a pointwise modulus of a noisy state crosses zero).
    pub notes: Vec<String>,
}

impl Estimate {
    /// θ by name.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.parameters
            .iter()
            .position(|p| p == name)
            .map(|i| self.theta[i])
    }
}

/// Why an estimate could not be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct EstimateError {
    /// Stable kebab-case code (`unidentifiable`, `rank-deficient`, `sign-violation`, ...).
    pub code: &'static str,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: String,
}

fn err(code: &'static str, message: impl Into<String>, hint: impl Into<String>) -> EstimateError {
    EstimateError {
        code,
        message: message.into(),
        hint: hint.into(),
    }
}

/// A measured-medium (`Φ2`) column whose modulus arguments keep their sign
/// in the data: its instrument is the noise-free `s·a_sim·…` rather than a
/// pointwise `|a_sim|` of a possibly crude simulation.
#[derive(Clone, Debug)]
struct FixedSignColumn {
    column: usize,
    /// `(term, output, sign of each factor's modulus argument)`.
    terms: Vec<(usize, usize, Vec<f64>)>,
}

/// Per-experiment facts read before estimating.
#[derive(Clone, Debug)]
struct ExperimentInfo {
    signs: Vec<f64>,
    /// Pointwise sign arguments on plain states whose sign changes in this
    /// experiment: `(sign argument, state)`; their sign is taken sample by
    /// sample from the point the regressors are evaluated at.
    varying: Vec<(usize, usize)>,
    fixed_sign_columns: Vec<FixedSignColumn>,
    measured_mean: Vec<f64>,
    bound: Vec<f64>,
    spread: f64,
    frozen: Option<Vec<f64>>,
}

#[derive(Clone, Debug)]
struct Block {
    outputs: Vec<usize>,
    /// Structurally kept predictor columns of the block, in column order.
    cols: Vec<usize>,
}

/// Fewest equations per column of the largest block (a bare minimum for the
/// moment matrices to have full rank with some margin).
const MIN_EQUATIONS_PER_COLUMN: usize = 3;

/// A moment column below this many machine epsilons per equation of its
/// Cauchy–Schwarz scale is rounding residue, not information.
const RESIDUE_EPSILONS: f64 = 64.0;

/// Condition number of the equilibrated moment matrix above which an
/// estimate is reported as ill-conditioned, naming the columns involved.
const CONDITION_WARNING: f64 = 1e8;

/// Fit points by which a refinement's simulation may fall below the best
/// earlier iterate before the refinement counts as running away.
const RUNAWAY_FIT_DROP: f64 = 5.0;

/// One iterate of the refined IV.
#[derive(Clone, Debug)]
struct Iterate {
    theta: Vec<f64>,
    sol: Vec<BlockSolution>,
    /// The θ (empty: delayed bootstrap) whose simulation gave the instruments.
    theta_sim: Vec<f64>,
    mu: Vec<f64>,
    moments: Vec<Vec<CrossMoments>>,
    /// Fit of this iterate's own simulation to the data, once simulated.
    fit: Option<f64>,
}

/// The per-block outcome of a solve.
#[derive(Clone, Debug)]
struct BlockSolution {
    /// Columns (predictor indices) estimated.
    kept: Vec<usize>,
    /// Numerically dropped columns with their held value.
    held: Vec<(usize, f64)>,
    /// Estimates of `kept`.
    values: Vec<f64>,
    /// `ϑ_K = Σ_i B_i · (Σ_k ζ_k of experiment i)` over the block's instrument rows.
    b: Vec<DMatrix<f64>>,
    /// Instrument rows (predictor columns) of ζ.
    rows: Vec<usize>,
    condition: f64,
    /// Columns that dominate the weakest direction when ill-conditioned.
    weak: Vec<usize>,
}

/// Visits every equation of an experiment: `f(z, φ, t)` with dense buffers
/// (`n_out × n_cols`) of instruments and regressors and the targets.
struct EquationWalker<'a> {
    model: &'a dyn Model,
    ir: &'a Ir,
    terms: &'a [crate::interp::TermPlan],
    kind: PredictorKind,
    instruments: Option<Instruments>,
    /// Delayed instruments take measured disturbances at their experiment
    /// mean (bootstrap of the refined IV) instead of one sample earlier.
    delayed_mean: bool,
    n_cols: usize,
}

#[derive(Debug)]
struct Diverged;

/// Largest magnitude of a measured regressor or target: squares stay below
/// 1e290, so sums of squares over 10¹⁸ samples stay finite.
pub const REGRESSOR_LIMIT: f64 = 1e145;

/// The first non-finite measured value found: `(experiment, sample, what)`.
type FirstBadValue = std::cell::RefCell<Option<(usize, usize, String)>>;

/// Receives each equation: instruments, regressors (`n_out × n_cols`) and targets.
type EquationSink<'a> = dyn FnMut(&[f64], &[f64], &[f64]) + 'a;

/// `(kept column, [(component, parameter, coefficient)])`: what a kept ρ column
/// estimates in terms of disturbance means and θ.
type MomentEquation = (usize, Vec<(usize, usize, f64)>);

/// How far an instrument simulation moved from a reference one, per output:
/// `‖x − x_ref‖ / ‖x_ref − x̄_ref‖` (0 without a reference).
#[derive(Clone, Debug, Default)]
struct SimChange {
    diff2: Vec<f64>,
    sum: Vec<f64>,
    sum2: Vec<f64>,
    n: usize,
    /// `Σ (y − x_sim)²`, `Σ y`, `Σ y²` per output: how well the instrument
    /// simulation tracks the measured states (its strength as an instrument).
    err2: Vec<f64>,
    y_sum: Vec<f64>,
    y_sum2: Vec<f64>,
    y_n: usize,
}

impl SimChange {
    /// Mean over outputs of the fit `100·(1 − ‖y − x_sim‖/‖y − ȳ‖)`.
    fn fit(&self) -> f64 {
        let n = self.y_n.max(1) as f64;
        let fits: Vec<f64> = (0..self.err2.len())
            .map(|o| {
                let var = (self.y_sum2[o] - self.y_sum[o] * self.y_sum[o] / n).max(0.0);
                if var > 0.0 {
                    100.0 * (1.0 - (self.err2[o] / var).sqrt())
                } else {
                    0.0
                }
            })
            .collect();
        fits.iter().sum::<f64>() / fits.len().max(1) as f64
    }

    fn relative(&self) -> f64 {
        let n = self.n.max(1) as f64;
        (0..self.diff2.len())
            .map(|o| {
                let mean = self.sum[o] / n;
                let var = (self.sum2[o] / n - mean * mean).max(0.0) * n;
                if var > 0.0 {
                    (self.diff2[o] / var).sqrt()
                } else {
                    0.0
                }
            })
            .fold(0.0, f64::max)
    }
}

impl EquationWalker<'_> {
    fn walk(
        &self,
        e: &dyn Source,
        info: &ExperimentInfo,
        theta_sim: &[f64],
        mu: &[f64],
        reference: Option<(&[f64], &[f64])>,
        f: &mut EquationSink,
    ) -> Result<SimChange, Diverged> {
        let ir = self.ir;
        let n_out = ir.states.len();
        let n_in = ir.inputs.len();
        // Measured rotation columns travel with the data; a planar heading does not.
        let n_rot = if matches!(ir.rotation, Rotation::Measured { .. }) {
            ir.rotation_vars.len()
        } else {
            0
        };
        let n_comp = ir.components.len();
        let planar = match &ir.rotation {
            Rotation::Planar { integrates, .. } => Some(*integrates),
            _ => None,
        };
        let h = e.step();
        let len = n_out * self.n_cols;
        let mut phi = vec![0.0; len];
        let mut z = vec![0.0; len];
        let mut t = vec![0.0; n_out];
        let (mut y1, mut u1, mut rot1, mut d1, mut psi1) = (
            vec![0.0; n_out],
            vec![0.0; n_in],
            vec![0.0; n_rot],
            vec![0.0; n_comp],
            0.0,
        );
        let (mut y2, mut rot2, mut d2, mut psi2) =
            (vec![0.0; n_out], vec![0.0; n_rot], vec![0.0; n_comp], 0.0);
        let mut x_sim = vec![0.0; n_out];
        let mut x_next = vec![0.0; n_out];
        let mut fbuf = vec![0.0; n_out];
        let mut psi_z = 0.0;
        let mut sim_dist = vec![0.0; n_comp];
        let measured: Vec<bool> = ir
            .components
            .iter()
            .map(|c| ir.disturbances[c.disturbance].measured)
            .collect();
        let mut k = 0usize;
        let mut diverged = false;
        // The reference simulation (previous instruments), stepped in lockstep.
        let mut x_ref = vec![0.0; n_out];
        let mut x_ref_next = vec![0.0; n_out];
        let mut psi_ref = 0.0;
        let mut ref_dist = vec![0.0; n_comp];
        let mut change = SimChange {
            diff2: vec![0.0; n_out],
            sum: vec![0.0; n_out],
            sum2: vec![0.0; n_out],
            n: 0,
            err2: vec![0.0; n_out],
            y_sum: vec![0.0; n_out],
            y_sum2: vec![0.0; n_out],
            y_n: 0,
        };
        // Rotations of the measured headings one and two samples back, and
        // buffers for the fixed-sign Φ2 instruments: nothing allocated per sample.
        let (mut rh1, mut rh2) = ([1.0, 0.0], [1.0, 0.0]);
        let mut fix_acc = vec![0.0; n_out];
        let mut fix_set = vec![false; n_out];
        // Signs of the pointwise moduli, sample by sample where they change.
        let mut signs = info.signs.clone();
        e.visit(&mut |row| {
            if diverged {
                return;
            }
            if k == 0 {
                x_sim.copy_from_slice(row.states);
                x_ref.copy_from_slice(row.states);
                psi_z = row.heading;
                psi_ref = row.heading;
            } else {
                // The anchored heading's rotation serves the instruments and the simulation.
                let rz = planar_rotation(psi_z);
                if k >= 2 {
                    let sig = Signals {
                        states: &y1,
                        inputs: &u1,
                        rotation: if planar.is_some() { &rh1 } else { &rot1 },
                        disturbances: &d1,
                    };
                    set_pointwise_signs(&mut signs, &info.varying, &y1);
                    self.model.regressors(self.kind, &sig, &signs, &mut phi);
                    match self.instruments {
                        None => z.copy_from_slice(&phi),
                        Some(Instruments::Simulated) => {
                            let sig = Signals {
                                states: &x_sim,
                                inputs: &u1,
                                rotation: if planar.is_some() { &rz } else { &rot2 },
                                disturbances: &info.measured_mean,
                            };
                            set_pointwise_signs(&mut signs, &info.varying, &x_sim);
                            self.model.regressors(self.kind, &sig, &signs, &mut z);
                            for fixed in &info.fixed_sign_columns {
                                fix_set.fill(false);
                                for (term, o, signs) in &fixed.terms {
                                    let plan = &self.terms[*term];
                                    let mut t = plan.coefficient;
                                    for ((arg, modulus), s) in plan.factors.iter().zip(signs) {
                                        let v = arg.eval(&sig, true);
                                        t *= if *modulus { s * v } else { v };
                                    }
                                    fix_acc[*o] = if fix_set[*o] { fix_acc[*o] + t } else { t };
                                    fix_set[*o] = true;
                                }
                                for o in 0..n_out {
                                    if fix_set[o] {
                                        z[o * self.n_cols + fixed.column] = fix_acc[o];
                                    }
                                }
                            }
                        }
                        Some(Instruments::Delayed) => {
                            let dist: &[f64] = if self.delayed_mean {
                                &info.measured_mean
                            } else {
                                &d2
                            };
                            let sig = Signals {
                                states: &y2,
                                inputs: &u1,
                                rotation: if planar.is_some() { &rh2 } else { &rot2 },
                                disturbances: dist,
                            };
                            set_pointwise_signs(&mut signs, &info.varying, &y2);
                            self.model.regressors(self.kind, &sig, &signs, &mut z);
                        }
                    }
                    for (o, eq) in ir.equations.iter().enumerate() {
                        t[o] = match eq.kind {
                            EquationKind::Der => (row.states[o] - y1[o]) / h,
                            EquationKind::Next => row.states[o],
                        };
                    }
                    f(&z, &phi, &t);
                }
                if self.instruments == Some(Instruments::Simulated) && !theta_sim.is_empty() {
                    // Advance the instrument simulation from k−1 to k.

                    simulation_disturbances(&measured, &d1, mu, &mut sim_dist);
                    let sig = Signals {
                        states: &x_sim,
                        inputs: &u1,
                        rotation: if planar.is_some() { &rz } else { &rot1 },
                        disturbances: &sim_dist,
                    };
                    self.model.step(theta_sim, h, &sig, &mut fbuf, &mut x_next);
                    if x_next
                        .iter()
                        .zip(&info.bound)
                        .any(|(x, b)| !x.is_finite() || x.abs() > *b)
                    {
                        diverged = true;
                        return;
                    }
                    if let Some(yaw) = planar {
                        psi_z = psi1 + h * x_sim[yaw];
                    }
                    x_sim.copy_from_slice(&x_next);
                    for (o, (&y, &x)) in row.states.iter().zip(&x_sim).enumerate() {
                        change.err2[o] += (y - x) * (y - x);
                        change.y_sum[o] += y;
                        change.y_sum2[o] += y * y;
                    }
                    change.y_n += 1;
                    if let Some((theta_ref, mu_ref)) = reference {
                        let rot_ref = rotation_at(planar.is_some(), psi_ref, &rot1);

                        simulation_disturbances(&measured, &d1, mu_ref, &mut ref_dist);
                        let sig = Signals {
                            states: &x_ref,
                            inputs: &u1,
                            rotation: rot_ref.as_slice(),
                            disturbances: &ref_dist,
                        };
                        self.model
                            .step(theta_ref, h, &sig, &mut fbuf, &mut x_ref_next);
                        if let Some(yaw) = planar {
                            psi_ref = psi1 + h * x_ref[yaw];
                        }
                        x_ref.copy_from_slice(&x_ref_next);
                        for o in 0..n_out {
                            let d = x_sim[o] - x_ref[o];
                            change.diff2[o] += d * d;
                            change.sum[o] += x_ref[o];
                            change.sum2[o] += x_ref[o] * x_ref[o];
                        }
                        change.n += 1;
                    }
                }
            }
            // Shift the history: (k−2) ← (k−1) ← k.
            y2.copy_from_slice(&y1);
            rot2.copy_from_slice(&rot1);
            d2.copy_from_slice(&d1);
            psi2 = psi1;
            y1.copy_from_slice(row.states);
            u1.copy_from_slice(row.inputs);
            rot1.copy_from_slice(row.rotation);
            d1.copy_from_slice(row.disturbances);
            psi1 = row.heading;
            if planar.is_some() {
                rh2 = rh1;
                rh1 = planar_rotation(row.heading);
            }
            k += 1;
        });
        if diverged { Err(Diverged) } else { Ok(change) }
    }
}

/// The disturbance values a simulation step uses: measured components as
/// recorded (one sample back), unmeasured ones at the current estimate of
/// their means.
fn simulation_disturbances(measured: &[bool], recorded: &[f64], means: &[f64], out: &mut [f64]) {
    for (((o, m), r), mean) in out.iter_mut().zip(measured).zip(recorded).zip(means) {
        *o = if *m { *r } else { *mean };
    }
}

/// Rotation variables from a heading (planar) or measured columns.
enum RotationValues<'a> {
    Planar([f64; 2]),
    Measured(&'a [f64]),
}

impl RotationValues<'_> {
    fn as_slice(&self) -> &[f64] {
        match self {
            RotationValues::Planar(a) => a,
            RotationValues::Measured(s) => s,
        }
    }
}

fn rotation_at(planar: bool, psi: f64, measured: &[f64]) -> RotationValues<'_> {
    if planar {
        RotationValues::Planar(planar_rotation(psi))
    } else {
        RotationValues::Measured(measured)
    }
}

/// The estimator for one model, method and set of experiments.
struct Estimator<'a> {
    model: &'a dyn Model,
    ir: &'a Ir,
    options: &'a Options,
    kind: PredictorKind,
    /// The centring used (the option, or the model's default).
    centring: Centring,
    /// Constant θ columns (`X_0`): under pooled centring their instrument,
    /// the constant, is not centred.
    constant_cols: Vec<bool>,
    n_cols: usize,
    blocks: Vec<Block>,
    block_of_output: Vec<usize>,
    /// Structurally dropped θ held at nominal (aggregation).
    held: Vec<(usize, f64)>,
    /// Preference rank of each column (lower = kept first).
    preference: Vec<usize>,
    nominal: Vec<f64>,
    infos: Vec<ExperimentInfo>,
    /// What each kept column estimates, as (column, coefficient) in predictor columns.
    meaning: BTreeMap<usize, Vec<(usize, f64)>>,
    warnings: Vec<String>,
    unexcited: Vec<String>,
    aggregates: Vec<String>,
    terms: Vec<crate::interp::TermPlan>,
}

/// Estimates θ (and nuisance parameters) of `model` from the experiments.
pub fn estimate(
    model: &dyn Model,
    experiments: &[&dyn Source],
    options: &Options,
) -> Result<Estimate, EstimateError> {
    let ir = model.ir();
    if experiments.is_empty() {
        return Err(err(
            "no-data",
            "no experiment given",
            "pass at least one --data file",
        ));
    }
    let nominal = match &options.nominal {
        Some(v) if v.len() == ir.parameters.len() => v.clone(),
        Some(v) => {
            return Err(err(
                "invalid-nominal",
                format!(
                    "the nominal model has {} values, the model {} parameters",
                    v.len(),
                    ir.parameters.len()
                ),
                "give one value per parameter",
            ));
        }
        None => ir.parameters.iter().map(|p| p.nominal).collect(),
    };
    let kind = options.method.predictor();
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    // Sign patterns, measured means, bounds and heading spread, in one visit each.
    let mut sign_patterns = Vec::new();
    let mut infos = Vec::new();
    for e in experiments {
        if e.len() < crate::data::MIN_SAMPLES {
            return Err(err(
                "too-few-samples",
                format!(
                    "experiment `{}` has {} samples; at least {} are needed",
                    e.name(),
                    e.len(),
                    crate::data::MIN_SAMPLES
                ),
                "record a longer experiment",
            ));
        }
        let s = detect(ir, kind, *e);
        for a in &s.arguments {
            if a.minority_fraction > 0.0 {
                let msg = format!(
                    "experiment `{}`: {} has sign {} in {:.1}% of the samples and the other sign in {:.2}% (paper A7 requires one sign per experiment)",
                    s.experiment,
                    a.argument,
                    if a.sign > 0 { "+" } else { "-" },
                    100.0 * (1.0 - a.minority_fraction),
                    100.0 * a.minority_fraction
                );
                if options.strict {
                    return Err(err(
                        "sign-violation",
                        msg,
                        "run experiments with a static offset large enough that the argument keeps its sign, or drop --strict to estimate anyway",
                    ));
                }
                warnings.push(msg);
            }
        }
        let crossing: Vec<String> = s
            .pointwise
            .iter()
            .zip(&s.crossings)
            .filter(|(a, _)| {
                a.minority_fraction > 0.0
                    && ir
                        .sign_args
                        .iter()
                        .any(|x| x.pointwise && x.name == a.argument)
            })
            .map(|(a, n)| {
                format!(
                    "{} ({n} sign change{}, {:.1}% of the samples of the minority sign)",
                    a.argument,
                    if *n == 1 { "" } else { "s" },
                    100.0 * a.minority_fraction
                )
            })
            .collect();
        if !crossing.is_empty() {
            notes.push(format!(
                "experiment `{}`: {} cross zero; their moduli are evaluated pointwise, as the simulation does (within the noise of zero, measurement noise biases |x| slightly upwards)",
                s.experiment,
                crossing.join(", ")
            ));
        }
        infos.push(experiment_info(ir, *e, &s, options));
        sign_patterns.push(s);
    }
    for (e, info) in experiments.iter().zip(&infos) {
        if info.frozen.is_some() {
            warnings.push(format!(
                "experiment `{}`: the heading barely varied (circular std {:.3} rad): R is treated as constant there (paper Remark 2)",
                e.name(),
                info.spread.max(0.0)
            ));
        }
    }
    let mut est = Estimator::new(
        model,
        options,
        kind,
        nominal,
        infos,
        &sign_patterns,
        warnings,
    )?;
    est.check_length(experiments)?;
    let mut estimate = est.run(experiments, sign_patterns)?;
    estimate.notes = notes;
    Ok(estimate)
}

fn experiment_info(
    ir: &Ir,
    e: &dyn Source,
    s: &ExperimentSigns,
    options: &Options,
) -> ExperimentInfo {
    let n_comp = ir.components.len();
    let n_out = ir.states.len();
    let mut sum = vec![0.0; n_comp];
    let mut max_abs = vec![0.0f64; n_out];
    let (mut sc, mut ss, mut n) = (0.0, 0.0, 0usize);
    let n_rot = ir.rotation_vars.len();
    let mut rot_sum = vec![0.0; n_rot];
    let mut rot_sq = vec![0.0; n_rot];
    e.visit(&mut |row| {
        for (a, v) in sum.iter_mut().zip(row.disturbances) {
            *a += v;
        }
        for (m, v) in max_abs.iter_mut().zip(row.states) {
            *m = m.max(v.abs());
        }
        sc += row.heading.cos();
        ss += row.heading.sin();
        for i in 0..row.rotation.len().min(n_rot) {
            rot_sum[i] += row.rotation[i];
            rot_sq[i] += row.rotation[i] * row.rotation[i];
        }
        n += 1;
    });
    let nf = n.max(1) as f64;
    let measured_mean: Vec<f64> = (0..n_comp)
        .map(|c| {
            if ir.disturbances[ir.components[c].disturbance].measured {
                sum[c] / nf
            } else {
                0.0
            }
        })
        .collect();
    let (spread, frozen) = match &ir.rotation {
        Rotation::Planar { .. } => {
            let (mc, ms) = (sc / nf, ss / nf);
            let r = (mc * mc + ms * ms).sqrt().min(1.0);
            let spread = (-2.0 * r.max(1e-300).ln()).sqrt();
            let frozen = (spread < options.heading_spread)
                .then(|| vec![sc / nf / r.max(1e-300), ss / nf / r.max(1e-300)]);
            (spread, frozen)
        }
        Rotation::Measured { .. } => {
            let spread = (0..n_rot)
                .map(|i| {
                    let mean = rot_sum[i] / nf;
                    (rot_sq[i] / nf - mean * mean).max(0.0).sqrt()
                })
                .fold(0.0, f64::max);
            (
                spread,
                (spread < options.heading_spread).then(|| rot_sum.iter().map(|v| v / nf).collect()),
            )
        }
        Rotation::None => (f64::INFINITY, None),
    };
    // Φ2 columns whose modulus arguments never change sign in these data.
    let mut fixed_sign_columns = Vec::new();
    if options.method.predictor() == PredictorKind::Measured {
        let sign_of = |arg: &leeway_structure::ir::Arg| -> Option<f64> {
            let i = ir.sign_args.iter().position(|a| a.arg == *arg)?;
            let found = s
                .pointwise
                .iter()
                .find(|a| a.argument == ir.sign_args[i].name)?;
            (found.minority_fraction == 0.0).then_some(f64::from(found.sign))
        };
        for (c, col) in ir.predictors.measured.iter().enumerate() {
            let mut terms = Vec::new();
            let mut ok = !col.entries.is_empty();
            for e in &col.entries {
                match e {
                    leeway_structure::ir::Entry::Term { term, output, .. } => {
                        let t = &ir.terms[*term];
                        let signs: Option<Vec<f64>> = t
                            .factors
                            .iter()
                            .map(|f| {
                                if f.modulus {
                                    sign_of(&f.arg)
                                } else {
                                    Some(1.0)
                                }
                            })
                            .collect();
                        match signs {
                            Some(v) => terms.push((*term, *output, v)),
                            None => ok = false,
                        }
                    }
                    leeway_structure::ir::Entry::Poly { .. } => ok = false,
                }
            }
            if ok {
                fixed_sign_columns.push(FixedSignColumn { column: c, terms });
            }
        }
    }
    // Only the plain arguments whose sign changes need a sign per sample; the
    // others keep the experiment's (only) sign from the pattern.
    let varying = plain_sign_args(ir)
        .into_iter()
        .filter(|(i, _)| {
            s.pointwise
                .iter()
                .any(|a| a.argument == ir.sign_args[*i].name && a.minority_fraction > 0.0)
        })
        .collect();
    ExperimentInfo {
        signs: s.pattern.iter().map(|v| f64::from(*v)).collect(),
        varying,
        fixed_sign_columns,
        measured_mean,
        bound: max_abs.iter().map(|m| 100.0 * (1.0 + m)).collect(),
        spread,
        frozen,
    }
}

impl<'a> Estimator<'a> {
    fn new(
        model: &'a dyn Model,
        options: &'a Options,
        kind: PredictorKind,
        nominal: Vec<f64>,
        infos: Vec<ExperimentInfo>,
        signs: &[ExperimentSigns],
        warnings: Vec<String>,
    ) -> Result<Estimator<'a>, EstimateError> {
        let ir = model.ir();
        let centring = options
            .centring
            .unwrap_or_else(|| Centring::for_model(ir, kind));
        let columns = ir.predictors.get(kind);
        let n_cols = columns.len();
        let analysis = Analysis::with_centring(ir, kind, centring);
        let constant_cols: Vec<bool> = (0..n_cols)
            .map(|c| !columns[c].kind.is_nuisance() && analysis.structural.is_constant(c))
            .collect();
        let exps: Vec<ExperimentStructure> = signs
            .iter()
            .zip(&infos)
            .map(|(s, info)| ExperimentStructure {
                varying: s
                    .pointwise
                    .iter()
                    .filter(|a| a.minority_fraction > 0.0)
                    .filter_map(|a| ir.sign_args.iter().position(|x| x.name == a.argument))
                    .collect(),
                pattern: s.pattern.clone(),
                frozen_rotation: info.frozen.as_ref().map(|v| {
                    v.iter()
                        .map(|x| Q::from_float(*x).unwrap_or_default())
                        .collect()
                }),
            })
            .collect();
        let red = analysis.reduce(Patterns::Experiments(&exps));
        let v = verdict(&analysis.names, &red);
        let mut held = Vec::new();
        let mut aggregates = Vec::new();
        if !v.identifiable {
            let distinct: Vec<Vec<i8>> = {
                let mut p: Vec<Vec<i8>> = signs.iter().map(|s| s.pattern.clone()).collect();
                p.sort();
                p.dedup();
                p
            };
            let combos: Vec<String> = v.combinations.iter().map(|c| c.message.clone()).collect();
            let remark2 = infos.iter().any(|i| i.frozen.is_some());
            let constants = constant_parameters(ir);
            let only_constants = v
                .combinations
                .iter()
                .all(|c| c.parameters.iter().all(|p| constants.contains(p)));
            if !options.aggregate {
                let required = analysis.required_patterns();
                let hint = match (&required, remark2) {
                    _ if only_constants && centring != Centring::None => format!(
                        "a constant term is estimable with uncentred instruments (--centring none: {}), or with --centring pooled; or remove the term",
                        Centring::None.reason(ir, kind)
                    ),
                    (_, true) => "the heading barely varied: run experiments that turn the craft (paper Remark 2), or estimate the identifiable combinations with --aggregate".to_string(),
                    (Some(r), false) if !r.is_empty() => format!(
                        "θ needs experiments with sign patterns {}; or estimate the identifiable combinations with --aggregate",
                        patterns_text(ir, r, kind)
                    ),
                    _ => "no set of experiments identifies θ with this predictor; estimate the identifiable combinations with --aggregate".to_string(),
                };
                return Err(err(
                    "unidentifiable",
                    format!(
                        "θ is not identifiable from these experiments (sign patterns {}): {}",
                        patterns_text(ir, &distinct, kind),
                        combos.join("; ")
                    ),
                    hint,
                ));
            }
            for a in &v.aggregates {
                aggregates.push(format!(
                    "{} estimates {} (absorbed parameters held at their nominal values)",
                    ir.parameters[a.parameter].name, a.estimates
                ));
            }
            for (c, col) in columns.iter().enumerate() {
                if let ColumnKind::Theta { parameter } = col.kind
                    && !red.pivot[c]
                {
                    held.push((c, nominal[parameter]));
                }
            }
        }
        // What each kept column estimates: itself plus the structurally dropped
        // columns expressed through it.
        let mut meaning: BTreeMap<usize, Vec<(usize, f64)>> = BTreeMap::new();
        for c in 0..n_cols {
            if red.pivot[c] {
                meaning.entry(c).or_default().push((c, 1.0));
            }
        }
        for d in 0..n_cols {
            if !red.pivot[d] {
                for (k, q) in &red.combination[d] {
                    meaning
                        .entry(*k)
                        .or_default()
                        .push((d, leeway_structure::exact::to_f64(q)));
                }
            }
        }
        // Blocks: outputs connected through shared columns.
        let n_out = ir.states.len();
        let mut parent: Vec<usize> = (0..n_out).collect();
        fn find(p: &mut [usize], x: usize) -> usize {
            let mut r = x;
            while p[r] != r {
                r = p[r];
            }
            p[x] = r;
            r
        }
        for col in columns {
            let outs = col.outputs();
            for w in outs.windows(2) {
                let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
                parent[b] = a;
            }
        }
        let mut blocks: Vec<Block> = Vec::new();
        let mut block_of_output = vec![0; n_out];
        for (o, slot) in block_of_output.iter_mut().enumerate() {
            let root = find(&mut parent, o);
            let b = match blocks
                .iter()
                .position(|b| find(&mut parent, b.outputs[0]) == root)
            {
                Some(b) => b,
                None => {
                    blocks.push(Block {
                        outputs: Vec::new(),
                        cols: Vec::new(),
                    });
                    blocks.len() - 1
                }
            };
            blocks[b].outputs.push(o);
            *slot = b;
        }
        for (c, col) in columns.iter().enumerate() {
            if red.pivot[c]
                && let Some(o) = col.outputs().first()
            {
                blocks[block_of_output[*o]].cols.push(c);
            }
        }
        let mut preference = vec![0; n_cols];
        for (rank, c) in analysis.order.iter().enumerate() {
            preference[*c] = rank;
        }
        Ok(Estimator {
            model,
            ir,
            options,
            kind,
            centring,
            constant_cols,
            n_cols,
            blocks,
            block_of_output,
            held,
            preference,
            nominal,
            infos,
            meaning,
            warnings,
            unexcited: Vec::new(),
            aggregates,
            terms: crate::interp::term_plans(ir),
        })
    }

    fn combine(&self) -> Combine {
        self.options.combine
    }

    /// Refuses records too short for the number of columns estimated together.
    fn check_length(&self, experiments: &[&dyn Source]) -> Result<(), EstimateError> {
        let equations: usize = experiments.iter().map(|e| e.len().saturating_sub(2)).sum();
        if let Some(block) = self.blocks.iter().max_by_key(|b| b.cols.len()) {
            let needed = MIN_EQUATIONS_PER_COLUMN * block.cols.len();
            if equations < needed {
                let outputs: Vec<&str> = block
                    .outputs
                    .iter()
                    .map(|o| self.ir.states[*o].as_str())
                    .collect();
                return Err(err(
                    "too-few-samples",
                    format!(
                        "{equations} equations for {} columns estimated together (outputs {}): at least {needed} are needed",
                        block.cols.len(),
                        outputs.join(", ")
                    ),
                    "record longer experiments (hundreds of samples per parameter give useful standard errors)",
                ));
            }
        }
        Ok(())
    }

    fn walker(&self) -> EquationWalker<'_> {
        self.walker_with(if self.options.method == Method::Ls {
            None
        } else {
            Some(self.options.instruments)
        })
    }

    fn walker_with(&self, instruments: Option<Instruments>) -> EquationWalker<'_> {
        EquationWalker {
            model: self.model,
            ir: self.ir,
            terms: &self.terms,
            kind: self.kind,
            instruments,
            delayed_mean: self.options.instruments == Instruments::Simulated,
            n_cols: self.n_cols,
        }
    }

    /// A measured regressor or target that is not finite, or so large that
    /// its square or a sum of squares leaves f64's range ([`REGRESSOR_LIMIT`]),
    /// in equation `k` (regressors at `k − 1`): `(sample, what)`.
    fn non_finite(&self, k: usize, phi: &[f64], t: &[f64]) -> Option<(usize, String)> {
        // The common case in one branch-free sweep (NaN fails `<=` too).
        let fine = |v: &f64| v.abs() <= REGRESSOR_LIMIT;
        if phi.iter().all(fine) && t.iter().all(fine) {
            return None;
        }
        let n = self.n_cols;
        let predictors = self.ir.predictors.get(self.kind);
        let wrong = |v: f64| !v.is_finite() || v.abs() > REGRESSOR_LIMIT;
        for (o, target) in t.iter().enumerate() {
            for (c, col) in predictors.iter().enumerate().take(n) {
                let v = phi[o * n + c];
                if wrong(v) && v != 0.0 {
                    return Some((
                        k - 1,
                        format!(
                            "the regressor {} of `{}` evaluates to {v:e}",
                            col.name, self.ir.states[o]
                        ),
                    ));
                }
            }
            if wrong(*target) {
                return Some((
                    k,
                    format!(
                        "the difference quotient of `{}` evaluates to {target:e}",
                        self.ir.states[o]
                    ),
                ));
            }
        }
        None
    }

    /// The located data error for a non-finite value found by the first pass:
    /// never a rank verdict.
    fn non_finite_error(&self, e: &dyn Source, sample: usize, what: &str) -> EstimateError {
        err(
            "non-finite-data",
            format!(
                "{}: {what} on this sample of experiment `{}`, beyond {REGRESSOR_LIMIT:e}: its products would overflow",
                e.locate(sample),
                e.name()
            ),
            "a value this large is a logging error or a unit mistake: repair the sample, or declare the column's unit in data { } so that values are in base units",
        )
    }

    /// One accumulation pass: `[experiment][output]` moment sums over the block's columns.
    /// With `finite`, the first pass also looks for non-finite measured
    /// values (no extra pass over the data): the first one found is stored
    /// as `(experiment, sample, what)`.
    fn accumulate(
        &self,
        experiments: &[&dyn Source],
        theta_sim: &[f64],
        mu: &[f64],
        reference: Option<(&[f64], &[f64])>,
        finite: Option<&FirstBadValue>,
    ) -> Result<(Vec<Vec<CrossMoments>>, f64, f64), Diverged> {
        // An empty θ asks for the delayed bootstrap pass of the refined IV.
        let walker = if theta_sim.is_empty() {
            self.walker_with(Some(Instruments::Delayed))
        } else {
            self.walker()
        };
        let n = self.n_cols;
        let mut all = Vec::with_capacity(experiments.len());
        let mut change = 0.0f64;
        let mut fit = 0.0f64;
        for (i, (e, info)) in experiments.iter().zip(&self.infos).enumerate() {
            // The sink sees equation k = 2, 3, …: regressors at k − 1, target at k.
            let mut k = 1usize;
            let mut acc: Vec<CrossMoments> = (0..self.ir.states.len())
                .map(|o| {
                    let m = self.blocks[self.block_of_output[o]].cols.len();
                    CrossMoments::new(m, m)
                })
                .collect();
            let mut zb: Vec<Vec<f64>> = self
                .blocks
                .iter()
                .map(|b| vec![0.0; b.cols.len()])
                .collect();
            let mut pb: Vec<Vec<f64>> = zb.clone();
            let c = walker.walk(*e, info, theta_sim, mu, reference, &mut |z, phi, t| {
                k += 1;
                if let Some(cell) = finite
                    && cell.borrow().is_none()
                    && let Some((sample, what)) = self.non_finite(k, phi, t)
                {
                    *cell.borrow_mut() = Some((i, sample, what));
                }
                for (o, a) in acc.iter_mut().enumerate() {
                    let b = self.block_of_output[o];
                    let cols = &self.blocks[b].cols;
                    let (zv, pv) = (&mut zb[b], &mut pb[b]);
                    for (j, c) in cols.iter().enumerate() {
                        zv[j] = z[o * n + c];
                        pv[j] = phi[o * n + c];
                    }
                    let mut target = t[o];
                    for (c, v) in &self.held {
                        target -= phi[o * n + c] * v;
                    }
                    a.push(zv, pv, target);
                }
            })?;
            change = change.max(c.relative());
            fit += c.fit() / experiments.len() as f64;
            all.push(acc);
        }
        Ok((all, change, fit))
    }

    /// The centre of output `o`'s instruments in experiment `i`: their mean
    /// there (per experiment), over all experiments (pooled; a constant
    /// column's instrument stays uncentred, it is the intercept), or zero.
    fn centre(&self, moments: &[Vec<CrossMoments>], i: usize, o: usize) -> DVector<f64> {
        let m = self.blocks[self.block_of_output[o]].cols.len();
        match self.centring {
            Centring::Experiment => moments[i][o].mean_z(),
            Centring::None => DVector::zeros(m),
            Centring::Pooled => {
                let total: usize = moments.iter().map(|e| e[o].n).sum();
                let mut pooled = moments
                    .iter()
                    .fold(DVector::zeros(m), |s, e| s + e[o].mean_z() * e[o].n as f64)
                    / total.max(1) as f64;
                for (j, c) in self.blocks[self.block_of_output[o]].cols.iter().enumerate() {
                    if self.constant_cols[*c] {
                        pooled[j] = 0.0;
                    }
                }
                pooled
            }
        }
    }

    /// Moment equations `(H_i, g_i)` of experiment `i`, block `b` (sums, not
    /// means), and for each column the scale `Σ_o ‖z̃_o‖·‖φ_o,j‖` that bounds
    /// its moments (Cauchy–Schwarz): a column far below it is rounding residue.
    fn equations(
        &self,
        moments: &[Vec<CrossMoments>],
        i: usize,
        b: usize,
    ) -> (DMatrix<f64>, DVector<f64>, Vec<f64>) {
        let block = &self.blocks[b];
        let m = block.cols.len();
        let mut h = DMatrix::zeros(m, m);
        let mut g = DVector::zeros(m);
        let mut bound = vec![0.0; m];
        for &o in &block.outputs {
            let acc = &moments[i][o];
            let c = self.centre(moments, i, o);
            let (ho, go) = match self.centring {
                Centring::Experiment => acc.centred(),
                _ => acc.about(&c),
            };
            let zn = acc.z_energy(&c).sqrt();
            for (bj, pe) in bound.iter_mut().zip(acc.phi_energy()) {
                *bj += zn * pe.sqrt();
            }
            h += ho;
            g += go;
        }
        (h, g, bound)
    }

    /// Solves every block; collects numeric rank findings.
    fn solve(
        &mut self,
        moments: &[Vec<CrossMoments>],
        record: bool,
    ) -> Result<Vec<BlockSolution>, EstimateError> {
        let mut out = Vec::with_capacity(self.blocks.len());
        let mut errors = Vec::new();
        for b in 0..self.blocks.len() {
            let cols = self.blocks[b].cols.clone();
            let m = cols.len();
            let e_count = moments.len();
            // The summed system (Σ H_i) ϑ = Σ g_i (IV by default, and LS's
            // normal equations), or the stacked one [H_i/n_i] ϑ = [g_i/n_i].
            let summed = self.options.method == Method::Ls || self.combine() == Combine::Summed;
            let (mut mat, rhs, scale_rows, bound): (
                DMatrix<f64>,
                DVector<f64>,
                Vec<f64>,
                Vec<f64>,
            ) = if summed {
                let mut a = DMatrix::zeros(m, m);
                let mut g = DVector::zeros(m);
                let mut bound = vec![0.0; m];
                for i in 0..e_count {
                    let (h, gi, bi) = self.equations(moments, i, b);
                    a += h;
                    g += gi;
                    for (s, v) in bound.iter_mut().zip(bi) {
                        *s += v;
                    }
                }
                if self.options.method == Method::Ls {
                    (a, g, vec![1.0; e_count], bound)
                } else {
                    // Divided by the total count, the summed system of one
                    // experiment is the stacked one bit for bit.
                    let total: usize = moments.iter().map(|e| e[self.blocks[b].outputs[0]].n).sum();
                    let n = total.max(1) as f64;
                    for v in &mut bound {
                        *v /= n;
                    }
                    (a / n, g / n, vec![1.0 / n; e_count], bound)
                }
            } else {
                let mut a = DMatrix::zeros(m * e_count, m);
                let mut g = DVector::zeros(m * e_count);
                let mut scales = Vec::new();
                let mut bound = vec![0.0; m];
                for i in 0..e_count {
                    let (h, gi, bi) = self.equations(moments, i, b);
                    let n = moments[i][self.blocks[b].outputs[0]].n.max(1) as f64;
                    a.view_mut((i * m, 0), (m, m)).copy_from(&(h / n));
                    g.rows_mut(i * m, m).copy_from(&(gi / n));
                    scales.push(1.0 / n);
                    for (s, v) in bound.iter_mut().zip(bi) {
                        *s += v / n;
                    }
                }
                (a, g, scales, bound)
            };
            // Scale-aware residue test over the whole system: a column whose
            // moments are at the rounding level of its own scale carries no
            // information, whatever the units (equilibration would otherwise
            // blow the residue up into a column).
            let equations: usize = moments.iter().map(|e| e[self.blocks[b].outputs[0]].n).sum();
            let residue = RESIDUE_EPSILONS * f64::EPSILON * (equations.max(1) as f64);
            for (j, bj) in bound.iter().enumerate() {
                if mat.column(j).norm() <= residue * bj {
                    mat.column_mut(j).fill(0.0);
                }
            }
            // Rows equilibrated too (each instrument's equation to unit norm):
            // an instrument in large units must not drown the others, so the
            // rank decision and the conditioning do not depend on the units.
            // One scale per instrument, the same in every experiment's rows
            // (stacked), so the experiments keep their relative weights.
            let instrument_norm: Vec<f64> = (0..m)
                .map(|r| {
                    (0..mat.nrows() / m)
                        .map(|i| mat.row(i * m + r).norm_squared())
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            let row_scale: Vec<f64> = (0..mat.nrows())
                .map(|r| {
                    let norm = instrument_norm[r % m];
                    if norm > 0.0 && norm.is_finite() {
                        1.0 / norm
                    } else {
                        1.0
                    }
                })
                .collect();
            let mut scaled = mat.clone();
            for (r, d) in row_scale.iter().enumerate() {
                scaled.row_mut(r).scale_mut(*d);
            }
            let mut order: Vec<usize> = (0..m).collect();
            order.sort_by_key(|j| self.preference[cols[*j]]);
            let sel = select_columns(&scaled, &order, self.options.rank_tolerance);
            // The square summed system is solved equilibrated (its solution
            // does not depend on row scaling); the stacked one as the paper
            // writes it, by unweighted least squares over the rows.
            let (mat, rhs, row_scale) = if summed {
                let mut rhs = rhs;
                for (r, d) in row_scale.iter().enumerate() {
                    rhs[r] *= d;
                }
                (scaled.clone(), rhs, row_scale)
            } else {
                (mat, rhs, vec![1.0; row_scale.len()])
            };
            let mut held = Vec::new();
            for (j, combo) in &sel.dropped {
                let c = cols[*j];
                let col = &self.ir.predictors.get(self.kind)[c];
                let text = if combo.is_empty() {
                    format!(
                        "{} is not excited by these data (its moments vanish)",
                        col.name
                    )
                } else {
                    let mut items: Vec<(String, Q)> = vec![];
                    for (k, a) in combo {
                        items.push((
                            self.ir.predictors.get(self.kind)[cols[*k]].name.clone(),
                            Q::from_float(round_sig(*a)).unwrap_or_default(),
                        ));
                    }
                    format!(
                        "{} is not separately excited: its column equals {}",
                        col.name,
                        linear_text_f(&items)
                    )
                };
                match col.kind {
                    ColumnKind::Theta { parameter } => {
                        let p = &self.ir.parameters[parameter];
                        let value = self.nominal[parameter];
                        if p.measured && self.kind == PredictorKind::Measured {
                            if record {
                                self.warnings.push(format!(
                                    "{text}: the measured {} enters the instruments as its experiment mean, and with these data the instrument of `{}` is a combination of the others (its regressor differs from theirs only through the {}'s fluctuations, or it has no modulus whose sign changes); `{}` is not separately excited by these data, so it is held at its nominal value {} and the parameters it is combined with estimate the aggregates",
                                    self.ir.disturbances[p.medium.unwrap_or(0)].name,
                                    p.name,
                                    self.ir.disturbances[p.medium.unwrap_or(0)].name,
                                    p.name,
                                    value
                                ));
                                self.unexcited.push(text.clone());
                                for (k, a) in combo {
                                    let kept = &self.ir.predictors.get(self.kind)[cols[*k]].name;
                                    let held = if value == 0.0 {
                                        p.name.clone()
                                    } else {
                                        format!("({} - {value})", p.name)
                                    };
                                    let coef = round_sig(*a);
                                    self.aggregates.push(format!(
                                        "{kept} estimates {kept} {} {}*{held}",
                                        if coef < 0.0 { "-" } else { "+" },
                                        coef.abs()
                                    ));
                                }
                            }
                            held.push((c, value));
                        } else if self.options.aggregate {
                            if record {
                                self.warnings.push(format!(
                                    "{text}; held at its nominal value {value} (--aggregate)"
                                ));
                                self.unexcited.push(text.clone());
                            }
                            held.push((c, value));
                        } else {
                            errors.push(text);
                        }
                    }
                    _ => {
                        if record {
                            self.unexcited.push(format!("{text} (nuisance; held at 0)"));
                        }
                        held.push((c, 0.0));
                    }
                }
            }
            let kept: Vec<usize> = sel.kept.iter().map(|j| cols[*j]).collect();
            // Right-hand side without the held columns' contribution.
            let mut g = rhs.clone();
            for (c, v) in &held {
                if let Some(j) = cols.iter().position(|x| x == c) {
                    g -= mat.column(j) * *v;
                }
            }
            let kj: Vec<usize> = sel.kept.clone();
            let mk = DMatrix::from_fn(mat.nrows(), kj.len(), |r, k| mat[(r, kj[k])]);
            let (values, mut pinv, condition) = solve_equilibrated(&mk, &g);
            // The map from the unscaled moment sums to ϑ includes the row scaling.
            for (c, d) in row_scale.iter().enumerate() {
                pinv.column_mut(c).scale_mut(*d);
            }
            // Conditioning judged on the equilibrated system, whatever the units.
            let condition = if summed {
                condition
            } else {
                let ks = DMatrix::from_fn(scaled.nrows(), kj.len(), |r, k| scaled[(r, kj[k])]);
                solve_equilibrated(&ks, &DVector::zeros(scaled.nrows())).2
            };
            let weak = if condition > CONDITION_WARNING {
                let ks = DMatrix::from_fn(scaled.nrows(), kj.len(), |r, k| scaled[(r, kj[k])]);
                weakest_direction(&ks)
                    .into_iter()
                    .map(|k| kept[k])
                    .collect()
            } else {
                Vec::new()
            };
            // B_i: ϑ_K = pinv · g, with g's experiment-i rows = (Σ_k ζ_k)·scale_i.
            let b_list = if self.options.method == Method::Ls {
                // ϑ = A⁻¹ Σ ζ restricted to the kept rows.
                let rows_idx = kj.clone();
                let sub = DMatrix::from_fn(kj.len(), rows_idx.len(), |r, k| pinv[(r, rows_idx[k])]);
                vec![sub; e_count]
            } else if summed {
                (0..e_count).map(|i| &pinv * scale_rows[i]).collect()
            } else {
                (0..e_count)
                    .map(|i| pinv.columns(i * m, m) * scale_rows[i])
                    .collect()
            };
            let rows = if self.options.method == Method::Ls {
                kept.clone()
            } else {
                cols.clone()
            };
            out.push(BlockSolution {
                kept,
                held,
                values: values.iter().copied().collect(),
                b: b_list,
                rows,
                condition,
                weak,
            });
        }
        if !errors.is_empty() {
            let remark2 = self
                .infos
                .iter()
                .any(|i| i.spread < 4.0 * self.options.heading_spread);
            return Err(err(
                "rank-deficient",
                format!(
                    "the data did not excite every parameter: {}",
                    errors.join("; ")
                ),
                if remark2 {
                    "the heading barely varied, which leaves the disturbance terms collinear with the others (paper Remark 2): turn the craft during the experiment; or estimate the identifiable combinations with --aggregate".to_string()
                } else {
                    "excite the named terms (richer input, experiments with other sign patterns), or estimate the identifiable combinations with --aggregate".to_string()
                },
            ));
        }
        Ok(out)
    }

    /// θ from block solutions (held parameters at nominal).
    fn theta_of(&self, sol: &[BlockSolution]) -> Vec<f64> {
        let mut theta = self.nominal.clone();
        let cols = self.ir.predictors.get(self.kind);
        for (c, v) in self.all_values(sol) {
            if let ColumnKind::Theta { parameter } = cols[c].kind {
                theta[parameter] = v;
            }
        }
        theta
    }

    fn all_values(&self, sol: &[BlockSolution]) -> Vec<(usize, f64)> {
        let mut v: Vec<(usize, f64)> = self.held.clone();
        for s in sol {
            v.extend(s.kept.iter().copied().zip(s.values.iter().copied()));
            v.extend(s.held.iter().copied());
        }
        v.sort_by_key(|(c, _)| *c);
        v
    }

    /// Unmeasured disturbance means from ρ̂ and θ̂ (paper Corollary 1), with
    /// standard errors by the delta method when a covariance is given.
    fn disturbance_means(
        &self,
        values: &BTreeMap<usize, f64>,
        theta: &[f64],
        cov: Option<&BTreeMap<(usize, usize), f64>>,
    ) -> Vec<DisturbanceMoment> {
        let cols = self.ir.predictors.get(self.kind);
        let unmeasured: Vec<usize> = (0..self.ir.components.len())
            .filter(|c| {
                let d = &self.ir.disturbances[self.ir.components[*c].disturbance];
                !d.measured || self.kind == PredictorKind::Augmented
            })
            .collect();
        if unmeasured.is_empty() || self.kind == PredictorKind::Basic {
            return Vec::new();
        }
        // Equations: value_k = Σ_{(d, q) ∈ meaning_k} q · μ_comp(d) · θ_param(d), for kept ρ-only columns.
        let mut eqs: Vec<MomentEquation> = Vec::new();
        for (k, items) in &self.meaning {
            if !values.contains_key(k) {
                continue;
            }
            let mut terms = Vec::new();
            let mut ok = true;
            for (d, q) in items {
                match cols[*d].kind {
                    ColumnKind::Rho {
                        component,
                        parameter,
                    } => terms.push((component, parameter, *q)),
                    _ => ok = false,
                }
            }
            if ok && !terms.is_empty() {
                eqs.push((*k, terms));
            }
        }
        if eqs.is_empty() {
            return Vec::new();
        }
        let solve_mu = |vals: &BTreeMap<usize, f64>, th: &[f64]| -> Option<Vec<f64>> {
            let a = DMatrix::from_fn(eqs.len(), unmeasured.len(), |r, j| {
                eqs[r]
                    .1
                    .iter()
                    .filter(|(c, _, _)| *c == unmeasured[j])
                    .map(|(_, p, q)| q * th[*p])
                    .sum()
            });
            let y = DVector::from_iterator(
                eqs.len(),
                eqs.iter().map(|(k, _)| vals.get(k).copied().unwrap_or(0.0)),
            );
            let svd = a.svd(true, true);
            let smax = svd.singular_values.max();
            if svd.singular_values.min() <= 1e-10 * smax || smax == 0.0 {
                return None;
            }
            svd.solve(&y, 0.0).ok().map(|v| v.iter().copied().collect())
        };
        let Some(mu) = solve_mu(values, theta) else {
            return Vec::new();
        };
        // Delta method over the estimated θ and ρ columns involved.
        let mut se = vec![None; unmeasured.len()];
        if let Some(cov) = cov {
            let mut vars: Vec<usize> = eqs.iter().map(|(k, _)| *k).collect();
            for (c, col) in cols.iter().enumerate() {
                if matches!(col.kind, ColumnKind::Theta { .. }) && cov.contains_key(&(c, c)) {
                    vars.push(c);
                }
            }
            vars.sort_unstable();
            vars.dedup();
            let mut jac = DMatrix::zeros(unmeasured.len(), vars.len());
            let mut ok = true;
            for (vi, &c) in vars.iter().enumerate() {
                let base = values.get(&c).copied().unwrap_or(0.0);
                let step = 1e-6 * base.abs().max(1e-8);
                let mut plus = values.clone();
                let mut minus = values.clone();
                plus.insert(c, base + step);
                minus.insert(c, base - step);
                let (mut tp, mut tm) = (theta.to_vec(), theta.to_vec());
                if let ColumnKind::Theta { parameter } = cols[c].kind {
                    tp[parameter] = base + step;
                    tm[parameter] = base - step;
                }
                match (solve_mu(&plus, &tp), solve_mu(&minus, &tm)) {
                    (Some(a), Some(b)) => {
                        for j in 0..unmeasured.len() {
                            jac[(j, vi)] = (a[j] - b[j]) / (2.0 * step);
                        }
                    }
                    _ => ok = false,
                }
            }
            if ok {
                let cm = DMatrix::from_fn(vars.len(), vars.len(), |a, b| {
                    cov.get(&(vars[a], vars[b])).copied().unwrap_or(0.0)
                });
                let cmu = &jac * cm * jac.transpose();
                for j in 0..unmeasured.len() {
                    se[j] = Some(cmu[(j, j)].max(0.0).sqrt());
                }
            }
        }
        unmeasured
            .iter()
            .enumerate()
            .map(|(j, c)| {
                let comp = &self.ir.components[*c];
                DisturbanceMoment {
                    disturbance: self.ir.disturbances[comp.disturbance].name.clone(),
                    component: comp.name.clone(),
                    mean: mu[j],
                    std_error: se[j],
                }
            })
            .collect()
    }

    fn run(
        &mut self,
        experiments: &[&dyn Source],
        sign_patterns: Vec<ExperimentSigns>,
    ) -> Result<Estimate, EstimateError> {
        let n_comp = self.ir.components.len();
        let mut theta_sim = self.nominal.clone();
        let mut mu = vec![0.0; n_comp];
        let refine =
            self.options.method != Method::Ls && self.options.instruments == Instruments::Simulated;
        let mut refinements = 0usize;
        let mut converged = !refine;
        let mut stopped = false;
        let bootstrap = refine && self.options.initial == Initial::Delayed;
        let first: Vec<f64> = if bootstrap {
            Vec::new()
        } else {
            theta_sim.clone()
        };
        let bad = std::cell::RefCell::new(None);
        let first_pass = self.accumulate(experiments, &first, &mu, None, Some(&bad));
        if let Some((i, sample, what)) = bad.into_inner() {
            return Err(self.non_finite_error(experiments[i], sample, &what));
        }
        let moments = match first_pass {
            Ok((m, _, _)) => m,
            Err(Diverged) => {
                // The simulation stopped the pass early: a bad value further
                // on is still a data error, not a divergence.
                let walker = self.walker_with(None);
                for (e, info) in experiments.iter().zip(&self.infos) {
                    let mut k = 1usize;
                    let mut found = None;
                    let _ = walker.walk(*e, info, &[], &[], None, &mut |_, phi, t| {
                        k += 1;
                        if found.is_none() {
                            found = self.non_finite(k, phi, t);
                        }
                    });
                    if let Some((sample, what)) = found {
                        return Err(self.non_finite_error(*e, sample, &what));
                    }
                }
                return Err(err(
                    "nominal-diverges",
                    "the simulation of the nominal model diverges on the input of these experiments",
                    "give nominal values closer to the craft (nominal { } in the model, or --nominal FILE)",
                ));
            }
        };
        let sol = self.solve(&moments, !refine)?;
        // The current iterate: its estimate, the simulation that produced its
        // instruments, and (once simulated itself) how well it tracks the data.
        let mut cur = Iterate {
            theta: self.theta_of(&sol),
            sol,
            theta_sim: first,
            mu: mu.clone(),
            moments,
            fit: None,
        };
        let mut best: Option<Iterate> = None;
        while refine && refinements < self.options.max_refinements {
            // Re-simulate with the estimate (and the disturbance means it implies),
            // damping towards the previous simulation if it diverges. The new
            // simulation is compared with the previous one in the same pass:
            // once the instruments stop moving, so does the estimate.
            let values: BTreeMap<usize, f64> = self.all_values(&cur.sol).into_iter().collect();
            let new_mu = self.mean_vector(&values, &cur.theta);
            let mut step = 1.0;
            let mut accepted = None;
            for _ in 0..6 {
                let trial: Vec<f64> = theta_sim
                    .iter()
                    .zip(&cur.theta)
                    .map(|(a, b)| a + step * (b - a))
                    .collect();
                let trial_mu: Vec<f64> = mu
                    .iter()
                    .zip(&new_mu)
                    .map(|(a, b)| a + step * (b - a))
                    .collect();
                if let Ok(r) = self.accumulate(
                    experiments,
                    &trial,
                    &trial_mu,
                    Some((&theta_sim, &mu)),
                    None,
                ) {
                    accepted = Some((trial, trial_mu, r));
                    break;
                }
                step *= 0.5;
            }
            let Some((trial, trial_mu, (m, change, fit))) = accepted else {
                self.warnings.push(format!(
                    "refinement stopped after {refinements}: the simulation with the refined estimate diverges even when damped; the iterate whose simulation fits the data best is reported"
                ));
                stopped = true;
                break;
            };
            if step < 1.0 {
                self.warnings.push(format!(
                    "refinement {} damped by {step} (the simulation with the full step diverged)",
                    refinements + 1
                ));
            } else {
                cur.fit = Some(fit);
                if best
                    .as_ref()
                    .is_none_or(|b| b.fit.unwrap_or(f64::NEG_INFINITY) < fit)
                {
                    best = Some(cur.clone());
                }
            }
            theta_sim = trial.clone();
            mu = trial_mu.clone();
            refinements += 1;
            let sol = self.solve(&m, false)?;
            let next = Iterate {
                theta: self.theta_of(&sol),
                sol,
                theta_sim: trial,
                mu: trial_mu,
                moments: m,
                fit: None,
            };
            if std::env::var("LEEWAY_DEBUG").is_ok() {
                eprintln!("refinement {refinements}: change {change:.3e} simulation fit {fit:.1}");
            }
            if change < self.options.tolerance {
                converged = true;
                cur = next;
                break;
            }
            // A refinement whose simulation tracks the data markedly worse than
            // an earlier iterate is running away (small samples): stop there.
            if let (true, Some(b), Some(f)) = (self.options.runaway_guard, &best, cur.fit)
                && b.fit.unwrap_or(f) - f > RUNAWAY_FIT_DROP
            {
                self.warnings.push(format!(
                    "refinement stopped after {refinements}: the simulation of the refined estimate tracks the data {:.1} fit points worse than an earlier iterate (small-sample runaway); the best iterate is reported",
                    b.fit.unwrap_or(f) - f
                ));
                cur = next;
                stopped = true;
                break;
            }
            cur = next;
        }
        if refine && !converged {
            // Report the iterate whose own simulation tracks the data best.
            if let (true, Some(b)) = (self.options.runaway_guard, best)
                && cur.fit.is_none_or(|f| f < b.fit.unwrap_or(f))
            {
                cur = b;
            }
            if !stopped {
                self.warnings.push(format!(
                    "the refined IV did not settle within {} refinements (instrument simulation still moving more than {} of its variation); the iterate whose simulation fits the data best is reported",
                    refinements, self.options.tolerance
                ));
            }
        }
        let theta_sim = cur.theta_sim.clone();
        let mu = cur.mu.clone();
        let moments = cur.moments;
        // Record the numeric findings of the reported solve.
        let sol = if refine {
            self.solve(&moments, true)?
        } else {
            cur.sol
        };
        let theta = self.theta_of(&sol);
        let columns = self.ir.predictors.get(self.kind);
        if !sol
            .iter()
            .flat_map(|s| &s.kept)
            .any(|c| !columns[*c].kind.is_nuisance())
        {
            return Err(err(
                "rank-deficient",
                "no physical parameter could be estimated from these data: every θ column is unexcited or held",
                "record experiments that excite the craft (varying inputs, turning), or check the data columns",
            ));
        }
        let values: BTreeMap<usize, f64> = self.all_values(&sol).into_iter().collect();
        let cov = if self.options.covariance {
            self.covariance(experiments, &moments, &sol, &theta_sim, &mu)
        } else {
            None
        };
        self.finish(
            sign_patterns,
            &sol,
            values,
            theta,
            cov,
            refinements,
            converged,
            experiments,
        )
    }

    fn mean_vector(&self, values: &BTreeMap<usize, f64>, theta: &[f64]) -> Vec<f64> {
        let mut mu = vec![0.0; self.ir.components.len()];
        for m in self.disturbance_means(values, theta, None) {
            if let Some(c) = self
                .ir
                .components
                .iter()
                .position(|c| c.name == m.component)
            {
                mu[c] = m.mean;
            }
        }
        mu
    }

    /// The sandwich covariance of the estimated columns: `Σ_i B_i G_i B_iᵀ`,
    /// `G_i` the long-run sum of `ζ_k = Σ_o z̃_o (ε_o − ε̄_o)` truncated at `lags`.
    fn covariance(
        &self,
        experiments: &[&dyn Source],
        moments: &[Vec<CrossMoments>],
        sol: &[BlockSolution],
        theta_sim: &[f64],
        mu: &[f64],
    ) -> Option<BTreeMap<(usize, usize), f64>> {
        // The instruments of the reported iterate (empty θ: the delayed bootstrap).
        let walker = if theta_sim.is_empty() && self.options.method != Method::Ls {
            self.walker_with(Some(Instruments::Delayed))
        } else {
            self.walker()
        };
        let n = self.n_cols;
        let values: BTreeMap<usize, f64> = self.all_values(sol).into_iter().collect();
        // ζ rows: the instrument rows of every block, concatenated.
        let mut offsets = Vec::new();
        let mut total = 0;
        for s in sol {
            offsets.push(total);
            total += s.rows.len();
        }
        // Dense values by column, and each ζ row's index within its block.
        let dense: Vec<f64> = (0..n)
            .map(|c| values.get(&c).copied().unwrap_or(0.0))
            .collect();
        let local: Vec<Vec<usize>> = sol
            .iter()
            .zip(&self.blocks)
            .map(|(s, b)| {
                s.rows
                    .iter()
                    .map(|c| b.cols.iter().position(|x| x == c).unwrap_or(0))
                    .collect()
            })
            .collect();
        let mut cov = DMatrix::zeros(
            sol.iter().map(|s| s.kept.len()).sum(),
            sol.iter().map(|s| s.kept.len()).sum(),
        );
        for (i, (e, info)) in experiments.iter().zip(&self.infos).enumerate() {
            // Centres and mean residuals per output.
            let centres: Vec<DVector<f64>> = (0..self.ir.states.len())
                .map(|o| self.centre(moments, i, o))
                .collect();
            let mean_res: Vec<f64> = (0..self.ir.states.len())
                .map(|o| {
                    let b = &self.blocks[self.block_of_output[o]];
                    let mp = moments[i][o].mean_phi();
                    moments[i][o].mean_t()
                        - b.cols
                            .iter()
                            .enumerate()
                            .map(|(j, c)| mp[j] * values.get(c).copied().unwrap_or(0.0))
                            .sum::<f64>()
                })
                .collect();
            let mut lr = LongRun::new(total, self.options.lags);
            let mut zeta = DVector::zeros(total);
            let ok = walker.walk(*e, info, theta_sim, mu, None, &mut |z, phi, t| {
                zeta.fill(0.0);
                for o in 0..self.ir.states.len() {
                    let bi = self.block_of_output[o];
                    let block = &self.blocks[bi];
                    let mut target = t[o];
                    for (c, v) in &self.held {
                        target -= phi[o * n + c] * v;
                    }
                    let mut res = target;
                    for c in &block.cols {
                        res -= phi[o * n + c] * dense[*c];
                    }
                    res -= mean_res[o];
                    let s = &sol[bi];
                    let source = if self.options.method == Method::Ls {
                        phi
                    } else {
                        z
                    };
                    for (r, (c, j)) in s.rows.iter().zip(&local[bi]).enumerate() {
                        zeta[offsets[bi] + r] += (source[o * n + c] - centres[o][*j]) * res;
                    }
                }
                lr.push(&zeta);
            });
            if ok.is_err() {
                return None;
            }
            let g = lr.sum_psd();
            // Assemble B_i (kept × rows) over blocks.
            let nk: usize = sol.iter().map(|s| s.kept.len()).sum();
            let mut b_all = DMatrix::zeros(nk, total);
            let mut row = 0;
            for (bi, s) in sol.iter().enumerate() {
                b_all
                    .view_mut((row, offsets[bi]), (s.kept.len(), s.rows.len()))
                    .copy_from(&s.b[i]);
                row += s.kept.len();
            }
            cov += &b_all * g * b_all.transpose();
        }
        let kept: Vec<usize> = sol.iter().flat_map(|s| s.kept.iter().copied()).collect();
        let mut out = BTreeMap::new();
        for (a, ca) in kept.iter().enumerate() {
            for (b, cb) in kept.iter().enumerate() {
                out.insert((*ca, *cb), cov[(a, b)]);
            }
        }
        Some(out)
    }

    #[allow(clippy::too_many_arguments)]
    fn finish(
        &mut self,
        sign_patterns: Vec<ExperimentSigns>,
        sol: &[BlockSolution],
        values: BTreeMap<usize, f64>,
        theta: Vec<f64>,
        cov: Option<BTreeMap<(usize, usize), f64>>,
        refinements: usize,
        converged: bool,
        experiments: &[&dyn Source],
    ) -> Result<Estimate, EstimateError> {
        let cols = self.ir.predictors.get(self.kind);
        let se = |c: usize| {
            cov.as_ref()
                .and_then(|m| m.get(&(c, c)))
                .map(|v| v.max(0.0).sqrt())
        };
        let estimated: Vec<usize> = sol.iter().flat_map(|s| s.kept.iter().copied()).collect();
        let numeric_held: BTreeMap<usize, f64> =
            sol.iter().flat_map(|s| s.held.iter().copied()).collect();
        let structural_held: BTreeMap<usize, f64> = self.held.iter().copied().collect();
        let names = leeway_structure::identify::Names {
            ir: self.ir,
            columns: cols,
            centring: self.centring,
        };
        let columns: Vec<ColumnEstimate> = cols
            .iter()
            .enumerate()
            .map(|(c, col)| {
                let kind = match col.kind {
                    ColumnKind::Theta { .. } => "theta",
                    ColumnKind::Rho { .. } => "rho",
                    ColumnKind::Lambda { .. } => "lambda",
                };
                let meaning = self.meaning.get(&c).map(|items| {
                    let q: Vec<(String, Q)> = items
                        .iter()
                        .map(|(d, v)| (names.moment(*d), Q::from_float(*v).unwrap_or_default()))
                        .collect();
                    linear_text(&q)
                });
                let (value, status) = if estimated.contains(&c) {
                    (values.get(&c).copied(), "estimated".to_string())
                } else if let Some(v) = structural_held.get(&c) {
                    (
                        Some(*v),
                        "held at nominal (not identifiable; aggregated)".to_string(),
                    )
                } else if let Some(v) = numeric_held.get(&c) {
                    (
                        Some(*v),
                        if col.kind.is_nuisance() {
                            "held at 0 (not excited)".to_string()
                        } else {
                            "held at nominal (not excited)".to_string()
                        },
                    )
                } else {
                    (
                        None,
                        "dropped (structurally dependent: absorbed by kept columns)".to_string(),
                    )
                };
                ColumnEstimate {
                    name: col.name.clone(),
                    kind,
                    value,
                    std_error: if estimated.contains(&c) { se(c) } else { None },
                    status,
                    estimates: meaning.unwrap_or_else(|| names.moment(c)),
                }
            })
            .collect();
        let theta_cols: Vec<Option<usize>> = (0..self.ir.parameters.len())
            .map(|p| {
                cols.iter()
                    .position(|c| c.kind == ColumnKind::Theta { parameter: p })
            })
            .collect();
        let std_errors = theta_cols
            .iter()
            .map(|c| c.filter(|c| estimated.contains(c)).and_then(se))
            .collect();
        let disturbances = if self.kind == PredictorKind::Basic {
            Vec::new()
        } else {
            self.disturbance_means(&values, &theta, cov.as_ref())
        };
        let condition = sol.iter().map(|s| s.condition).fold(0.0, f64::max);
        for s in sol.iter().filter(|s| s.condition > CONDITION_WARNING) {
            let weak: Vec<&str> = s.weak.iter().map(|c| cols[*c].name.as_str()).collect();
            self.warnings.push(format!(
                "the moment matrix is ill-conditioned (condition number {:.2e}): the weakest direction involves {}, whose estimates are unreliable (nearly collinear, or barely excited by these data)",
                s.condition,
                if weak.is_empty() { "several columns".to_string() } else { weak.join(", ") }
            ));
        }
        let structural_kept: usize = self.blocks.iter().map(|b| b.cols.len()).sum();
        let how = if self.options.centring.is_some() {
            "as asked"
        } else {
            "the default for this model"
        };
        let centring = match (self.options.method, self.centring) {
            (Method::Ls, Centring::Experiment) => format!(
                "experiment ({how}): an intercept per output and experiment — least squares keeps the constants that cos² = 1 − sin² and the disturbance means create; {}",
                self.centring.reason(self.ir, self.kind)
            ),
            (Method::Ls, Centring::Pooled) => format!(
                "pooled ({how}): one intercept per output over all experiments (the model's constant term where it has one); {}",
                self.centring.reason(self.ir, self.kind)
            ),
            (Method::Ls, Centring::None) => format!(
                "none ({how}): no intercept beyond the model's constant terms; {}",
                self.centring.reason(self.ir, self.kind)
            ),
            (_, c) => format!("{} ({how}): {}", c.name(), c.reason(self.ir, self.kind)),
        };
        let instruments = match (self.options.method, self.options.instruments) {
            (Method::Ls, _) => "none (least squares: the regressors themselves)".to_string(),
            (_, Instruments::Simulated) => format!(
                "simulated model ({}), refined with the estimate; rotation from the heading anchored to the previous measurement; measured disturbances as their experiment mean",
                match self.options.initial {
                    Initial::Nominal => "first simulation: the nominal model",
                    Initial::Delayed =>
                        "first simulation: an estimate with delayed-measurement instruments",
                }
            ),
            (_, Instruments::Delayed) => {
                "regressors of the measurements one sample earlier".to_string()
            }
        };
        let equations = experiments.iter().map(|e| e.len().saturating_sub(2)).sum();
        Ok(Estimate {
            method: self.options.method,
            parameters: self.ir.parameters.iter().map(|p| p.name.clone()).collect(),
            theta,
            std_errors,
            columns,
            disturbances,
            sign_patterns,
            diagnostics: Diagnostics {
                predictor: format!("{:?}", self.kind).to_lowercase(),
                experiments: experiments.len(),
                equations,
                columns: cols.len(),
                estimated: estimated.len(),
                rank: estimated.len().min(structural_kept),
                condition_number: condition,
                refinements,
                converged,
                instruments,
                centring,
                combine: if self.options.method == Method::Ls {
                    "summed (least squares: the normal equations of all experiments)".to_string()
                } else {
                    self.combine().name().to_string()
                },
                lags: self.options.lags,
                unexcited: self.unexcited.clone(),
                aggregates: self.aggregates.clone(),
            },
            warnings: self.warnings.clone(),
            notes: Vec::new(),
        })
    }
}

/// Significant digits for messages.
fn round_sig(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    format!("{v:.2e}").parse().unwrap_or(v)
}

fn linear_text_f(items: &[(String, Q)]) -> String {
    let mut out = String::new();
    for (i, (name, q)) in items.iter().enumerate() {
        let v = leeway_structure::exact::to_f64(q);
        if i == 0 {
            out.push_str(&format!("{v}*{name}"));
        } else {
            out.push_str(&format!(
                " {} {}*{name}",
                if v < 0.0 { "-" } else { "+" },
                v.abs()
            ));
        }
    }
    out
}

/// Greedy column selection in preference order on the column-equilibrated
/// matrix (modified Gram–Schmidt, reorthogonalised): a column is kept when
/// its residual against the kept ones exceeds `tol` relative to its norm.
pub(crate) struct Selection {
    pub(crate) kept: Vec<usize>,
    /// Dropped column with its combination of kept columns (original units).
    pub(crate) dropped: Vec<(usize, Vec<(usize, f64)>)>,
}

pub(crate) fn select_columns(m: &DMatrix<f64>, order: &[usize], tol: f64) -> Selection {
    let rows = m.nrows();
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut kept = Vec::new();
    let mut dropped_idx = Vec::new();
    for &j in order {
        let col = m.column(j).into_owned();
        let norm = col.norm();
        if norm == 0.0 || !norm.is_finite() {
            dropped_idx.push(j);
            continue;
        }
        let mut v = col / norm;
        for _ in 0..2 {
            for q in &basis {
                let d = q.dot(&v);
                v.axpy(-d, q, 1.0);
            }
        }
        let r = v.norm();
        if r > tol.max(1e-300) && basis.len() < rows {
            basis.push(v / r);
            kept.push(j);
        } else {
            dropped_idx.push(j);
        }
    }
    kept.sort_unstable();
    let mk = DMatrix::from_fn(rows, kept.len(), |r, k| m[(r, kept[k])]);
    let dropped = dropped_idx
        .into_iter()
        .map(|j| {
            if kept.is_empty() || m.column(j).norm() == 0.0 {
                return (j, Vec::new());
            }
            let (alpha, _, _) = solve_equilibrated(&mk, &m.column(j).into_owned());
            let scale = m.column(j).norm();
            let combo = kept
                .iter()
                .zip(alpha.iter())
                .filter(|(k, a)| (**a * m.column(**k).norm()).abs() > 1e-3 * scale)
                .map(|(k, a)| (*k, *a))
                .collect();
            (j, combo)
        })
        .collect();
    Selection { kept, dropped }
}

/// The columns (indices into `m`) that dominate the right singular vector
/// of the smallest singular value of the column-equilibrated `m`.
fn weakest_direction(m: &DMatrix<f64>) -> Vec<usize> {
    let cols = m.ncols();
    if cols == 0 || m.nrows() == 0 {
        return Vec::new();
    }
    let d: Vec<f64> = (0..cols)
        .map(|j| m.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    let scaled = DMatrix::from_fn(m.nrows(), cols, |r, c| m[(r, c)] / d[c]);
    let svd = scaled.svd(false, true);
    let Some(vt) = svd.v_t else {
        return Vec::new();
    };
    let (weakest, _) = svd.singular_values.argmin();
    let v = vt.row(weakest);
    let top = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    (0..cols).filter(|j| v[*j].abs() >= 0.3 * top).collect()
}

/// Least-squares solution of `M x = g` with column equilibration; returns
/// `x`, the pseudo-inverse mapping `g ↦ x`, and the condition number.
pub(crate) fn solve_equilibrated(
    m: &DMatrix<f64>,
    g: &DVector<f64>,
) -> (DVector<f64>, DMatrix<f64>, f64) {
    let cols = m.ncols();
    if cols == 0 || m.nrows() == 0 {
        return (DVector::zeros(0), DMatrix::zeros(0, m.nrows()), 1.0);
    }
    let d: Vec<f64> = (0..cols)
        .map(|j| m.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    let scaled = DMatrix::from_fn(m.nrows(), cols, |r, c| m[(r, c)] / d[c]);
    let svd = scaled.svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    let condition = if smin > 0.0 {
        smax / smin
    } else {
        f64::INFINITY
    };
    let pinv = svd
        .pseudo_inverse(0.0)
        .unwrap_or_else(|_| DMatrix::zeros(cols, m.nrows()));
    let pinv = DMatrix::from_fn(cols, m.nrows(), |r, c| pinv[(r, c)] / d[r]);
    let x = &pinv * g;
    (x, pinv, condition)
}
