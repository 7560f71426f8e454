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
    m: usize,
    p: usize,
    z0: Vec<f64>,
    phi0: Vec<f64>,
    t0: f64,
    /// `Σ (z − z₀)(φ − φ₀)ᵀ`, row-major `m × p`.
    s_zphi: Vec<f64>,
    s_zt: Vec<f64>,
    s_z: Vec<f64>,
    s_phi: Vec<f64>,
    s_t: f64,
    /// `Σ (z − z₀)²` and `Σ (φ − φ₀)²` per entry: the scales against which a
    /// moment is judged to be rounding residue.
    s_zz: Vec<f64>,
    s_pp: Vec<f64>,
    dz: Vec<f64>,
    dphi: Vec<f64>,
}

impl CrossMoments {
    /// Empty sums for `m` instruments and `p` regressors.
    pub fn new(m: usize, p: usize) -> CrossMoments {
        CrossMoments {
            n: 0,
            m,
            p,
            z0: vec![0.0; m],
            phi0: vec![0.0; p],
            t0: 0.0,
            s_zphi: vec![0.0; m * p],
            s_zt: vec![0.0; m],
            s_z: vec![0.0; m],
            s_phi: vec![0.0; p],
            s_t: 0.0,
            s_zz: vec![0.0; m],
            s_pp: vec![0.0; p],
            dz: vec![0.0; m],
            dphi: vec![0.0; p],
        }
    }

    /// Adds one sample.
    #[inline]
    pub fn push(&mut self, z: &[f64], phi: &[f64], t: f64) {
        if self.n == 0 {
            self.z0.copy_from_slice(&z[..self.m]);
            self.phi0.copy_from_slice(&phi[..self.p]);
            self.t0 = t;
        }
        for ((d, a), b) in self.dz.iter_mut().zip(z).zip(&self.z0) {
            *d = a - b;
        }
        for ((d, a), b) in self.dphi.iter_mut().zip(phi).zip(&self.phi0) {
            *d = a - b;
        }
        let dt = t - self.t0;
        for (row, &zi) in self.s_zphi.chunks_exact_mut(self.p).zip(&self.dz) {
            for (s, &f) in row.iter_mut().zip(&self.dphi) {
                *s += zi * f;
            }
        }
        for (((s, sz), szz), &zi) in self
            .s_zt
            .iter_mut()
            .zip(self.s_z.iter_mut())
            .zip(self.s_zz.iter_mut())
            .zip(&self.dz)
        {
            *s += zi * dt;
            *sz += zi;
            *szz += zi * zi;
        }
        for ((s, spp), &f) in self
            .s_phi
            .iter_mut()
            .zip(self.s_pp.iter_mut())
            .zip(&self.dphi)
        {
            *s += f;
            *spp += f * f;
        }
        self.s_t += dt;
        self.n += 1;
    }

    /// Mean of the instruments.
    pub fn mean_z(&self) -> DVector<f64> {
        let n = self.n.max(1) as f64;
        DVector::from_iterator(
            self.m,
            self.z0.iter().zip(&self.s_z).map(|(a, s)| a + s / n),
        )
    }
    /// Mean of the regressors.
    pub fn mean_phi(&self) -> DVector<f64> {
        let n = self.n.max(1) as f64;
        DVector::from_iterator(
            self.p,
            self.phi0.iter().zip(&self.s_phi).map(|(a, s)| a + s / n),
        )
    }
    /// Mean of the target.
    pub fn mean_t(&self) -> f64 {
        if self.n == 0 {
            self.t0
        } else {
            self.t0 + self.s_t / self.n as f64
        }
    }

    /// `Σ_k ‖z(k) − c‖²`: the instruments' energy about a centre `c`.
    pub fn z_energy(&self, c: &DVector<f64>) -> f64 {
        let n = self.n as f64;
        (0..self.m)
            .map(|i| {
                let d = self.z0[i] - c[i];
                (self.s_zz[i] + 2.0 * d * self.s_z[i] + n * d * d).max(0.0)
            })
            .sum()
    }
    /// `Σ_k φ_j(k)²` per regressor (uncentred).
    pub fn phi_energy(&self) -> Vec<f64> {
        let n = self.n as f64;
        (0..self.p)
            .map(|j| {
                let a = self.phi0[j];
                (self.s_pp[j] + 2.0 * a * self.s_phi[j] + n * a * a).max(0.0)
            })
            .collect()
    }

    /// The centred co-moments `Σ (z − z̄)(φ − φ̄)ᵀ` and `Σ (z − z̄)(t − t̄)`:
    /// the moment equations `Σ (z − z̄)(t − φᵀϑ)` with instruments centred per
    /// experiment.
    pub fn centred(&self) -> (DMatrix<f64>, DVector<f64>) {
        let n = self.n.max(1) as f64;
        let h = DMatrix::from_fn(self.m, self.p, |i, j| {
            self.s_zphi[i * self.p + j] - self.s_z[i] * self.s_phi[j] / n
        });
        let g = DVector::from_fn(self.m, |i, _| self.s_zt[i] - self.s_z[i] * self.s_t / n);
        (h, g)
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
/// The symmetric part is accumulated as its upper triangle, each lag once.
#[derive(Clone, Debug)]
pub struct LongRun {
    lags: usize,
    dim: usize,
    /// Upper triangle of `Σ ζζᵀ`, row-major `dim × dim`.
    own: Vec<f64>,
    /// `Σ_j Σ_k ζ_k ζ_{k−j}ᵀ`, row-major.
    cross: Vec<f64>,
    history: Vec<Vec<f64>>,
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
            dim: m,
            own: vec![0.0; m * m],
            cross: vec![0.0; m * m],
            history: vec![vec![0.0; m]; lags],
            next: 0,
            filled: 0,
            n: 0,
        }
    }
    /// Adds `ζ_k`.
    pub fn push(&mut self, zeta: &DVector<f64>) {
        let m = self.dim;
        let z = zeta.as_slice();
        for i in 0..m {
            let zi = z[i];
            if zi == 0.0 {
                continue;
            }
            let row = &mut self.own[i * m..(i + 1) * m];
            for j in i..m {
                row[j] += zi * z[j];
            }
        }
        for j in 0..self.filled.min(self.lags) {
            let idx = (self.next + self.lags - 1 - j) % self.lags;
            let past = &self.history[idx];
            for (i, &zi) in z.iter().enumerate() {
                if zi == 0.0 {
                    continue;
                }
                let row = &mut self.cross[i * m..(i + 1) * m];
                for (c, &p) in row.iter_mut().zip(past) {
                    *c += zi * p;
                }
            }
        }
        self.history[self.next].copy_from_slice(z);
        self.next = (self.next + 1) % self.lags;
        self.filled = (self.filled + 1).min(self.lags);
        self.n += 1;
    }
    /// The long-run sum, made positive semi-definite by clipping negative
    /// eigenvalues (truncated kernels need not be PSD in finite samples).
    pub fn sum_psd(&self) -> DMatrix<f64> {
        let m = self.dim;
        if m == 0 {
            return DMatrix::zeros(0, 0);
        }
        let sym = DMatrix::from_fn(m, m, |i, j| {
            let own = if i <= j {
                self.own[i * m + j]
            } else {
                self.own[j * m + i]
            };
            own + self.cross[i * m + j] + self.cross[j * m + i]
        });
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
