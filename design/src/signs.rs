//! The sign arguments a design must hold (paper A7, A13): which ones a
//! predictor fixes per experiment, the band each must clear against the
//! plan's disturbances and noise, and their margins along a trajectory.

use crate::plan::Conditions;
use leeway_model::interp::{ArgPlan, arg_plan};
use leeway_model::model::{Signals, planar_rotation};
use leeway_structure::identify::{pointwise_signs, relevant_signs};
use leeway_structure::ir::{Ir, PredictorKind, Signal};

/// A sign argument held on one side in every sample of an experiment.
#[derive(Clone, Debug)]
pub struct Held {
    /// Index in the IR's sign arguments.
    pub index: usize,
    /// `water.u`.
    pub name: String,
    /// +1 or −1: the side the experiment's pattern asks for.
    pub sign: f64,
    /// How far from zero it must stay (three standard deviations of the
    /// disturbance and noise in it, plus the uncertainty of the mean).
    pub band: f64,
    /// The largest share of the plan's mean disturbance in the argument,
    /// over every heading (a craft meets the medium from any side).
    pub worst_mean: f64,
    pub(crate) plan: ArgPlan,
}

impl Held {
    /// `sign · argument` at a sample (the margin before the band).
    pub fn value(&self, sig: &Signals) -> f64 {
        self.sign * self.plan.eval(sig, true)
    }
}

/// The arguments `kind` fixes under `pattern` (±1 per sign argument).
pub fn held(ir: &Ir, kind: PredictorKind, pattern: &[i8], conditions: &Conditions) -> Vec<Held> {
    relevant_signs(ir, kind)
        .into_iter()
        .map(|i| {
            let a = &ir.sign_args[i];
            let plan = arg_plan(ir, &a.arg);
            Held {
                index: i,
                name: a.name.clone(),
                sign: f64::from(pattern.get(i).copied().unwrap_or(1)),
                band: band(&plan, conditions),
                worst_mean: worst_mean(ir, &plan, conditions),
                plan,
            }
        })
        .collect()
}

/// Plain-state arguments a predictor evaluates pointwise: their moduli need
/// sign changes, not offsets. Returns the states' indices.
pub fn pointwise_states(ir: &Ir, kind: PredictorKind) -> Vec<usize> {
    let mut states: Vec<usize> = pointwise_signs(ir, kind)
        .into_iter()
        .filter(|i| ir.sign_args[*i].pointwise)
        .filter_map(|i| match ir.sign_args[i].arg.signal {
            Signal::State(s) => Some(s),
            Signal::Input(_) => None,
        })
        .collect();
    states.sort_unstable();
    states.dedup();
    states
}

/// `max over ψ of |share of the mean disturbance|`, on 360 headings.
fn worst_mean(ir: &Ir, plan: &ArgPlan, c: &Conditions) -> f64 {
    let states = vec![0.0; ir.states.len()];
    let inputs = vec![0.0; ir.inputs.len()];
    (0..360)
        .map(|d| {
            let rotation = planar_rotation(f64::from(d).to_radians());
            let sig = Signals {
                states: &states,
                inputs: &inputs,
                rotation: &rotation,
                disturbances: &c.mean,
            };
            plan.eval(&sig, true).abs()
        })
        .fold(0.0, f64::max)
}

/// The band an argument must clear: `3·max(σ_v, σ_e)` over the components
/// in it and the state's noise (A7's `max(η_e, η_v)`), plus the largest
/// uncertainty of a mean in it.
fn band(plan: &ArgPlan, c: &Conditions) -> f64 {
    let state_noise = match plan.signal {
        Signal::State(s) => c.state_noise.get(s).copied().flatten().unwrap_or(0.0),
        Signal::Input(_) => 0.0,
    };
    let (mut spread, mut uncertainty) = (state_noise, 0.0f64);
    for (_, comp) in &plan.shares {
        spread = spread.max(c.std[*comp]);
        uncertainty = uncertainty.max(c.uncertainty[*comp]);
    }
    3.0 * spread + uncertainty
}
