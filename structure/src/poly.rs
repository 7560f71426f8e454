//! Exact canonical polynomials over the signals of a model, reduced to the
//! normal form that makes equal regressors compare equal: sign variables
//! square to one, and with a planar heading `cos² = 1 − sin²`.

use crate::exact::{Q, fmt_q};
use num_traits::{One, Zero};
use std::collections::BTreeMap;

/// A variable of the expansion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Var {
    /// The fixed sign of sign argument `i` within an experiment (`s² = 1`).
    Sign(usize),
    /// A (noisy, measured) state.
    State(usize),
    /// An exact input.
    Input(usize),
    /// `|input|`, evaluated pointwise (inputs are exact).
    AbsInput(usize),
    /// A rotation variable: with a planar heading `Rot(0) = cos ψ`, `Rot(1) = sin ψ`;
    /// with a measured rotation, one data column each.
    Rot(usize),
    /// A measured disturbance component (global component index).
    Measured(usize),
    /// An unmeasured disturbance component (global component index).
    Dist(usize),
}

/// A product of variables with positive powers, sorted by variable.
pub type Monomial = Vec<(Var, u32)>;

/// How monomials reduce.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NormalForm {
    /// `Rot(0)² = 1 − Rot(1)²` (planar heading).
    pub planar: bool,
}

/// A polynomial with exact rational coefficients, always in normal form and
/// without zero coefficients.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Poly {
    /// Monomial → coefficient.
    pub terms: BTreeMap<Monomial, Q>,
}

impl Poly {
    /// The zero polynomial.
    pub fn zero() -> Poly {
        Poly::default()
    }
    /// A constant.
    pub fn constant(q: Q) -> Poly {
        let mut p = Poly::zero();
        p.add_term(Vec::new(), q);
        p
    }
    /// A single variable.
    pub fn var(v: Var) -> Poly {
        let mut p = Poly::zero();
        p.add_term(vec![(v, 1)], Q::one());
        p
    }
    /// True when zero.
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }
    fn add_term(&mut self, m: Monomial, q: Q) {
        use std::collections::btree_map::Entry;
        if q.is_zero() {
            return;
        }
        match self.terms.entry(m) {
            Entry::Occupied(mut e) => {
                *e.get_mut() += q;
                if e.get().is_zero() {
                    e.remove();
                }
            }
            Entry::Vacant(e) => {
                e.insert(q);
            }
        }
    }
    /// `self + other`.
    pub fn add(&self, other: &Poly) -> Poly {
        let mut p = self.clone();
        for (m, q) in &other.terms {
            p.add_term(m.clone(), q.clone());
        }
        p
    }
    /// `q · self`.
    pub fn scale(&self, q: &Q) -> Poly {
        let mut p = Poly::zero();
        if q.is_zero() {
            return p;
        }
        for (m, c) in &self.terms {
            p.terms.insert(m.clone(), c * q);
        }
        p
    }
    /// `self − other`.
    pub fn sub(&self, other: &Poly) -> Poly {
        self.add(&other.scale(&-Q::one()))
    }
    /// `self · other`, reduced to normal form.
    pub fn mul(&self, other: &Poly, nf: NormalForm) -> Poly {
        let mut p = Poly::zero();
        for (ma, qa) in &self.terms {
            for (mb, qb) in &other.terms {
                let qab = qa * qb;
                let mut products = mul_monomials(ma, mb, nf);
                if products.len() == 1 {
                    // The usual case: no cos² to reduce, a coefficient 1.
                    if let Some((m, q)) = products.pop() {
                        p.add_term(m, if q.is_one() { qab } else { q * qab });
                    }
                    continue;
                }
                for (m, q) in products {
                    p.add_term(m, q * &qab);
                }
            }
        }
        p
    }
    /// Substitutes values for sign variables (`signs[i]` is ±1).
    pub fn with_signs(&self, signs: &[i8]) -> Poly {
        let mut p = Poly::zero();
        for (m, q) in &self.terms {
            let mut q = q.clone();
            let mut rest = Vec::with_capacity(m.len());
            for (v, e) in m {
                match v {
                    Var::Sign(i) => {
                        if signs.get(*i).copied().unwrap_or(1) < 0 && e % 2 == 1 {
                            q = -q;
                        }
                    }
                    _ => rest.push((*v, *e)),
                }
            }
            p.add_term(rest, q);
        }
        p
    }
    /// Drops the constant monomial (annihilated by zero-mean instruments).
    pub fn without_constant(&self) -> Poly {
        let mut p = self.clone();
        p.terms.remove(&Vec::new());
        p
    }
    /// Groups by the monomial in the variables selected by `pick`:
    /// `self = Σ key · rest`. Returns `key → rest`.
    pub fn split_by(&self, pick: impl Fn(&Var) -> bool) -> BTreeMap<Monomial, Poly> {
        let mut out: BTreeMap<Monomial, Poly> = BTreeMap::new();
        for (m, q) in &self.terms {
            let (key, rest): (Monomial, Monomial) = m.iter().partition(|(v, _)| pick(v));
            out.entry(key).or_default().add_term(rest, q.clone());
        }
        out.retain(|_, p| !p.is_zero());
        out
    }
    /// The total degree in the variables selected by `pick`.
    pub fn max_degree(&self, pick: impl Fn(&Var) -> bool) -> u32 {
        self.terms
            .keys()
            .map(|m| m.iter().filter(|(v, _)| pick(v)).map(|(_, e)| e).sum())
            .max()
            .unwrap_or(0)
    }
    /// Renders with the given variable names: `-2*s[water.u]*u*cos(psi) + 1`.
    pub fn render(&self, name: &dyn Fn(&Var) -> String) -> String {
        if self.terms.is_empty() {
            return "0".to_string();
        }
        let mut out = String::new();
        // Higher-degree monomials first reads like the paper (u^2 before u).
        let mut items: Vec<(&Monomial, &Q)> = self.terms.iter().collect();
        items.sort_by_key(|(m, _)| std::cmp::Reverse(m.iter().map(|(_, e)| *e).sum::<u32>()));
        for (i, (m, q)) in items.into_iter().enumerate() {
            let neg = *q < Q::zero();
            let mag = if neg { -q.clone() } else { q.clone() };
            if i == 0 {
                if neg {
                    out.push('-');
                }
            } else {
                out.push_str(if neg { " - " } else { " + " });
            }
            let body = render_monomial(m, name);
            if body.is_empty() {
                out.push_str(&fmt_q(&mag));
            } else if mag.is_one() {
                out.push_str(&body);
            } else {
                out.push_str(&format!("{}*{}", fmt_q(&mag), body));
            }
        }
        out
    }
}

/// `x*y^2`-style rendering of a monomial.
pub fn render_monomial(m: &Monomial, name: &dyn Fn(&Var) -> String) -> String {
    m.iter()
        .map(|(v, e)| {
            if *e == 1 {
                name(v)
            } else {
                format!("{}^{}", name(v), e)
            }
        })
        .collect::<Vec<_>>()
        .join("*")
}

fn mul_monomials(a: &Monomial, b: &Monomial, nf: NormalForm) -> Vec<(Monomial, Q)> {
    // Both sorted by variable: merge them, signs squaring to one.
    let mut product: Monomial = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let next = match (a.get(i), b.get(j)) {
            (Some(x), Some(y)) if x.0 == y.0 => {
                i += 1;
                j += 1;
                (x.0, x.1 + y.1)
            }
            (Some(x), Some(y)) if x.0 < y.0 => {
                i += 1;
                *x
            }
            (Some(x), None) => {
                i += 1;
                *x
            }
            (_, Some(y)) => {
                j += 1;
                *y
            }
            (None, None) => break,
        };
        product.push(next);
    }
    product.retain_mut(|(v, e)| match v {
        Var::Sign(_) if *e % 2 == 1 => {
            *e = 1;
            true
        }
        Var::Sign(_) => false,
        _ => true,
    });
    let cos = product
        .iter()
        .find(|(v, _)| *v == Var::Rot(0))
        .map_or(0, |(_, e)| *e);
    if !(nf.planar && cos >= 2) {
        return vec![(product, Q::one())];
    }
    let mut merged: BTreeMap<Var, u32> = BTreeMap::new();
    for (v, e) in a.iter().chain(b.iter()) {
        *merged.entry(*v).or_insert(0) += e;
    }
    let mut base: Monomial = Vec::new();
    let mut cos_pow = 0;
    for (v, e) in merged {
        match v {
            Var::Sign(_) => {
                if e % 2 == 1 {
                    base.push((v, 1));
                }
            }
            Var::Rot(0) if nf.planar => cos_pow = e,
            _ => base.push((v, e)),
        }
    }
    // cos^(2k+r) = cos^r (1 - sin^2)^k
    let k = cos_pow / 2;
    let r = cos_pow % 2;
    let mut out = Vec::new();
    for j in 0..=k {
        let coeff = binomial(k, j) * if j % 2 == 1 { -Q::one() } else { Q::one() };
        let mut m: BTreeMap<Var, u32> = base.iter().copied().collect();
        if r == 1 {
            m.insert(Var::Rot(0), 1);
        }
        if j > 0 {
            *m.entry(Var::Rot(1)).or_insert(0) += 2 * j;
        }
        out.push((m.into_iter().collect(), coeff));
    }
    out
}

fn binomial(n: u32, k: u32) -> Q {
    let mut r = Q::one();
    for i in 0..k {
        r = r * Q::from_integer((n - i).into()) / Q::from_integer((i + 1).into());
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    const NF: NormalForm = NormalForm { planar: true };

    fn name(v: &Var) -> String {
        match v {
            Var::Rot(0) => "c".into(),
            Var::Rot(1) => "s".into(),
            other => format!("{other:?}"),
        }
    }

    #[test]
    fn cos_squared_reduces() {
        let c = Poly::var(Var::Rot(0));
        let s = Poly::var(Var::Rot(1));
        let sum = c.mul(&c, NF).add(&s.mul(&s, NF));
        assert_eq!(sum, Poly::constant(Q::one()));
        let c4 = c.mul(&c, NF).mul(&c.mul(&c, NF), NF);
        assert_eq!(c4.render(&name), "s^4 - 2*s^2 + 1");
    }

    #[test]
    fn signs_square_to_one() {
        let s = Poly::var(Var::Sign(0));
        assert_eq!(s.mul(&s, NF), Poly::constant(Q::one()));
        let p = s.mul(&Poly::var(Var::State(0)), NF);
        assert_eq!(p.with_signs(&[-1]).render(&name), "-State(0)");
    }

    #[test]
    fn normal_form_is_idempotent() {
        let c = Poly::var(Var::Rot(0));
        let p = c.mul(&c, NF).mul(&Poly::var(Var::State(1)), NF);
        let again = p.mul(&Poly::constant(Q::one()), NF);
        assert_eq!(p, again);
    }
}
