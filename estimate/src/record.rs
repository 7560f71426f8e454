//! Per-experiment facts read once before estimating: sign pattern, measured means, state bounds, heading spread, fixed-sign Φ2 columns.

use crate::method::Method;
use leeway_model::model::HeadingRotation;
use leeway_model::signs::{ExperimentSigns, SignCounter, plain_sign_args};
use leeway_structure::ir::{Ir, PredictorKind, Rotation};

/// A measured-medium (`Φ2`) column whose modulus arguments keep their sign
/// in the data: its instrument is the noise-free `s·a_sim·…` rather than a
/// pointwise `|a_sim|` of a possibly crude simulation.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(super) struct FixedSignColumn {
    pub(super) column: usize,
    /// `(term, output, sign of each factor's modulus argument)`.
    pub(super) terms: Vec<(usize, usize, Vec<f64>)>,
}

/// Per-experiment facts read before estimating.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct ExperimentInfo {
    pub(super) signs: Vec<f64>,
    /// Pointwise sign arguments on plain states whose sign changes in this
    /// experiment: `(sign argument, state)`; their sign is taken sample by
    /// sample from the point the regressors are evaluated at.
    pub(super) varying: Vec<(usize, usize)>,
    pub(super) fixed_sign_columns: Vec<FixedSignColumn>,
    pub(super) measured_mean: Vec<f64>,
    pub(super) bound: Vec<f64>,
    pub(super) spread: f64,
    pub(super) frozen: Option<Vec<f64>>,
}

/// Where an in-memory experiment's facts visit stood after its samples:
/// the visit of a longer record that begins with them goes on from here.
#[derive(Clone, Debug)]
pub(super) struct FactsState {
    pub(super) len: usize,
    pub(super) counter: SignCounter,
    pub(super) sums: RecordSums,
    pub(super) headings: HeadingRotation,
}

/// The sums an experiment's facts are read from, sample by sample (in the
/// facts pass's one visit, beside the sign counts).
#[derive(Clone, Debug)]
pub(super) struct RecordSums {
    sum: Vec<f64>,
    max_abs: Vec<f64>,
    sc: f64,
    ss: f64,
    n: usize,
    rot_sum: Vec<f64>,
    rot_sq: Vec<f64>,
}

impl RecordSums {
    pub(super) fn new(ir: &Ir) -> RecordSums {
        let n_rot = ir.rotation_vars.len();
        RecordSums {
            sum: vec![0.0; ir.components.len()],
            max_abs: vec![0.0; ir.states.len()],
            sc: 0.0,
            ss: 0.0,
            n: 0,
            rot_sum: vec![0.0; n_rot],
            rot_sq: vec![0.0; n_rot],
        }
    }

    /// One sample, with its heading's rotation.
    #[inline]
    pub(super) fn sample(&mut self, row: &leeway_model::experiment::Row, [c, s]: [f64; 2]) {
        for (a, v) in self.sum.iter_mut().zip(row.disturbances) {
            *a += v;
        }
        for (m, v) in self.max_abs.iter_mut().zip(row.states) {
            *m = m.max(v.abs());
        }
        self.sc += c;
        self.ss += s;
        let n_rot = self.rot_sum.len();
        for i in 0..row.rotation.len().min(n_rot) {
            self.rot_sum[i] += row.rotation[i];
            self.rot_sq[i] += row.rotation[i] * row.rotation[i];
        }
        self.n += 1;
    }
}

/// The facts of an experiment from its sums and sign pattern.
pub(super) fn record_info(
    ir: &Ir,
    sums: RecordSums,
    s: &ExperimentSigns,
    method: Method,
    heading_spread: f64,
) -> ExperimentInfo {
    let RecordSums {
        sum,
        max_abs,
        sc,
        ss,
        n,
        rot_sum,
        rot_sq,
    } = sums;
    let n_comp = ir.components.len();
    let nf = n.max(1) as f64;
    let measured_mean: Vec<f64> = (0..n_comp)
        .map(|c| {
            if ir.disturbances[ir.components[c].disturbance].measured {
                sum[c] / nf
            } else {
                0.0
            }
        })
        .collect();
    let (spread, frozen) = heading_spread_of(ir, (sc, ss), (&rot_sum, &rot_sq), nf, heading_spread);
    let fixed_sign_columns = if method.predictor() == PredictorKind::Measured {
        fixed_sign_columns(ir, s)
    } else {
        Vec::new()
    };
    // Only the plain arguments whose sign changes need a sign per sample; the
    // others keep the experiment's (only) sign from the pattern.
    let varying = plain_sign_args(ir)
        .into_iter()
        .filter(|(i, _)| {
            s.pointwise
                .iter()
                .any(|a| a.argument == ir.sign_args[*i].name && a.minority_fraction > 0.0)
        })
        .collect();
    ExperimentInfo {
        signs: s.pattern.iter().map(|v| f64::from(*v)).collect(),
        varying,
        fixed_sign_columns,
        measured_mean,
        bound: max_abs.iter().map(|m| 100.0 * (1.0 + m)).collect(),
        spread,
        frozen,
    }
}

/// How much an experiment's heading varied (the circular spread of a planar
/// heading from the sums of its cosine and sine, `(sc, ss)`; the largest
/// standard deviation of measured rotation columns from their sums and
/// sums of squares), over `nf` samples; and the constant rotation it is
/// treated with when below `heading_spread` (paper Remark 2).
fn heading_spread_of(
    ir: &Ir,
    (sc, ss): (f64, f64),
    (rot_sum, rot_sq): (&[f64], &[f64]),
    nf: f64,
    heading_spread: f64,
) -> (f64, Option<Vec<f64>>) {
    let n_rot = ir.rotation_vars.len();
    match &ir.rotation {
        Rotation::Planar { .. } => {
            let (mc, ms) = (sc / nf, ss / nf);
            let r = (mc * mc + ms * ms).sqrt().min(1.0);
            let spread = (-2.0 * r.max(1e-300).ln()).sqrt();
            let frozen = (spread < heading_spread)
                .then(|| vec![sc / nf / r.max(1e-300), ss / nf / r.max(1e-300)]);
            (spread, frozen)
        }
        Rotation::Measured { .. } => {
            let spread = (0..n_rot)
                .map(|i| {
                    let mean = rot_sum[i] / nf;
                    (rot_sq[i] / nf - mean * mean).max(0.0).sqrt()
                })
                .fold(0.0, f64::max);
            (
                spread,
                (spread < heading_spread).then(|| rot_sum.iter().map(|v| v / nf).collect()),
            )
        }
        Rotation::None => (f64::INFINITY, None),
    }
}

/// The Φ2 columns whose modulus arguments never change sign in the data of
/// sign pattern `s`, with each term's fixed signs.
fn fixed_sign_columns(ir: &Ir, s: &ExperimentSigns) -> Vec<FixedSignColumn> {
    let mut fixed_sign_columns = Vec::new();
    let sign_of = |arg: &leeway_structure::ir::Arg| -> Option<f64> {
        let i = ir.sign_args.iter().position(|a| a.arg == *arg)?;
        let found = s
            .pointwise
            .iter()
            .find(|a| a.argument == ir.sign_args[i].name)?;
        (found.minority_fraction == 0.0).then_some(f64::from(found.sign))
    };
    for (c, col) in ir.predictors.measured.iter().enumerate() {
        let mut terms = Vec::new();
        let mut ok = !col.entries.is_empty();
        for e in &col.entries {
            match e {
                leeway_structure::ir::Entry::Term { term, output, .. } => {
                    let t = &ir.terms[*term];
                    let signs: Option<Vec<f64>> = t
                        .factors
                        .iter()
                        .map(|f| {
                            if f.modulus {
                                sign_of(&f.arg)
                            } else {
                                Some(1.0)
                            }
                        })
                        .collect();
                    match signs {
                        Some(v) => terms.push((*term, *output, v)),
                        None => ok = false,
                    }
                }
                leeway_structure::ir::Entry::Poly { .. } => ok = false,
            }
        }
        if ok {
            fixed_sign_columns.push(FixedSignColumn { column: c, terms });
        }
    }
    fixed_sign_columns
}
