//! Pass 2, terms: every right-hand side → a sum of class terms
//! `coefficient · θ_p · (a | |a| | a·b | a·|b|)`, rejecting everything outside
//! the second-order modulus class with a located error. A parameter alone
//! is a constant term. An expression's operand chain is walked iteratively,
//! recursing only into right operands, whose depth the grammar's guards
//! bound.

use crate::exact::{Q, coefficient_fits, decimal, fmt_q};
use crate::ir::{Arg, Factor, Signal};
use crate::resolve::decl::{Resolved, Symbol};
use crate::resolve::symbols::{invalid_number, names};
use leeway_grammar::{BinOp, Diagnostic, Expr, Ident, Path, Span};
use num_traits::{One, Zero};
use std::collections::BTreeMap;

/// Largest number of products one equation may expand to.
pub const MAX_PRODUCTS: usize = 4096;

/// A validated term.
#[derive(Clone, Debug)]
pub struct TermDecl {
    /// Output index.
    pub output: usize,
    /// Exact coefficient.
    pub coefficient: Q,
    /// Parameter index.
    pub parameter: usize,
    /// Canonical factors (modulus factor last).
    pub factors: Vec<Factor>,
    /// Source span.
    pub span: Span,
}

/// A parameter and where it is first used.
#[derive(Clone, Debug)]
pub struct ParamDecl {
    /// Name.
    pub name: String,
    /// First use.
    pub span: Span,
}

#[derive(Clone, Debug)]
enum Atom {
    Param(Ident),
    Signal(Arg),
    Abs(Arg),
}

#[derive(Clone, Debug)]
struct Product {
    coeff: Q,
    atoms: Vec<Atom>,
    span: Span,
}

struct Ctx<'a> {
    r: &'a Resolved,
    diags: &'a mut Vec<Diagnostic>,
}

/// Lowers every equation. Returns the parameters (first-use order) and terms.
pub fn lower_terms(r: &Resolved, diags: &mut Vec<Diagnostic>) -> (Vec<ParamDecl>, Vec<TermDecl>) {
    let mut params: Vec<ParamDecl> = Vec::new();
    let mut param_index: BTreeMap<String, usize> = BTreeMap::new();
    let mut terms: Vec<TermDecl> = Vec::new();
    let mut ctx = Ctx { r, diags };
    for eq in r.equations.iter().flatten() {
        let Some(products) = sum_of_products(&eq.rhs, &mut ctx) else {
            continue;
        };
        // Combine equal terms (same parameter and factors) by adding coefficients.
        let mut combined: BTreeMap<(usize, Vec<Factor>), usize> = BTreeMap::new();
        let mut local: Vec<TermDecl> = Vec::new();
        for p in products {
            let Some((pname, factors)) = classify(&p, &mut ctx) else {
                continue;
            };
            let pi = match param_index.get(&pname.name) {
                Some(i) => *i,
                None => {
                    param_index.insert(pname.name.clone(), params.len());
                    params.push(ParamDecl {
                        name: pname.name.clone(),
                        span: pname.span,
                    });
                    params.len() - 1
                }
            };
            match combined.get(&(pi, factors.clone())) {
                Some(&k) => {
                    local[k].coefficient += &p.coeff;
                    local[k].span = local[k].span.join(p.span);
                }
                None => {
                    combined.insert((pi, factors.clone()), local.len());
                    local.push(TermDecl {
                        output: eq.state,
                        coefficient: p.coeff,
                        parameter: pi,
                        factors,
                        span: p.span,
                    });
                }
            }
        }
        for t in local {
            if t.coefficient.is_zero() {
                ctx.diags.push(
                    Diagnostic::warning(
                        "terms-cancel",
                        format!(
                            "the terms of `{}` in this equation cancel",
                            params[t.parameter].name
                        ),
                    )
                    .with_primary(t.span, "sums to zero")
                    .with_help("remove them, or check the signs"),
                );
            } else {
                terms.push(t);
            }
        }
    }
    // Only parameters that survived in some term.
    let mut used = vec![false; params.len()];
    for t in &terms {
        used[t.parameter] = true;
    }
    let mut remap = vec![usize::MAX; params.len()];
    let mut kept = Vec::new();
    for (i, p) in params.into_iter().enumerate() {
        if used[i] {
            remap[i] = kept.len();
            kept.push(p);
        }
    }
    for t in &mut terms {
        t.parameter = remap[t.parameter];
    }
    common_terms(r, &kept, &terms, ctx.diags);
    (kept, terms)
}

fn sum_of_products(e: &Expr, ctx: &mut Ctx) -> Option<Vec<Product>> {
    match e {
        Expr::Number(n) => match decimal(&n.text) {
            Ok(q) => Some(vec![Product {
                coeff: q,
                atoms: Vec::new(),
                span: n.span,
            }]),
            Err(why) => {
                ctx.diags.push(invalid_number(why, n.span));
                None
            }
        },
        Expr::Path(p) => {
            let atom = resolve_path(p, ctx)?;
            Some(vec![Product {
                coeff: Q::one(),
                atoms: vec![atom],
                span: p.span,
            }])
        }
        Expr::Abs(inner, span) => {
            let arg = modulus_arg(inner, *span, ctx)?;
            Some(vec![Product {
                coeff: Q::one(),
                atoms: vec![Atom::Abs(arg)],
                span: *span,
            }])
        }
        Expr::Neg(inner, span) => {
            let mut v = sum_of_products(inner, ctx)?;
            for p in &mut v {
                p.coeff = -p.coeff.clone();
                p.span = p.span.join(*span);
            }
            Some(v)
        }
        Expr::Paren(inner, _) => sum_of_products(inner, ctx),
        Expr::Binary { .. } => {
            // A chain `a op b op c …` is a left-deep tree as long as the
            // expression: walk its left spine iteratively, recursing only into
            // right operands (bounded by the nesting and sign limits).
            let mut spine = Vec::new();
            let mut leftmost = e;
            while let Expr::Binary { op, lhs, rhs, span } = leftmost {
                spine.push((*op, rhs.as_ref(), *span));
                leftmost = lhs;
            }
            let mut acc = sum_of_products(leftmost, ctx);
            for (op, rhs, span) in spine.into_iter().rev() {
                let r = sum_of_products(rhs, ctx);
                acc = match (acc, r) {
                    (Some(l), Some(r)) => combine(op, l, r, rhs, span, ctx),
                    _ => None,
                };
            }
            acc
        }
    }
}

/// `l op r` for the products of both operands.
fn combine(
    op: BinOp,
    l: Vec<Product>,
    r: Vec<Product>,
    rhs: &Expr,
    span: Span,
    ctx: &mut Ctx,
) -> Option<Vec<Product>> {
    match op {
        BinOp::Add => Some([l, r].concat()),
        BinOp::Sub => {
            let mut v = l;
            v.extend(r.into_iter().map(|mut p| {
                p.coeff = -p.coeff;
                p
            }));
            Some(v)
        }
        BinOp::Mul => {
            if l.len().saturating_mul(r.len()) > MAX_PRODUCTS {
                ctx.diags.push(
                    Diagnostic::error(
                        "expression-too-large",
                        format!("this product expands to more than {MAX_PRODUCTS} terms"),
                    )
                    .with_primary(span, "too many terms")
                    .with_help(
                        "write the terms out; a second-order model has a handful per equation",
                    ),
                );
                return None;
            }
            let mut v = Vec::with_capacity(l.len() * r.len());
            for a in &l {
                for b in &r {
                    let mut atoms = a.atoms.clone();
                    atoms.extend(b.atoms.iter().cloned());
                    v.push(Product {
                        coeff: &a.coeff * &b.coeff,
                        atoms,
                        span: a.span.join(b.span),
                    });
                }
            }
            coefficients_fit(v, span, ctx)
        }
        BinOp::Div => {
            if r.iter().any(|p| !p.atoms.is_empty()) {
                ctx.diags.push(
                    Diagnostic::error("division-by-signal", "only division by a number is allowed")
                        .with_primary(rhs.span(), "not a number")
                        .with_help("a regressor divided by a signal or parameter is outside the second-order modulus class; fold known constants into a number"),
                );
                return None;
            }
            let d: Q = r
                .iter()
                .map(|p| p.coeff.clone())
                .fold(Q::zero(), |a, b| a + b);
            if d.is_zero() {
                ctx.diags.push(
                    Diagnostic::error("division-by-zero", "division by zero")
                        .with_primary(rhs.span(), "equals 0")
                        .with_help("check the coefficient"),
                );
                return None;
            }
            let v = l
                .into_iter()
                .map(|mut p| {
                    p.coeff /= d.clone();
                    p.span = p.span.join(rhs.span());
                    p
                })
                .collect();
            coefficients_fit(v, span, ctx)
        }
    }
}

fn coefficients_fit(v: Vec<Product>, span: Span, ctx: &mut Ctx) -> Option<Vec<Product>> {
    if v.iter().all(|p| coefficient_fits(&p.coeff)) {
        return Some(v);
    }
    ctx.diags.push(
        Diagnostic::error("invalid-number", "the numbers of this product multiply out beyond the range of an f64 (about 1e±307) or beyond 4096 bits of exact precision")
            .with_primary(span, "here")
            .with_help("multiply the numbers out and write the coefficient once, e.g. 2.5e-3*X*u"),
    );
    None
}

fn resolve_path(p: &Path, ctx: &mut Ctx) -> Option<Atom> {
    let base = ctx.r.symbols.get(&p.base.name).map(|(s, _)| *s);
    let atom = match &p.field {
        None => resolve_name(p, base, ctx),
        Some(field) => resolve_field(p, field, base, ctx),
    }?;
    // `?` marks a term's parameter as a candidate; on a signal it means nothing.
    if p.candidate && !matches!(atom, Atom::Param(_)) {
        ctx.diags.push(
            Diagnostic::error(
                "candidate-not-parameter",
                format!(
                    "`?{}` marks a signal, not a parameter, as a candidate",
                    p.text()
                ),
            )
            .with_primary(p.span, "a declared signal")
            .with_help("write the `?` before the term's parameter: `?Y_vv*v*|v|`"),
        );
        return None;
    }
    Some(atom)
}

/// A name alone: a parameter (undeclared), a state or an input; any other
/// declared name is an error here.
fn resolve_name(p: &Path, base: Option<Symbol>, ctx: &mut Ctx) -> Option<Atom> {
    let r = ctx.r;
    match base {
        None => Some(Atom::Param(p.base.clone())),
        Some(Symbol::State(i)) => Some(Atom::Signal(Arg {
            signal: Signal::State(i),
            relative: None,
        })),
        Some(Symbol::Input(i)) => Some(Atom::Signal(Arg {
            signal: Signal::Input(i),
            relative: None,
        })),
        Some(Symbol::Heading | Symbol::RotationColumn(_)) => {
            ctx.diags.push(
                Diagnostic::error("not-a-regressor-signal", format!("`{}` belongs to the rotation R and cannot appear in a term", p.base.name))
                    .with_primary(p.span, "part of R")
                    .with_help("R enters only through relative velocities such as `water.u`; terms use states, inputs and relative-velocity components"),
            );
            None
        }
        Some(Symbol::Disturbance(_) | Symbol::Component(_)) => {
            ctx.diags.push(
                Diagnostic::error(
                    "disturbance-used-directly",
                    format!(
                        "`{}` is a disturbance; it enters only through a relative velocity",
                        p.base.name
                    ),
                )
                .with_primary(p.span, "a disturbance")
                .with_help(
                    "declare `water = relative(current)` and write components such as `water.u`",
                ),
            );
            None
        }
        Some(Symbol::Relative(_)) => {
            ctx.diags.push(
                Diagnostic::error(
                    "relative-needs-component",
                    format!(
                        "`{}` is a relative velocity; name one of its components",
                        p.base.name
                    ),
                )
                .with_primary(p.span, "which component?")
                .with_help(format!(
                    "write `{}.{}`",
                    p.base.name,
                    r.states.first().map(|s| s.name.as_str()).unwrap_or("u")
                )),
            );
            None
        }
    }
}

/// `name.field`: a component of a relative velocity.
fn resolve_field(p: &Path, field: &Ident, base: Option<Symbol>, ctx: &mut Ctx) -> Option<Atom> {
    let r = ctx.r;
    match base {
        Some(Symbol::Relative(ri)) => match r.symbols.get(&field.name) {
            Some((Symbol::State(i), _)) => Some(Atom::Signal(Arg {
                signal: Signal::State(*i),
                relative: Some(ri),
            })),
            _ => {
                ctx.diags.push(
                    Diagnostic::error(
                        "unknown-name",
                        format!("`{}` has no component `{}`", p.base.name, field.name),
                    )
                    .with_primary(field.span, "not a state")
                    .with_help(format!(
                        "components of a relative velocity are states: {}",
                        names(&r.states)
                    )),
                );
                None
            }
        },
        Some(_) => {
            ctx.diags.push(
                Diagnostic::error("unknown-name", format!("`{}` has no components", p.base.name))
                    .with_primary(p.span, "only relative velocities have components")
                    .with_help("write the signal alone, or declare a relative velocity `name = relative(disturbance)`"),
            );
            None
        }
        None => {
            ctx.diags.push(
                Diagnostic::error(
                    "unknown-name",
                    format!("`{}` is not a declared relative velocity", p.base.name),
                )
                .with_primary(p.base.span, "not declared")
                .with_help(format!(
                    "declared relative velocities: {}",
                    names(
                        &r.relatives
                            .iter()
                            .map(|(i, _)| i.clone())
                            .collect::<Vec<_>>()
                    )
                )),
            );
            None
        }
    }
}

fn modulus_arg(inner: &Expr, span: Span, ctx: &mut Ctx) -> Option<Arg> {
    let mut e = inner;
    while let Expr::Paren(i, _) = e {
        e = i;
    }
    match e {
        Expr::Path(p) => match resolve_path(p, ctx)? {
            Atom::Signal(arg) => Some(arg),
            _ => {
                ctx.diags.push(
                    Diagnostic::error("parameter-in-modulus", format!("`{}` would be a parameter inside a modulus", p.base.name))
                        .with_primary(p.span, "parameter (not a declared signal)")
                        .with_help("parameters multiply a modulus, e.g. X*|u|; if this is a signal, declare it as a state or input"),
                );
                None
            }
        },
        Expr::Binary {
            op: BinOp::Add | BinOp::Sub,
            ..
        } => {
            ctx.diags.push(
                Diagnostic::error("modulus-of-sum", "a modulus of a sum is not in the model class")
                    .with_primary(span, "sum inside |..|")
                    .with_help("declare the medium once (`water = relative(current)`) and write `|water.u|`; that is the only sum a modulus may hold"),
            );
            None
        }
        Expr::Abs(..) => {
            ctx.diags.push(
                Diagnostic::error(
                    "nested-modulus",
                    "a modulus inside a modulus is not in the model class",
                )
                .with_primary(span, "nested |..|")
                .with_help("||a|| is |a|: write it once"),
            );
            None
        }
        _ => {
            ctx.diags.push(
                Diagnostic::error("modulus-of-product", "a modulus may hold one signal only")
                    .with_primary(span, "more than one signal or a number inside |..|")
                    .with_help("move numbers and parameters outside (2*X*|u|); |a*b| = |a|*|b| is outside the class"),
            );
            None
        }
    }
}

fn arg_text(r: &Resolved, a: &Arg) -> String {
    let base = match a.signal {
        Signal::State(i) => r.states[i].name.clone(),
        Signal::Input(i) => r.inputs[i].name.clone(),
    };
    match a.relative {
        Some(ri) => format!("{}.{}", r.relatives[ri].0.name, base),
        None => base,
    }
}

/// The factor text of a term in the user's names, e.g. `water.u*|water.u|`.
pub fn factors_text(r: &Resolved, factors: &[Factor]) -> String {
    if factors.is_empty() {
        // A constant term: its regressor is the number 1.
        return "1".to_string();
    }
    factors
        .iter()
        .map(|f| {
            if f.modulus {
                format!("|{}|", arg_text(r, &f.arg))
            } else {
                arg_text(r, &f.arg)
            }
        })
        .collect::<Vec<_>>()
        .join("*")
}

/// The medium (disturbance) of an argument.
pub fn arg_medium(r: &Resolved, a: &Arg) -> Option<usize> {
    a.relative.map(|ri| r.relatives[ri].1)
}

fn classify(p: &Product, ctx: &mut Ctx) -> Option<(Ident, Vec<Factor>)> {
    let params: Vec<&Ident> = p
        .atoms
        .iter()
        .filter_map(|a| {
            if let Atom::Param(i) = a {
                Some(i)
            } else {
                None
            }
        })
        .collect();
    let mut factors: Vec<Factor> = p
        .atoms
        .iter()
        .filter_map(|a| match a {
            Atom::Signal(arg) => Some(Factor {
                arg: *arg,
                modulus: false,
            }),
            Atom::Abs(arg) => Some(Factor {
                arg: *arg,
                modulus: true,
            }),
            Atom::Param(_) => None,
        })
        .collect();
    // Every check reports, in this order, before the term is refused.
    let one_parameter = check_one_parameter(p, &params, &factors, ctx);
    // A parameter alone is a constant force (thrust at a constant propeller
    // rate, a trim offset): a column like any other wherever the instruments
    // keep constants; `identify` decides under which centring it is identifiable.
    let in_class = check_order(p, &factors, ctx);
    let one_medium = check_one_medium(p, &factors, ctx);
    if !(one_parameter && in_class && one_medium) {
        return None;
    }
    factors.sort_by_key(|f| (f.modulus, f.arg));
    Some((params[0].clone(), factors))
}

/// A term has exactly one parameter.
fn check_one_parameter(p: &Product, params: &[&Ident], factors: &[Factor], ctx: &mut Ctx) -> bool {
    let r = ctx.r;
    let mut ok = true;
    if params.is_empty() {
        let message = if factors.is_empty() {
            "a constant term has no parameter".to_string()
        } else {
            format!("the term `{}` has no parameter", factors_text(r, factors))
        };
        ctx.diags.push(
            Diagnostic::error("missing-parameter", message)
                .with_primary(p.span, "no parameter")
                .with_help("every term is `parameter * regressor`; give it a parameter (e.g. K*r*v) and list its known value in `nominal { }`"),
        );
        ok = false;
    } else if params.len() > 1 {
        ctx.diags.push(nonlinear_parameter(p, params));
        ok = false;
    }
    ok
}

/// The error for a term with several parameters, each extra one labelled.
fn nonlinear_parameter(p: &Product, params: &[&Ident]) -> Diagnostic {
    let mut list: Vec<&str> = Vec::new();
    for q in params {
        if !list.contains(&q.name.as_str()) {
            list.push(q.name.as_str());
        }
    }
    let quoted: Vec<String> = list.iter().map(|n| format!("`{n}`")).collect();
    let msg = match quoted.as_slice() {
        [one] if params.len() == 2 => {
            format!("parameter {one} appears twice in one term: the model would not be linear in θ")
        }
        [one] => format!(
            "parameter {one} appears {} times in one term: the model would not be linear in θ",
            params.len()
        ),
        [a, b] => format!(
            "{a} and {b} are both parameters in one term: the model would not be linear in θ"
        ),
        [_, _, ..] => format!(
            "{} are all parameters in one term: the model would not be linear in θ",
            leeway_grammar::and_list(quoted.iter())
        ),
        [] => String::new(),
    };
    let mut d = Diagnostic::error("nonlinear-parameter", msg).with_primary(
        p.span,
        format!("{} unknown factors in one term", params.len()),
    );
    for extra in params.iter().skip(1).take(leeway_grammar::MAX_LISTED) {
        let label = if extra.name == params[0].name {
            format!("`{}` again", extra.name)
        } else {
            format!(
                "`{}` is not a declared signal, so it is a parameter",
                extra.name
            )
        };
        d = d.with_secondary(extra.span, label);
    }
    d.with_help(
        "each term has exactly one parameter; names not declared as signals are parameters, so declare misspelt or missing signals",
    )
}

/// At most second order, and not a product of two moduli.
fn check_order(p: &Product, factors: &[Factor], ctx: &mut Ctx) -> bool {
    let r = ctx.r;
    let mut ok = true;
    if factors.len() > 2 {
        ctx.diags.push(
            Diagnostic::error(
                "order-too-high",
                format!(
                    "the term `{}` is beyond second order",
                    factors_text(r, factors)
                ),
            )
            .with_primary(p.span, format!("{} signals in one term", factors.len()))
            .with_help("second-order modulus terms are a, |a|, a*b and a*|b|"),
        );
        ok = false;
    } else if factors.len() == 2 && factors.iter().all(|f| f.modulus) {
        ctx.diags.push(
            Diagnostic::error(
                "modulus-product",
                format!("`{}` is not in the model class", factors_text(r, factors)),
            )
            .with_primary(p.span, "two moduli in one term")
            .with_help("the class allows a*|b|; for |a|*|a| write a*a"),
        );
        ok = false;
    }
    ok
}

/// The signals of a term are relative to one medium at most.
fn check_one_medium(p: &Product, factors: &[Factor], ctx: &mut Ctx) -> bool {
    let r = ctx.r;
    let mut ok = true;
    let media: Vec<usize> = {
        let mut m: Vec<usize> = factors
            .iter()
            .filter_map(|f| arg_medium(r, &f.arg))
            .collect();
        m.sort_unstable();
        m.dedup();
        m
    };
    if media.len() > 1 {
        let list: Vec<String> = media
            .iter()
            .map(|d| r.disturbances[*d].name.name.clone())
            .collect();
        ctx.diags.push(
            Diagnostic::error("mixed-media", format!("one term mixes velocities relative to {}", list.join(" and ")))
                .with_primary(p.span, "two media in one term")
                .with_help("each term belongs to one medium (f_som1 or f_som2); split the physics into one term per medium"),
        );
        ok = false;
    }
    ok
}

/// The common-term rules of paper A11/A12.
fn common_terms(
    r: &Resolved,
    params: &[ParamDecl],
    terms: &[TermDecl],
    diags: &mut Vec<Diagnostic>,
) {
    type Shape = Vec<(Signal, bool)>;
    let shape = |t: &TermDecl| -> Shape {
        t.factors
            .iter()
            .map(|f| (f.arg.signal, f.modulus))
            .collect()
    };
    let medium =
        |t: &TermDecl| -> Option<usize> { t.factors.iter().find_map(|f| arg_medium(r, &f.arg)) };
    // Terms of one output and one shape, in order: grouping them first keeps
    // this linear in the number of terms (comparing all pairs was quadratic).
    let mut groups: BTreeMap<(usize, Shape), Vec<usize>> = BTreeMap::new();
    for (i, t) in terms.iter().enumerate() {
        groups.entry((t.output, shape(t))).or_default().push(i);
    }
    // Each later term is paired with one earlier term of the group: the first
    // (input-only terms), or the first of another medium (state terms).
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    for group in groups.values() {
        let mut first_of: BTreeMap<Option<usize>, usize> = BTreeMap::new();
        for &j in group {
            let b = &terms[j];
            let input_only = b
                .factors
                .iter()
                .all(|f| matches!(f.arg.signal, Signal::Input(_)));
            let earlier = if input_only {
                group
                    .iter()
                    .copied()
                    .find(|&i| i < j && terms[i].parameter != b.parameter)
            } else {
                first_of
                    .iter()
                    .filter(|(m, i)| **m != medium(b) && terms[**i].parameter != b.parameter)
                    .map(|(_, i)| *i)
                    .min()
            };
            if let Some(i) = earlier {
                pairs.push((i, j));
            }
            first_of.entry(medium(b)).or_insert(j);
        }
    }
    pairs.sort_unstable();
    for (i, j) in pairs {
        let (a, b) = (&terms[i], &terms[j]);
        {
            let (pa, pb) = (&params[a.parameter].name, &params[b.parameter].name);
            let input_only = a
                .factors
                .iter()
                .all(|f| matches!(f.arg.signal, Signal::Input(_)));
            if input_only {
                diags.push(
                    Diagnostic::error(
                        "common-input-term",
                        format!(
                            "`{pa}` and `{pb}` multiply the same input-only term `{}` in the equation of `{}`: they enter only as {pa} + {pb}",
                            factors_text(r, &a.factors),
                            r.states[a.output].name
                        ),
                    )
                    .with_primary(b.span, format!("`{pb}` here"))
                    .with_secondary(a.span, format!("`{pa}` here"))
                    .with_help(format!("merge them into one parameter, e.g. keep `{pa}` alone: no data can tell apart two parameters of one input-only term (paper A11)")),
                );
            } else if medium(a) != medium(b) {
                let name = |m: Option<usize>| {
                    m.map_or("no medium".to_string(), |d| {
                        r.disturbances[d].name.name.clone()
                    })
                };
                diags.push(
                    Diagnostic::note(
                        "common-state-term",
                        format!(
                            "`{pa}` ({}) and `{pb}` ({}) share the state-dependent term {} in `{}`",
                            name(medium(a)),
                            name(medium(b)),
                            factors_text(r, &strip(&a.factors)),
                            r.states[a.output].name
                        ),
                    )
                    .with_primary(b.span, "")
                    .with_secondary(a.span, "")
                    .with_help("they are told apart only if R·v1 ≠ R·v2 in the data (paper A12): the media must move differently"),
                );
            }
        }
    }
}

fn strip(f: &[Factor]) -> Vec<Factor> {
    f.iter()
        .map(|x| Factor {
            arg: Arg {
                signal: x.arg.signal,
                relative: None,
            },
            modulus: x.modulus,
        })
        .collect()
}

/// The exact coefficient as a short string.
pub fn coefficient_text(q: &Q) -> String {
    fmt_q(q)
}
