//! The interpreter's evaluation plans: what is computed once per call into a
//! small table of values, and the products read from it, grouped by shape.
//!
//! Every regressor entry and every term is a product `k · t[f0] · t[f1] · …`
//! of its coefficient and values of the table, in the IR's order: for a
//! `Poly` entry the signs and then the variables, for a term its factors
//! (`|a|` is a value of its own). So one calling convention serves every
//! shape, and the plan only has to say, per slot, which table values to
//! multiply. The table holds, in this order: the states, inputs, rotation
//! variables and signs the plan reads (copied prefixes of the `Signals`),
//! then the derived values — disturbed arguments `x − ((p0 + p1) + …)` and
//! moduli — each computed once per call, however many entries use it, then
//! room for intermediate products (the entries of summed slots, the
//! weighted terms of `rhs`). It lives on the stack (a per-thread one for a
//! plan of more than 64 values): no call allocates.
//!
//! Slots are grouped by the number of factors of their only entry, so each
//! group is a tight loop without a branch per slot; a slot with more than
//! three factors (none in the model class: a sign and two variables at
//! most) takes the general path. A slot summing several entries (a
//! parameter multiplying a sum) has its entries computed the same way into
//! the table, then added in order. The structurally zero slots are written
//! from a precomputed list of runs, not by clearing the whole buffer first.
//!
//! Nothing is reordered: each product and each sum is evaluated operation
//! for operation as `leeway_structure::ir::Entry` defines it (and as
//! generated code does); only *when* each is computed, and where it is
//! kept, differs.

mod block;

use crate::model::Signals;
use leeway_structure::ir::{
    Arg, Column, Entry, EvalVar, Ir, Pointwise, PredictorKind, Share, Signal, Term,
};
use std::cell::RefCell;
use std::collections::BTreeMap;

/// A table of at most this many values lives on the stack of the call
/// (every example model needs fewer than 40).
const STACK_TABLE: usize = 64;

thread_local! {
    /// The table of a larger plan: one per thread, grown to the largest
    /// plan once, so that no call allocates.
    static LARGE_TABLE: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` on a table of `len` values (contents unspecified: every plan
/// writes each value before it reads it).
#[inline(always)]
fn with_table<R>(len: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    // Cleared on every call: no larger than the plan needs.
    if len <= 16 {
        let mut table = [0.0; 16];
        return f(&mut table[..len]);
    }
    if len <= 32 {
        let mut table = [0.0; 32];
        return f(&mut table[..len]);
    }
    if len <= STACK_TABLE {
        let mut table = [0.0; STACK_TABLE];
        return f(&mut table[..len]);
    }
    LARGE_TABLE.with(|t| {
        // `f` never re-enters `with_table`, so the cell is free here.
        let mut t = t.borrow_mut();
        if t.len() < len {
            t.resize(len, 0.0);
        }
        f(&mut t[..len])
    })
}

/// One disturbance share of a disturbed argument, with its rotation entry
/// as a table index.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TableShare {
    share: Share,
    /// The rotation variable's index in the table (unused for `Share::One`).
    rot: u32,
    /// The global disturbance component.
    component: u32,
}

impl TableShare {
    /// `R_lk·d`, `−(R_lk·d)` or `d`.
    #[inline(always)]
    fn value(&self, t: &[f64], disturbances: &[f64]) -> f64 {
        let d = disturbances[self.component as usize];
        match self.share {
            Share::Rot(_) => t[self.rot as usize] * d,
            Share::NegRot(_) => -(t[self.rot as usize] * d),
            Share::One => d,
        }
    }
}

/// A disturbed argument `t[value] = t[base] − ((p0 + p1) + …)` over `S`
/// shares.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Disturbed<S> {
    value: u32,
    base: u32,
    shares: S,
}

/// Where each value of the per-call table comes from.
///
/// Derived values are grouped by kind, each kind a loop of its own:
/// disturbed arguments first (they read only copied values), then moduli
/// (of copied values or of disturbed arguments).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Table {
    /// Offsets of the inputs, rotation variables and signs (states at 0).
    inputs_at: usize,
    rotation_at: usize,
    signs_at: usize,
    /// How many leading states, inputs, rotation variables and signs are
    /// read (and copied): only those the plan uses, so the plan reads no
    /// more of the `Signals` than generated code does.
    copy: [usize; 4],
    /// One share (a body-frame component, or one non-zero rotation entry).
    disturbed_once: Vec<Disturbed<TableShare>>,
    /// Two shares (a planar rotation): `t[base] − (p0 + p1)`.
    disturbed_twice: Vec<Disturbed<[TableShare; 2]>>,
    /// Any number: `shares[start..end]`.
    disturbed: Vec<Disturbed<(u32, u32)>>,
    shares: Vec<TableShare>,
    /// `t[value] = |t[of]|` as `(value, of)`.
    moduli: Vec<(u32, u32)>,
    len: usize,
}

impl Table {
    /// Fills the table for one call: copies, then derived values.
    #[inline(always)]
    fn fill(&self, sig: &Signals, signs: &[f64], t: &mut [f64]) {
        let [x, u, rot, s] = self.copy;
        copy(&mut t[..x], &sig.states[..x]);
        copy(&mut t[self.inputs_at..self.inputs_at + u], &sig.inputs[..u]);
        copy(
            &mut t[self.rotation_at..self.rotation_at + rot],
            &sig.rotation[..rot],
        );
        copy(&mut t[self.signs_at..self.signs_at + s], &signs[..s]);
        let d = sig.disturbances;
        for a in &self.disturbed_once {
            t[a.value as usize] = t[a.base as usize] - a.shares.value(t, d);
        }
        for a in &self.disturbed_twice {
            let [p0, p1] = a.shares;
            t[a.value as usize] = t[a.base as usize] - (p0.value(t, d) + p1.value(t, d));
        }
        for a in &self.disturbed {
            // `(p0 + p1) + …`, starting from `p0` (not `0.0 + p0`, which
            // turns a `-0.0` share into `0.0`).
            let (start, end) = a.shares;
            let mut sum = 0.0;
            for (k, sh) in self.shares[start as usize..end as usize].iter().enumerate() {
                let p = sh.value(t, d);
                sum = if k == 0 { p } else { sum + p };
            }
            t[a.value as usize] = t[a.base as usize] - sum;
        }
        for &(value, of) in &self.moduli {
            t[value as usize] = t[of as usize].abs();
        }
    }
}

/// `dest = src` (equal lengths, a few values): short copies inline rather
/// than a call to `memcpy`.
#[inline(always)]
fn copy(dest: &mut [f64], src: &[f64]) {
    match (dest, src) {
        (_, []) => {}
        ([d0], [s0]) => *d0 = *s0,
        ([d0, d1], [s0, s1]) => (*d0, *d1) = (*s0, *s1),
        ([d0, d1, d2], [s0, s1, s2]) => (*d0, *d1, *d2) = (*s0, *s1, *s2),
        ([d0, d1, d2, d3], [s0, s1, s2, s3]) => {
            (*d0, *d1, *d2, *d3) = (*s0, *s1, *s2, *s3);
        }
        (dest, src) => dest.copy_from_slice(src),
    }
}

/// A product as built: its coefficient and its factors' table indices.
type Built = (f64, Vec<u32>);

/// Builds a [`Table`], handing out the index of each value the plan reads
/// (every value once).
struct TableBuilder<'a> {
    ir: &'a Ir,
    table: Table,
    moduli: BTreeMap<u32, u32>,
    disturbed: BTreeMap<Arg, u32>,
}

impl<'a> TableBuilder<'a> {
    fn new(ir: &'a Ir) -> Self {
        let [n_x, n_u, n_rot, n_s] = extents(ir);
        let inputs_at = n_x;
        let rotation_at = inputs_at + n_u;
        let signs_at = rotation_at + n_rot;
        TableBuilder {
            ir,
            table: Table {
                inputs_at,
                rotation_at,
                signs_at,
                copy: [0; 4],
                len: signs_at + n_s,
                ..Table::default()
            },
            moduli: BTreeMap::new(),
            disturbed: BTreeMap::new(),
        }
    }

    /// A copied value: `source` 0..4 = states, inputs, rotation, signs.
    fn copied(&mut self, source: usize, i: usize) -> u32 {
        let copy = &mut self.table.copy[source];
        *copy = (*copy).max(i + 1);
        let at = [
            0,
            self.table.inputs_at,
            self.table.rotation_at,
            self.table.signs_at,
        ][source];
        (at + i) as u32
    }

    fn signal(&mut self, s: Signal) -> u32 {
        match s {
            Signal::State(i) => self.copied(0, i),
            Signal::Input(i) => self.copied(1, i),
        }
    }

    /// The index of a new derived value.
    fn next_value(&mut self) -> u32 {
        self.table.len += 1;
        (self.table.len - 1) as u32
    }

    fn modulus(&mut self, of: u32) -> u32 {
        if let Some(&v) = self.moduli.get(&of) {
            return v;
        }
        let value = self.next_value();
        self.table.moduli.push((value, of));
        self.moduli.insert(of, value);
        value
    }

    /// An argument's value: the plain signal, or (disturbed, with shares)
    /// `x − ((p0 + p1) + …)`, computed once per call.
    fn arg(&mut self, arg: &Arg, disturbed: bool) -> u32 {
        let base = self.signal(arg.signal);
        if !disturbed {
            return base;
        }
        if let Some(&v) = self.disturbed.get(arg) {
            return v;
        }
        let shares = self.ir.arg_shares(arg);
        if shares.is_empty() {
            return base;
        }
        let shares: Vec<TableShare> = shares
            .into_iter()
            .map(|(share, component)| TableShare {
                share,
                rot: match share {
                    Share::Rot(r) | Share::NegRot(r) => self.copied(2, r),
                    Share::One => 0,
                },
                component: component as u32,
            })
            .collect();
        let value = self.next_value();
        let t = &mut self.table;
        match *shares.as_slice() {
            [share] => t.disturbed_once.push(Disturbed {
                value,
                base,
                shares: share,
            }),
            [p0, p1] => t.disturbed_twice.push(Disturbed {
                value,
                base,
                shares: [p0, p1],
            }),
            _ => {
                let start = t.shares.len() as u32;
                t.shares.extend(shares);
                t.disturbed.push(Disturbed {
                    value,
                    base,
                    shares: (start, t.shares.len() as u32),
                });
            }
        }
        self.disturbed.insert(*arg, value);
        value
    }

    fn var(&mut self, v: &EvalVar) -> u32 {
        match *v {
            EvalVar::State(i) => self.copied(0, i),
            EvalVar::Input(i) => self.copied(1, i),
            EvalVar::AbsInput(i) => {
                let u = self.copied(1, i);
                self.modulus(u)
            }
            EvalVar::Rot(i) => self.copied(2, i),
        }
    }

    /// A term as a product.
    fn term(&mut self, t: &Term, disturbed: bool) -> Built {
        let factors = t
            .factors
            .iter()
            .map(|f| {
                let a = self.arg(&f.arg, disturbed);
                if f.modulus { self.modulus(a) } else { a }
            })
            .collect();
        (t.coefficient, factors)
    }

    /// A regressor entry as a product.
    fn entry(&mut self, e: &Entry) -> Built {
        match e {
            Entry::Poly {
                coefficient,
                signs,
                vars,
                ..
            } => {
                let mut factors: Vec<u32> = signs.iter().map(|&i| self.copied(3, i)).collect();
                factors.extend(vars.iter().map(|v| self.var(v)));
                (*coefficient, factors)
            }
            Entry::Term {
                term, pointwise, ..
            } => match self.ir.terms.get(*term) {
                Some(t) => self.term(t, *pointwise == Pointwise::Measured),
                // Cannot happen for an IR from `compile`; generated code
                // writes NaN there too.
                None => (f64::NAN, Vec::new()),
            },
        }
    }
}

/// How many states, inputs, rotation variables and signs the table has
/// room for: the IR's declarations, or more where a (hand-made) IR's columns
/// or terms refer beyond them — so every index has a value of its own, and
/// reading it fails on the `Signals` slice as generated code would.
fn extents(ir: &Ir) -> [usize; 4] {
    let mut n = [
        ir.states.len(),
        ir.inputs.len(),
        ir.rotation_vars.len(),
        ir.sign_args.len(),
    ];
    let mut see = |source: usize, i: usize| n[source] = n[source].max(i + 1);
    for t in &ir.terms {
        for f in &t.factors {
            match f.arg.signal {
                Signal::State(i) => see(0, i),
                Signal::Input(i) => see(1, i),
            }
            for (share, _) in ir.arg_shares(&f.arg) {
                if let Share::Rot(r) | Share::NegRot(r) = share {
                    see(2, r);
                }
            }
        }
    }
    let columns = [
        &ir.predictors.basic,
        &ir.predictors.augmented,
        &ir.predictors.measured,
    ];
    for e in columns
        .iter()
        .flat_map(|c| c.iter())
        .flat_map(|c| &c.entries)
    {
        if let Entry::Poly { signs, vars, .. } = e {
            for &i in signs {
                see(3, i);
            }
            for v in vars {
                match *v {
                    EvalVar::State(i) => see(0, i),
                    EvalVar::Input(i) | EvalVar::AbsInput(i) => see(1, i),
                    EvalVar::Rot(i) => see(2, i),
                }
            }
        }
    }
    n
}

/// A product of `A` factors written to `dest[at]`: `((k · t[f0]) · t[f1]) · …`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Product<const A: usize> {
    coefficient: f64,
    factors: [u32; A],
    at: u32,
}

impl<const A: usize> Product<A> {
    #[inline(always)]
    fn value(&self, t: &[f64]) -> f64 {
        let mut v = self.coefficient;
        for &f in &self.factors {
            v *= t[f as usize];
        }
        v
    }
}

/// A product of any length: `factors[start..end]` of its plan.
#[derive(Clone, Copy, Debug, PartialEq)]
struct General {
    coefficient: f64,
    start: u32,
    end: u32,
}

impl General {
    #[inline]
    fn value(&self, factors: &[u32], t: &[f64]) -> f64 {
        let mut v = self.coefficient;
        for &f in &factors[self.start as usize..self.end as usize] {
            v *= t[f as usize];
        }
        v
    }
}

/// Products grouped by their number of factors, each group a loop of its
/// own; more than three factors take the general path.
#[derive(Clone, Debug, Default, PartialEq)]
struct Products {
    constant: Vec<Product<0>>,
    one: Vec<Product<1>>,
    two: Vec<Product<2>>,
    three: Vec<Product<3>>,
    general: Vec<(u32, General)>,
    factors: Vec<u32>,
}

impl Products {
    fn push(&mut self, at: u32, coefficient: f64, factors: &[u32]) {
        match *factors {
            [] => self.constant.push(Product {
                coefficient,
                factors: [],
                at,
            }),
            [a] => self.one.push(Product {
                coefficient,
                factors: [a],
                at,
            }),
            [a, b] => self.two.push(Product {
                coefficient,
                factors: [a, b],
                at,
            }),
            [a, b, c] => self.three.push(Product {
                coefficient,
                factors: [a, b, c],
                at,
            }),
            _ => {
                let start = self.factors.len() as u32;
                self.factors.extend_from_slice(factors);
                let end = self.factors.len() as u32;
                self.general.push((
                    at,
                    General {
                        coefficient,
                        start,
                        end,
                    },
                ));
            }
        }
    }

    /// `dest[at] = product(t)` for every product.
    #[inline(always)]
    fn write(&self, t: &[f64], dest: &mut [f64]) {
        for p in &self.constant {
            dest[p.at as usize] = p.coefficient;
        }
        for p in &self.one {
            dest[p.at as usize] = p.value(t);
        }
        for p in &self.two {
            dest[p.at as usize] = p.value(t);
        }
        for p in &self.three {
            dest[p.at as usize] = p.value(t);
        }
        for (at, p) in &self.general {
            dest[*at as usize] = p.value(&self.factors, t);
        }
    }
}

/// A predictor's plan.
///
/// A slot with one entry is one product written to the buffer. A slot
/// summing several entries (a parameter multiplying a sum) has its entries'
/// products written to the table first (after the derived values), then
/// added in order `((e0 + e1) + e2) + …`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct RegressorPlan {
    table: Table,
    /// Length of the buffer (`n_outputs × n_columns`).
    len: usize,
    /// Where the entries of summed slots start in the table.
    entries_at: usize,
    /// Entries of summed slots, written to `table[entries_at..]`.
    entries: Products,
    /// Single-entry slots, written to the buffer.
    slots: Products,
    /// `out[slot] = e[a] + e[b]` (indices relative to `entries_at`).
    pairs: Vec<(u32, u32, u32)>,
    /// `out[slot] = ((e[i0] + e[i1]) + e[i2]) + …` over `summands[start..end]`.
    sums: Vec<(u32, u32, u32)>,
    summands: Vec<u32>,
    /// Runs `[start, end)` of structurally zero slots.
    zeros: Vec<(u32, u32)>,
}

impl RegressorPlan {
    fn new(ir: &Ir, columns: &[Column]) -> RegressorPlan {
        RegressorPlan::of_slots(ir, columns, None)
    }

    /// The plan of the slots `wanted` says (every slot: `None`); the others
    /// are left to the buffer, as structurally zero slots are (so
    /// [`RegressorPlan::eval_nonzero`] writes only the wanted ones), and
    /// the table holds only what the wanted slots read.
    pub(super) fn of_slots(ir: &Ir, columns: &[Column], wanted: Option<&[bool]>) -> RegressorPlan {
        let n = columns.len();
        let n_out = ir.states.len();
        let mut b = TableBuilder::new(ir);
        let mut plan = RegressorPlan {
            len: n * n_out,
            ..RegressorPlan::default()
        };
        let mut written = vec![false; plan.len];
        // Summed slots' entries, placed after the table once it is built.
        let mut summed: Vec<(u32, Vec<Built>)> = Vec::new();
        for (j, col) in columns.iter().enumerate() {
            for o in col.outputs() {
                let slot = o * n + j;
                // An output beyond the model's states (a hand-made IR) has
                // no slot in the buffer.
                let Some(w) = written.get_mut(slot) else {
                    continue;
                };
                if wanted.is_some_and(|wanted| !wanted.get(slot).copied().unwrap_or(false)) {
                    continue;
                }
                *w = true;
                let mut products: Vec<Built> = col
                    .entries
                    .iter()
                    .filter(|e| e.output() == o)
                    .map(|e| b.entry(e))
                    .collect();
                match products.pop() {
                    Some((k, f)) if products.is_empty() => plan.slots.push(slot as u32, k, &f),
                    Some(last) => {
                        products.push(last);
                        summed.push((slot as u32, products));
                    }
                    None => {}
                }
            }
        }
        plan.table = b.table;
        plan.entries_at = plan.table.len;
        let mut e = 0u32;
        for (slot, products) in summed {
            let first = e;
            for (k, f) in products {
                plan.entries.push(e, k, &f);
                e += 1;
            }
            if e - first == 2 {
                plan.pairs.push((slot, first, first + 1));
            } else {
                let start = plan.summands.len() as u32;
                plan.summands.extend(first..e);
                plan.sums.push((slot, start, plan.summands.len() as u32));
            }
        }
        plan.table.len += e as usize;
        let mut k = 0;
        while k < written.len() {
            if written[k] {
                k += 1;
                continue;
            }
            let start = k;
            while k < written.len() && !written[k] {
                k += 1;
            }
            plan.zeros.push((start as u32, k as u32));
        }
        plan
    }

    /// Writes every slot of `out[..len]`. Never inlined, so that profiles
    /// name it rather than the thread-local's closure.
    #[inline(never)]
    pub(super) fn eval(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        let out = &mut out[..self.len];
        with_table(self.table.len, |t| self.eval_in(t, sig, signs, out, true));
    }

    /// [`RegressorPlan::eval`] without writing the structurally zero slots
    /// (`Model::regressors_update`).
    #[inline(never)]
    pub(super) fn eval_nonzero(&self, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        let out = &mut out[..self.len];
        with_table(self.table.len, |t| self.eval_in(t, sig, signs, out, false));
    }

    /// [`RegressorPlan::eval`] on a table.
    #[inline(always)]
    fn eval_in(&self, t: &mut [f64], sig: &Signals, signs: &[f64], out: &mut [f64], zeros: bool) {
        self.table.fill(sig, signs, t);
        let (t, e) = t.split_at_mut(self.entries_at);
        let t: &[f64] = t;
        self.entries.write(t, e);
        let e: &[f64] = e;
        if zeros {
            for &(start, end) in &self.zeros {
                out[start as usize..end as usize].fill(0.0);
            }
        }
        self.slots.write(t, out);
        for &(slot, a, b) in &self.pairs {
            out[slot as usize] = e[a as usize] + e[b as usize];
        }
        for &(slot, start, end) in &self.sums {
            let mut acc = 0.0;
            for (k, &i) in self.summands[start as usize..end as usize]
                .iter()
                .enumerate()
            {
                let v = e[i as usize];
                acc = if k == 0 { v } else { acc + v };
            }
            out[slot as usize] = acc;
        }
    }
}

/// A term of the right-hand side weighted by its parameter:
/// `θ_p · (k · t[f0] · …)`, written to the table's value `at`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Weighted<const A: usize> {
    parameter: u32,
    product: Product<A>,
}

impl<const A: usize> Weighted<A> {
    #[inline(always)]
    fn write(terms: &[Self], theta: &[f64], t: &[f64], dest: &mut [f64]) {
        for w in terms {
            dest[w.product.at as usize] = theta[w.parameter as usize] * w.product.value(t);
        }
    }
}

/// The right-hand side's plan: the weighted terms `θ_p · term`, each
/// evaluated by a loop per number of factors into the table (after the
/// derived values) in output and term order, then summed per output in
/// term order `((w0 + w1) + w2) + …`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct RhsPlan {
    table: Table,
    /// Where the weighted terms start in the table.
    terms_at: usize,
    constant: Vec<Weighted<0>>,
    one: Vec<Weighted<1>>,
    two: Vec<Weighted<2>>,
    /// More factors than the model class has: `(parameter, product)`.
    general: Vec<(u32, u32, General)>,
    factors: Vec<u32>,
    /// Per output, its weighted terms `[start, end)` (relative to `terms_at`).
    outputs: Vec<(u32, u32)>,
}

impl RhsPlan {
    fn new(ir: &Ir) -> RhsPlan {
        let n_out = ir.states.len();
        let mut b = TableBuilder::new(ir);
        let mut by_output: Vec<Vec<&Term>> = vec![Vec::new(); n_out];
        for t in &ir.terms {
            if let Some(v) = by_output.get_mut(t.output) {
                v.push(t);
            }
        }
        let mut plan = RhsPlan::default();
        let mut at = 0u32;
        for terms in by_output {
            let start = at;
            for t in terms {
                let (coefficient, factors) = b.term(t, true);
                let parameter = t.parameter as u32;
                match *factors.as_slice() {
                    [] => plan.constant.push(Weighted {
                        parameter,
                        product: Product {
                            coefficient,
                            factors: [],
                            at,
                        },
                    }),
                    [f0] => plan.one.push(Weighted {
                        parameter,
                        product: Product {
                            coefficient,
                            factors: [f0],
                            at,
                        },
                    }),
                    [f0, f1] => plan.two.push(Weighted {
                        parameter,
                        product: Product {
                            coefficient,
                            factors: [f0, f1],
                            at,
                        },
                    }),
                    _ => {
                        let f = plan.factors.len() as u32;
                        plan.factors.extend(factors);
                        let end = plan.factors.len() as u32;
                        plan.general.push((
                            at,
                            parameter,
                            General {
                                coefficient,
                                start: f,
                                end,
                            },
                        ));
                    }
                }
                at += 1;
            }
            plan.outputs.push((start, at));
        }
        plan.table = b.table;
        plan.terms_at = plan.table.len;
        plan.table.len += at as usize;
        plan
    }

    /// `out[o] = θ_p0 · term0 + θ_p1 · term1 + …` (0 without terms).
    /// Never inlined, so that profiles name it.
    #[inline(never)]
    pub(super) fn eval(&self, theta: &[f64], sig: &Signals, out: &mut [f64]) {
        let out = &mut out[..self.outputs.len()];
        with_table(self.table.len, |t| self.eval_in(t, theta, sig, out));
    }

    /// [`RhsPlan::eval`] on a table.
    #[inline(always)]
    fn eval_in(&self, t: &mut [f64], theta: &[f64], sig: &Signals, out: &mut [f64]) {
        self.table.fill(sig, &[], t);
        let (t, w) = t.split_at_mut(self.terms_at);
        let t: &[f64] = t;
        Weighted::write(&self.constant, theta, t, w);
        Weighted::write(&self.one, theta, t, w);
        Weighted::write(&self.two, theta, t, w);
        for (at, p, product) in &self.general {
            w[*at as usize] = theta[*p as usize] * product.value(&self.factors, t);
        }
        let w: &[f64] = w;
        for (o, &(start, end)) in out.iter_mut().zip(&self.outputs) {
            *o = match w[start as usize..end as usize].split_first() {
                None => 0.0,
                Some((&first, rest)) => {
                    let mut acc = first;
                    for &v in rest {
                        acc += v;
                    }
                    acc
                }
            };
        }
    }
}

/// Every plan of a model.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Plans {
    pub(super) basic: RegressorPlan,
    pub(super) augmented: RegressorPlan,
    pub(super) measured: RegressorPlan,
    pub(super) rhs: RhsPlan,
}

impl Plans {
    /// The regressor plan of `kind`.
    pub(super) fn regressors(&self, kind: PredictorKind) -> &RegressorPlan {
        match kind {
            PredictorKind::Basic => &self.basic,
            PredictorKind::Augmented => &self.augmented,
            PredictorKind::Measured => &self.measured,
        }
    }

    pub(super) fn new(ir: &Ir) -> Plans {
        Plans {
            basic: RegressorPlan::new(ir, &ir.predictors.basic),
            augmented: RegressorPlan::new(ir, &ir.predictors.augmented),
            measured: RegressorPlan::new(ir, &ir.predictors.measured),
            rhs: RhsPlan::new(ir),
        }
    }
}
