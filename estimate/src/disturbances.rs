//! Unmeasured disturbance means from the nuisance estimates (paper Corollary 1).

use crate::estimator::Estimator;
use crate::outcome::DisturbanceMoment;
use leeway_structure::ir::{ColumnKind, PredictorKind};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;

/// `(kept column, [(component, parameter, coefficient)])`: what a kept ρ column
/// estimates in terms of disturbance means and θ.
type MomentEquation = (usize, Vec<(usize, usize, f64)>);

impl Estimator<'_> {
    /// Unmeasured disturbance means from ρ̂ and θ̂ (paper Corollary 1), with
    /// standard errors by the delta method when a covariance is given.
    pub(super) fn disturbance_means(
        &self,
        values: &BTreeMap<usize, f64>,
        theta: &[f64],
        cov: Option<&BTreeMap<(usize, usize), f64>>,
    ) -> Vec<DisturbanceMoment> {
        let unmeasured: Vec<usize> = (0..self.ir.components.len())
            .filter(|c| {
                let d = &self.ir.disturbances[self.ir.components[*c].disturbance];
                !d.measured || self.kind == PredictorKind::Augmented
            })
            .collect();
        if unmeasured.is_empty() || self.kind == PredictorKind::Basic {
            return Vec::new();
        }
        let eqs = self.rho_equations(values);
        if eqs.is_empty() {
            return Vec::new();
        }
        let Some(mu) = solve_means(&eqs, &unmeasured, values, theta) else {
            return Vec::new();
        };
        let se = match cov {
            Some(cov) => self.delta_method(&eqs, &unmeasured, values, theta, cov),
            None => vec![None; unmeasured.len()],
        };
        unmeasured
            .iter()
            .enumerate()
            .map(|(j, c)| {
                let comp = &self.ir.components[*c];
                DisturbanceMoment {
                    disturbance: self.ir.disturbances[comp.disturbance].name.clone(),
                    component: comp.name.clone(),
                    mean: mu[j],
                    std_error: se[j],
                }
            })
            .collect()
    }

    /// The equations of the estimated columns that estimate ρ columns only:
    /// value_k = Σ_{(d, q) ∈ meaning_k} q · μ_comp(d) · θ_param(d).
    fn rho_equations(&self, values: &BTreeMap<usize, f64>) -> Vec<MomentEquation> {
        let cols = self.ir.predictors.get(self.kind);
        let mut eqs: Vec<MomentEquation> = Vec::new();
        for (k, items) in &self.meaning {
            if !values.contains_key(k) {
                continue;
            }
            let mut terms = Vec::new();
            let mut ok = true;
            for (d, q) in items {
                match cols[*d].kind {
                    ColumnKind::Rho {
                        component,
                        parameter,
                    } => terms.push((component, parameter, *q)),
                    _ => ok = false,
                }
            }
            if ok && !terms.is_empty() {
                eqs.push((*k, terms));
            }
        }
        eqs
    }

    /// The standard errors of the `unmeasured` means by the delta method
    /// over the estimated θ and ρ columns involved (central differences
    /// of [`solve_means`]); none where a perturbed solve fails.
    fn delta_method(
        &self,
        eqs: &[MomentEquation],
        unmeasured: &[usize],
        values: &BTreeMap<usize, f64>,
        theta: &[f64],
        cov: &BTreeMap<(usize, usize), f64>,
    ) -> Vec<Option<f64>> {
        let cols = self.ir.predictors.get(self.kind);
        let mut se = vec![None; unmeasured.len()];
        let mut vars: Vec<usize> = eqs.iter().map(|(k, _)| *k).collect();
        for (c, col) in cols.iter().enumerate() {
            if matches!(col.kind, ColumnKind::Theta { .. }) && cov.contains_key(&(c, c)) {
                vars.push(c);
            }
        }
        vars.sort_unstable();
        vars.dedup();
        let mut jac = DMatrix::zeros(unmeasured.len(), vars.len());
        let mut ok = true;
        for (vi, &c) in vars.iter().enumerate() {
            let base = values.get(&c).copied().unwrap_or(0.0);
            let step = 1e-6 * base.abs().max(1e-8);
            let mut plus = values.clone();
            let mut minus = values.clone();
            plus.insert(c, base + step);
            minus.insert(c, base - step);
            let (mut tp, mut tm) = (theta.to_vec(), theta.to_vec());
            if let ColumnKind::Theta { parameter } = cols[c].kind {
                tp[parameter] = base + step;
                tm[parameter] = base - step;
            }
            match (
                solve_means(eqs, unmeasured, &plus, &tp),
                solve_means(eqs, unmeasured, &minus, &tm),
            ) {
                (Some(a), Some(b)) => {
                    for j in 0..unmeasured.len() {
                        jac[(j, vi)] = (a[j] - b[j]) / (2.0 * step);
                    }
                }
                _ => ok = false,
            }
        }
        if ok {
            let cm = DMatrix::from_fn(vars.len(), vars.len(), |a, b| {
                cov.get(&(vars[a], vars[b])).copied().unwrap_or(0.0)
            });
            let cmu = &jac * cm * jac.transpose();
            for j in 0..unmeasured.len() {
                se[j] = Some(cmu[(j, j)].max(0.0).sqrt());
            }
        }
        se
    }

    pub(super) fn mean_vector(&self, values: &BTreeMap<usize, f64>, theta: &[f64]) -> Vec<f64> {
        let mut mu = vec![0.0; self.ir.components.len()];
        for m in self.disturbance_means(values, theta, None) {
            if let Some(c) = self
                .ir
                .components
                .iter()
                .position(|c| c.name == m.component)
            {
                mu[c] = m.mean;
            }
        }
        mu
    }
}

/// The `unmeasured` components' means that solve the equations `eqs` at
/// the column values `vals` and θ `th`; none where they do not determine
/// them.
fn solve_means(
    eqs: &[MomentEquation],
    unmeasured: &[usize],
    vals: &BTreeMap<usize, f64>,
    th: &[f64],
) -> Option<Vec<f64>> {
    let a = DMatrix::from_fn(eqs.len(), unmeasured.len(), |r, j| {
        eqs[r]
            .1
            .iter()
            .filter(|(c, _, _)| *c == unmeasured[j])
            .map(|(_, p, q)| q * th[*p])
            .sum()
    });
    let y = DVector::from_iterator(
        eqs.len(),
        eqs.iter().map(|(k, _)| vals.get(k).copied().unwrap_or(0.0)),
    );
    // An SVD panics on a NaN: an overflowed product has no mean.
    if !a.iter().chain(y.iter()).all(|v| v.is_finite()) {
        return None;
    }
    let svd = a.svd(true, true);
    let smax = svd.singular_values.max();
    if svd.singular_values.min() <= 1e-10 * smax || smax == 0.0 {
        return None;
    }
    svd.solve(&y, 0.0).ok().map(|v| v.iter().copied().collect())
}
