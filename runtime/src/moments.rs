//! Streaming moment sums with constant memory.
//!
//! Sums are shifted by the first sample (`Σ (z − z₀)(φ − φ₀)ᵀ`), which keeps
//! the centred co-moments accurate even for regressors that barely vary
//! around a large mean, at one multiply-add per entry and sample.

use nalgebra::{DMatrix, DVector};

/// Shifted cross-moment sums of instruments `z`, regressors `φ` and target `t`.
#[derive(Clone, Debug)]
pub struct CrossMoments {
    /// Samples.
    pub n: usize,
    z0: DVector<f64>,
    phi0: DVector<f64>,
    t0: f64,
    s_zphi: DMatrix<f64>,
    s_zt: DVector<f64>,
    s_z: DVector<f64>,
    s_phi: DVector<f64>,
    s_t: f64,
    dz: DVector<f64>,
    dphi: DVector<f64>,
}

impl CrossMoments {
    /// Empty sums for `m` instruments and `p` regressors.
    pub fn new(m: usize, p: usize) -> CrossMoments {
        CrossMoments {
            n: 0,
            z0: DVector::zeros(m),
            phi0: DVector::zeros(p),
            t0: 0.0,
            s_zphi: DMatrix::zeros(m, p),
            s_zt: DVector::zeros(m),
            s_z: DVector::zeros(m),
            s_phi: DVector::zeros(p),
            s_t: 0.0,
            dz: DVector::zeros(m),
            dphi: DVector::zeros(p),
        }
    }

    /// Adds one sample.
    #[inline]
    pub fn push(&mut self, z: &[f64], phi: &[f64], t: f64) {
        if self.n == 0 {
            self.z0.as_mut_slice().copy_from_slice(z);
            self.phi0.as_mut_slice().copy_from_slice(phi);
            self.t0 = t;
        }
        for (d, (a, b)) in self.dz.iter_mut().zip(z.iter().zip(self.z0.iter())) {
            *d = a - b;
        }
        for (d, (a, b)) in self.dphi.iter_mut().zip(phi.iter().zip(self.phi0.iter())) {
            *d = a - b;
        }
        let dt = t - self.t0;
        self.s_zphi.ger(1.0, &self.dz, &self.dphi, 1.0);
        self.s_zt.axpy(dt, &self.dz, 1.0);
        self.s_z += &self.dz;
        self.s_phi += &self.dphi;
        self.s_t += dt;
        self.n += 1;
    }

    /// Mean of the instruments.
    pub fn mean_z(&self) -> DVector<f64> {
        if self.n == 0 {
            self.z0.clone()
        } else {
            &self.z0 + &self.s_z / self.n as f64
        }
    }
    /// Mean of the regressors.
    pub fn mean_phi(&self) -> DVector<f64> {
        if self.n == 0 {
            self.phi0.clone()
        } else {
            &self.phi0 + &self.s_phi / self.n as f64
        }
    }
    /// Mean of the target.
    pub fn mean_t(&self) -> f64 {
        if self.n == 0 {
            self.t0
        } else {
            self.t0 + self.s_t / self.n as f64
        }
    }

    /// The centred co-moments `Σ (z − z̄)(φ − φ̄)ᵀ` and `Σ (z − z̄)(t − t̄)`:
    /// the moment equations `Σ (z − z̄)(t − φᵀϑ)` with instruments centred per
    /// experiment.
    pub fn centred(&self) -> (DMatrix<f64>, DVector<f64>) {
        if self.n == 0 {
            return (
                DMatrix::zeros(self.s_zphi.nrows(), self.s_zphi.ncols()),
                DVector::zeros(self.s_zt.len()),
            );
        }
        let n = self.n as f64;
        (
            &self.s_zphi - &self.s_z * self.s_phi.transpose() / n,
            &self.s_zt - &self.s_z * (self.s_t / n),
        )
    }

    /// The moment equations `Σ (z − c)(t − φᵀϑ) = g − Hϑ` with instruments
    /// centred at `c` (a pooled mean, or zero for no centring): `(H, g)`.
    pub fn about(&self, c: &DVector<f64>) -> (DMatrix<f64>, DVector<f64>) {
        let (h, g) = self.centred();
        if self.n == 0 {
            return (h, g);
        }
        let n = self.n as f64;
        let dz = self.mean_z() - c;
        (
            h + &dz * self.mean_phi().transpose() * n,
            g + &dz * (self.mean_t() * n),
        )
    }
}

/// Long-run covariance sums of a vector series `ζ_k` truncated at `lags`
/// (uniform weights, the right kernel for the MA(1) residual of an Euler
/// difference): `Σ ζ_k ζ_kᵀ + Σ_{j=1..L} Σ (ζ_k ζ_{k−j}ᵀ + ζ_{k−j} ζ_kᵀ)`.
#[derive(Clone, Debug)]
pub struct LongRun {
    lags: usize,
    sum: DMatrix<f64>,
    history: Vec<DVector<f64>>,
    next: usize,
    filled: usize,
    /// Samples seen.
    pub n: usize,
}

impl LongRun {
    /// Empty sums for dimension `m` with `lags ≥ 1`.
    pub fn new(m: usize, lags: usize) -> LongRun {
        let lags = lags.max(1);
        LongRun {
            lags,
            sum: DMatrix::zeros(m, m),
            history: vec![DVector::zeros(m); lags],
            next: 0,
            filled: 0,
            n: 0,
        }
    }
    /// Adds `ζ_k`.
    pub fn push(&mut self, zeta: &DVector<f64>) {
        self.sum.ger(1.0, zeta, zeta, 1.0);
        for j in 0..self.filled.min(self.lags) {
            let idx = (self.next + self.lags - 1 - j) % self.lags;
            let past = &self.history[idx];
            self.sum.ger(1.0, zeta, past, 1.0);
            self.sum.ger(1.0, past, zeta, 1.0);
        }
        self.history[self.next].copy_from(zeta);
        self.next = (self.next + 1) % self.lags;
        self.filled = (self.filled + 1).min(self.lags);
        self.n += 1;
    }
    /// The long-run sum, made positive semi-definite by clipping negative
    /// eigenvalues (truncated kernels need not be PSD in finite samples).
    pub fn sum_psd(&self) -> DMatrix<f64> {
        let sym = (&self.sum + self.sum.transpose()) * 0.5;
        let eig = sym.clone().symmetric_eigen();
        if eig.eigenvalues.iter().all(|v| *v >= 0.0) {
            return sym;
        }
        let clipped = eig.eigenvalues.map(|v| v.max(0.0));
        &eig.eigenvectors * DMatrix::from_diagonal(&clipped) * eig.eigenvectors.transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifted_sums_match_two_pass_covariance() {
        let zs: Vec<[f64; 2]> = (0..50)
            .map(|k| [1e6 + (k as f64).sin(), 3.0 + 0.1 * k as f64])
            .collect();
        let mut m = CrossMoments::new(2, 2);
        for z in &zs {
            m.push(z, z, z[0] + 2.0 * z[1]);
        }
        let (c, ct) = m.centred();
        let (c2, ct2) = m.about(&m.mean_z());
        assert!((&c - c2).abs().max() < 1e-9 && (&ct - ct2).abs().max() < 1e-9);
        let mut exact = DMatrix::zeros(2, 2);
        let mut exact_t = DVector::zeros(2);
        let mu = [
            zs.iter().map(|z| z[0]).sum::<f64>() / 50.0,
            zs.iter().map(|z| z[1]).sum::<f64>() / 50.0,
        ];
        let mt = mu[0] + 2.0 * mu[1];
        for z in &zs {
            let d = DVector::from_row_slice(&[z[0] - mu[0], z[1] - mu[1]]);
            exact += &d * d.transpose();
            exact_t += &d * (z[0] + 2.0 * z[1] - mt);
        }
        assert!((c - exact).abs().max() < 1e-6);
        assert!((ct - exact_t).abs().max() < 1e-6);
    }

    #[test]
    fn long_run_of_white_noise_is_its_covariance_sum() {
        let mut lr = LongRun::new(1, 1);
        for k in 0..4 {
            lr.push(&DVector::from_element(
                1,
                if k % 2 == 0 { 1.0 } else { -1.0 },
            ));
        }
        // 4 · 1 + 2 · (−1) · 3 = −2 → clipped to 0.
        assert_eq!(lr.sum_psd()[(0, 0)], 0.0);
    }
}
