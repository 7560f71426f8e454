//! The run-time interpreter of the IR: the columns are compiled once into a
//! flat evaluation plan, then evaluated per sample without walking the IR
//! and without allocating. Its arithmetic follows the IR's evaluation order
//! exactly (see `leeway_structure::ir::Entry`), as generated code does, so the
//! two agree bit for bit.

use crate::model::{Model, Signals};
use leeway_structure::ir::{Arg, Column, Entry, EvalVar, Ir, Pointwise, Signal};

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

#[derive(Clone, Debug)]
enum EntryPlan {
    Poly {
        coefficient: f64,
        signs: Vec<usize>,
        vars: Vec<EvalVar>,
    },
    Term {
        term: usize,
        disturbed: bool,
    },
}

#[derive(Clone, Debug)]
struct Slot {
    index: usize,
    entries: Vec<EntryPlan>,
}

#[derive(Clone, Debug)]
struct PredictorPlan {
    len: usize,
    slots: Vec<Slot>,
}

fn plan_predictor(columns: &[Column], n_outputs: usize) -> PredictorPlan {
    let n = columns.len();
    let mut slots: Vec<Slot> = Vec::new();
    for (j, col) in columns.iter().enumerate() {
        for o in col.outputs() {
            let entries = col
                .entries
                .iter()
                .filter(|e| e.output() == o)
                .map(|e| match e {
                    Entry::Poly {
                        coefficient,
                        signs,
                        vars,
                        ..
                    } => EntryPlan::Poly {
                        coefficient: *coefficient,
                        signs: signs.clone(),
                        vars: vars.clone(),
                    },
                    Entry::Term {
                        term, pointwise, ..
                    } => EntryPlan::Term {
                        term: *term,
                        disturbed: *pointwise == Pointwise::Measured,
                    },
                })
                .collect();
            slots.push(Slot {
                index: o * n + j,
                entries,
            });
        }
    }
    PredictorPlan {
        len: n * n_outputs,
        slots,
    }
}

/// A model interpreted from its IR.
#[derive(Clone, Debug)]
pub struct Interpreter {
    ir: Ir,
    terms: Vec<TermPlan>,
    by_output: Vec<Vec<usize>>,
    basic: PredictorPlan,
    augmented: PredictorPlan,
    measured: PredictorPlan,
}

impl Interpreter {
    /// Compiles the evaluation plan of a model.
    pub fn new(ir: Ir) -> Interpreter {
        let n_out = ir.states.len();
        let terms: Vec<TermPlan> = ir
            .terms
            .iter()
            .map(|t| TermPlan {
                coefficient: t.coefficient,
                factors: t
                    .factors
                    .iter()
                    .map(|f| (arg_plan(&ir, &f.arg), f.modulus))
                    .collect(),
                parameter: t.parameter,
                output: t.output,
            })
            .collect();
        let by_output = (0..n_out)
            .map(|o| (0..terms.len()).filter(|t| terms[*t].output == o).collect())
            .collect();
        let basic = plan_predictor(&ir.predictors.basic, n_out);
        let augmented = plan_predictor(&ir.predictors.augmented, n_out);
        let measured = plan_predictor(&ir.predictors.measured, n_out);
        Interpreter {
            ir,
            terms,
            by_output,
            basic,
            augmented,
            measured,
        }
    }

    #[inline]
    fn eval_plan(&self, plan: &PredictorPlan, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        out[..plan.len].fill(0.0);
        for slot in &plan.slots {
            let mut acc = 0.0;
            for (k, e) in slot.entries.iter().enumerate() {
                let v = match e {
                    EntryPlan::Poly {
                        coefficient,
                        signs: s,
                        vars,
                    } => {
                        let mut t = *coefficient;
                        for i in s {
                            t *= signs[*i];
                        }
                        for v in vars {
                            t *= match v {
                                EvalVar::State(i) => sig.states[*i],
                                EvalVar::Input(i) => sig.inputs[*i],
                                EvalVar::AbsInput(i) => sig.inputs[*i].abs(),
                                EvalVar::Rot(i) => sig.rotation[*i],
                            };
                        }
                        t
                    }
                    EntryPlan::Term { term, disturbed } => self.terms[*term].eval(sig, *disturbed),
                };
                acc = if k == 0 { v } else { acc + v };
            }
            out[slot.index] = acc;
        }
    }
}

impl Model for Interpreter {
    fn ir(&self) -> &Ir {
        &self.ir
    }
    fn basic(&self, sig: &Signals, out: &mut [f64]) {
        self.eval_plan(&self.basic, sig, &[], out);
    }
    fn augmented(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        self.eval_plan(&self.augmented, sig, signs, out);
    }
    fn measured(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        self.eval_plan(&self.measured, sig, signs, out);
    }
    fn rhs(&self, theta: &[f64], sig: &Signals, out: &mut [f64]) {
        for (o, terms) in self.by_output.iter().enumerate() {
            let mut acc = 0.0;
            for (k, &t) in terms.iter().enumerate() {
                let plan = &self.terms[t];
                let v = theta[plan.parameter] * plan.eval(sig, true);
                acc = if k == 0 { v } else { acc + v };
            }
            out[o] = acc;
        }
    }
}
