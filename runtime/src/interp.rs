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

/// One summand of a slot, flattened: a monomial (`term == NO_TERM`) or a
/// pointwise term.
#[derive(Clone, Copy, Debug)]
struct FlatEntry {
    coefficient: f64,
    signs: (u32, u32),
    vars: (u32, u32),
    term: u32,
    disturbed: bool,
}

const NO_TERM: u32 = u32::MAX;

/// A predictor's evaluation plan in flat arrays: slots (one per column and
/// output) own ranges of entries; entries own ranges of sign and variable
/// indices. Variables index a per-sample table `[x, u, |u|, rot]`.
#[derive(Clone, Debug)]
struct PredictorPlan {
    len: usize,
    slots: Vec<(u32, u32, u32)>,
    entries: Vec<FlatEntry>,
    signs: Vec<u32>,
    vars: Vec<u32>,
}

/// Largest value table kept on the stack.
const TABLE: usize = 64;

fn var_index(v: &EvalVar, n_x: usize, n_u: usize) -> u32 {
    (match v {
        EvalVar::State(i) => *i,
        EvalVar::Input(i) => n_x + *i,
        EvalVar::AbsInput(i) => n_x + n_u + *i,
        EvalVar::Rot(i) => n_x + 2 * n_u + *i,
    }) as u32
}

fn plan_predictor(columns: &[Column], n_outputs: usize, n_x: usize, n_u: usize) -> PredictorPlan {
    let n = columns.len();
    let mut plan = PredictorPlan {
        len: n * n_outputs,
        slots: Vec::new(),
        entries: Vec::new(),
        signs: Vec::new(),
        vars: Vec::new(),
    };
    for (j, col) in columns.iter().enumerate() {
        for o in col.outputs() {
            let start = plan.entries.len() as u32;
            for e in col.entries.iter().filter(|e| e.output() == o) {
                let fe = match e {
                    Entry::Poly {
                        coefficient,
                        signs,
                        vars,
                        ..
                    } => {
                        let s0 = plan.signs.len() as u32;
                        plan.signs.extend(signs.iter().map(|i| *i as u32));
                        let v0 = plan.vars.len() as u32;
                        plan.vars
                            .extend(vars.iter().map(|v| var_index(v, n_x, n_u)));
                        FlatEntry {
                            coefficient: *coefficient,
                            signs: (s0, plan.signs.len() as u32),
                            vars: (v0, plan.vars.len() as u32),
                            term: NO_TERM,
                            disturbed: false,
                        }
                    }
                    Entry::Term {
                        term, pointwise, ..
                    } => FlatEntry {
                        coefficient: 0.0,
                        signs: (0, 0),
                        vars: (0, 0),
                        term: *term as u32,
                        disturbed: *pointwise == Pointwise::Measured,
                    },
                };
                plan.entries.push(fe);
            }
            plan.slots
                .push(((o * n + j) as u32, start, plan.entries.len() as u32));
        }
    }
    plan
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
    table_len: usize,
}

impl Interpreter {
    /// Compiles the evaluation plan of a model.
    pub fn new(ir: Ir) -> Interpreter {
        let n_out = ir.states.len();
        let n_u = ir.inputs.len();
        let terms = term_plans(&ir);
        let by_output = (0..n_out)
            .map(|o| (0..terms.len()).filter(|t| terms[*t].output == o).collect())
            .collect();
        let basic = plan_predictor(&ir.predictors.basic, n_out, n_out, n_u);
        let augmented = plan_predictor(&ir.predictors.augmented, n_out, n_out, n_u);
        let measured = plan_predictor(&ir.predictors.measured, n_out, n_out, n_u);
        let table_len = n_out + 2 * n_u + ir.rotation_vars.len();
        Interpreter {
            ir,
            terms,
            by_output,
            basic,
            augmented,
            measured,
            table_len,
        }
    }

    #[inline]
    fn eval_plan(&self, plan: &PredictorPlan, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        let mut stack = [0.0f64; TABLE];
        let mut heap = Vec::new();
        let table: &mut [f64] = if self.table_len <= TABLE {
            &mut stack[..self.table_len]
        } else {
            heap.resize(self.table_len, 0.0);
            &mut heap
        };
        let (n_x, n_u) = (sig.states.len(), sig.inputs.len());
        table[..n_x].copy_from_slice(sig.states);
        table[n_x..n_x + n_u].copy_from_slice(sig.inputs);
        for (d, u) in table[n_x + n_u..n_x + 2 * n_u].iter_mut().zip(sig.inputs) {
            *d = u.abs();
        }
        let rot_len = self.table_len - n_x - 2 * n_u;
        table[n_x + 2 * n_u..].copy_from_slice(&sig.rotation[..rot_len]);
        out[..plan.len].fill(0.0);
        for &(index, start, end) in &plan.slots {
            let mut acc = 0.0;
            for (k, e) in plan.entries[start as usize..end as usize]
                .iter()
                .enumerate()
            {
                let v = if e.term == NO_TERM {
                    let mut t = e.coefficient;
                    for &i in &plan.signs[e.signs.0 as usize..e.signs.1 as usize] {
                        t *= signs[i as usize];
                    }
                    for &i in &plan.vars[e.vars.0 as usize..e.vars.1 as usize] {
                        t *= table[i as usize];
                    }
                    t
                } else {
                    self.terms[e.term as usize].eval(sig, e.disturbed)
                };
                acc = if k == 0 { v } else { acc + v };
            }
            out[index as usize] = acc;
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
