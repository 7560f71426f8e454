//! Straight-line evaluation code: the regressors of each predictor, the
//! right-hand side and the simulation step, written as one Rust expression
//! per buffer slot.
//!
//! Every expression follows the evaluation order fixed on
//! `leeway_structure::ir::Entry` — the order the run-time interpreter follows —
//! operation for operation: a `Poly` entry is `((k * s_i) * …) * v * …`; a
//! `Term` entry is `(k * a) * b` or `(k * a) * |b|` with each disturbed argument
//! `x − ((p0 + p1) + …)`; a slot is `((e0 + e1) + e2) + …`; `rhs` is
//! `θ_p * term + …` in term order. Rust neither reassociates nor contracts
//! floating-point operations, so the generated code and the interpreter agree
//! bit for bit; the disturbance shares of an argument come from one function,
//! `Ir::arg_shares`, used by both. Nothing here allocates or loops at run
//! time. `regressors_update` writes only the structurally nonzero slots; each
//! predictor's method fills its buffer with zeros and then runs it.

use crate::tokens::index;
use leeway_structure::grammar::EquationKind;
use leeway_structure::ir::{Arg, Column, Entry, EvalVar, Ir, Pointwise, Share, Signal, Term};
use proc_macro2::{Ident, Span, TokenStream};
use quote::quote;

/// The largest index read from each signal slice.
#[derive(Clone, Copy, Debug, Default)]
struct Reads {
    x: Option<usize>,
    u: Option<usize>,
    rot: Option<usize>,
    d: Option<usize>,
    s: Option<usize>,
    theta: Option<usize>,
}

fn note(slot: &mut Option<usize>, i: usize) {
    *slot = Some(slot.map_or(i, |m| m.max(i)));
}

/// The code of one method body under construction: which slices it reads and
/// which disturbed arguments it binds as locals (in first-use order).
struct Body<'a> {
    ir: &'a Ir,
    reads: Reads,
    args: Vec<(Arg, Ident, TokenStream)>,
}

impl<'a> Body<'a> {
    fn new(ir: &'a Ir) -> Self {
        Body {
            ir,
            reads: Reads::default(),
            args: Vec::new(),
        }
    }

    fn signal(&mut self, s: Signal) -> TokenStream {
        match s {
            Signal::State(i) => {
                note(&mut self.reads.x, i);
                let i = index(i);
                quote!(x[#i])
            }
            Signal::Input(i) => {
                note(&mut self.reads.u, i);
                let i = index(i);
                quote!(u[#i])
            }
        }
    }

    fn var(&mut self, v: &EvalVar) -> TokenStream {
        match *v {
            EvalVar::State(i) => self.signal(Signal::State(i)),
            EvalVar::Input(i) => self.signal(Signal::Input(i)),
            EvalVar::AbsInput(i) => {
                let u = self.signal(Signal::Input(i));
                quote!(#u.abs())
            }
            EvalVar::Rot(i) => {
                note(&mut self.reads.rot, i);
                let i = index(i);
                quote!(rot[#i])
            }
        }
    }

    /// A local's name for a disturbed argument: `water_u` for `water.u`,
    /// made unique among this body's locals.
    fn arg_name(&self, arg: &Arg) -> Ident {
        let ir = self.ir;
        let base = match (arg.signal, arg.relative) {
            (Signal::State(l), Some(r)) => format!(
                "{}_{}",
                ir.relatives.get(r).map_or("rel", |r| r.name.as_str()),
                ir.states.get(l).map_or("x", String::as_str)
            ),
            _ => "arg".to_string(),
        };
        let taken = |n: &str| self.args.iter().any(|(_, id, _)| id == n);
        let mut name = base.clone();
        let mut k = 1;
        while taken(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        // Built from two `.som` identifiers joined by `_`: never a keyword.
        crate::tokens::rust_ident(&name)
            .unwrap_or_else(|| Ident::new(&format!("arg_{}", self.args.len()), Span::call_site()))
    }

    /// An argument's value: the plain signal, or (disturbed) a local bound to
    /// `x − ((p0 + p1) + …)` over the argument's disturbance shares.
    fn arg(&mut self, arg: &Arg, disturbed: bool) -> TokenStream {
        let shares = self.ir.arg_shares(arg);
        if !disturbed || shares.is_empty() {
            return self.signal(arg.signal);
        }
        if let Some((_, name, _)) = self.args.iter().find(|(a, _, _)| a == arg) {
            return quote!(#name);
        }
        let base = self.signal(arg.signal);
        let parts: Vec<TokenStream> = shares
            .iter()
            .map(|&(share, c)| {
                note(&mut self.reads.d, c);
                let c = index(c);
                match share {
                    Share::Rot(k) => {
                        note(&mut self.reads.rot, k);
                        let k = index(k);
                        quote!(rot[#k] * d[#c])
                    }
                    Share::NegRot(k) => {
                        note(&mut self.reads.rot, k);
                        let k = index(k);
                        quote!(-(rot[#k] * d[#c]))
                    }
                    Share::One => quote!(d[#c]),
                }
            })
            .collect();
        // `+` is left-associative: `p0 + p1 + p2` is `((p0 + p1) + p2)`.
        let value = if parts.len() == 1 {
            let p = &parts[0];
            quote!(#base - #p)
        } else {
            quote!(#base - (#(#parts)+*))
        };
        let name = self.arg_name(arg);
        self.args.push((*arg, name.clone(), value));
        quote!(#name)
    }

    /// `k * a`, `k * |a|`, `k * a * b`, `k * a * |b|` (left-associative).
    fn term(&mut self, t: &Term, disturbed: bool) -> TokenStream {
        let mut value = crate::tokens::float(t.coefficient);
        for f in &t.factors {
            let a = self.arg(&f.arg, disturbed);
            value = if f.modulus {
                quote!(#value * #a.abs())
            } else {
                quote!(#value * #a)
            };
        }
        value
    }

    fn entry(&mut self, e: &Entry) -> TokenStream {
        match e {
            Entry::Poly {
                coefficient,
                signs,
                vars,
                ..
            } => {
                let mut value = crate::tokens::float(*coefficient);
                for &i in signs {
                    note(&mut self.reads.s, i);
                    let i = index(i);
                    value = quote!(#value * s[#i]);
                }
                for v in vars {
                    let v = self.var(v);
                    value = quote!(#value * #v);
                }
                value
            }
            Entry::Term {
                term, pointwise, ..
            } => match self.ir.terms.get(*term) {
                Some(t) => self.term(t, *pointwise == Pointwise::Measured),
                // Cannot happen: the IR comes from `compile`, whose term indices are valid.
                None => quote!(::core::f64::NAN),
            },
        }
    }

    /// `let` bindings of the slices and argument locals this body reads.
    fn bindings(&self) -> TokenStream {
        let slice = |name: &str, field: TokenStream, max: Option<usize>| -> TokenStream {
            match max {
                Some(m) => {
                    let name = Ident::new(name, Span::call_site());
                    let n = index(m + 1);
                    quote!(let #name = &#field[..#n];)
                }
                None => TokenStream::new(),
            }
        };
        let r = self.reads;
        let mut out = TokenStream::new();
        out.extend(slice("x", quote!(sig.states), r.x));
        out.extend(slice("u", quote!(sig.inputs), r.u));
        out.extend(slice("rot", quote!(sig.rotation), r.rot));
        out.extend(slice("d", quote!(sig.disturbances), r.d));
        out.extend(slice("s", quote!(signs), r.s));
        out.extend(slice("theta", quote!(theta), r.theta));
        for (_, name, value) in &self.args {
            out.extend(quote!(let #name = #value;));
        }
        out
    }

    fn reads_sig(&self) -> bool {
        let r = self.reads;
        r.x.is_some() || r.u.is_some() || r.rot.is_some() || r.d.is_some()
    }
}

/// A parameter name, prefixed with `_` when the body does not read it (so
/// user crates see no `unused_variables` warning).
fn param(name: &str, used: bool) -> Ident {
    let name = if used {
        name.to_string()
    } else {
        format!("_{name}")
    };
    Ident::new(&name, Span::call_site())
}

/// One predictor's evaluation: the statements that write each structurally
/// nonzero (output, column) slot of `out` (after the bindings they read),
/// the buffer's length, and which parameters they read.
pub(crate) struct PredictorBody {
    pub(crate) stmts: TokenStream,
    pub(crate) len: usize,
    pub(crate) reads_sig: bool,
    pub(crate) reads_signs: bool,
}

/// The statements of `basic`, `augmented` or `measured` without the zero
/// fill: `regressors_update` runs them on a buffer whose other slots are
/// already zero, and each predictor's trait method fills with zeros (as the
/// interpreter does) and then runs them.
pub(crate) fn predictor(ir: &Ir, columns: &[Column]) -> PredictorBody {
    let n_out = ir.states.len();
    let n = columns.len();
    let mut body = Body::new(ir);
    let mut slots: Vec<(usize, TokenStream)> = Vec::new();
    for (j, col) in columns.iter().enumerate() {
        for o in col.outputs() {
            let values: Vec<TokenStream> = col
                .entries
                .iter()
                .filter(|e| e.output() == o)
                .map(|e| body.entry(e))
                .collect();
            let k = index(o * n + j);
            slots.push((o * n + j, quote!(out[#k] = #(#values)+*;)));
        }
    }
    slots.sort_by_key(|(k, _)| *k);
    let len = n * n_out;
    let bindings = body.bindings();
    let stmts = slots.into_iter().map(|(_, s)| s);
    let shape = if len > 0 {
        let l = index(len);
        quote!(let out = &mut out[..#l];)
    } else {
        TokenStream::new()
    };
    PredictorBody {
        stmts: quote! {
            #bindings
            #shape
            #(#stmts)*
        },
        len,
        reads_sig: body.reads_sig(),
        reads_signs: body.reads.s.is_some(),
    }
}

/// The trait methods of the three predictors: `regressors_update` (every
/// structurally nonzero slot, one arm per predictor) and `basic`,
/// `augmented`, `measured` (zeros, then `regressors_update`).
pub(crate) fn predictors(ir: &Ir) -> TokenStream {
    let kind = quote!(::leeway::__private::PredictorKind);
    let bodies = [
        (quote!(Basic), predictor(ir, &ir.predictors.basic)),
        (quote!(Augmented), predictor(ir, &ir.predictors.augmented)),
        (quote!(Measured), predictor(ir, &ir.predictors.measured)),
    ];
    let sig = param("sig", bodies.iter().any(|(_, b)| b.reads_sig));
    let signs = param("signs", bodies.iter().any(|(_, b)| b.reads_signs));
    let out = param("out", bodies.iter().any(|(_, b)| b.len > 0));
    let arms = bodies.iter().map(|(name, b)| {
        let stmts = &b.stmts;
        quote!(#kind::#name => { #stmts })
    });
    let filled = |name: TokenStream, b: &PredictorBody, signs_param: bool| {
        let l = index(b.len);
        let fill = if b.len > 0 {
            quote!(out[..#l].fill(0.0);)
        } else {
            TokenStream::new()
        };
        let (signature, signs_arg) = if signs_param {
            (
                quote!((&self, sig: &::leeway::__private::Signals<'_>, signs: &[f64], out: &mut [f64])),
                quote!(signs),
            )
        } else {
            (
                quote!((&self, sig: &::leeway::__private::Signals<'_>, out: &mut [f64])),
                quote!(&[]),
            )
        };
        let method = Ident::new(&name.to_string().to_lowercase(), Span::call_site());
        quote! {
            fn #method #signature {
                #fill
                self.regressors_update(#kind::#name, sig, #signs_arg, out)
            }
        }
    };
    let basic = filled(quote!(Basic), &bodies[0].1, false);
    let augmented = filled(quote!(Augmented), &bodies[1].1, true);
    let measured = filled(quote!(Measured), &bodies[2].1, true);
    quote! {
        fn regressors_update(&self, kind: #kind, #sig: &::leeway::__private::Signals<'_>, #signs: &[f64], #out: &mut [f64]) {
            match kind {
                #(#arms)*
            }
        }
        #basic
        #augmented
        #measured
    }
}

/// The body of `rhs`: per output, `θ_p * term + …` in term order, every
/// argument disturbed by all components of its medium.
pub(crate) fn rhs(ir: &Ir) -> TokenStream {
    let n_out = ir.states.len();
    let mut body = Body::new(ir);
    let mut stmts = Vec::new();
    for o in 0..n_out {
        let values: Vec<TokenStream> = ir
            .terms
            .iter()
            .filter(|t| t.output == o)
            .map(|t| {
                note(&mut body.reads.theta, t.parameter);
                let p = index(t.parameter);
                let term = body.term(t, true);
                quote!(theta[#p] * (#term))
            })
            .collect();
        let k = index(o);
        stmts.push(if values.is_empty() {
            quote!(out[#k] = 0.0;)
        } else {
            quote!(out[#k] = #(#values)+*;)
        });
    }
    let theta = param("theta", body.reads.theta.is_some());
    let sig = param("sig", body.reads_sig());
    let out_param = param("out", n_out > 0);
    let bindings = body.bindings();
    let shape = if n_out > 0 {
        let n = index(n_out);
        quote!(let out = &mut out[..#n];)
    } else {
        TokenStream::new()
    };
    quote! {
        (&self, #theta: &[f64], #sig: &::leeway::__private::Signals<'_>, #out_param: &mut [f64]) {
            #bindings
            #shape
            #(#stmts)*
        }
    }
}

/// The body of `step`: `rhs`, then `x⁺ = x + h·f` (`der`) or `x⁺ = f`
/// (`next`) per equation, as the trait's provided method computes it.
pub(crate) fn step(ir: &Ir) -> TokenStream {
    let n = ir.equations.len();
    let der = ir.equations.iter().any(|e| e.kind == EquationKind::Der);
    let stmts = ir.equations.iter().enumerate().map(|(o, e)| {
        let o = index(o);
        match e.kind {
            EquationKind::Der => quote!(next[#o] = x[#o] + h * f[#o];),
            EquationKind::Next => quote!(next[#o] = f[#o];),
        }
    });
    let h = param("h", der);
    let bindings = if n > 0 {
        let n = index(n);
        let x = if der {
            quote!(let x = &sig.states[..#n];)
        } else {
            TokenStream::new()
        };
        quote! {
            #x
            let f = &f[..#n];
            let next = &mut next[..#n];
        }
    } else {
        TokenStream::new()
    };
    quote! {
        (&self, theta: &[f64], #h: f64, sig: &::leeway::__private::Signals<'_>, f: &mut [f64], next: &mut [f64]) {
            ::leeway::__private::Model::rhs(self, theta, sig, f);
            #bindings
            #(#stmts)*
        }
    }
}
