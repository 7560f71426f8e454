//! The sandwich covariance of the estimated columns (long-run sums of the moment residuals).

use super::*;

impl Estimator<'_> {
    /// The sandwich covariance of the estimated columns: `Σ_i B_i G_i B_iᵀ`,
    /// `G_i` the long-run sum of `ζ_k = Σ_o z̃_o (ε_o − ε̄_o)` truncated at `lags`.
    pub(super) fn covariance(
        &self,
        experiments: &[&dyn Source],
        moments: &[Vec<CrossMoments>],
        sol: &[BlockSolution],
        theta_sim: &[f64],
        mu: &[f64],
    ) -> Option<BTreeMap<(usize, usize), f64>> {
        // The instruments of the reported iterate (empty θ: the delayed bootstrap).
        let walker = if theta_sim.is_empty() && self.options.method != Method::Ls {
            self.walker_with(Some(Instruments::Delayed))
        } else {
            self.walker()
        };
        let n = self.n_cols;
        let values: BTreeMap<usize, f64> = self.all_values(sol).into_iter().collect();
        // ζ rows: the instrument rows of every block, concatenated.
        let mut offsets = Vec::new();
        let mut total = 0;
        for s in sol {
            offsets.push(total);
            total += s.rows.len();
        }
        // Dense values by column, and each ζ row's index within its block.
        let dense: Vec<f64> = (0..n)
            .map(|c| values.get(&c).copied().unwrap_or(0.0))
            .collect();
        let local: Vec<Vec<usize>> = sol
            .iter()
            .zip(&self.blocks)
            .map(|(s, b)| {
                s.rows
                    .iter()
                    .map(|c| b.cols.iter().position(|x| x == c).unwrap_or(0))
                    .collect()
            })
            .collect();
        let mut cov = DMatrix::zeros(
            sol.iter().map(|s| s.kept.len()).sum(),
            sol.iter().map(|s| s.kept.len()).sum(),
        );
        for (i, (e, info)) in experiments.iter().zip(&self.infos).enumerate() {
            // Centres and mean residuals per output.
            let centres: Vec<DVector<f64>> = (0..self.ir.states.len())
                .map(|o| self.centre(moments, i, o))
                .collect();
            let mean_res: Vec<f64> = (0..self.ir.states.len())
                .map(|o| {
                    let b = &self.blocks[self.block_of_output[o]];
                    let mp = moments[i][o].mean_phi();
                    moments[i][o].mean_t()
                        - b.cols
                            .iter()
                            .enumerate()
                            .map(|(j, c)| mp[j] * values.get(c).copied().unwrap_or(0.0))
                            .sum::<f64>()
                })
                .collect();
            let mut lr = LongRun::new(total, self.options.lags);
            let mut zeta = DVector::zeros(total);
            let ok = walker.walk(*e, info, theta_sim, mu, None, &mut |z, phi, t| {
                zeta.fill(0.0);
                for o in 0..self.ir.states.len() {
                    let bi = self.block_of_output[o];
                    let block = &self.blocks[bi];
                    let mut target = t[o];
                    for (c, v) in &self.held {
                        target -= phi[o * n + c] * v;
                    }
                    let mut res = target;
                    for c in &block.cols {
                        res -= phi[o * n + c] * dense[*c];
                    }
                    res -= mean_res[o];
                    let s = &sol[bi];
                    let source = if self.options.method == Method::Ls {
                        phi
                    } else {
                        z
                    };
                    for (r, (c, j)) in s.rows.iter().zip(&local[bi]).enumerate() {
                        zeta[offsets[bi] + r] += (source[o * n + c] - centres[o][*j]) * res;
                    }
                }
                lr.push(&zeta);
            });
            if ok.is_err() {
                return None;
            }
            let g = lr.sum_psd();
            // Assemble B_i (kept × rows) over blocks.
            let nk: usize = sol.iter().map(|s| s.kept.len()).sum();
            let mut b_all = DMatrix::zeros(nk, total);
            let mut row = 0;
            for (bi, s) in sol.iter().enumerate() {
                b_all
                    .view_mut((row, offsets[bi]), (s.kept.len(), s.rows.len()))
                    .copy_from(&s.b[i]);
                row += s.kept.len();
            }
            cov += &b_all * g * b_all.transpose();
        }
        let kept: Vec<usize> = sol.iter().flat_map(|s| s.kept.iter().copied()).collect();
        let mut out = BTreeMap::new();
        for (a, ca) in kept.iter().enumerate() {
            for (b, cb) in kept.iter().enumerate() {
                out.insert((*ca, *cb), cov[(a, b)]);
            }
        }
        Some(out)
    }
}
