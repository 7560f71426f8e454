//! One accumulation pass: moment sums per experiment and output, and the moment equations they give.

use super::*;

impl Estimator<'_> {
    /// One accumulation pass: `[experiment][output]` moment sums over the block's columns.
    /// With `finite`, the first pass also looks for non-finite measured
    /// values (no extra pass over the data): the first one found is stored
    /// as `(experiment, sample, what)`.
    pub(super) fn accumulate(
        &self,
        experiments: &[&dyn Source],
        theta_sim: &[f64],
        mu: &[f64],
        reference: Option<(&[f64], &[f64])>,
        finite: Option<&FirstBadValue>,
    ) -> Result<(Vec<Vec<CrossMoments>>, f64, f64), Diverged> {
        // An empty θ asks for the delayed bootstrap pass of the refined IV.
        let walker = if theta_sim.is_empty() {
            self.walker_with(Some(Instruments::Delayed))
        } else {
            self.walker()
        };
        let n = self.n_cols;
        let mut all = Vec::with_capacity(experiments.len());
        let mut change = 0.0f64;
        let mut fit = 0.0f64;
        for (i, (e, info)) in experiments.iter().zip(&self.infos).enumerate() {
            // The sink sees equation k = 2, 3, …: regressors at k − 1, target at k.
            let mut k = 1usize;
            let mut acc: Vec<MomentAccumulator> = (0..self.ir.states.len())
                .map(|o| {
                    let m = self.blocks[self.block_of_output[o]].cols.len();
                    MomentAccumulator::new(m, m)
                })
                .collect();
            let c = walker.walk(*e, info, theta_sim, mu, reference, &mut |z, phi, t| {
                k += 1;
                if let Some(cell) = finite
                    && cell.borrow().is_none()
                    && let Some((sample, what)) = self.non_finite(k, phi, t)
                {
                    *cell.borrow_mut() = Some((i, sample, what));
                }
                for (o, a) in acc.iter_mut().enumerate() {
                    let cols = &self.blocks[self.block_of_output[o]].cols;
                    let mut target = t[o];
                    for (c, v) in &self.held {
                        target -= phi[o * n + c] * v;
                    }
                    a.push_columns(
                        &z[o * n..(o + 1) * n],
                        &phi[o * n..(o + 1) * n],
                        cols,
                        target,
                    );
                }
            })?;
            change = change.max(c.relative());
            fit += c.fit() / experiments.len() as f64;
            all.push(acc.into_iter().map(MomentAccumulator::finish).collect());
        }
        Ok((all, change, fit))
    }

    /// The centre of output `o`'s instruments in experiment `i`: their mean
    /// there (per experiment), over all experiments (pooled; a constant
    /// column's instrument stays uncentred, it is the intercept), or zero.
    pub(super) fn centre(&self, moments: &[Vec<CrossMoments>], i: usize, o: usize) -> DVector<f64> {
        let m = self.blocks[self.block_of_output[o]].cols.len();
        match self.centring {
            Centring::Experiment => moments[i][o].mean_z(),
            Centring::None => DVector::zeros(m),
            Centring::Pooled => {
                let total: usize = moments.iter().map(|e| e[o].n).sum();
                let mut pooled = moments
                    .iter()
                    .fold(DVector::zeros(m), |s, e| s + e[o].mean_z() * e[o].n as f64)
                    / total.max(1) as f64;
                for (j, c) in self.blocks[self.block_of_output[o]].cols.iter().enumerate() {
                    if self.constant_cols[*c] {
                        pooled[j] = 0.0;
                    }
                }
                pooled
            }
        }
    }

    /// Moment equations `(H_i, g_i)` of experiment `i`, block `b` (sums, not
    /// means), and for each column the scale `Σ_o ‖z̃_o‖·‖φ_o,j‖` that bounds
    /// its moments (Cauchy–Schwarz): a column far below it is rounding residue.
    pub(super) fn equations(
        &self,
        moments: &[Vec<CrossMoments>],
        i: usize,
        b: usize,
    ) -> (DMatrix<f64>, DVector<f64>, Vec<f64>) {
        let block = &self.blocks[b];
        let m = block.cols.len();
        let mut h = DMatrix::zeros(m, m);
        let mut g = DVector::zeros(m);
        let mut bound = vec![0.0; m];
        for &o in &block.outputs {
            let acc = &moments[i][o];
            let c = self.centre(moments, i, o);
            let (ho, go) = match self.centring {
                Centring::Experiment => acc.centred(),
                _ => acc.about(&c),
            };
            let zn = acc.z_energy(&c).sqrt();
            for (bj, pe) in bound.iter_mut().zip(acc.phi_energy()) {
                *bj += zn * pe.sqrt();
            }
            h += ho;
            g += go;
        }
        (h, g, bound)
    }
}
