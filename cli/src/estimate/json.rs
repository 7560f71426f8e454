//! The JSON document of `leeway estimate --json`: a contract scripts rely on
//! (README, "Estimating"). Fields may be added; none is renamed or removed.
//! It is printed for every outcome: on an error the result fields are empty
//! and `errors` says why.

use super::{EstimateArgs, MethodArg, Outcome};
use crate::output::Ordered;
use crate::problem::{Failure, JsonError};
use leeway_runtime::estimate::{ColumnEstimate, Diagnostics};
use leeway_runtime::signs::ArgSign;
use serde::Serialize;

/// The whole document.
#[derive(Debug, Serialize)]
pub struct Report {
    /// `model Name`, or null when the model did not compile (set whenever it
    /// compiled, also on a data or estimate error).
    model: Option<String>,
    /// The model file as given.
    file: String,
    /// The data files as given.
    data: Vec<String>,
    /// `ls`, `iv1`, `iv2` or `iv3`.
    method: &'static str,
    /// Experiments and their sample counts.
    experiments: Vec<Experiment>,
    /// θ by name, in the model's order (held parameters at their nominal value).
    estimates: Ordered<f64>,
    /// Standard errors of θ (null for held parameters).
    std_errors: Ordered<Option<f64>>,
    /// θ with status and meaning.
    parameters: Vec<Column>,
    /// The nuisance parameters (moments of the unmeasured disturbances times θ).
    nuisance: Vec<Column>,
    /// `{disturbance: {component: {mean, std_error}}}` for unmeasured media.
    disturbances: Ordered<Ordered<Moment>>,
    /// Per experiment, the sign of every modulus argument.
    sign_patterns: Vec<SignPattern>,
    /// How the estimate was computed (an empty object on error).
    diagnostics: serde_json::Value,
    /// Per data file: comment lines skipped, time-stamp jitter, resampling.
    data_files: Vec<crate::model::DataFileJson>,
    /// `{signal: unit}` as declared in the model's `data { }` (values converted to base units).
    data_units: Ordered<String>,
    warnings: Vec<String>,
    /// Facts worth knowing that need no action (e.g. pointwise moduli crossing zero).
    notes: Vec<String>,
    errors: Vec<JsonError>,
}

#[derive(Debug, Serialize)]
struct Experiment {
    name: String,
    samples: usize,
}

#[derive(Debug, Serialize)]
struct Column {
    name: String,
    /// `theta`, `rho` or `lambda`.
    kind: &'static str,
    value: Option<f64>,
    std_error: Option<f64>,
    /// `estimated`, `held at nominal`, `held at 0`, `dropped`.
    status: String,
    /// What the value estimates.
    estimates: String,
    /// For a parameter that estimates an aggregate, the sum it stands for
    /// (`X_uu + W_uu`); null otherwise.
    aggregate: Option<String>,
}

#[derive(Debug, Serialize)]
struct Moment {
    mean: f64,
    std_error: Option<f64>,
}

#[derive(Debug, Serialize)]
struct SignPattern {
    experiment: String,
    /// `{argument: "+" | "-"}` for the arguments the predictor fixes.
    pattern: Ordered<&'static str>,
    arguments: Vec<Argument>,
    /// Arguments relative to a measured medium, evaluated pointwise by IV3.
    pointwise: Vec<Argument>,
}

#[derive(Debug, Serialize)]
struct Argument {
    argument: String,
    sign: &'static str,
    /// Fraction of the samples with the other sign (0 when paper A7 holds).
    minority_fraction: f64,
}

#[derive(Debug, Serialize)]
struct DiagnosticsJson<'a> {
    #[serde(flatten)]
    estimator: &'a Diagnostics,
    /// Gain of `Δψ/h` on the yaw rate per experiment (≈ 1 when consistent).
    heading_gains: Ordered<Option<f64>>,
}

fn sign(s: i8) -> &'static str {
    if s < 0 { "-" } else { "+" }
}

fn argument(a: &ArgSign) -> Argument {
    Argument {
        argument: a.argument.clone(),
        sign: sign(a.sign),
        minority_fraction: a.minority_fraction,
    }
}

fn column(c: &ColumnEstimate, aggregates: &[String]) -> Column {
    Column {
        aggregate: super::text::aggregate_of(c, aggregates),
        name: c.name.clone(),
        kind: c.kind,
        value: c.value,
        std_error: c.std_error,
        status: c.status.clone(),
        estimates: c.estimates.clone(),
    }
}

/// The method's name on the command line.
pub fn method_name(m: MethodArg) -> &'static str {
    match m {
        MethodArg::Ls => "ls",
        MethodArg::Iv1 => "iv1",
        MethodArg::Iv2 => "iv2",
        MethodArg::Iv3 => "iv3",
    }
}

/// The document for a result or a failure.
pub fn report(
    args: &EstimateArgs,
    model: Option<String>,
    result: &Result<Outcome, Failure>,
    warnings: Vec<String>,
) -> Report {
    let mut r = Report {
        model,
        file: args.model.display().to_string(),
        data: args.data.iter().map(|p| p.display().to_string()).collect(),
        method: method_name(args.method),
        experiments: Vec::new(),
        estimates: Ordered::default(),
        std_errors: Ordered::default(),
        parameters: Vec::new(),
        nuisance: Vec::new(),
        disturbances: Ordered::default(),
        sign_patterns: Vec::new(),
        diagnostics: serde_json::Value::Object(serde_json::Map::new()),
        data_files: Vec::new(),
        data_units: Ordered::default(),
        warnings,
        notes: Vec::new(),
        errors: Vec::new(),
    };
    let o = match result {
        Ok(o) => o,
        Err(f) => {
            r.errors = f.json();
            return r;
        }
    };
    let e = &o.estimate;
    r.model = Some(o.model.clone());
    r.notes = e.notes.clone();
    r.data_files = crate::model::data_files_json(&o.data_notes);
    r.data_units = Ordered(
        o.data_units
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect(),
    );
    r.experiments = o
        .experiments
        .iter()
        .map(|(name, samples)| Experiment {
            name: name.clone(),
            samples: *samples,
        })
        .collect();
    r.estimates = Ordered(e.parameters.iter().cloned().zip(e.theta.clone()).collect());
    r.std_errors = Ordered(
        e.parameters
            .iter()
            .cloned()
            .zip(e.std_errors.clone())
            .collect(),
    );
    r.parameters = e
        .columns
        .iter()
        .filter(|c| c.kind == "theta")
        .map(|c| column(c, &e.diagnostics.aggregates))
        .collect();
    r.nuisance = e
        .columns
        .iter()
        .filter(|c| c.kind != "theta")
        .map(|c| column(c, &e.diagnostics.aggregates))
        .collect();
    let mut disturbances: Vec<(String, Ordered<Moment>)> = Vec::new();
    for m in &e.disturbances {
        let moment = Moment {
            mean: m.mean,
            std_error: m.std_error,
        };
        match disturbances.iter_mut().find(|(d, _)| *d == m.disturbance) {
            Some((_, comps)) => comps.0.push((m.component.clone(), moment)),
            None => disturbances.push((
                m.disturbance.clone(),
                Ordered(vec![(m.component.clone(), moment)]),
            )),
        }
    }
    r.disturbances = Ordered(disturbances);
    r.sign_patterns = e
        .sign_patterns
        .iter()
        .map(|s| SignPattern {
            experiment: s.experiment.clone(),
            pattern: Ordered(
                s.arguments
                    .iter()
                    .map(|a| (a.argument.clone(), sign(a.sign)))
                    .collect(),
            ),
            arguments: s.arguments.iter().map(argument).collect(),
            pointwise: s.pointwise.iter().map(argument).collect(),
        })
        .collect();
    let diagnostics = DiagnosticsJson {
        estimator: &e.diagnostics,
        heading_gains: Ordered(o.heading_gains.clone()),
    };
    r.diagnostics = serde_json::to_value(&diagnostics)
        .unwrap_or_else(|_| serde_json::Value::Object(serde_json::Map::new()));
    r
}
