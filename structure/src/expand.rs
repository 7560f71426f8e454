//! Passes 3–4, signs and expansion: substitute `a = x_l − Σ_j R_lj v_j` into
//! every term, fix each modulus by its sign (`|a| = s_a·a`), expand the
//! squares and group by the disturbance monomial: degree 0 → `Φ`, `v_j` →
//! `ρ_(j,p)`, `v_j v_m` → `λ_(jm,p)`. Measured media give `Φ2` columns
//! evaluated pointwise.
//!
//! A sign argument is fixed per experiment only when it is relative to a
//! medium the predictor does not take from data (paper A7); a plain state's
//! modulus ([`SignArg::pointwise`](crate::ir::SignArg::pointwise)) is
//! evaluated sample by sample by every predictor, and the analysis keeps its
//! sign symbolic. Structural polynomials keep the monomials that are
//! constant within an experiment; the centring
//! ([`Centring`](crate::ir::Centring)) decides which of them the instruments
//! annihilate, so a constant is identifiable exactly where the estimator
//! keeps it.

use crate::exact::{Q, fmt_q, to_f64};
use crate::ir::{
    Arg, Column, ColumnKind, Entry, EvalVar, Pointwise, SignArg, Signal, StructVar, StructuralEntry,
};
use crate::poly::{NormalForm, Poly, Var};
use crate::resolve::decl::{Resolved, RotationDecl};
use crate::terms::{ParamDecl, TermDecl, arg_medium, factors_text};
use num_traits::One;
use std::collections::BTreeMap;

/// Which disturbances are expanded as nuisance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Every medium unmeasured (IV2).
    Augmented,
    /// Measured media evaluated from data (IV3).
    Measured,
}

/// The normal form of this model's rotation.
pub fn normal_form(r: &Resolved) -> NormalForm {
    NormalForm {
        planar: matches!(r.rotation, RotationDecl::Planar { .. }),
    }
}

/// Sign arguments: every state argument under a modulus, in order of first
/// use. Its modulus is `s·a` with a sign variable `s`: fixed per experiment
/// for an argument relative to an unmeasured medium (paper A7), evaluated
/// pointwise (`s = sign(a)` sample by sample) for a plain state, and for a
/// measured medium in IV3.
pub fn sign_args(r: &Resolved, terms: &[TermDecl]) -> Vec<SignArg> {
    let mut out: Vec<SignArg> = Vec::new();
    let mut seen: std::collections::BTreeSet<Arg> = std::collections::BTreeSet::new();
    for t in terms {
        for f in &t.factors {
            if f.modulus && matches!(f.arg.signal, Signal::State(_)) && seen.insert(f.arg) {
                let medium = arg_medium(r, &f.arg);
                let measured = medium.is_some_and(|d| r.disturbances[d].measured);
                out.push(SignArg {
                    pointwise: medium.is_none(),
                    name: factors_text(
                        r,
                        &[crate::ir::Factor {
                            arg: f.arg,
                            modulus: false,
                        }],
                    ),
                    arg: f.arg,
                    measured,
                });
            }
        }
    }
    out
}

/// `R_l,j` as a polynomial: the body-frame share of earth component `pos` in state `l`.
fn rotation_entry(r: &Resolved, l: usize, pos: usize) -> Poly {
    match &r.rotation {
        RotationDecl::Planar { axes, .. } => {
            let c = Poly::var(Var::Rot(0));
            let s = Poly::var(Var::Rot(1));
            // Rz(ψ)ᵀ = [[c, s], [−s, c]] on (surge, sway).
            match (l == axes[0], l == axes[1], pos) {
                (true, _, 0) => c,
                (true, _, 1) => s,
                (_, true, 0) => s.scale(&-Q::one()),
                (_, true, 1) => c,
                _ => Poly::zero(),
            }
        }
        RotationDecl::Measured { rows, .. } => {
            match rows.get(l).and_then(|row| row.get(pos)).copied().flatten() {
                Some(k) => Poly::var(Var::Rot(k)),
                None => Poly::zero(),
            }
        }
        RotationDecl::None => Poly::zero(),
    }
}

/// What the expansion looks up per factor, indexed once per model (a model
/// may have 10⁴ states, sign arguments and body-frame components).
pub struct Lookup {
    nf: NormalForm,
    /// The sign argument of each argument under a modulus.
    sign_of: BTreeMap<Arg, usize>,
    /// The components of a body-frame disturbance acting on a state:
    /// (disturbance, state) → components.
    body: BTreeMap<(usize, usize), Vec<usize>>,
}

impl Lookup {
    /// Indexes a model's sign arguments and body-frame components.
    pub fn new(r: &Resolved, signs: &[SignArg]) -> Lookup {
        let mut body: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
        for (d, dist) in r.disturbances.iter().enumerate() {
            if dist.earth {
                continue;
            }
            for &c in &dist.components {
                if let Some(l) = r.components[c].state {
                    body.entry((d, l)).or_default().push(c);
                }
            }
        }
        Lookup {
            nf: normal_form(r),
            sign_of: signs
                .iter()
                .enumerate()
                .rev()
                .map(|(i, s)| (s.arg, i))
                .collect(),
            body,
        }
    }
}

/// The argument `a` as a polynomial (disturbance components as variables).
pub fn arg_poly(r: &Resolved, arg: &Arg, view: View, lookup: &Lookup) -> Poly {
    let nf = lookup.nf;
    let l = match arg.signal {
        Signal::Input(i) => return Poly::var(Var::Input(i)),
        Signal::State(l) => l,
    };
    let mut p = Poly::var(Var::State(l));
    let Some(ri) = arg.relative else { return p };
    let d = r.relatives[ri].1;
    let dist = &r.disturbances[d];
    let measured_here = dist.measured && view == View::Measured;
    if !dist.earth {
        // Body frame: only the components given for this state act on it.
        for &c in lookup.body.get(&(d, l)).into_iter().flatten() {
            let v = if measured_here {
                Var::Measured(c)
            } else {
                Var::Dist(c)
            };
            p = p.sub(&Poly::var(v));
        }
        return p;
    }
    for (pos, &c) in dist.components.iter().enumerate() {
        let v = if measured_here {
            Var::Measured(c)
        } else {
            Var::Dist(c)
        };
        let share = rotation_entry(r, l, pos);
        if !share.is_zero() {
            p = p.sub(&share.mul(&Poly::var(v), nf));
        }
    }
    p
}

/// `coefficient · Π factors` with every state modulus replaced by its sign
/// variable.
pub fn term_poly(r: &Resolved, t: &TermDecl, view: View, lookup: &Lookup) -> Poly {
    let nf = lookup.nf;
    let mut p = Poly::constant(t.coefficient.clone());
    for f in &t.factors {
        let base = if f.modulus {
            match f.arg.signal {
                Signal::Input(i) => Poly::var(Var::AbsInput(i)),
                Signal::State(_) => {
                    // |a| = s_a·a. For a measured medium in the measured view the
                    // modulus is evaluated pointwise, but its sign still matters
                    // structurally: a sign change (even within one experiment)
                    // separates a·|b| from a·b. The analysis decides per experiment
                    // whether that sign is fixed or varies.
                    let a = arg_poly(r, &f.arg, view, lookup);
                    match lookup.sign_of.get(&f.arg).copied() {
                        Some(i) => Poly::var(Var::Sign(i)).mul(&a, nf),
                        None => a,
                    }
                }
            }
        } else {
            arg_poly(r, &f.arg, view, lookup)
        };
        p = p.mul(&base, nf);
    }
    p
}

fn column_name(kind: &ColumnKind, params: &[ParamDecl], r: &Resolved) -> String {
    let comp = |c: usize| r.components[c].name.name.clone();
    match kind {
        ColumnKind::Theta { parameter } => params[*parameter].name.clone(),
        ColumnKind::Rho {
            component,
            parameter,
        } => format!("rho[{},{}]", comp(*component), params[*parameter].name),
        ColumnKind::Lambda {
            components: [a, b],
            parameter,
        } if a == b => {
            format!("lambda[{}^2,{}]", comp(*a), params[*parameter].name)
        }
        ColumnKind::Lambda {
            components: [a, b],
            parameter,
        } => {
            format!(
                "lambda[{}*{},{}]",
                comp(*a),
                comp(*b),
                params[*parameter].name
            )
        }
    }
}

fn eval_entries(output: usize, p: &Poly) -> Vec<Entry> {
    p.terms
        .iter()
        .map(|(m, q)| {
            let mut signs = Vec::new();
            let mut vars = Vec::new();
            for (v, e) in m {
                let ev = match v {
                    Var::Sign(i) => {
                        signs.push(*i);
                        continue;
                    }
                    Var::State(i) => EvalVar::State(*i),
                    Var::Input(i) => EvalVar::Input(*i),
                    Var::AbsInput(i) => EvalVar::AbsInput(*i),
                    Var::Rot(i) => EvalVar::Rot(*i),
                    // Disturbances are factored out into nuisance parameters and
                    // measured media are evaluated pointwise: neither reaches here.
                    Var::Measured(_) | Var::Dist(_) => continue,
                };
                for _ in 0..*e {
                    vars.push(ev);
                }
            }
            Entry::Poly {
                output,
                coefficient: to_f64(q),
                coefficient_exact: fmt_q(q),
                signs,
                vars,
            }
        })
        .collect()
}

fn structural_entries(output: usize, p: &Poly) -> Vec<StructuralEntry> {
    p.terms
        .iter()
        .map(|(m, q)| StructuralEntry {
            output,
            coefficient: fmt_q(q),
            vars: m
                .iter()
                .filter_map(|(v, e)| {
                    let sv = match v {
                        Var::Sign(i) => StructVar::Sign(*i),
                        Var::State(i) => StructVar::State(*i),
                        Var::Input(i) => StructVar::Input(*i),
                        Var::AbsInput(i) => StructVar::AbsInput(*i),
                        Var::Rot(i) => StructVar::Rot(*i),
                        Var::Measured(i) => StructVar::Measured(*i),
                        Var::Dist(_) => return None,
                    };
                    Some((sv, *e))
                })
                .collect(),
        })
        .collect()
}

/// Accumulated per-output polynomials of one column.
type Acc = BTreeMap<ColumnKind, BTreeMap<usize, Poly>>;

fn accumulate(acc: &mut Acc, t: &TermDecl, poly: &Poly) {
    let parts = poly.split_by(|v| matches!(v, Var::Dist(_)));
    for (key, rest) in parts {
        let kind = match key.as_slice() {
            [] => ColumnKind::Theta {
                parameter: t.parameter,
            },
            [(Var::Dist(j), 1)] => ColumnKind::Rho {
                component: *j,
                parameter: t.parameter,
            },
            [(Var::Dist(j), 2)] => ColumnKind::Lambda {
                components: [*j, *j],
                parameter: t.parameter,
            },
            [(Var::Dist(j), 1), (Var::Dist(m), 1)] => ColumnKind::Lambda {
                components: [*j, *m],
                parameter: t.parameter,
            },
            // A class term has degree ≤ 2 in v; nothing else can occur.
            _ => continue,
        };
        let slot = acc.entry(kind).or_default().entry(t.output).or_default();
        *slot = slot.add(&rest);
    }
}

fn order_key(k: &ColumnKind) -> (u8, usize, usize, usize) {
    match k {
        ColumnKind::Theta { parameter } => (0, *parameter, 0, 0),
        ColumnKind::Rho {
            component,
            parameter,
        } => (1, *parameter, *component, 0),
        ColumnKind::Lambda {
            components: [a, b],
            parameter,
        } => (2, *parameter, *a, *b),
    }
}

fn finish(
    acc: Acc,
    params: &[ParamDecl],
    r: &Resolved,
    pointwise: &BTreeMap<usize, Vec<(usize, usize, Poly)>>,
) -> Vec<Column> {
    let mut kinds: Vec<ColumnKind> = acc.keys().cloned().collect();
    for p in pointwise.keys() {
        let k = ColumnKind::Theta { parameter: *p };
        if !acc.contains_key(&k) {
            kinds.push(k);
        }
    }
    kinds.sort_by_key(order_key);
    kinds
        .into_iter()
        .filter_map(|kind| {
            let mut entries = Vec::new();
            let mut structural = Vec::new();
            if let Some(per_output) = acc.get(&kind) {
                for (o, p) in per_output {
                    entries.extend(eval_entries(*o, p));
                    structural.extend(structural_entries(*o, p));
                }
            }
            if let ColumnKind::Theta { parameter } = kind
                && let Some(list) = pointwise.get(&parameter)
            {
                for (term, output, poly) in list {
                    entries.push(Entry::Term {
                        output: *output,
                        term: *term,
                        pointwise: Pointwise::Measured,
                    });
                    structural.extend(structural_entries(*output, poly));
                }
            }
            if entries.is_empty() {
                return None;
            }
            Some(Column {
                name: column_name(&kind, params, r),
                kind,
                entries,
                structural,
            })
        })
        .collect()
}

/// The columns of the augmented (IV2) and measured (IV3) predictors, and the
/// basic one (IV1).
pub fn expand(
    r: &Resolved,
    params: &[ParamDecl],
    terms: &[TermDecl],
    signs: &[SignArg],
) -> (Vec<Column>, Vec<Column>, Vec<Column>) {
    let lookup = Lookup::new(r, signs);
    let mut aug: Acc = BTreeMap::new();
    let mut meas: Acc = BTreeMap::new();
    let mut pointwise: BTreeMap<usize, Vec<(usize, usize, Poly)>> = BTreeMap::new();
    for (ti, t) in terms.iter().enumerate() {
        let pa = term_poly(r, t, View::Augmented, &lookup);
        accumulate(&mut aug, t, &pa);
        let measured_medium = t
            .factors
            .iter()
            .find_map(|f| arg_medium(r, &f.arg))
            .is_some_and(|d| r.disturbances[d].measured);
        if measured_medium {
            let pm = term_poly(r, t, View::Measured, &lookup);
            pointwise
                .entry(t.parameter)
                .or_default()
                .push((ti, t.output, pm));
        } else {
            accumulate(&mut meas, t, &pa);
        }
    }
    let augmented = finish(aug, params, r, &BTreeMap::new());
    let measured = finish(meas, params, r, &pointwise);
    // Terms and θ columns by parameter, in one pass each (not one per parameter).
    let mut by_param: Vec<Vec<Entry>> = vec![Vec::new(); params.len()];
    for (ti, t) in terms.iter().enumerate() {
        if let Some(v) = by_param.get_mut(t.parameter) {
            v.push(Entry::Term {
                output: t.output,
                term: ti,
                pointwise: Pointwise::Undisturbed,
            });
        }
    }
    let mut theta_column: BTreeMap<usize, &Column> = BTreeMap::new();
    for c in &augmented {
        if let ColumnKind::Theta { parameter } = c.kind {
            theta_column.entry(parameter).or_insert(c);
        }
    }
    let basic: Vec<Column> = by_param
        .into_iter()
        .enumerate()
        .map(|(p, entries)| {
            let kind = ColumnKind::Theta { parameter: p };
            let structural = theta_column
                .get(&p)
                .map(|c| c.structural.clone())
                .unwrap_or_default();
            Column {
                name: params[p].name.clone(),
                kind,
                entries,
                structural,
            }
        })
        .collect();
    (basic, augmented, measured)
}
