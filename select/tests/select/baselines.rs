//! The least-squares selections peers use, run on the same data as the IV
//! selection: FROLS (orthogonal forward regression ranked by the
//! error-reduction ratio, stopped by BIC; sysidentpy) and STLSQ
//! (sequentially thresholded least squares, its threshold chosen by
//! leave-one-experiment-out cross-validation; pysindy).
//!
//! Both work on leeway's least-squares regression of the full candidate
//! model — IV3's predictor (a candidate's θ column with the nuisance
//! columns its relative velocities bring), an intercept per output and
//! experiment — through its normal equations per experiment
//! (`H_i = Σ φ̃φ̃ᵀ`, `g_i = Σ φ̃ t̃`, centred per experiment) and the centred
//! sum of squares of the target, so every subset's residual sum of squares
//! is `Σ t̃² − g_Sᵀ H_SS⁻¹ g_S` without another pass over the data. A
//! candidate enters or leaves with all its columns.

use leeway_estimate::{EstimateOptions, Method, estimate};
use leeway_model::{Experiment, Interpreter, Source};
use leeway_structure::ir::{ColumnKind, Ir};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeSet;

/// One equation's least-squares normal equations per experiment.
struct Equation {
    /// Predictor columns of the block.
    cols: Vec<usize>,
    /// Per experiment: `H_i`, `g_i`, `Σ t̃²`, samples.
    h: Vec<DMatrix<f64>>,
    g: Vec<DVector<f64>>,
    tt: Vec<f64>,
    n: Vec<usize>,
    /// Positions (in `cols`) of the columns always in the model.
    required: Vec<usize>,
    /// The candidates of this equation: name and positions of their columns.
    candidates: Vec<(String, Vec<usize>)>,
}

/// The least-squares normal equations of the full candidate model.
pub struct Normal {
    equations: Vec<Equation>,
}

impl Normal {
    /// Least squares on `model` (the compiled candidate model) over `data`;
    /// `candidates`: the names of its candidate parameters.
    pub fn of(
        model: &Interpreter,
        candidates: &[String],
        data: &[Experiment],
        lags: usize,
    ) -> Normal {
        let ir: &Ir = leeway_model::Model::ir(model);
        let sources: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
        let options = EstimateOptions {
            method: Method::Ls,
            lags,
            covariance: true,
            ..EstimateOptions::default()
        };
        let est = estimate(model, &sources, &options).expect("least squares");
        let system = est
            .moment_system
            .expect("every column of the candidate model is excited: least squares keeps its sums");
        let columns = ir.predictors.get(Method::Ls.predictor());
        let equations = system
            .blocks
            .iter()
            .map(|b| {
                assert_eq!(b.kept, b.cols, "least squares estimates every column");
                let outputs: BTreeSet<usize> =
                    b.cols.iter().flat_map(|c| columns[*c].outputs()).collect();
                assert_eq!(outputs.len(), 1, "one output per block");
                let o = *outputs.first().expect("one output");
                let (tt, n): (Vec<f64>, Vec<usize>) =
                    data.iter().map(|e| centred_target(e, o)).unzip();
                let param = |j: usize| columns[b.cols[j]].kind.parameter();
                let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
                let mut required = Vec::new();
                for j in 0..b.cols.len() {
                    let name = &ir.parameters[param(j)].name;
                    if !candidates.contains(name) {
                        required.push(j);
                    } else if let Some(g) = groups.iter_mut().find(|(c, _)| c == name) {
                        g.1.push(j);
                    } else {
                        groups.push((name.clone(), vec![j]));
                    }
                }
                Equation {
                    cols: b.cols.clone(),
                    h: b.h.iter().map(|h| (h + h.transpose()) * 0.5).collect(),
                    g: b.g.clone(),
                    tt,
                    n,
                    required,
                    candidates: groups,
                }
            })
            .collect();
        Normal { equations }
    }
}

/// `Σ (t − t̄)²` and the samples of output `o`'s target
/// `t_k = (x_{k+1} − x_k)/h` in one experiment.
fn centred_target(e: &Experiment, o: usize) -> (f64, usize) {
    let mut x = Vec::with_capacity(e.len());
    e.visit(&mut |row| x.push(row.states[o]));
    let t: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]) / e.h).collect();
    let mean = t.iter().sum::<f64>() / t.len().max(1) as f64;
    (t.iter().map(|v| (v - mean) * (v - mean)).sum(), t.len())
}

impl Equation {
    /// `(Σ H_i, Σ g_i, Σ t̃²)` over the experiments `on`.
    fn sums(&self, on: &[usize]) -> (DMatrix<f64>, DVector<f64>, f64) {
        let m = self.cols.len();
        on.iter().fold(
            (DMatrix::zeros(m, m), DVector::zeros(m), 0.0),
            |(h, g, t), &i| (h + &self.h[i], g + &self.g[i], t + self.tt[i]),
        )
    }

    /// Least squares over the columns `set` (positions): θ over every
    /// column (zero outside `set`) and the residual sum of squares.
    fn solve(sums: &(DMatrix<f64>, DVector<f64>, f64), set: &[usize]) -> (DVector<f64>, f64) {
        let (h, g, tt) = sums;
        let k = set.len();
        let mut theta = DVector::zeros(g.len());
        if k == 0 {
            return (theta, *tt);
        }
        // Columns to unit norm before solving: θ and nuisance columns differ in scale.
        let d: Vec<f64> = set
            .iter()
            .map(|j| {
                let v = h[(*j, *j)];
                if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 }
            })
            .collect();
        let a = DMatrix::from_fn(k, k, |r, c| h[(set[r], set[c])] * d[r] * d[c]);
        let b = DVector::from_fn(k, |r, _| g[set[r]] * d[r]);
        let beta = a
            .clone()
            .svd(true, true)
            .solve(&b, 1e-12 * a.norm())
            .expect("an SVD solve");
        for (r, j) in set.iter().enumerate() {
            theta[*j] = beta[r] * d[r];
        }
        let explained = beta.dot(&b);
        (theta, (tt - explained).max(0.0))
    }

    /// The held-out residual sum of squares of `theta` on experiment `i`.
    fn held_out(&self, i: usize, theta: &DVector<f64>) -> f64 {
        (self.tt[i] - 2.0 * theta.dot(&self.g[i])
            + (theta.transpose() * &self.h[i] * theta)[(0, 0)])
            .max(0.0)
    }

    /// Columns of the required terms and of the candidates `kept`.
    fn set(&self, kept: &[usize]) -> Vec<usize> {
        let mut s = self.required.clone();
        for c in kept {
            s.extend(&self.candidates[*c].1);
        }
        s.sort_unstable();
        s
    }

    /// FROLS: from the required terms, the candidate whose columns reduce
    /// the residual sum of squares most (the largest error-reduction ratio
    /// of its columns orthogonalised against those already in) enters
    /// next, down to every candidate; the model on this path with the
    /// least BIC `n·ln(RSS/n) + k·ln n` (k columns) is chosen.
    fn frols(&self) -> Vec<usize> {
        let all: Vec<usize> = (0..self.h.len()).collect();
        let sums = self.sums(&all);
        let n: usize = self.n.iter().sum();
        let nf = n as f64;
        let bic = |set: &[usize]| {
            let (_, rss) = Equation::solve(&sums, set);
            nf * (rss / nf).ln() + set.len() as f64 * nf.ln()
        };
        let mut kept: Vec<usize> = Vec::new();
        let mut best = (bic(&self.set(&kept)), 0);
        let mut order = Vec::new();
        while kept.len() < self.candidates.len() {
            let next = (0..self.candidates.len())
                .filter(|c| !kept.contains(c))
                .map(|c| {
                    let mut with = kept.clone();
                    with.push(c);
                    (c, Equation::solve(&sums, &self.set(&with)).1)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(c, _)| c)
                .expect("a candidate left");
            kept.push(next);
            order.push(next);
            let b = bic(&self.set(&kept));
            if b < best.0 {
                best = (b, kept.len());
            }
        }
        order[..best.1].to_vec()
    }

    /// STLSQ with threshold `lambda` on the experiments `on`: least squares,
    /// then every candidate whose standardised coefficient `|θ|·‖φ̃‖/‖t̃‖`
    /// (its θ column) is below `lambda` dropped, until none is; θ of the
    /// final model.
    fn stlsq(&self, on: &[usize], lambda: f64) -> (Vec<usize>, DVector<f64>) {
        let sums = self.sums(on);
        let mut kept: Vec<usize> = (0..self.candidates.len()).collect();
        loop {
            let (theta, _) = Equation::solve(&sums, &self.set(&kept));
            let small: Vec<usize> = kept
                .iter()
                .copied()
                .filter(|c| {
                    let j = self.candidates[*c].1[0];
                    theta[j].abs() * (sums.0[(j, j)] / sums.2).sqrt() < lambda
                })
                .collect();
            if small.is_empty() {
                return (kept, theta);
            }
            kept.retain(|c| !small.contains(c));
        }
    }
}

/// STLSQ's thresholds tried: 10^(−3 + k/4), k = 0..=12 (0.001 to 1, four
/// per decade; the mantissas written out, as `powf` differs across libms).
pub fn thresholds() -> Vec<f64> {
    let mantissas = [
        1.0,
        1.778_279_410_038_923,
        3.162_277_660_168_379_5,
        5.623_413_251_903_491,
    ];
    let mut out: Vec<f64> = [1e-3, 1e-2, 1e-1]
        .iter()
        .flat_map(|d| mantissas.iter().map(move |m| d * m))
        .collect();
    out.push(1.0);
    out
}

impl Normal {
    /// FROLS with BIC, per equation: the candidates kept.
    pub fn frols(&self) -> Vec<String> {
        self.equations
            .iter()
            .flat_map(|e| e.frols().into_iter().map(|c| e.candidates[c].0.clone()))
            .collect()
    }

    /// The threshold STLSQ uses: the one of [`thresholds`] whose models,
    /// fitted with each experiment left out in turn, predict the left-out
    /// experiment's targets best (residual sum of squares relative to each
    /// equation's, summed; ties to the larger threshold).
    pub fn stlsq_threshold(&self) -> f64 {
        let count = self.equations[0].h.len();
        let mut best = (f64::INFINITY, 0.0);
        for lambda in thresholds().into_iter().rev() {
            let mut err = 0.0;
            for out in 0..count {
                let train: Vec<usize> = (0..count).filter(|i| *i != out).collect();
                for e in &self.equations {
                    let (_, theta) = e.stlsq(&train, lambda);
                    err += e.held_out(out, &theta) / e.tt[out];
                }
            }
            if err < best.0 {
                best = (err, lambda);
            }
        }
        best.1
    }

    /// STLSQ with the cross-validated threshold on every experiment: the
    /// candidates kept and the threshold.
    pub fn stlsq(&self) -> (Vec<String>, f64) {
        let lambda = self.stlsq_threshold();
        let all: Vec<usize> = (0..self.equations[0].h.len()).collect();
        let kept = self
            .equations
            .iter()
            .flat_map(|e| {
                let (k, _) = e.stlsq(&all, lambda);
                k.into_iter().map(|c| e.candidates[c].0.clone())
            })
            .collect();
        (kept, lambda)
    }

    /// θ columns of the full least-squares fit by parameter name (a check
    /// that the normal equations are the estimate's).
    pub fn full_theta(&self, ir: &Ir) -> Vec<(String, f64)> {
        let columns = ir.predictors.get(Method::Ls.predictor());
        let mut out = Vec::new();
        for e in &self.equations {
            let all: Vec<usize> = (0..e.h.len()).collect();
            let cols: Vec<usize> = (0..e.cols.len()).collect();
            let (theta, _) = Equation::solve(&e.sums(&all), &cols);
            for (j, c) in e.cols.iter().enumerate() {
                if let ColumnKind::Theta { parameter } = columns[*c].kind {
                    out.push((ir.parameters[parameter].name.clone(), theta[j]));
                }
            }
        }
        out
    }
}
