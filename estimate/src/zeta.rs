//! The moment residual `ζ_k` of one sample, as the covariance pass sums it:
//! per output `o`, the residual `ε = t − Σ φ_c·θ_c − ε̄` and the rows
//! `(z̃_c − centre)·ε` it adds to `ζ`. The plan is laid out once per
//! experiment — flat indices into the walk's buffers, values and centres
//! beside them — so that each sample is a few tight loops; every sum is
//! made in the order the pass always made it, with the same bits.

use crate::dense::{Dense, EquationBlock};
use crate::moments::{BLOCK, LongRun};
use crate::protocol::{LongRunPass, PassPlan};

/// One output's part of `ζ`.
struct OutputZeta {
    /// Its target's index.
    output: usize,
    /// `(index into φ, value)`: held columns first, then estimated ones.
    terms: Vec<(usize, f64)>,
    /// The mean residual `ε̄`.
    mean: f64,
    /// `(ζ row, index into the instruments' buffer, centre)`.
    rows: Vec<(usize, usize, f64)>,
}

/// How one experiment's samples give `ζ_k`.
pub(super) struct ZetaPlan {
    outputs: Vec<OutputZeta>,
    /// The regressors are their own instruments (least squares).
    own: bool,
}

impl ZetaPlan {
    /// The plan of pass `lr` with `plan`, for an experiment whose
    /// instruments' centres (per output, by block index) and mean residuals
    /// are `centres` and `mean_res`.
    pub(super) fn new(
        plan: &PassPlan,
        lr: &LongRunPass,
        centres: &[Vec<f64>],
        mean_res: &[f64],
    ) -> ZetaPlan {
        let n = plan.n_cols;
        let outputs = lr
            .rows
            .iter()
            .enumerate()
            .map(|(o, rows)| {
                let held = plan.held.iter().map(|&(c, v)| (o * n + c, v));
                let estimated = plan.cols[o].iter().map(|&c| (o * n + c, lr.values[c]));
                OutputZeta {
                    output: o,
                    terms: held.chain(estimated).collect(),
                    mean: mean_res[o],
                    rows: rows
                        .iter()
                        .map(|&(r, c, j)| (r, o * n + c, centres[o][j]))
                        .collect(),
                }
            })
            .collect();
        ZetaPlan {
            outputs,
            own: lr.own,
        }
    }

    /// Adds `ζ_k` of the sample with instruments `z`, regressors `phi` and
    /// targets `t` into `zeta` (zeroed).
    #[inline]
    pub(super) fn add<D: Dense>(&self, z: D, phi: D, t: &[f64], zeta: &mut [f64]) {
        let source = if self.own { phi } else { z };
        for out in &self.outputs {
            let mut res = t[out.output];
            for &(i, v) in &out.terms {
                res -= phi.at(i) * v;
            }
            res -= out.mean;
            out.add_rows(source, res, zeta);
        }
    }

    /// Adds `ζ_k` of each sample of `block` to `sums`, as [`ZetaPlan::add`]
    /// would one by one: the residuals of every sample first, each term
    /// across the block's samples (contiguous, so it vectorises), with each
    /// sample's operations in the same order — the same bits. `res` is
    /// scratch.
    pub(super) fn add_block(&self, block: EquationBlock, res: &mut Vec<f64>, sums: &mut LongRun) {
        let n = block.n;
        res.resize(self.outputs.len() * BLOCK, 0.0);
        for (out, res) in self.outputs.iter().zip(res.chunks_exact_mut(BLOCK)) {
            let res = &mut res[..n];
            for (s, r) in res.iter_mut().enumerate() {
                *r = block.t[s * block.n_out + out.output];
            }
            for &(i, v) in &out.terms {
                let phi = &block.phi[i * n..(i + 1) * n];
                for (r, &p) in res.iter_mut().zip(phi) {
                    *r -= p * v;
                }
            }
            for r in res.iter_mut() {
                *r -= out.mean;
            }
        }
        // A block that begins the long-run sums' block: each row of `ζ`
        // across the samples (a slot's values contiguous), outputs and rows
        // in the order below, so each entry gets the same additions.
        let source = if self.own { block.phi } else { block.z };
        let whole = sums.push_rows_with(n, |rows, w| {
            for (out, res) in self.outputs.iter().zip(res.chunks_exact(BLOCK)) {
                for &(r, i, centre) in &out.rows {
                    let values = &source[i * n..][..n];
                    for ((row, &v), &res) in rows.chunks_exact_mut(w).zip(values).zip(res) {
                        row[r] += (v - centre) * res;
                    }
                }
            }
        });
        if whole {
            return;
        }
        for s in 0..n {
            let (z, phi, _) = block.equation(s);
            let source = if self.own { phi } else { z };
            sums.push_with(|zeta| {
                for (out, res) in self.outputs.iter().zip(res.chunks_exact(BLOCK)) {
                    out.add_rows(source, res[s], zeta);
                }
            });
        }
    }
}

impl OutputZeta {
    /// `ζ`'s rows of this output: `(z̃_c − centre)·ε` added to each.
    #[inline(always)]
    fn add_rows<D: Dense>(&self, source: D, res: f64, zeta: &mut [f64]) {
        for &(r, i, centre) in &self.rows {
            zeta[r] += (source.at(i) - centre) * res;
        }
    }
}
