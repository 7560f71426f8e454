//! One accumulation pass: moment sums per experiment and output, and the moment equations they give.

use crate::estimator::Estimator;
use crate::moments::CrossMoments;
use crate::outcome::{EstimateError, err};
use crate::protocol::{BadValue, Pass, PassRequest, PrefixInstruments, Summary};
use leeway_structure::identify::Centring;
use nalgebra::{DMatrix, DVector};

/// How a moment pass ended.
pub(super) enum Accumulated {
    /// `[experiment][output]` moment sums, the largest relative move of the
    /// instrument simulation, and its mean fit to the data.
    Done(Vec<Vec<CrossMoments>>, f64, f64),
    /// The instrument simulation diverged in some experiment.
    Diverged,
    /// A non-finite measured value, in experiment `i` (scanning passes).
    Bad(usize, BadValue),
}

impl Estimator<'_> {
    /// One moment pass over every experiment: `[experiment][output]` moment
    /// sums over the block's columns, combined in experiment order. With
    /// `scan`, the first pass also looks for non-finite measured values (no
    /// extra pass over the data).
    pub(super) fn accumulate(
        &self,
        theta_sim: &[f64],
        mu: &[f64],
        reference: Option<(&[f64], &[f64])>,
        scan: bool,
        prefix: Vec<Option<PrefixInstruments>>,
    ) -> Result<Accumulated, EstimateError> {
        let request = PassRequest {
            plan: self.pass_plan(),
            pass: Pass::Moments {
                theta_sim: theta_sim.to_vec(),
                mu: mu.to_vec(),
                reference: reference.map(|(t, m)| (t.to_vec(), m.to_vec())),
                scan,
                prefix,
            },
            infos: self.infos.clone(),
            head: None,
        };
        let summaries = self.pass(&request)?;
        // The first bad value in experiment order is a data error, whatever diverged.
        for (i, s) in summaries.iter().enumerate() {
            if let Summary::Moments { bad: Some(b), .. } | Summary::Diverged { bad: Some(b) } = &s.0
            {
                return Ok(Accumulated::Bad(i, b.clone()));
            }
        }
        let mut all = Vec::with_capacity(summaries.len());
        let mut change = 0.0f64;
        let mut fit = 0.0f64;
        let count = self.facts.len();
        for s in summaries {
            match s.0 {
                Summary::Moments {
                    moments, change: c, ..
                } => {
                    change = change.max(c.relative());
                    fit += c.fit() / count as f64;
                    all.push(moments);
                }
                Summary::Diverged { .. } => return Ok(Accumulated::Diverged),
                Summary::LongRun { .. } | Summary::FreeRun(_) => return Err(mismatched()),
            }
        }
        if all.len() != count {
            return Err(mismatched());
        }
        Ok(Accumulated::Done(all, change, fit))
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

/// A pass runner answered with the wrong kind or number of summaries.
pub(super) fn mismatched() -> EstimateError {
    err(
        "invalid-pass",
        "a pass returned summaries that do not match the request (kind or number of experiments)",
        "a distributed pass must return one summary per experiment, in experiment order",
    )
}
