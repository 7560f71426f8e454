//! Sign patterns read from data and checked against paper A7: within one
//! experiment every modulus argument that carries noise or an unmeasured
//! disturbance must keep its sign. The moduli of plain states are signed
//! sample by sample instead ([`plain_sign_args`], [`set_pointwise_signs`]):
//! every predictor evaluates them exactly as [`simulate`](crate::simulate)
//! does (`scenarios/tests/scenarios/real_logs.rs`).

use crate::experiment::Source;
use crate::interp::{ArgPlan, arg_plan};
use crate::model::HeadingRotation;
use leeway_structure::identify::{pointwise_signs, relevant_signs};
use leeway_structure::ir::{Ir, PredictorKind, Rotation, SignPattern};
use serde::{Deserialize, Serialize};

/// One argument's sign in one experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArgSign {
    /// `water.u`.
    pub argument: String,
    /// The majority sign, `+1` or `-1`.
    pub sign: i8,
    /// Fraction of samples with the other sign (or zero): 0 when A7 holds.
    pub minority_fraction: f64,
    /// True when measured disturbance values entered the argument.
    pub used_measured_medium: bool,
}

/// The sign pattern of one experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExperimentSigns {
    /// Experiment name.
    pub experiment: String,
    /// `±1` for every sign argument of the model (`+1` where irrelevant).
    pub pattern: SignPattern,
    /// The arguments the predictor fixes.
    pub arguments: Vec<ArgSign>,
    /// Arguments the predictor evaluates pointwise — plain states always,
    /// measured media in IV3 — whose signs may change within the experiment
    /// (the crossings are counted in `crossings`).
    pub pointwise: Vec<ArgSign>,
    /// Zero crossings of each pointwise argument (same order as `pointwise`).
    pub crossings: Vec<usize>,
}

impl ExperimentSigns {
    /// The worst minority fraction.
    pub fn worst(&self) -> Option<&ArgSign> {
        self.arguments
            .iter()
            .max_by(|a, b| a.minority_fraction.total_cmp(&b.minority_fraction))
    }
}

/// Reads the sign pattern of an experiment. An argument relative to a
/// measured medium is evaluated with the measured disturbance; one relative
/// to an unmeasured medium by its state alone (the disturbance is unknown;
/// A5/A7 require the state to dominate it).
pub fn detect(ir: &Ir, kind: PredictorKind, source: &dyn Source) -> ExperimentSigns {
    let mut counter = SignCounter::new(ir, kind);
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let mut headings = HeadingRotation::default();
    source.visit(&mut |row| {
        let rot_buf;
        let rotation: &[f64] = if planar {
            rot_buf = headings.next(row.heading);
            &rot_buf
        } else {
            row.rotation
        };
        counter.sample(&crate::model::Signals {
            states: row.states,
            inputs: row.inputs,
            rotation,
            disturbances: row.disturbances,
        });
    });
    counter.finish(ir, source.name())
}

/// The sign counts of [`detect`], sample by sample, for a caller that
/// reads other facts in the same visit.
#[derive(Clone, Debug)]
pub struct SignCounter {
    plans: Vec<(usize, ArgPlan, bool)>,
    n_fixed: usize,
    pos: Vec<usize>,
    neg: Vec<usize>,
    crossings: Vec<usize>,
    last: Vec<i8>,
    n: usize,
}

impl SignCounter {
    /// Counts for the arguments `kind` fixes, then those it evaluates pointwise.
    pub fn new(ir: &Ir, kind: PredictorKind) -> SignCounter {
        let args = if kind == PredictorKind::Basic {
            Vec::new()
        } else {
            relevant_signs(ir, kind)
        };
        // Plain states are pointwise in every predictor (IV1's too: its sign
        // changes decide the structure seen by the data).
        let extra: Vec<usize> = if kind == PredictorKind::Basic {
            (0..ir.sign_args.len())
                .filter(|i| ir.sign_args[*i].pointwise)
                .collect()
        } else {
            pointwise_signs(ir, kind)
        };
        let plans: Vec<(usize, ArgPlan, bool)> = args
            .iter()
            .chain(extra.iter())
            .map(|&i| {
                let a = &ir.sign_args[i];
                (i, arg_plan(ir, &a.arg), a.measured)
            })
            .collect();
        let k = plans.len();
        SignCounter {
            plans,
            n_fixed: args.len(),
            pos: vec![0; k],
            neg: vec![0; k],
            crossings: vec![0; k],
            last: vec![0; k],
            n: 0,
        }
    }

    /// One sample (the rotation already evaluated).
    #[inline]
    pub fn sample(&mut self, sig: &crate::model::Signals) {
        for (k, (_, plan, measured)) in self.plans.iter().enumerate() {
            let v = plan.eval(sig, *measured);
            let sign = if v > 0.0 {
                self.pos[k] += 1;
                1
            } else {
                self.neg[k] += 1;
                -1
            };
            if self.last[k] != 0 && self.last[k] != sign {
                self.crossings[k] += 1;
            }
            self.last[k] = sign;
        }
        self.n += 1;
    }

    /// The experiment's sign pattern.
    pub fn finish(mut self, ir: &Ir, experiment: &str) -> ExperimentSigns {
        let (pos, neg, n) = (&self.pos, &self.neg, self.n);
        let mut pattern = vec![1i8; ir.sign_args.len()];
        let mut arguments: Vec<ArgSign> = self
            .plans
            .iter()
            .enumerate()
            .map(|(k, (i, _, measured))| {
                let sign = if neg[k] > pos[k] { -1 } else { 1 };
                // Pointwise arguments get their majority sign too: it is the sign
                // wherever they do not change sign (then the analysis uses it).
                pattern[*i] = sign;
                let minority = pos[k].min(neg[k]);
                ArgSign {
                    argument: ir.sign_args[*i].name.clone(),
                    sign,
                    minority_fraction: if n == 0 {
                        0.0
                    } else {
                        minority as f64 / n as f64
                    },
                    used_measured_medium: *measured,
                }
            })
            .collect();
        let pointwise = arguments.split_off(self.n_fixed);
        ExperimentSigns {
            experiment: experiment.to_string(),
            pattern,
            arguments,
            pointwise,
            crossings: self.crossings.split_off(self.n_fixed),
        }
    }
}

/// The sign arguments on plain states, `(sign argument, state)`: every
/// predictor evaluates their moduli pointwise, `|x| = sign(x)·x`.
pub fn plain_sign_args(ir: &Ir) -> Vec<(usize, usize)> {
    ir.sign_args
        .iter()
        .enumerate()
        .filter(|(_, a)| a.pointwise)
        .filter_map(|(i, a)| match a.arg.signal {
            leeway_structure::ir::Signal::State(l) => Some((i, l)),
            leeway_structure::ir::Signal::Input(_) => None,
        })
        .collect()
}

/// Sets the sign of each given plain-state argument from the states the
/// regressors are about to be evaluated at, so that a pattern-taking
/// regressor evaluation computes `x·|x|` exactly as the simulation does.
#[inline]
pub fn set_pointwise_signs(signs: &mut [f64], args: &[(usize, usize)], states: &[f64]) {
    for &(i, l) in args {
        signs[i] = if states[l] < 0.0 { -1.0 } else { 1.0 };
    }
}
