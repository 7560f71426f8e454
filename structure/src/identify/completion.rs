//! The completion: a set of sign patterns, at most one per sign character,
//! that identifies whatever the symbolic signs identify in some blocks.
//!
//! Per row family (output, monomial without its signs) the evaluation matrix
//! of its sign characters is brought to full column rank, each new pattern a
//! non-root of a null-vector polynomial found variable by variable. Under
//! per-experiment centring the families of monomials constant within an
//! experiment are skipped (the centring annihilates them), so n media need
//! n experiments, not n + 1.

use crate::exact::{Q, Small, field_row, insert_row, small_to_q};
use crate::ir::{Centring, SignPattern, StructVar};
use num_traits::{One, Zero};
use std::collections::{BTreeMap, BTreeSet};

use super::analysis::Analysis;
use super::structural::{FamilyKey, odd_signs};

/// A multilinear polynomial in sign variables: odd sign set → coefficient.
type SignPolynomial = BTreeMap<Vec<usize>, Q>;

/// One family of rows for [`Analysis::completion`]: its sign characters and
/// the reduced row echelon form of its evaluation matrix so far, in `i128`
/// fractions while they fit (the matrix holds ±1), else exactly in big
/// rationals, rebuilt from the rows added.
struct Family {
    chars: Vec<Vec<usize>>,
    /// The evaluation rows added so far (±1 per character).
    rows: Vec<Vec<i8>>,
    basis: Basis,
}

/// A reduced basis: pivot column and row.
enum Basis {
    Small(Vec<(usize, Vec<Small>)>),
    Big(Vec<(usize, Vec<Q>)>),
}

impl Basis {
    fn len(&self) -> usize {
        match self {
            Basis::Small(b) => b.len(),
            Basis::Big(b) => b.len(),
        }
    }
}

impl Family {
    fn new(chars: Vec<Vec<usize>>) -> Family {
        Family {
            chars,
            rows: Vec::new(),
            basis: Basis::Small(Vec::new()),
        }
    }
    /// Adds the row of pattern `p`.
    fn add(&mut self, p: &SignPattern) {
        if self.basis.len() == self.chars.len() {
            return;
        }
        let signs: Vec<i8> = self
            .chars
            .iter()
            .map(|ch| {
                if ch.iter().filter(|i| p[**i] < 0).count() % 2 == 1 {
                    -1
                } else {
                    1
                }
            })
            .collect();
        self.rows.push(signs);
        let added = match &mut self.basis {
            Basis::Small(b) => field_row::<Small>(&self.rows[self.rows.len() - 1])
                .and_then(|row| insert_row(b, row)),
            Basis::Big(b) => {
                field_row::<Q>(&self.rows[self.rows.len() - 1]).and_then(|row| insert_row(b, row))
            }
        };
        if added.is_none() {
            // Overflow: redo every row exactly (cannot overflow).
            let mut big = Vec::new();
            for r in &self.rows {
                if let Some(row) = field_row::<Q>(r) {
                    let _ = insert_row(&mut big, row);
                }
            }
            self.basis = Basis::Big(big);
        }
    }
    /// `Σ c_S χ_S` for a null vector `c` of the evaluation matrix, if it is
    /// rank deficient: a free column `j`, minus its pivot rows' entries.
    fn null_poly(&self) -> Option<SignPolynomial> {
        let pivots: BTreeSet<usize> = match &self.basis {
            Basis::Small(b) => b.iter().map(|(pc, _)| *pc).collect(),
            Basis::Big(b) => b.iter().map(|(pc, _)| *pc).collect(),
        };
        let j = (0..self.chars.len()).find(|j| !pivots.contains(j))?;
        let mut poly = BTreeMap::new();
        poly.insert(self.chars[j].clone(), Q::one());
        // Column `j` of each basis row only (the rest is never needed).
        let entries: Vec<(usize, Q)> = match &self.basis {
            Basis::Small(b) => b
                .iter()
                .map(|(pc, row)| (*pc, small_to_q(&row[j])))
                .collect(),
            Basis::Big(b) => b.iter().map(|(pc, row)| (*pc, row[j].clone())).collect(),
        };
        for (pc, x) in entries {
            if !x.is_zero() {
                poly.insert(self.chars[pc].clone(), -x);
            }
        }
        Some(poly)
    }
}

/// A point of {±1}ⁿ (over `args`, the rest +1) where the first of these
/// nonzero multilinear polynomials `Σ c_S χ_S` does not vanish, and as many
/// of the others as the choices allow: variable by variable, write each
/// `g + s·h`; if `h ≠ 0` one of `g + h`, `g − h` is nonzero (they differ by
/// `2h`), so a polynomial forbids at most one sign; the first one alive is
/// obeyed, the others by majority. The first stays nonzero to the end, a
/// nonzero constant.
fn nonzero_point(polys: Vec<SignPolynomial>, args: &[usize], n: usize) -> SignPattern {
    let mut p = vec![1i8; n];
    let mut alive = polys;
    for &i in args {
        // For each polynomial: (g + h, g − h), or None when s_i is absent.
        let split: Vec<Option<(SignPolynomial, SignPolynomial)>> = alive
            .iter()
            .map(|poly| {
                if !poly.keys().any(|set| set.binary_search(&i).is_ok()) {
                    return None;
                }
                let mut plus: SignPolynomial = BTreeMap::new();
                let mut minus: SignPolynomial = BTreeMap::new();
                for (set, c) in poly {
                    match set.binary_search(&i) {
                        Ok(k) => {
                            let mut rest = set.clone();
                            rest.remove(k);
                            *plus.entry(rest.clone()).or_insert_with(Q::zero) += c;
                            *minus.entry(rest).or_insert_with(Q::zero) -= c;
                        }
                        Err(_) => {
                            *plus.entry(set.clone()).or_insert_with(Q::zero) += c;
                            *minus.entry(set.clone()).or_insert_with(Q::zero) += c;
                        }
                    }
                }
                plus.retain(|_, c| !c.is_zero());
                minus.retain(|_, c| !c.is_zero());
                Some((plus, minus))
            })
            .collect();
        let first_forbids_plus = matches!(&split[0], Some((plus, _)) if plus.is_empty());
        let first_forbids_minus = matches!(&split[0], Some((_, minus)) if minus.is_empty());
        let sign = if first_forbids_plus {
            -1
        } else if first_forbids_minus {
            1
        } else {
            let kills = |minus_side: bool| {
                split
                    .iter()
                    .filter(|s| match s {
                        Some((plus, minus)) => {
                            if minus_side {
                                minus.is_empty()
                            } else {
                                plus.is_empty()
                            }
                        }
                        None => false,
                    })
                    .count()
            };
            if kills(true) < kills(false) { -1 } else { 1 }
        };
        p[i] = sign;
        alive = alive
            .into_iter()
            .zip(split)
            .filter_map(|(poly, s)| match s {
                None => Some(poly),
                Some((plus, minus)) => {
                    let next = if sign > 0 { plus } else { minus };
                    (!next.is_empty()).then_some(next)
                }
            })
            .collect();
    }
    p
}
impl Analysis<'_> {
    /// A set of patterns over `args` that identifies whatever the symbolic
    /// signs identify in these blocks, all-plus first. Rows of one family
    /// (output, monomial without its signs) are `Σ_S χ_S(p)·b_S` over the
    /// sign characters `S` the family holds, so a set whose evaluation
    /// matrix `[χ_S(p)]` has full column rank in every family has the
    /// symbolic null space. While a family is rank deficient, a null vector
    /// `c` of its matrix gives the nonzero multilinear polynomial `Σ c_S χ_S`;
    /// a point where it does not vanish (found variable by variable, keeping
    /// as many other deficient families' polynomials nonzero as possible)
    /// raises that family's rank. At most one pattern per character.
    /// The patterns are over `args` only (see [`Patterns::Local`]).
    pub(super) fn completion(&self, args: &[usize], blocks: &[usize]) -> Vec<SignPattern> {
        // Characters by position in `args`.
        let local = |vars: &[(StructVar, u32)]| -> Vec<usize> {
            odd_signs(vars, args)
                .iter()
                .filter_map(|i| args.binary_search(i).ok())
                .collect()
        };
        let mut by_family: BTreeMap<FamilyKey, BTreeSet<Vec<usize>>> = BTreeMap::new();
        for &b in blocks {
            for &c in &self.blocks[b] {
                for (o, _, vars) in &self.structural.cols[c] {
                    let rest: Vec<(StructVar, u32)> = vars
                        .iter()
                        .filter(|(v, _)| !matches!(v, StructVar::Sign(_)))
                        .copied()
                        .collect();
                    // A monomial constant within an experiment gives no row
                    // under per-experiment centring (symbolic or not), so its
                    // family needs no pattern of its own.
                    if rest.is_empty() && self.names.centring == Centring::Experiment {
                        continue;
                    }
                    let entry = by_family.entry((*o, rest.clone())).or_default();
                    entry.insert(local(vars));
                    if rest.is_empty() {
                        entry.insert(Vec::new());
                    }
                }
            }
        }
        let mut families: Vec<Family> = by_family
            .into_values()
            .filter(|chars| chars.len() > 1)
            .map(|chars| Family::new(chars.into_iter().collect()))
            .collect();
        let positions: Vec<usize> = (0..args.len()).collect();
        let mut set = vec![vec![1i8; args.len()]];
        for f in &mut families {
            f.add(&set[0]);
        }
        loop {
            let polys: Vec<SignPolynomial> =
                families.iter().filter_map(Family::null_poly).collect();
            if polys.is_empty() {
                break;
            }
            let p = nonzero_point(polys, &positions, args.len());
            for f in &mut families {
                f.add(&p);
            }
            set.push(p);
        }
        set
    }
}
