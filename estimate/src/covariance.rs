//! The sandwich covariance of the estimated columns (long-run sums of the moment residuals).

use crate::accumulate::mismatched;
use crate::estimator::Estimator;
use crate::free_run::FreeRunSums;
use crate::method::Method;
use crate::moments::CrossMoments;
use crate::outcome::EstimateError;
use crate::protocol::{LongRunPass, Pass, PassRequest, Summary};
use crate::solve::BlockSolution;
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// Covariance entries by (column, column) of the estimated columns.
pub(super) type ColumnCovariance = BTreeMap<(usize, usize), f64>;

/// What the covariance pass gives: the covariance (none if an instrument
/// simulation diverged), the free runs if asked, and each experiment's
/// long-run sum over the concatenated ζ rows (with each block's offset).
pub(super) struct CovariancePass {
    pub(super) cov: Option<ColumnCovariance>,
    pub(super) free_runs: Option<Vec<FreeRunSums>>,
    pub(super) long_runs: Option<(Vec<DMatrix<f64>>, Vec<usize>)>,
}

impl Estimator<'_> {
    /// The sandwich covariance of the estimated columns: `Σ_i B_i G_i B_iᵀ`,
    /// `G_i` the long-run sum of `ζ_k = Σ_o z̃_o (ε_o − ε̄_o)` truncated at
    /// `lags`, one pass whose sums are combined in experiment order. The
    /// pass also runs the free run `(θ, means)` of each experiment if asked
    /// (the estimate's own simulation), whose sums come back in experiment
    /// order.
    pub(super) fn covariance(
        &self,
        moments: &[Vec<CrossMoments>],
        sol: &[BlockSolution],
        (theta_sim, mu): (&[f64], &[f64]),
        free_run: Option<(Vec<f64>, Vec<f64>)>,
    ) -> Result<CovariancePass, EstimateError> {
        let n = self.n_cols;
        let values: BTreeMap<usize, f64> = self.all_values(sol).into_iter().collect();
        // ζ rows: the instrument rows of every block, concatenated.
        let mut offsets = Vec::new();
        let mut total = 0;
        for s in sol {
            offsets.push(total);
            total += s.rows.len();
        }
        // Dense values by column, and each ζ row's column and index within its block.
        let dense: Vec<f64> = (0..n)
            .map(|c| values.get(&c).copied().unwrap_or(0.0))
            .collect();
        let rows = self.zeta_rows(sol, &offsets);
        let (centres, mean_res) = self.centres_and_mean_residuals(moments, &values);
        let runs_free = free_run.is_some();
        let request = PassRequest {
            plan: self.pass_plan(),
            pass: Pass::LongRun(LongRunPass {
                theta_sim: theta_sim.to_vec(),
                mu: mu.to_vec(),
                lags: self.options.lags,
                own: self.options.method == Method::Ls,
                values: dense,
                dim: total,
                rows,
                centres,
                mean_res,
                free_run,
            }),
            infos: self.infos.clone(),
            head: None,
        };
        let summaries = self.pass(&request)?;
        if summaries.len() != self.facts.len() {
            return Err(mismatched());
        }
        let mut free_runs = Vec::with_capacity(summaries.len());
        let mut long_runs = Vec::with_capacity(summaries.len());
        for s in summaries {
            let Summary::LongRun {
                dim,
                sums,
                free_run: run,
            } = s.0
            else {
                return Err(mismatched());
            };
            if run.is_some() != runs_free {
                return Err(mismatched());
            }
            free_runs.extend(run);
            long_runs.push(match sums {
                Some(sums) if dim == total && sums.len() == total * total => {
                    Some(DMatrix::from_row_slice(total, total, &sums))
                }
                Some(_) => return Err(mismatched()),
                None => None,
            });
        }
        let free_runs = runs_free.then_some(free_runs);
        // A diverged instrument simulation anywhere: no covariance.
        let Some(long_runs) = long_runs.into_iter().collect::<Option<Vec<_>>>() else {
            return Ok(CovariancePass {
                cov: None,
                free_runs,
                long_runs: None,
            });
        };
        let nk: usize = sol.iter().map(|s| s.kept.len()).sum();
        let mut cov = DMatrix::zeros(nk, nk);
        for (i, g) in long_runs.iter().enumerate() {
            let b_all = experiment_map(sol, &offsets, (nk, total), i);
            cov += &b_all * g * b_all.transpose();
        }
        let kept: Vec<usize> = sol.iter().flat_map(|s| s.kept.iter().copied()).collect();
        let mut out = BTreeMap::new();
        for (a, ca) in kept.iter().enumerate() {
            for (b, cb) in kept.iter().enumerate() {
                out.insert((*ca, *cb), cov[(a, b)]);
            }
        }
        Ok(CovariancePass {
            cov: Some(out),
            free_runs,
            long_runs: Some((long_runs, offsets)),
        })
    }

    /// Each output's ζ rows: `(row, column, index within its block)`, the
    /// rows of block `b` from `offsets[b]` on.
    fn zeta_rows(
        &self,
        sol: &[BlockSolution],
        offsets: &[usize],
    ) -> Vec<Vec<(usize, usize, usize)>> {
        let n_out = self.ir.states.len();
        (0..n_out)
            .map(|o| {
                let bi = self.block_of_output[o];
                let b = &self.blocks[bi];
                sol[bi]
                    .rows
                    .iter()
                    .enumerate()
                    .map(|(r, c)| {
                        let j = b.cols.iter().position(|x| x == c).unwrap_or(0);
                        (offsets[bi] + r, *c, j)
                    })
                    .collect()
            })
            .collect()
    }

    /// Centres and mean residuals per experiment and output, at the column
    /// `values`.
    #[allow(clippy::type_complexity)]
    fn centres_and_mean_residuals(
        &self,
        moments: &[Vec<CrossMoments>],
        values: &BTreeMap<usize, f64>,
    ) -> (Vec<Vec<Vec<f64>>>, Vec<Vec<f64>>) {
        let n_out = self.ir.states.len();
        let mut centres = Vec::with_capacity(moments.len());
        let mut mean_res = Vec::with_capacity(moments.len());
        for i in 0..moments.len() {
            centres.push(
                (0..n_out)
                    .map(|o| self.centre(moments, i, o).iter().copied().collect())
                    .collect(),
            );
            mean_res.push(
                (0..n_out)
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
                    .collect(),
            );
        }
        (centres, mean_res)
    }
}

/// `B_i` of experiment `i` over every block (kept × ζ rows: `shape`), the
/// rows of block `b` from `offsets[b]` on.
fn experiment_map(
    sol: &[BlockSolution],
    offsets: &[usize],
    shape: (usize, usize),
    i: usize,
) -> DMatrix<f64> {
    let mut b_all = DMatrix::zeros(shape.0, shape.1);
    let mut row = 0;
    for (bi, s) in sol.iter().enumerate() {
        b_all
            .view_mut((row, offsets[bi]), (s.kept.len(), s.rows.len()))
            .copy_from(&s.b[i]);
        row += s.kept.len();
    }
    b_all
}
