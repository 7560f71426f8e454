//! A sub-model's IV estimate from sub-blocks of the full candidate model's
//! moment sums: no pass over the data.
//!
//! The full model's instruments stay the instruments of every sub-model, so
//! a sub-model with fewer columns than instruments is over-identified: it is
//! solved as efficient GMM, `θ = (HᵀS⁻¹H)⁻¹HᵀS⁻¹g`, with `S` the long-run
//! covariance of the moment residuals at the full model's estimate (valid
//! for every sub-model that contains the truth), its covariance
//! `(HᵀS⁻¹H)⁻¹` and Hansen's `J = rᵀS⁻¹r`, `r = g − Hθ`, χ² with
//! `instruments − columns` degrees of freedom when the dropped terms are
//! truly zero. For the full model (square) it is the estimate's own solve.

use leeway_estimate::MomentSystem;
use leeway_model::correlation::chi_squared_tail;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use std::collections::BTreeMap;

/// Eigenvalues below this fraction of the largest count as zero in a
/// pseudo-inverse (equilibrated matrices: a column that is rounding residue).
const PINV_TOLERANCE: f64 = 1e-12;

/// A sub-model's estimate.
#[derive(Clone, Debug)]
pub struct SubEstimate {
    /// Estimated columns' values, by predictor column.
    pub values: BTreeMap<usize, f64>,
    /// Covariance of the estimated columns, by block: the columns and the matrix.
    pub covariance: Vec<(Vec<usize>, DMatrix<f64>)>,
    /// Hansen's J over every block.
    pub j: f64,
    /// Its degrees of freedom: instruments − estimated columns.
    pub df: usize,
}

/// How a sub-model is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solve {
    /// Efficient GMM on the full model's instruments (IV).
    Gmm,
    /// The square system over the sub-model's own columns (least squares'
    /// normal equations; no covariance).
    Square,
}

/// Solves the sub-model whose columns are those of `system`'s kept columns
/// with `active(column)`, from the experiments `train` (indices), the
/// estimate's held columns subtracted at `held` values (a column neither
/// kept nor in `held` counts as zero).
pub fn solve_sub(
    system: &MomentSystem,
    active: &dyn Fn(usize) -> bool,
    held: &BTreeMap<usize, f64>,
    train: &[usize],
    how: Solve,
) -> SubEstimate {
    let mut out = SubEstimate {
        values: BTreeMap::new(),
        covariance: Vec::new(),
        j: 0.0,
        df: 0,
    };
    for block in &system.blocks {
        let m = block.cols.len();
        let mut h = DMatrix::zeros(m, m);
        let mut g = DVector::zeros(m);
        let mut s = DMatrix::zeros(m, m);
        for &i in train {
            h += &block.h[i];
            g += &block.g[i];
            s += &block.long_run[i];
        }
        for (j, c) in block.cols.iter().enumerate() {
            if let Some(v) = held.get(c).filter(|_| !block.kept.contains(c)) {
                g -= h.column(j) * *v;
            }
        }
        let rows: Vec<usize> = (0..m)
            .filter(|j| block.kept.contains(&block.cols[*j]))
            .collect();
        let cols: Vec<usize> = rows
            .iter()
            .copied()
            .filter(|j| active(block.cols[*j]))
            .collect();
        // A block with every column dropped still has its moment
        // conditions: they count in J (at θ = 0), else an empty equation
        // would look like a perfect fit.
        if cols.is_empty() && !matches!(how, Solve::Gmm) {
            continue;
        }
        let names: Vec<usize> = cols.iter().map(|j| block.cols[*j]).collect();
        let (values, cov) = match how {
            Solve::Gmm => {
                let (values, cov, j) = gmm(&h, &g, &s, &rows, &cols);
                out.j += j;
                out.df += rows.len() - cols.len();
                (values, Some(cov))
            }
            Solve::Square => (square(&h, &g, &cols), None),
        };
        for (c, v) in names.iter().zip(values.iter()) {
            out.values.insert(*c, *v);
        }
        if let Some(cov) = cov.filter(|_| !names.is_empty()) {
            out.covariance.push((names, cov));
        }
    }
    out
}

/// Efficient GMM over instrument `rows` and regressor `cols` (positions in
/// the block), equilibrated: the values, their covariance and J.
fn gmm(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    s: &DMatrix<f64>,
    rows: &[usize],
    cols: &[usize],
) -> (DVector<f64>, DMatrix<f64>, f64) {
    let (r, k) = (rows.len(), cols.len());
    // Rows to unit long-run variance, columns to unit norm.
    let d: Vec<f64> = rows
        .iter()
        .map(|i| {
            let v = s[(*i, *i)];
            if v > 0.0 && v.is_finite() {
                1.0 / v.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let ss = DMatrix::from_fn(r, r, |a, b| s[(rows[a], rows[b])] * d[a] * d[b]);
    let w = pinv_symmetric(&((&ss + ss.transpose()) * 0.5));
    let hs = DMatrix::from_fn(r, k, |a, b| h[(rows[a], cols[b])] * d[a]);
    let gs = DVector::from_fn(r, |a, _| g[rows[a]] * d[a]);
    let c: Vec<f64> = (0..k)
        .map(|b| {
            let n = hs.column(b).norm();
            if n > 0.0 && n.is_finite() {
                1.0 / n
            } else {
                1.0
            }
        })
        .collect();
    let a = DMatrix::from_fn(r, k, |i, j| hs[(i, j)] * c[j]);
    let atw = a.transpose() * &w;
    let m = &atw * &a;
    let minv = pinv_symmetric(&((&m + m.transpose()) * 0.5));
    let beta = &minv * (&atw * &gs);
    let res = &gs - &a * &beta;
    let j = (res.transpose() * &w * &res)[(0, 0)];
    let values = DVector::from_fn(k, |i, _| beta[i] * c[i]);
    let cov = DMatrix::from_fn(k, k, |i, jj| minv[(i, jj)] * c[i] * c[jj]);
    (values, cov, j.max(0.0))
}

/// The square system `H_KK θ = g_K`, equilibrated, by pseudo-inverse.
fn square(h: &DMatrix<f64>, g: &DVector<f64>, cols: &[usize]) -> DVector<f64> {
    let k = cols.len();
    let c: Vec<f64> = cols
        .iter()
        .map(|j| {
            let v = h[(*j, *j)].abs();
            if v > 0.0 && v.is_finite() {
                1.0 / v.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let a = DMatrix::from_fn(k, k, |i, j| h[(cols[i], cols[j])] * c[i] * c[j]);
    let b = DVector::from_fn(k, |i, _| g[cols[i]] * c[i]);
    let beta = a
        .clone()
        .svd(true, true)
        .solve(&b, PINV_TOLERANCE * a.norm())
        .unwrap_or_else(|_| DVector::zeros(k));
    DVector::from_fn(k, |i, _| beta[i] * c[i])
}

/// The pseudo-inverse of a symmetric matrix.
pub(crate) fn pinv_symmetric(a: &DMatrix<f64>) -> DMatrix<f64> {
    let n = a.nrows();
    if n == 0 {
        return a.clone();
    }
    let e = SymmetricEigen::new(a.clone());
    let top = e.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut out = DMatrix::zeros(n, n);
    for (i, l) in e.eigenvalues.iter().enumerate() {
        if l.abs() > PINV_TOLERANCE * top && l.is_finite() {
            let v = e.eigenvectors.column(i);
            out += (v * v.transpose()) / *l;
        }
    }
    out
}

/// `P(χ²_df > x)` (1 for a statistic of 0 or no degrees of freedom).
pub fn chi2_sf(x: f64, df: usize) -> f64 {
    if x <= 0.0 || df == 0 {
        return 1.0;
    }
    chi_squared_tail(x, df)
}

#[cfg(test)]
mod tests {
    use super::{Solve, chi2_sf, solve_sub};
    use leeway_estimate::{MomentBlock, MomentSystem};
    use nalgebra::{DMatrix, DVector};
    use std::collections::BTreeMap;

    /// A block whose columns are all dropped keeps its moment conditions in
    /// J (at θ = 0): `gᵀ S⁻¹ g` over its instruments, with as many degrees
    /// of freedom. Before, the block was skipped and the empty model's J
    /// was 0 — the best score on the path.
    #[test]
    fn a_block_with_every_column_dropped_counts_in_j() {
        let system = MomentSystem {
            blocks: vec![MomentBlock {
                cols: vec![0, 1],
                kept: vec![0, 1],
                h: vec![DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 1.0])],
                g: vec![DVector::from_row_slice(&[4.0, 3.0])],
                long_run: vec![DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 1.0])],
            }],
        };
        let none = solve_sub(&system, &|_| false, &BTreeMap::new(), &[0], Solve::Gmm);
        // g = (4, 3), S = diag(4, 1): J = 16/4 + 9/1 = 13.
        assert!((none.j - 13.0).abs() < 1e-9, "J {}", none.j);
        assert_eq!(none.df, 2);
        assert!(none.values.is_empty() && none.covariance.is_empty());
        let full = solve_sub(&system, &|_| true, &BTreeMap::new(), &[0], Solve::Gmm);
        assert!(full.j.abs() < 1e-9 && full.df == 0);
        assert!((full.values[&0] - 2.0).abs() < 1e-9 && (full.values[&1] - 3.0).abs() < 1e-9);
    }

    #[test]
    fn chi_square_tail_matches_tables() {
        // χ²₁ 95 % point 3.841, χ²₅ 99 % point 15.086, χ²₂ tail exp(−x/2).
        assert!((chi2_sf(3.841_458_820_694_124, 1) - 0.05).abs() < 1e-9);
        assert!((chi2_sf(15.086_272_469_388_99, 5) - 0.01).abs() < 1e-9);
        assert!((chi2_sf(7.0, 2) - (-3.5f64).exp()).abs() < 1e-12);
    }
}
