//! The reported solve's moment equations kept for sub-model solves: the sums
//! a selection among candidate terms reuses instead of passing over the data again.

use crate::estimator::Estimator;
use crate::moments::CrossMoments;
use crate::outcome::{MomentBlock, MomentSystem};
use crate::solve::BlockSolution;
use nalgebra::DMatrix;

impl Estimator<'_> {
    /// Each block's moment equations per experiment with the long-run
    /// covariance of its moment residuals (`long_runs`: per experiment over
    /// the concatenated ζ rows, each block from its offset). `None` where
    /// ζ's rows are not the block's columns (least squares).
    pub(super) fn moment_system(
        &self,
        moments: &[Vec<CrossMoments>],
        sol: &[BlockSolution],
        (long_runs, offsets): (Vec<DMatrix<f64>>, Vec<usize>),
    ) -> Option<MomentSystem> {
        let mut blocks = Vec::with_capacity(self.blocks.len());
        for (b, (block, s)) in self.blocks.iter().zip(sol).enumerate() {
            if s.rows != block.cols {
                return None;
            }
            let m = block.cols.len();
            let mut h = Vec::with_capacity(moments.len());
            let mut g = Vec::with_capacity(moments.len());
            let mut long_run = Vec::with_capacity(moments.len());
            for (i, lr) in long_runs.iter().enumerate() {
                let (hi, gi, _) = self.equations(moments, i, b);
                h.push(hi);
                g.push(gi);
                long_run.push(lr.view((offsets[b], offsets[b]), (m, m)).into_owned());
            }
            blocks.push(MomentBlock {
                cols: block.cols.clone(),
                kept: s.kept.clone(),
                h,
                g,
                long_run,
            });
        }
        Some(MomentSystem { blocks })
    }
}
