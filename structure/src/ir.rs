//! The model-structure IR: plain data, enough both to emit Rust code and to
//! evaluate regressors at run time, and to re-run the exact identifiability
//! analysis for the sign patterns found in data.
//!
//! Per predictor (basic, augmented, measured) the IR holds a list of
//! columns, each with its evaluation entries and the structural polynomials
//! from which the estimator re-runs the exact analysis.
//!
//! Evaluation order is part of the contract: generated code and the run-time
//! interpreter evaluate every column as described on [`Entry`], so they agree
//! bit for bit.

use leeway_grammar::{EquationKind, Span};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A compiled model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ir {
    /// `model Name`.
    pub name: String,
    /// The declared sample time `h` of `der` equations (else read from data).
    pub step: Option<f64>,
    /// Measured states, in declaration order (the outputs, one equation each).
    pub states: Vec<String>,
    /// Exact inputs.
    pub inputs: Vec<String>,
    /// How `R` is obtained.
    pub rotation: Rotation,
    /// Names of the rotation variables: `cos(psi)`, `sin(psi)` for a planar
    /// heading, the data columns of a measured rotation.
    pub rotation_vars: Vec<String>,
    /// Disturbances (media).
    pub disturbances: Vec<Disturbance>,
    /// All disturbance components, flattened; indices are global.
    pub components: Vec<Component>,
    /// Named relative velocities.
    pub relatives: Vec<Relative>,
    /// One equation per state, in state order.
    pub equations: Vec<Equation>,
    /// θ: every parameter, in order of first appearance.
    pub parameters: Vec<Parameter>,
    /// The model's terms `coefficient · parameter · factors`, as written.
    pub terms: Vec<Term>,
    /// Arguments under a modulus that need a fixed sign within an experiment.
    pub sign_args: Vec<SignArg>,
    /// The regressor columns of each predictor.
    pub predictors: Predictors,
    /// Data column for each signal whose column name differs (`data { }`).
    pub data_columns: BTreeMap<String, String>,
    /// The unit each signal's column is logged in, as written (`data { r in
    /// deg/s }`; see [`crate::units`]); values are converted to the base unit
    /// on load. Absent from older IR, and left out when empty so that models
    /// without units embed the same JSON as before.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub data_units: BTreeMap<String, String>,
    /// The declared dead times of inputs (`delay tau 10 steps`), at most one
    /// per input: the equation at sample k sees `tau(k − d)`. Absent from
    /// older IR, and left out when empty so that models without a dead time
    /// embed the same JSON as before.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub delays: Vec<Delay>,
    /// The identifiability report computed at compile time.
    pub report: Report,
}

/// The longest dead time, in samples: a record then starts its equations
/// that many samples late, and a longer one is a typing slip (a dead time
/// in samples where seconds were meant).
pub const MAX_DELAY_SAMPLES: usize = 100_000;

/// The relative tolerance within which a dead time in seconds must be a
/// whole number of sample times.
pub const DELAY_TOLERANCE: f64 = 1e-9;

/// The dead time of one input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Delay {
    /// The input (index into [`Ir::inputs`]).
    pub input: usize,
    /// How long.
    pub lag: Lag,
}

/// A dead time, in samples or (when the model declares no `step`) in
/// seconds, to be resolved against each record's sample time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Lag {
    /// Whole samples.
    Samples(usize),
    /// Seconds, a whole number of the record's sample times.
    Seconds(f64),
}

/// Why a dead time in seconds is no number of samples at a sample time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LagProblem {
    /// `seconds / h` is not within [`DELAY_TOLERANCE`] of a whole number.
    NotWhole {
        /// `seconds / h`.
        ratio: f64,
    },
    /// More than [`MAX_DELAY_SAMPLES`] samples.
    TooLong {
        /// `seconds / h`, rounded.
        samples: f64,
    },
}

impl Lag {
    /// The samples of this dead time at the sample time `h`.
    pub fn samples(self, h: f64) -> Result<usize, LagProblem> {
        match self {
            Lag::Samples(n) => Ok(n),
            Lag::Seconds(s) => samples_in(s, h),
        }
    }
}

/// `seconds` as a whole number of sample times `h` (within
/// [`DELAY_TOLERANCE`] relative), at most [`MAX_DELAY_SAMPLES`]: the one rule
/// the compiler (with `step`) and the loading of records (without) apply.
pub fn samples_in(seconds: f64, h: f64) -> Result<usize, LagProblem> {
    let ratio = seconds / h;
    if !ratio.is_finite() || ratio < 0.0 {
        return Err(LagProblem::NotWhole { ratio });
    }
    let n = ratio.round();
    if (ratio - n).abs() > DELAY_TOLERANCE * n.max(1.0) {
        return Err(LagProblem::NotWhole { ratio });
    }
    if n > MAX_DELAY_SAMPLES as f64 {
        return Err(LagProblem::TooLong { samples: n });
    }
    Ok(n as usize)
}

impl Ir {
    /// Each input's dead time in samples at the sample time `h` (0 where
    /// none is declared), or the first input whose dead time is no whole
    /// number of samples there.
    pub fn dead_times(&self, h: f64) -> Result<Vec<usize>, (String, LagProblem)> {
        let mut out = vec![0; self.inputs.len()];
        for d in &self.delays {
            let n = d
                .lag
                .samples(h)
                .map_err(|p| (self.inputs.get(d.input).cloned().unwrap_or_default(), p))?;
            if let Some(slot) = out.get_mut(d.input) {
                *slot = n;
            }
        }
        Ok(out)
    }
}

/// Where the rotation matrix `R` (body ← earth) comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Rotation {
    /// No earth-frame disturbance: no rotation.
    None,
    /// `R = Rz(ψ)ᵀ` acting on `axes`; `ψ` is measured and integrates a yaw rate.
    Planar {
        /// The heading signal (a data column).
        heading: String,
        /// The yaw-rate state it integrates.
        integrates: usize,
        /// The (surge, sway) states.
        axes: [usize; 2],
    },
    /// `R` read from data columns: `rows[state][component]` is a rotation
    /// variable index, or `None` for zero.
    Measured {
        /// One row per state.
        rows: Vec<Vec<Option<usize>>>,
    },
}

/// A disturbance (medium).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Disturbance {
    /// Its name, e.g. `current`.
    pub name: String,
    /// Measured (IV3's `y_aux`) or not.
    pub measured: bool,
    /// Earth frame (rotated by `R`) or body frame.
    pub earth: bool,
    /// Global indices of its components.
    pub components: Vec<usize>,
}

/// One component of a disturbance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Component {
    /// Its name (a data column when measured), e.g. `north`.
    pub name: String,
    /// The disturbance it belongs to.
    pub disturbance: usize,
    /// For a body-frame component, the state it acts on.
    pub state: Option<usize>,
}

/// `name = relative(disturbance)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Relative {
    /// E.g. `water`.
    pub name: String,
    /// The medium.
    pub disturbance: usize,
}

/// The equation of one state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Equation {
    /// The state (output) index.
    pub state: usize,
    /// `der` (x⁺ = x + h f) or `next` (x⁺ = f).
    pub kind: EquationKind,
}

/// A physical parameter (an entry of θ).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// As written in the model.
    pub name: String,
    /// From `nominal { }` (0 when unlisted).
    pub nominal: f64,
    /// The medium of its terms, if any (`None`: terms in states and inputs only).
    pub medium: Option<usize>,
    /// True when that medium is measured (IV3's `θ2`, regressors `Φ2`).
    pub measured: bool,
    /// The outputs it appears in.
    pub outputs: Vec<usize>,
}

/// A signal a factor is built from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Signal {
    /// A state.
    State(usize),
    /// An input.
    Input(usize),
}

/// An argument of a second-order modulus function: a signal, possibly relative
/// to a medium (`water.u` = `u − (R·v_current)_u`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Arg {
    /// The signal.
    pub signal: Signal,
    /// The relative velocity (index into [`Ir::relatives`]), for states.
    pub relative: Option<usize>,
}

/// `arg` or `|arg|`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Factor {
    /// The argument.
    pub arg: Arg,
    /// Under a modulus.
    pub modulus: bool,
}

/// One term of an equation: `coefficient · θ_parameter · Π factors`, with one
/// of the class's shapes `a`, `|a|`, `a·b`, `a·|b|`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Term {
    /// The output (state) whose equation holds the term.
    pub output: usize,
    /// The numeric coefficient, rounded once from the exact value.
    pub coefficient: f64,
    /// The exact coefficient, `p/q`.
    pub coefficient_exact: String,
    /// The parameter.
    pub parameter: usize,
    /// One or two factors; a modulus factor comes last.
    pub factors: Vec<Factor>,
    /// The term as the user's names write it, e.g. `water.u*|water.u|`.
    pub text: String,
    /// Where it was written.
    pub span: Span,
}

/// One disturbance share of a relative argument: the entry `R_l,pos` of the
/// rotation (or the identity of a body-frame component) that multiplies a
/// disturbance component `d` in `x_l − (R·v)_l`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Share {
    /// `rot[k] * d`.
    Rot(usize),
    /// `-(rot[k] * d)`.
    NegRot(usize),
    /// `d` (body frame).
    One,
}

impl Ir {
    /// The disturbance shares of an argument, in the evaluation order of
    /// [`Entry`]: the components of its medium in order, non-zero rotation
    /// entries only; empty for an input or a plain state. The argument's value
    /// is `x − ((p0 + p1) + …)` over these shares. Indices outside the IR are
    /// skipped, never a panic.
    pub fn arg_shares(&self, arg: &Arg) -> Vec<(Share, usize)> {
        let mut shares = Vec::new();
        let (Signal::State(l), Some(ri)) = (arg.signal, arg.relative) else {
            return shares;
        };
        let Some(d) = self
            .relatives
            .get(ri)
            .and_then(|r| self.disturbances.get(r.disturbance))
        else {
            return shares;
        };
        for (pos, &c) in d.components.iter().enumerate() {
            let share = if d.earth {
                match &self.rotation {
                    Rotation::Planar { axes, .. } => match (l == axes[0], l == axes[1], pos) {
                        (true, _, 0) => Some(Share::Rot(0)),
                        (true, _, 1) => Some(Share::Rot(1)),
                        (_, true, 0) => Some(Share::NegRot(1)),
                        (_, true, 1) => Some(Share::Rot(0)),
                        _ => None,
                    },
                    Rotation::Measured { rows } => rows
                        .get(l)
                        .and_then(|r| r.get(pos))
                        .copied()
                        .flatten()
                        .map(Share::Rot),
                    Rotation::None => None,
                }
            } else if self.components.get(c).is_some_and(|k| k.state == Some(l)) {
                Some(Share::One)
            } else {
                None
            };
            if let Some(s) = share {
                shares.push((s, c));
            }
        }
        shares
    }
}

/// An argument under a modulus whose sign is fixed within an experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignArg {
    /// `water.u`, `r`.
    pub name: String,
    /// The argument.
    pub arg: Arg,
    /// True when the argument is relative to a measured medium: IV3 evaluates
    /// it pointwise, IV2 (all media unmeasured) needs its sign fixed.
    pub measured: bool,
    /// True when the argument holds no disturbance at all (a plain state such
    /// as `v` in `v*|v|`): every predictor evaluates its modulus pointwise,
    /// exactly as the simulation does, so its sign may change within an
    /// experiment (the sign variable then stays symbolic in the analysis).
    #[serde(default)]
    pub pointwise: bool,
}

/// The three predictors of the paper.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum PredictorKind {
    /// `Φ(y, u)ᵀθ`, every modulus pointwise, disturbances ignored (IV1).
    Basic,
    /// `[Φ; Φ_ρ; Φ_λ]ᵀ[θ; ρ; λ]` with every disturbance unmeasured (IV2).
    Augmented,
    /// Augmented for unmeasured media, `Φ2(y − R y_aux)` for measured ones (IV3, LS).
    Measured,
}

/// Regressor columns of each predictor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Predictors {
    /// IV1: θ columns only.
    pub basic: Vec<Column>,
    /// IV2: θ columns, then every ρ, then every λ (unreduced).
    pub augmented: Vec<Column>,
    /// IV3: θ columns, then ρ and λ of the unmeasured media (unreduced).
    pub measured: Vec<Column>,
}

impl Predictors {
    /// The columns of one predictor.
    pub fn get(&self, kind: PredictorKind) -> &[Column] {
        match kind {
            PredictorKind::Basic => &self.basic,
            PredictorKind::Augmented => &self.augmented,
            PredictorKind::Measured => &self.measured,
        }
    }
}

/// What a column's coefficient is.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum ColumnKind {
    /// A physical parameter θ_p.
    Theta {
        /// Index into [`Ir::parameters`].
        parameter: usize,
    },
    /// `ρ = E[v_j]·θ_p`.
    Rho {
        /// Global component index `j`.
        component: usize,
        /// `p`.
        parameter: usize,
    },
    /// `λ = E[v_j v_m]·θ_p`, `j ≤ m`.
    Lambda {
        /// `(j, m)`.
        components: [usize; 2],
        /// `p`.
        parameter: usize,
    },
}

impl ColumnKind {
    /// True for nuisance columns.
    pub fn is_nuisance(&self) -> bool {
        !matches!(self, ColumnKind::Theta { .. })
    }
    /// The physical parameter involved.
    pub fn parameter(&self) -> usize {
        match self {
            ColumnKind::Theta { parameter }
            | ColumnKind::Rho { parameter, .. }
            | ColumnKind::Lambda { parameter, .. } => *parameter,
        }
    }
}

/// A regressor column: the coefficient it multiplies, how to evaluate it
/// (per output), and its structural polynomial for the exact rank analysis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Column {
    /// `X_uu`, `rho[north,X_uu]`, `lambda[north*east,X_uu]`.
    pub name: String,
    /// What it multiplies.
    pub kind: ColumnKind,
    /// Evaluation: the column's value in output `o` is the sum, in order, of
    /// its entries with `output == o`.
    pub entries: Vec<Entry>,
    /// Structural polynomial per output, sign variables symbolic. Monomials
    /// that are constant within an experiment (no variable but signs) are
    /// kept: whether the instruments annihilate them depends on the centring
    /// ([`Centring`]).
    pub structural: Vec<StructuralEntry>,
}

/// The columns with entries in each of `n_outputs` outputs, in their order:
/// one pass over the columns (filtering them once per output is quadratic in
/// the size of the model).
pub fn columns_by_output<'a>(
    columns: impl IntoIterator<Item = &'a Column>,
    n_outputs: usize,
) -> Vec<Vec<&'a Column>> {
    let mut by: Vec<Vec<&'a Column>> = vec![Vec::new(); n_outputs];
    for c in columns {
        for out in c.outputs() {
            if let Some(v) = by.get_mut(out) {
                v.push(c);
            }
        }
    }
    by
}

impl Column {
    /// The outputs this column has entries in.
    pub fn outputs(&self) -> Vec<usize> {
        let mut o: Vec<usize> = self.entries.iter().map(Entry::output).collect();
        o.sort_unstable();
        o.dedup();
        o
    }
}

/// A variable of an evaluated monomial.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum EvalVar {
    /// `x[i]`.
    State(usize),
    /// `u[i]`.
    Input(usize),
    /// `|u[i]|`.
    AbsInput(usize),
    /// `rot[i]`.
    Rot(usize),
}

/// Which disturbance values a pointwise term is evaluated with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Pointwise {
    /// Disturbances taken as zero (the basic predictor: `Φ(y, u)`).
    Undisturbed,
    /// Measured disturbance components from the data (`Φ2(y − R y_aux)`).
    Measured,
}

/// One summand of a column in one output.
///
/// Evaluation order (shared by codegen and the interpreter):
/// * `Poly`: `t = coefficient; for i in signs { t = t * sign[i] }; for v in vars { t = t * v }`.
/// * `Term`: the term's arguments are evaluated as `x − ((R_l0·d_0 + R_l1·d_1) + …)`
///   over the non-zero rotation entries in component order (plain `x` when
///   undisturbed); then `a`: `k*a`, `|a|`: `k*|a|`, `a·b`: `(k*a)*b`,
///   `a·|b|`: `(k*a)*|b|` with `k` the term's coefficient.
/// * The column value is `((e0 + e1) + e2) + …` over its entries in one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Entry {
    /// A monomial with a sign factor.
    Poly {
        /// The output.
        output: usize,
        /// The exact coefficient rounded once.
        coefficient: f64,
        /// The exact coefficient `p/q`.
        coefficient_exact: String,
        /// Sign arguments whose signs multiply the entry.
        signs: Vec<usize>,
        /// Variables, with repetition for powers, in sorted order.
        vars: Vec<EvalVar>,
    },
    /// A whole term evaluated pointwise (modulus taken of the value).
    Term {
        /// The output.
        output: usize,
        /// Index into [`Ir::terms`].
        term: usize,
        /// With which disturbance values.
        pointwise: Pointwise,
    },
}

impl Entry {
    /// The output of the entry.
    pub fn output(&self) -> usize {
        match self {
            Entry::Poly { output, .. } | Entry::Term { output, .. } => *output,
        }
    }
}

/// A variable of a structural polynomial.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum StructVar {
    /// A sign variable (`s² = 1`).
    Sign(usize),
    /// A state.
    State(usize),
    /// An input.
    Input(usize),
    /// `|input|`.
    AbsInput(usize),
    /// A rotation variable.
    Rot(usize),
    /// A measured disturbance component.
    Measured(usize),
}

/// A structural monomial `coefficient · Π var^power` in one output.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct StructuralEntry {
    /// The output.
    pub output: usize,
    /// Exact coefficient `p/q`.
    pub coefficient: String,
    /// Variables with powers, sorted.
    pub vars: Vec<(StructVar, u32)>,
}

/// A sign pattern: one `±1` per sign argument.
pub type SignPattern = Vec<i8>;

/// How the instruments are centred, which decides which constants they
/// annihilate (paper A9): a monomial that is constant within an experiment
/// (the `1` of `cos² = 1 − sin²`, a constant term `X_0`, a sign alone).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Centring {
    /// Zero mean per experiment: every constant within an experiment is
    /// annihilated, and with it the means of the disturbances.
    Experiment,
    /// Zero mean over all experiments pooled: a constant common to every
    /// experiment is annihilated unless the model has a constant term in that
    /// output (whose own instrument, the constant, is kept: it spans the same
    /// instruments as no centring); constants that differ between
    /// experiments are kept.
    Pooled,
    /// No centring: constants are columns like any other.
    None,
}

impl Centring {
    /// `experiment`, `pooled`, `none`.
    pub fn name(self) -> &'static str {
        match self {
            Centring::Experiment => "experiment",
            Centring::Pooled => "pooled",
            Centring::None => "none",
        }
    }
}

/// The compile-time identifiability report of the model as declared
/// (the measured predictor, IV3; equal to IV2's when nothing is measured).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// θ identifiable from the required sign patterns.
    pub identifiable: bool,
    /// θ identifiable from one experiment whatever its sign pattern.
    pub any_single_pattern: bool,
    /// The smallest set of sign patterns found that identifies θ (empty if none).
    pub required_patterns: Vec<SignPattern>,
    /// The sign patterns the verdicts below were computed for.
    pub patterns: Vec<SignPattern>,
    /// Unidentifiable combinations at `patterns`.
    pub unidentifiable: Vec<Combination>,
    /// What separates each unidentifiable group, if anything does.
    pub separations: Vec<Separation>,
    /// Nuisance reduction at `patterns`.
    pub nuisance: NuisanceReport,
    /// With aggregation: what each kept parameter estimates.
    pub aggregates: Vec<Aggregate>,
    /// Notes for the user (common state-dependent terms, constant terms, ...).
    pub notes: Vec<String>,
    /// The instrument centring the verdicts assume (the model's default
    /// unless asked otherwise): it decides which constants are annihilated.
    #[serde(default)]
    pub centring: Option<Centring>,
    /// Why that centring is valid for this model.
    #[serde(default)]
    pub centring_reason: String,
    /// `None` when the search for the smallest set of experiments was exact;
    /// otherwise what its budget left untried. θ is then still proven
    /// identifiable from `required_patterns` (the verdict is exact), but a
    /// smaller set may exist, and `any_single_pattern` may be unproven.
    #[serde(default)]
    pub search_cut: Option<String>,
}

impl Report {
    /// `identifiable`, `not-identifiable` or `undecided` (θ identifiable from
    /// `required_patterns`, but whether fewer experiments suffice was cut by
    /// the search budget).
    pub fn verdict(&self) -> &'static str {
        match (self.identifiable, &self.search_cut) {
            (false, _) => "not-identifiable",
            (true, None) => "identifiable",
            (true, Some(_)) => "undecided",
        }
    }
}

/// A set of parameters that enter only through combinations.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Combination {
    /// The θ indices involved.
    pub parameters: Vec<usize>,
    /// The identifiable combinations, e.g. `X_uu + W_uu`.
    pub identifiable: Vec<String>,
    /// One sentence: `X_uu and W_uu enter only as X_uu + W_uu`.
    pub message: String,
}

/// Whether and how experiments separate a group.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Separation {
    /// The θ indices of the group.
    pub parameters: Vec<usize>,
    /// The smallest set of sign patterns that separates them, if one exists,
    /// each over [`Separation::arguments`] only (`patterns[e][k]` is the sign
    /// of `arguments[k]` in experiment `e`; every other sign is `+`), so the
    /// report grows with the model, not with its square ([`Separation::full`]
    /// gives them over every sign argument).
    pub patterns: Option<Vec<SignPattern>>,
    /// The sign arguments (indices into `Ir::sign_args`, increasing) the
    /// patterns give.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub arguments: Vec<usize>,
    /// One sentence.
    pub message: String,
}

impl Separation {
    /// The patterns over all `n` sign arguments.
    pub fn full(&self, n: usize) -> Option<Vec<SignPattern>> {
        self.patterns.as_ref().map(|set| {
            set.iter()
                .map(|p| {
                    let mut full = vec![1i8; n];
                    for (k, a) in self.arguments.iter().enumerate() {
                        if let (Some(slot), Some(s)) = (full.get_mut(*a), p.get(k)) {
                            *slot = *s;
                        }
                    }
                    full
                })
                .collect()
        })
    }
}

/// The nuisance parameters before and after reduction to an identifiable basis.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct NuisanceReport {
    /// Unreduced count.
    pub before: usize,
    /// Kept count.
    pub after: usize,
    /// Kept columns (indices into the predictor's columns) and what each estimates.
    pub kept: Vec<KeptNuisance>,
    /// Dropped columns and why.
    pub dropped: Vec<DroppedNuisance>,
}

/// A kept nuisance column.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeptNuisance {
    /// Column index in the predictor.
    pub column: usize,
    /// Its name.
    pub name: String,
    /// What it estimates, e.g. `E[north]·X_u` or a combination.
    pub estimates: String,
}

/// A dropped nuisance column.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DroppedNuisance {
    /// Column index in the predictor.
    pub column: usize,
    /// Its name.
    pub name: String,
    /// `= 2·rho[..] − lambda[..]`, or `constant within an experiment`.
    pub reason: String,
}

/// A kept θ column that estimates an aggregate.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Aggregate {
    /// θ index of the kept parameter.
    pub parameter: usize,
    /// What it estimates, e.g. `X_uu + W_uu`.
    pub estimates: String,
    /// θ indices held at their nominal values and absorbed here.
    pub absorbed: Vec<usize>,
}
