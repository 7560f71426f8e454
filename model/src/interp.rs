//! The run-time interpreter of the IR: the columns and terms are compiled
//! once into evaluation plans (`plan`), then evaluated per sample without
//! walking the IR and without allocating. Per call, every value a plan reads
//! — signals, moduli, disturbed arguments — is computed once into a small
//! table; each slot is then a product of table values, evaluated by a loop
//! per shape (number of factors), and the structurally zero slots are
//! written from precomputed runs. Its arithmetic follows the IR's evaluation
//! order exactly (see `leeway_structure::ir::Entry`), as generated code does,
//! so the two agree bit for bit (`tests/bit_exact.rs`,
//! `model/tests/model/interpreter.rs`).
//!
//! [`Interpreter::regressors_block`] evaluates the same plans for a block of
//! samples at once, each product a loop over the samples.
//!
//! [`ArgPlan`] and [`TermPlan`] evaluate one argument or term on its own,
//! for the estimator's fixed-sign instruments and the sign detection.

mod plan;

use crate::model::{Model, Signals, SlotRegressors};
use leeway_structure::grammar::EquationKind;
use leeway_structure::ir::{Arg, Ir, PredictorKind, Signal};
use plan::{Plans, RegressorPlan};

pub use leeway_structure::ir::Share;

/// How to evaluate a term argument: the base signal, and the rotated
/// disturbance shares subtracted from it (`x − ((p0 + p1) + …)`).
#[derive(Clone, Debug, PartialEq)]
pub struct ArgPlan {
    /// The base signal.
    pub signal: Signal,
    /// `(share, component)` in component order; empty for a plain signal.
    pub shares: Vec<(Share, usize)>,
}

/// The disturbance shares of an argument, in the IR's order: the
/// components of its medium in order, non-zero rotation entries only.
pub fn arg_plan(ir: &Ir, arg: &Arg) -> ArgPlan {
    ArgPlan {
        signal: arg.signal,
        shares: ir.arg_shares(arg),
    }
}

impl ArgPlan {
    /// The argument's value; `disturbed == false` ignores the shares.
    #[inline]
    pub fn eval(&self, sig: &Signals, disturbed: bool) -> f64 {
        let base = match self.signal {
            Signal::State(i) => sig.states[i],
            Signal::Input(i) => sig.inputs[i],
        };
        if !disturbed || self.shares.is_empty() {
            return base;
        }
        let mut sum = 0.0;
        for (k, (share, c)) in self.shares.iter().enumerate() {
            let d = sig.disturbances[*c];
            let p = match share {
                Share::Rot(r) => sig.rotation[*r] * d,
                Share::NegRot(r) => -(sig.rotation[*r] * d),
                Share::One => d,
            };
            sum = if k == 0 { p } else { sum + p };
        }
        base - sum
    }
}

/// A term ready to evaluate pointwise.
#[derive(Clone, Debug, PartialEq)]
pub struct TermPlan {
    /// Coefficient.
    pub coefficient: f64,
    /// Arguments with their modulus flags (one or two).
    pub factors: Vec<(ArgPlan, bool)>,
    /// Parameter index.
    pub parameter: usize,
    /// Output.
    pub output: usize,
}

/// Evaluation plans of every term of a model, in term order.
pub fn term_plans(ir: &Ir) -> Vec<TermPlan> {
    ir.terms
        .iter()
        .map(|t| TermPlan {
            coefficient: t.coefficient,
            factors: t
                .factors
                .iter()
                .map(|f| (arg_plan(ir, &f.arg), f.modulus))
                .collect(),
            parameter: t.parameter,
            output: t.output,
        })
        .collect()
}

impl TermPlan {
    /// `k*a`, `k*|a|`, `(k*a)*b`, `(k*a)*|b|`.
    #[inline]
    pub fn eval(&self, sig: &Signals, disturbed: bool) -> f64 {
        let mut t = self.coefficient;
        for (a, modulus) in &self.factors {
            let v = a.eval(sig, disturbed);
            t *= if *modulus { v.abs() } else { v };
        }
        t
    }
}

/// A model interpreted from its IR.
#[derive(Clone, Debug)]
pub struct Interpreter {
    ir: Ir,
    plans: Plans,
    /// Per output: `x⁺ = f` (`next`) rather than `x⁺ = x + h f` (`der`).
    next: Vec<bool>,
}

impl Interpreter {
    /// Compiles the evaluation plans of a model.
    pub fn new(ir: Ir) -> Interpreter {
        let plans = Plans::new(&ir);
        let next = ir
            .equations
            .iter()
            .map(|e| e.kind == EquationKind::Next)
            .collect();
        Interpreter { ir, plans, next }
    }

    /// The regressors of a block of `n = samples.len()` samples at once,
    /// slot-major: slot `k` (= `o · n_columns + j`, as in a per-sample
    /// buffer) of sample `s` at `out[k · n + s]`, every slot of
    /// `out[..n_outputs · n_columns · n]` written. `signs` holds the sign
    /// pattern of each sample in turn (`sign_args.len()` values each;
    /// ignored by the basic predictor). Bit for bit what
    /// [`Model::regressors`] gives sample by sample, at about half the cost
    /// for blocks of 32 (docs/performance.md): the plan is read once per
    /// block, and its products loop over the samples. Like the per-sample methods it panics when a slice is
    /// shorter than the model needs.
    pub fn regressors_block(
        &self,
        kind: PredictorKind,
        samples: &[Signals],
        signs: &[f64],
        out: &mut [f64],
    ) {
        let n_signs = self.ir.sign_args.len();
        match kind {
            PredictorKind::Basic => self.plans.basic.eval_block(samples, &[], 0, out),
            PredictorKind::Augmented => self
                .plans
                .augmented
                .eval_block(samples, signs, n_signs, out),
            PredictorKind::Measured => self.plans.measured.eval_block(samples, signs, n_signs, out),
        }
    }
}

/// Some slots of a predictor, by the interpreter's plan of only those.
struct PlannedSlots(RegressorPlan);

impl SlotRegressors for PlannedSlots {
    fn update(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        self.0.eval_nonzero(sig, signs, out);
    }
    fn evaluates_blocks(&self) -> bool {
        true
    }
    fn update_block(&self, samples: &[Signals], signs: &[f64], n_signs: usize, out: &mut [f64]) {
        self.0.eval_block_nonzero(samples, signs, n_signs, out);
    }
}

impl Model for Interpreter {
    fn ir(&self) -> &Ir {
        &self.ir
    }
    fn basic(&self, sig: &Signals, out: &mut [f64]) {
        self.plans.basic.eval(sig, &[], out);
    }
    fn augmented(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        self.plans.augmented.eval(sig, signs, out);
    }
    fn measured(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        self.plans.measured.eval(sig, signs, out);
    }
    fn regressors_update(
        &self,
        kind: PredictorKind,
        sig: &Signals,
        signs: &[f64],
        out: &mut [f64],
    ) {
        self.plans.regressors(kind).eval_nonzero(sig, signs, out);
    }
    fn regressor_slots(
        &self,
        kind: PredictorKind,
        wanted: &[bool],
    ) -> Option<Box<dyn SlotRegressors>> {
        let columns = self.ir.predictors.get(kind);
        Some(Box::new(PlannedSlots(RegressorPlan::of_slots(
            &self.ir,
            columns,
            Some(wanted),
        ))))
    }
    fn rhs(&self, theta: &[f64], sig: &Signals, out: &mut [f64]) {
        self.plans.rhs.eval(theta, sig, out);
    }
    fn step(&self, theta: &[f64], h: f64, sig: &Signals, f: &mut [f64], next: &mut [f64]) {
        self.plans.rhs.eval(theta, sig, f);
        // As the trait's provided `step` computes it.
        for (o, &is_next) in self.next.iter().enumerate() {
            next[o] = if is_next {
                f[o]
            } else {
                sig.states[o] + h * f[o]
            };
        }
    }
}
