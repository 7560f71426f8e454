//! Exact scalars and exact linear algebra (no float tolerance anywhere).
//!
//! Elimination runs first over `i128` fractions with checked arithmetic and,
//! should any intermediate overflow, again over arbitrary-precision rationals:
//! the result is exact either way, and fast in the common case of small
//! integer coefficients.
//!
//! Literals are checked on their text ([`MAX_SIGNIFICANT_DIGITS`], a normal
//! `f64`'s range) before any big-integer arithmetic, and products of
//! literals stay within an `f64`'s range and [`MAX_COEFFICIENT_BITS`], so no
//! literal makes the exact arithmetic slow.

use num_bigint::BigInt;
use num_integer::Integer;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};

/// The exact rational type used throughout the structure compiler.
pub type Q = BigRational;

/// Most significant digits in a number literal (from its first to its last
/// non-zero digit): far beyond an `f64`'s 17, and small enough that no literal
/// makes the exact arithmetic slow.
pub const MAX_SIGNIFICANT_DIGITS: usize = 40;

/// Largest decimal exponent of a literal's leading digit: every non-zero
/// literal lies in `1e-307 ≤ |x| < 1e308`, so it is a normal `f64`.
pub const MAX_DECIMAL_EXPONENT: i64 = 307;

/// Largest size, in bits, of the numerator plus denominator of an exact
/// coefficient built from literals (`2.5e-3*X*u/7`): 4096 bits holds any
/// product of a few literals; more would only slow the exact arithmetic.
pub const MAX_COEFFICIENT_BITS: u64 = 4096;

/// Parses a decimal literal (`-0.015`, `1e-3`, `.5`) into an exact rational,
/// or `None`; see [`decimal`] for the reason.
pub fn parse_decimal(text: &str) -> Option<Q> {
    decimal(text).ok()
}

/// A literal as the user wrote it, cut to a readable length for a message.
pub fn shown(text: &str) -> String {
    let chars: Vec<char> = text.chars().take(33).collect();
    if chars.len() <= 32 {
        return text.to_string();
    }
    let head: String = chars[..24].iter().collect();
    format!("{head}… ({} characters)", text.chars().count())
}

/// Parses a decimal literal into an exact rational, or says in one sentence
/// why it is refused: not a decimal, more than [`MAX_SIGNIFICANT_DIGITS`]
/// significant digits, or a magnitude outside `1e-307 ≤ |x| < 1e308`. The
/// limits are checked on the text, before any big-integer arithmetic, with
/// checked integer operations.
pub fn decimal(text: &str) -> Result<Q, String> {
    let not_a_number = || format!("`{}` is not a number", shown(text));
    let t = text.trim();
    let (neg, t) = match t.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, t.strip_prefix('+').unwrap_or(t)),
    };
    let (mantissa, exp_text) = match t.find(['e', 'E']) {
        Some(i) => (&t[..i], Some(&t[i + 1..])),
        None => (t, None),
    };
    let (int, frac) = match mantissa.find('.') {
        Some(i) => (&mantissa[..i], &mantissa[i + 1..]),
        None => (mantissa, ""),
    };
    if int.is_empty() && frac.is_empty() {
        return Err(not_a_number());
    }
    if !int.bytes().chain(frac.bytes()).all(|c| c.is_ascii_digit()) {
        return Err(not_a_number());
    }
    let out_of_range = || {
        format!(
            "`{}` is out of range: a non-zero number must lie between 1e-{MAX_DECIMAL_EXPONENT} and 1e{} in magnitude",
            shown(text),
            MAX_DECIMAL_EXPONENT + 1
        )
    };
    // The exponent, bounded on its text: 7 digits already exceed any range.
    let exp: i64 = match exp_text {
        None => 0,
        Some(e) => {
            let (e_neg, digits) = match e.strip_prefix('-') {
                Some(r) => (true, r),
                None => (false, e.strip_prefix('+').unwrap_or(e)),
            };
            if digits.is_empty() || !digits.bytes().all(|c| c.is_ascii_digit()) {
                return Err(not_a_number());
            }
            let digits = digits.trim_start_matches('0');
            if digits.len() > 6 {
                // Zero times any power of ten is still zero.
                if int.bytes().chain(frac.bytes()).all(|c| c == b'0') {
                    return Ok(Q::zero());
                }
                return Err(out_of_range());
            }
            let v: i64 = digits.parse().unwrap_or(0);
            if e_neg { -v } else { v }
        }
    };
    let all = || int.bytes().chain(frac.bytes());
    let Some(lead) = all().position(|c| c != b'0') else {
        return Ok(Q::zero());
    };
    let last = int.len() + frac.len() - 1 - all().rev().position(|c| c != b'0').unwrap_or(0);
    let significant = last + 1 - lead;
    if significant > MAX_SIGNIFICANT_DIGITS {
        return Err(format!(
            "`{}` has {significant} significant digits; at most {MAX_SIGNIFICANT_DIGITS} are accepted",
            shown(text)
        ));
    }
    // The power of ten of the leading digit: lengths are below 2^21, the exponent below 10^6.
    let leading = (int.len() as i64) - 1 - (lead as i64) + exp;
    if !(-MAX_DECIMAL_EXPONENT..=MAX_DECIMAL_EXPONENT).contains(&leading) {
        return Err(out_of_range());
    }
    let digits: String = all().skip(lead).take(significant).map(char::from).collect();
    let mut num: BigInt = digits.parse().map_err(|_| not_a_number())?;
    if neg {
        num = -num;
    }
    // The value is digits × 10^scale, |scale| ≤ 307 + 40.
    let scale = leading - (significant as i64 - 1);
    let p = num_traits::pow(BigInt::from(10), scale.unsigned_abs() as usize);
    Ok(if scale >= 0 {
        Q::from_integer(num * p)
    } else {
        Q::new(num, p)
    })
}

/// Whether an exact coefficient is small enough for the exact arithmetic
/// ([`MAX_COEFFICIENT_BITS`]) and, when non-zero, within the range of a
/// normal `f64` (about `2^-1020 … 2^1023`).
pub fn coefficient_fits(q: &Q) -> bool {
    if Zero::is_zero(q) {
        return true;
    }
    let (n, d) = (q.numer().bits(), q.denom().bits());
    if n.saturating_add(d) > MAX_COEFFICIENT_BITS {
        return false;
    }
    let log2 = n as i64 - d as i64;
    (-1020..=1023).contains(&log2)
}

/// The nearest `f64` to an exact rational (ties to even), so generated code
/// and the interpreter start from the same bits.
pub fn to_f64(q: &Q) -> f64 {
    if Zero::is_zero(q) {
        return 0.0;
    }
    // Scale to a 64-bit-plus integer quotient, then let the float division of
    // two exactly representable halves round once. For the coefficients a model
    // holds (short decimals) numerator and denominator fit 2^53 and one division
    // is correctly rounded.
    if let (Some(n), Some(d)) = (q.numer().to_i64(), q.denom().to_i64())
        && n.unsigned_abs() <= (1 << 53)
        && d.unsigned_abs() <= (1 << 53)
    {
        return n as f64 / d as f64;
    }
    // Long rationals: 128 significant bits, then one rounding.
    let neg = q.is_negative();
    let a = q.abs();
    let (n, d) = (a.numer().clone(), a.denom().clone());
    let shift = 128i64 - (n.bits() as i64 - d.bits() as i64);
    let scaled = if shift >= 0 {
        (n << shift as usize) / d
    } else {
        n / (d << (-shift) as usize)
    };
    let v = scale_by_pow2(scaled.to_f64().unwrap_or(f64::INFINITY), -shift);
    if neg { -v } else { v }
}

/// `x · 2^e`, exactly (each factor is a power of two built from its bits).
fn scale_by_pow2(mut x: f64, mut e: i64) -> f64 {
    while e != 0 {
        let step = e.clamp(-1000, 1000);
        x *= f64::from_bits(((1023 + step) as u64) << 52);
        e -= step;
    }
    x
}

/// Exact rational rendering: `3`, `-1/2`.
pub fn fmt_q(q: &Q) -> String {
    if q.is_integer() {
        q.numer().to_string()
    } else {
        format!("{}/{}", q.numer(), q.denom())
    }
}

/// Parses [`fmt_q`]'s output.
pub fn parse_q(s: &str) -> Option<Q> {
    match s.split_once('/') {
        Some((n, d)) => {
            let d: BigInt = d.parse().ok()?;
            if d.is_zero() {
                return None;
            }
            Some(Q::new(n.parse().ok()?, d))
        }
        None => Some(Q::from_integer(s.parse().ok()?)),
    }
}

/// A field with fallible operations (overflow returns `None`).
pub(crate) trait Field: Clone + PartialEq {
    fn is_zero(&self) -> bool;
    fn sub(&self, o: &Self) -> Option<Self>;
    fn mul(&self, o: &Self) -> Option<Self>;
    fn div(&self, o: &Self) -> Option<Self>;
    fn from_q(q: &Q) -> Option<Self>;
    fn to_q(&self) -> Q;
}

/// An `i128` fraction in lowest terms with a positive denominator.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Small {
    n: i128,
    d: i128,
}

impl Small {
    fn make(n: i128, d: i128) -> Option<Small> {
        if d == 0 {
            return None;
        }
        let g = n.gcd(&d);
        let (mut n, mut d) = if g == 0 { (0, 1) } else { (n / g, d / g) };
        if d < 0 {
            n = n.checked_neg()?;
            d = d.checked_neg()?;
        }
        Some(Small { n, d })
    }
}

impl Field for Small {
    fn is_zero(&self) -> bool {
        self.n == 0
    }
    fn sub(&self, o: &Self) -> Option<Self> {
        let g = self.d.gcd(&o.d);
        let l = (self.d / g).checked_mul(o.d)?;
        let a = self.n.checked_mul(l / self.d)?;
        let b = o.n.checked_mul(l / o.d)?;
        Small::make(a.checked_sub(b)?, l)
    }
    fn mul(&self, o: &Self) -> Option<Self> {
        let g1 = self.n.gcd(&o.d).max(1);
        let g2 = o.n.gcd(&self.d).max(1);
        Small::make(
            (self.n / g1).checked_mul(o.n / g2)?,
            (self.d / g2).checked_mul(o.d / g1)?,
        )
    }
    fn div(&self, o: &Self) -> Option<Self> {
        if o.n == 0 {
            return None;
        }
        self.mul(&Small::make(o.d, o.n)?)
    }
    fn from_q(q: &Q) -> Option<Self> {
        Small::make(q.numer().to_i128()?, q.denom().to_i128()?)
    }
    fn to_q(&self) -> Q {
        Q::new(BigInt::from(self.n), BigInt::from(self.d))
    }
}

impl Field for Q {
    fn is_zero(&self) -> bool {
        Zero::is_zero(self)
    }
    fn sub(&self, o: &Self) -> Option<Self> {
        Some(self - o)
    }
    fn mul(&self, o: &Self) -> Option<Self> {
        Some(self * o)
    }
    fn div(&self, o: &Self) -> Option<Self> {
        if Zero::is_zero(o) {
            None
        } else {
            Some(self / o)
        }
    }
    fn from_q(q: &Q) -> Option<Self> {
        Some(q.clone())
    }
    fn to_q(&self) -> Q {
        self.clone()
    }
}

/// Reduced row-echelon form of a matrix whose columns are taken in the given
/// order: which columns are pivots (linearly independent of the columns
/// before them), and for every other column its exact expression as a
/// combination of the pivot columns.
#[derive(Clone, Debug, PartialEq)]
pub struct Echelon {
    /// `pivot[j]`: column `j` is independent of columns `0..j`.
    pub pivot: Vec<bool>,
    /// For each non-pivot column `j`: `col_j = Σ q · col_k` over pivot columns `k`.
    pub combination: Vec<Vec<(usize, Q)>>,
}

impl Echelon {
    /// The rank.
    pub fn rank(&self) -> usize {
        self.pivot.iter().filter(|p| **p).count()
    }
    /// A basis of the null space: one vector per non-pivot column,
    /// `e_j − Σ q e_k`, as sparse `(column, value)` lists.
    pub fn null_space(&self) -> Vec<Vec<(usize, Q)>> {
        (0..self.pivot.len())
            .filter(|j| !self.pivot[*j])
            .map(|j| {
                let mut v = vec![(j, Q::one())];
                v.extend(self.combination[j].iter().map(|(k, q)| (*k, -q.clone())));
                v.sort_by_key(|(k, _)| *k);
                v
            })
            .collect()
    }
}

/// Exact RREF of a dense matrix given as rows (all of length `n_cols`).
pub fn echelon(rows: &[Vec<Q>], n_cols: usize) -> Echelon {
    if let Some(e) = echelon_in::<Small>(rows, n_cols) {
        return e;
    }
    // Overflow in the fast path: redo exactly with big rationals (cannot fail).
    echelon_in::<Q>(rows, n_cols).unwrap_or(Echelon {
        pivot: vec![false; n_cols],
        combination: vec![Vec::new(); n_cols],
    })
}

fn echelon_in<F: Field>(rows: &[Vec<Q>], n_cols: usize) -> Option<Echelon> {
    let mut m: Vec<Vec<F>> = Vec::with_capacity(rows.len());
    for r in rows {
        let row: Option<Vec<F>> = r.iter().map(F::from_q).collect();
        m.push(row?);
    }
    let mut pivot = vec![false; n_cols];
    let mut pivot_row_of: Vec<Option<usize>> = vec![None; n_cols];
    let mut next_row = 0;
    for col in 0..n_cols {
        let Some(p) = (next_row..m.len()).find(|&i| !m[i][col].is_zero()) else {
            continue;
        };
        m.swap(next_row, p);
        let inv = m[next_row][col].clone();
        for x in m[next_row][col..n_cols].iter_mut() {
            *x = x.div(&inv)?;
        }
        let pivot_row = m[next_row].clone();
        for (i, row) in m.iter_mut().enumerate() {
            if i != next_row && !row[col].is_zero() {
                let f = row[col].clone();
                for (x, pv) in row[col..n_cols].iter_mut().zip(&pivot_row[col..n_cols]) {
                    if !pv.is_zero() {
                        *x = x.sub(&f.mul(pv)?)?;
                    }
                }
            }
        }
        pivot[col] = true;
        pivot_row_of[col] = Some(next_row);
        next_row += 1;
        if next_row == m.len() {
            break;
        }
    }
    let mut combination = vec![Vec::new(); n_cols];
    for (j, comb) in combination.iter_mut().enumerate() {
        if pivot[j] {
            continue;
        }
        for (k, pr) in pivot_row_of.iter().enumerate() {
            if let Some(r) = pr
                && !m[*r][j].is_zero()
            {
                comb.push((k, m[*r][j].to_q()));
            }
        }
    }
    Some(Echelon { pivot, combination })
}

/// Adds one row to a reduced basis; `None` on overflow (the basis is then
/// left part-updated, and rebuilt by the caller in big rationals).
pub(crate) fn insert_row<F: Field>(
    basis: &mut Vec<(usize, Vec<F>)>,
    mut row: Vec<F>,
) -> Option<()> {
    for (pc, b) in basis.iter() {
        if !row[*pc].is_zero() {
            let f = row[*pc].clone();
            for (x, r) in row.iter_mut().zip(b) {
                if !r.is_zero() {
                    *x = x.sub(&f.mul(r)?)?;
                }
            }
        }
    }
    let Some(pc) = row.iter().position(|q| !q.is_zero()) else {
        return Some(());
    };
    let inv = row[pc].clone();
    for x in row.iter_mut() {
        if !x.is_zero() {
            *x = x.div(&inv)?;
        }
    }
    for (_, b) in basis.iter_mut() {
        if !b[pc].is_zero() {
            let f = b[pc].clone();
            for (x, r) in b.iter_mut().zip(&row) {
                if !r.is_zero() {
                    *x = x.sub(&f.mul(r)?)?;
                }
            }
        }
    }
    basis.push((pc, row));
    Some(())
}

/// A row of ±1 in a field.
pub(crate) fn field_row<F: Field>(signs: &[i8]) -> Option<Vec<F>> {
    let (one, minus) = (F::from_q(&Q::one())?, F::from_q(&-Q::one())?);
    Some(
        signs
            .iter()
            .map(|s| if *s < 0 { minus.clone() } else { one.clone() })
            .collect(),
    )
}

/// An `i128` fraction as a big rational.
pub(crate) fn small_to_q(x: &Small) -> Q {
    x.to_q()
}

/// A sparse row: `(column, value)` with columns increasing and no zero value.
pub type SparseRow = Vec<(usize, Q)>;

/// Exact RREF of a sparse matrix: the same [`Echelon`] as [`echelon`] on the
/// dense matrix (the reduced row echelon form is unique), at a cost that
/// follows the nonzeros rather than rows × columns. Rows are inserted one by
/// one into a reduced basis: a row is reduced by the basis rows of the
/// pivot columns it holds (in reduced form those touch no other pivot
/// column), its first remaining column becomes a pivot, and that column is
/// cleared from the other basis rows.
pub fn echelon_sparse(rows: &[SparseRow], n_cols: usize) -> Echelon {
    if let Some(e) = sparse_in::<Small>(rows, n_cols) {
        return e;
    }
    // Overflow in the fast path: redo exactly with big rationals (cannot fail).
    sparse_in::<Q>(rows, n_cols).unwrap_or(Echelon {
        pivot: vec![false; n_cols],
        combination: vec![Vec::new(); n_cols],
    })
}

/// `a − f·b` for sparse rows (columns increasing), without zeros.
fn axpy<F: Field>(a: &[(usize, F)], f: &F, b: &[(usize, F)]) -> Option<Vec<(usize, F)>> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let ca = a.get(i).map_or(usize::MAX, |e| e.0);
        let cb = b.get(j).map_or(usize::MAX, |e| e.0);
        if ca < cb {
            out.push(a[i].clone());
            i += 1;
        } else {
            let fb = f.mul(&b[j].1)?;
            let v = if ca == cb {
                i += 1;
                a[i - 1].1.sub(&fb)?
            } else {
                F::from_q(&Q::zero())?.sub(&fb)?
            };
            if !v.is_zero() {
                out.push((cb, v));
            }
            j += 1;
        }
    }
    Some(out)
}

fn sparse_in<F: Field>(rows: &[SparseRow], n_cols: usize) -> Option<Echelon> {
    let mut basis: Vec<Vec<(usize, F)>> = Vec::new();
    // The basis row of each pivot column.
    let mut pivot_of: Vec<Option<usize>> = vec![None; n_cols];
    for r in rows {
        let mut row: Vec<(usize, F)> = Vec::with_capacity(r.len());
        for (c, q) in r {
            if *c < n_cols && !Zero::is_zero(q) {
                row.push((*c, F::from_q(q)?));
            }
        }
        // Reduce by the basis rows of the pivot columns the row holds: their
        // values stay those of the row, as basis rows vanish on other pivots.
        let at_pivots: Vec<(usize, F)> = row
            .iter()
            .filter_map(|(c, x)| pivot_of[*c].map(|b| (b, x.clone())))
            .collect();
        for (b, f) in &at_pivots {
            row = axpy(&row, f, &basis[*b])?;
        }
        let Some((p, lead)) = row.first().cloned() else {
            continue;
        };
        for e in row.iter_mut() {
            e.1 = e.1.div(&lead)?;
        }
        for b in basis.iter_mut() {
            if let Ok(k) = b.binary_search_by_key(&p, |e| e.0) {
                let f = b[k].1.clone();
                *b = axpy(b, &f, &row)?;
            }
        }
        pivot_of[p] = Some(basis.len());
        basis.push(row);
    }
    let pivot: Vec<bool> = pivot_of.iter().map(Option::is_some).collect();
    let mut combination: Vec<Vec<(usize, Q)>> = vec![Vec::new(); n_cols];
    for (k, b) in pivot_of.iter().enumerate() {
        let Some(b) = b else { continue };
        for (j, v) in &basis[*b] {
            if !pivot[*j] {
                combination[*j].push((k, v.to_q()));
            }
        }
    }
    Some(Echelon { pivot, combination })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(n: i64, d: i64) -> Q {
        Q::new(n.into(), d.into())
    }

    #[test]
    fn decimals_are_exact() {
        assert_eq!(parse_decimal("0.00015"), Some(q(3, 20000)));
        assert_eq!(parse_decimal("-1e-3"), Some(q(-1, 1000)));
        assert_eq!(parse_decimal(".5"), Some(q(1, 2)));
        assert_eq!(parse_decimal("2.5E2"), Some(q(250, 1)));
        assert_eq!(parse_decimal("1."), Some(q(1, 1)));
        assert_eq!(parse_decimal("."), None);
        assert_eq!(parse_decimal("1e99999"), None);
        assert_eq!(parse_decimal("0e99999999999999999999"), Some(q(0, 1)));
        assert_eq!(
            parse_decimal("1.50000000000000000000000000000000000000000000000"),
            Some(q(3, 2))
        );
        assert_eq!(
            parse_decimal("0.000000000000000000000000000000000000000000000000001"),
            Some(Q::new(1.into(), num_traits::pow(BigInt::from(10), 51)))
        );
    }

    #[test]
    fn literal_limits_are_checked_on_the_text() {
        // Extreme exponents: `1e-9223372036854775808` must not wrap
        // `scale.abs()` (it once hung).
        for text in [
            "1e-9223372036854775808",
            "1e9223372036854775807",
            "1e399",
            "1e-399",
            "-1e308",
            "1e-308",
            "123e306",
        ] {
            let e = decimal(text).err().unwrap_or_default();
            assert!(e.contains("is out of range"), "{text}: {e}");
        }
        assert_eq!(decimal("9.99e307").map(|q| to_f64(&q)), Ok(9.99e307));
        assert_eq!(decimal("1e-307").map(|q| to_f64(&q)), Ok(1e-307));
        assert_eq!(decimal("100e-309").map(|q| to_f64(&q)), Ok(1e-307));
        // 100k digits: refused at once (no quadratic gcd), the message stays short.
        let long = "7".repeat(100_000);
        let start = std::time::Instant::now();
        let e = decimal(&long).err().unwrap_or_default();
        assert!(start.elapsed().as_millis() < 500);
        assert_eq!(
            e,
            format!(
                "`{}… (100000 characters)` has 100000 significant digits; at most 40 are accepted",
                "7".repeat(24)
            )
        );
        assert!(decimal(&"1".repeat(40)).is_ok());
        assert!(decimal(&format!("0.{}1", "0".repeat(100_000))).is_err());
        assert!(coefficient_fits(&q(1, 3)));
        assert!(!coefficient_fits(&Q::from_integer(num_traits::pow(
            BigInt::from(10),
            309
        ))));
    }

    #[test]
    fn f64_conversion_rounds_once() {
        assert_eq!(to_f64(&q(1, 10)), 0.1);
        assert_eq!(to_f64(&q(-3, 20000)), -0.00015);
        assert_eq!(
            to_f64(&parse_decimal("0.0000000000000000000001").unwrap_or_default()),
            1e-22
        );
    }

    #[test]
    fn echelon_finds_dependencies_in_order() {
        // c0 = (1,0,1), c1 = (2,0,2) = 2 c0, c2 = (0,1,0), c3 = c0 + c2.
        let rows = vec![
            vec![q(1, 1), q(2, 1), q(0, 1), q(1, 1)],
            vec![q(0, 1), q(0, 1), q(1, 1), q(1, 1)],
            vec![q(1, 1), q(2, 1), q(0, 1), q(1, 1)],
        ];
        let e = echelon(&rows, 4);
        assert_eq!(e.pivot, vec![true, false, true, false]);
        assert_eq!(e.combination[1], vec![(0, q(2, 1))]);
        assert_eq!(e.combination[3], vec![(0, q(1, 1)), (2, q(1, 1))]);
        assert_eq!(e.rank(), 2);
    }

    #[test]
    fn overflow_falls_back_to_big_rationals() {
        let big = Q::from_integer(BigInt::from(i128::MAX) * BigInt::from(4));
        let rows = vec![
            vec![big.clone(), big.clone() * q(3, 1)],
            vec![q(1, 1), q(3, 1)],
        ];
        let e = echelon(&rows, 2);
        assert_eq!(e.pivot, vec![true, false]);
        assert_eq!(e.combination[1], vec![(0, q(3, 1))]);
    }
}
