//! Validation: θ simulated on recorded experiments and fitted, as MATLAB's
//! `compare` does, with what a user must be told about it (constant
//! measurements, divergence, fits below the mean) — one implementation for
//! `leeway validate` and `leeway.validate`.

use crate::experiment::Experiment;
use crate::model::Model;
use crate::simulate::{Disturbances, Trajectory, fits, heading_fit, simulate};
use leeway_structure::ir::Rotation;

/// One θ simulated on one recorded experiment, against its measurement.
#[derive(Clone, Debug, PartialEq)]
pub struct Validation {
    /// The simulation (from the experiment's first sample, with its inputs,
    /// measured disturbances and rotation).
    pub trajectory: Trajectory,
    /// Fit per state in % ([`fit`](crate::simulate::fit)); `None` when the
    /// measurement is constant or the simulation diverged.
    pub fits: Vec<Option<f64>>,
    /// For a planar heading, the fit of the integrated heading against the
    /// measured one [`unwrap_heading`](crate::simulate::unwrap_heading)
    /// (`Some(None)` when undefined); `None` for a model without one.
    pub heading_fit: Option<Option<f64>>,
}

impl Validation {
    /// The simulation left the finite numbers.
    pub fn diverged(&self) -> bool {
        self.trajectory.diverged
    }

    /// The fits per output: the states, then the heading when integrated.
    pub fn outputs(&self) -> Vec<Option<f64>> {
        let mut out = self.fits.clone();
        out.extend(self.heading_fit);
        out
    }
}

/// Simulates `model` with `theta` on the experiment and fits every output,
/// as MATLAB's `compare` does.
pub fn validate(
    model: &dyn Model,
    theta: &[f64],
    data: &Experiment,
    disturbances: Disturbances,
) -> Validation {
    let trajectory = simulate(model, theta, data, disturbances);
    let fits = fits(data, &trajectory)
        .into_iter()
        .map(|f| f.is_finite().then_some(f))
        .collect();
    // A diverged simulation has no fit, its integrated heading included
    // (the heading stays finite for a while after the states run away).
    let heading_fit = matches!(model.ir().rotation, Rotation::Planar { .. }).then(|| {
        let f = heading_fit(data, &trajectory);
        (f.is_finite() && !trajectory.diverged).then_some(f)
    });
    Validation {
        trajectory,
        fits,
        heading_fit,
    }
}

impl Validation {
    /// A warning when the simulation fits an output worse than the
    /// measurement's own mean would (a fit below 0 %): such a model does not
    /// describe the data, whatever else it fits. `names`: the outputs (the
    /// states, then the heading), `what`: the θ and experiment, for the text.
    pub fn below_mean(&self, names: &[String], what: &str) -> Option<String> {
        if self.diverged() {
            return None; // said as a divergence
        }
        let below: Vec<String> = names
            .iter()
            .zip(self.outputs())
            .filter_map(|(n, f)| f.filter(|f| *f < 0.0).map(|f| format!("`{n}` at {f:.1} %")))
            .collect();
        (!below.is_empty()).then(|| {
            format!(
                "{what}: the simulation fits {} — worse than the data's mean, a constant, would: the model does not describe these data",
                leeway_structure::grammar::and_list(below)
            )
        })
    }
}

/// The mean fit over experiments per output ([`Validation::outputs`]):
/// `None` for every output when an experiment diverged (a mean would flatter
/// the model), and for an output no experiment defines; experiments whose
/// measurement is constant (fit undefined) are left out.
pub fn mean_fits(validations: &[Validation]) -> Vec<Option<f64>> {
    let outputs: Vec<Vec<Option<f64>>> = validations.iter().map(Validation::outputs).collect();
    let n = outputs.first().map_or(0, Vec::len);
    let diverged = validations.iter().any(Validation::diverged);
    (0..n)
        .map(|o| {
            if diverged {
                return None;
            }
            let defined: Vec<f64> = outputs.iter().filter_map(|f| f[o]).collect();
            (!defined.is_empty()).then(|| defined.iter().sum::<f64>() / defined.len() as f64)
        })
        .collect()
}

/// Several θ validated on the same experiments.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The outputs: the states, then the heading when integrated.
    pub outputs: Vec<String>,
    /// Per θ, per experiment.
    pub validations: Vec<Vec<Validation>>,
    /// Per θ, the mean fit of each output over the experiments.
    pub means: Vec<Vec<Option<f64>>>,
    /// What the user must be told, in order: an output constant in the data
    /// (once, for the first θ), a simulation that diverged, fits below the
    /// data's mean.
    pub warnings: Vec<String>,
}

/// Validates every θ (named by `names`; `θ` where a name is missing) on
/// every experiment, each θ with its constant disturbances (`disturbances[m]`
/// for `thetas[m]`: an estimate's own means, say; zero where missing).
pub fn compare(
    model: &dyn Model,
    thetas: &[Vec<f64>],
    names: &[String],
    experiments: &[Experiment],
    disturbances: &[Vec<f64>],
) -> Comparison {
    let ir = model.ir();
    let mut outputs = ir.states.clone();
    if let Rotation::Planar { heading, .. } = &ir.rotation {
        outputs.push(heading.clone());
    }
    let mut warnings = Vec::new();
    let mut all = Vec::with_capacity(thetas.len());
    let mut means = Vec::with_capacity(thetas.len());
    for (m, theta) in thetas.iter().enumerate() {
        let name = names.get(m).map_or("θ", String::as_str);
        let zero = vec![0.0; ir.components.len()];
        let held = disturbances.get(m).unwrap_or(&zero);
        let validations: Vec<Validation> = experiments
            .iter()
            .map(|e| {
                let v = validate(model, theta, e, Disturbances::Constant(held));
                warnings.extend(told(&v, e, name, m == 0, &outputs, &ir.states));
                v
            })
            .collect();
        means.push(mean_fits(&validations));
        all.push(validations);
    }
    Comparison {
        outputs,
        validations: all,
        means,
        warnings,
    }
}

/// What one validation tells the user (see [`Comparison::warnings`]).
fn told(
    v: &Validation,
    e: &Experiment,
    name: &str,
    first: bool,
    outputs: &[String],
    states: &[String],
) -> Vec<String> {
    let mut warnings = Vec::new();
    for (f, output) in v.fits.iter().zip(states) {
        // Said once, for the first θ: it is a property of the data.
        if f.is_none() && !v.diverged() && first {
            warnings.push(format!(
                "experiment `{}`: `{output}` is constant in the data, so its fit is undefined",
                e.name
            ));
        }
    }
    if v.diverged() {
        warnings.push(format!(
            "{name}, experiment `{}`: the simulation diverged (the states left the finite numbers); check the parameters",
            e.name
        ));
    }
    warnings.extend(v.below_mean(outputs, &format!("{name}, experiment `{}`", e.name)));
    warnings
}
