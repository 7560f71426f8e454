//! `leeway.simulate` and `leeway.validate`: the libraries' simulation and
//! validation (`leeway_data::input`, `leeway_model::simulate`), the code
//! `leeway simulate` and `leeway validate` run, on frames handed over from
//! Python. A simulation's input frame is read by the CLI's input reader (the
//! frame written once as CSV text in memory, every value in its shortest
//! round-trip form, so the reader sees the bits numpy holds); validation data
//! are loaded as `leeway.estimate` loads them.

use crate::data::{self, FrameArg, borrow_frames};
use crate::failure::Failure;
use crate::model::Model;
use crate::options::load_options;
use leeway_data::Columns;
use leeway_data::DataError;
use leeway_data::input::OptionNames;
use leeway_data::input::read_input;
use leeway_data::write;
use leeway_model::Interpreter;
use leeway_model::Source;
use leeway_model::experiment::column_name;
use leeway_model::given::{
    NoiseOption, SimulationNoise, components_hint, disturbance_slots, estimated_unmeasured,
    given_value_ok, held_disturbances, simulation_noise,
};
use leeway_model::simulate::Disturbances;
use leeway_model::simulate::simulate_written;
use leeway_model::validation::compare;
use leeway_report::heading_gains;
use leeway_report::heading_warnings;
use leeway_report::unit_warnings;
use leeway_scenarios::noisy::simulate_noisy;
use leeway_structure::grammar::and_list;
use leeway_structure::ir::{Ir, Rotation};
use numpy::PyArray1;
use pyo3::prelude::*;

/// The largest initial value or disturbance accepted, as on the command line.
const MAX_VALUE: f64 = 1e12;

/// The Python keywords as hints name them.
const NAMES: OptionNames = OptionNames {
    x0: |name| format!("x0={{\"{name}\": VALUE}}"),
    step: "step=H",
};

fn checked(what: &str, name: &str, v: f64) -> Result<f64, Failure> {
    if given_value_ok(v) {
        Ok(v)
    } else {
        Err(Failure::option(
            format!(
                "{what}[{name:?}] = {v} is not a finite number of at most {MAX_VALUE:e} in magnitude"
            ),
            Some("give values in the model's base units".into()),
        ))
    }
}

/// Initial values by state or heading name (as `--x0` takes them).
fn initial_values(ir: &Ir, x0: &[(String, f64)]) -> Result<Vec<(String, f64)>, Failure> {
    let heading = match &ir.rotation {
        Rotation::Planar { heading, .. } => Some(heading.as_str()),
        _ => None,
    };
    let mut known: Vec<&str> = ir.states.iter().map(String::as_str).collect();
    known.extend(heading);
    x0.iter()
        .map(|(name, v)| {
            if !known.contains(&name.as_str()) {
                return Err(Failure::option(
                    format!(
                        "x0: `{name}` is not a state or the heading of model `{}`",
                        ir.name
                    ),
                    Some(format!(
                        "initial values can be given for {}",
                        leeway_structure::grammar::join_capped(&known, ", ")
                    )),
                ));
            }
            Ok((name.clone(), checked("x0", name, *v)?))
        })
        .collect()
}

/// The unmeasured disturbance components a simulation holds, as
/// `(current.north, value, origin)`: `given` (or `"zero"`), else the
/// estimate's `means`, else zero with a warning in Python's spelling.
pub(crate) type Held = Vec<(String, f64, &'static str)>;

/// The disturbances a simulation with `what` holds (see [`Held`]): values
/// for the model and the warning when a medium is zero by default.
pub(crate) fn held(
    ir: &Ir,
    given: &[(String, f64)],
    zero: bool,
    means: Option<&[(String, f64)]>,
    what: &str,
) -> Result<(Vec<f64>, Held, Option<String>), Failure> {
    let slots = |pairs: &[(String, f64)], label: &str| -> Result<Vec<Option<f64>>, Failure> {
        let mut named = Vec::with_capacity(pairs.len());
        for (name, v) in pairs {
            named.push((name.as_str(), checked(label, name, *v)?));
        }
        if label != "disturbances" {
            // An estimate's means: a medium this model measures comes from the data.
            named = estimated_unmeasured(ir, &named);
        }
        disturbance_slots(ir, &named).map_err(|p| {
            Failure::option(format!("{label}: {}", p.reason), Some(components_hint(ir)))
        })
    };
    let given = slots(given, "disturbances")?;
    let estimated = match means {
        Some(m) => slots(m, "the estimate's disturbance means")?,
        None => vec![None; ir.components.len()],
    };
    let held = held_disturbances(ir, &given, zero, &estimated);
    let (media, components) = held.defaulted(ir);
    let warning = (!media.is_empty()).then(|| {
        let why = if means.is_some() {
            "the estimate has no mean for it"
        } else {
            "it holds no disturbance means (an Estimate does)"
        };
        let values: Vec<String> = components.iter().map(|c| format!("{c:?}: VALUE")).collect();
        format!(
            "{} taken as zero while simulating with {what}: {why}; pass disturbances={{{}}} or disturbances=\"zero\"",
            and_list(media.iter().map(|m| format!("`{m}`"))),
            values.join(", ")
        )
    });
    let named = held
        .named(ir)
        .into_iter()
        .map(|(n, v, o)| (n, v, o.as_str()))
        .collect();
    Ok((held.values, named, warning))
}

/// Values by name as `leeway_model::given` takes them.
fn named(given: &[(String, f64)]) -> Vec<(&str, f64)> {
    given.iter().map(|(n, v)| (n.as_str(), *v)).collect()
}

/// The noises of a simulation as `simulation_noise` reads them, its
/// problems in Python's spelling (`noise["w"]: ...`).
fn noise(
    ir: &Ir,
    disturbance_std: &[(String, f64)],
    correlation_time: &[(String, f64)],
    sensors: &[(String, f64)],
) -> Result<SimulationNoise, Failure> {
    simulation_noise(
        ir,
        &named(disturbance_std),
        &named(correlation_time),
        &named(sensors),
    )
    .map_err(|p| {
        let (keyword, given) = match p.option {
            NoiseOption::DisturbanceStd => ("disturbance_std", disturbance_std),
            NoiseOption::CorrelationTime => ("correlation_time", correlation_time),
            NoiseOption::Sensor => ("noise", sensors),
        };
        let name = given.get(p.index).map_or("", |(n, _)| n.as_str());
        let mut hint = p.option.hint(ir);
        if p.option == NoiseOption::CorrelationTime {
            hint.push_str("; a correlation time shapes a component given a disturbance_std");
        }
        Failure::option(format!("{keyword}[{name:?}]: {}", p.reason), Some(hint))
    })
}

/// A simulated trajectory: the columns of `leeway simulate`'s output
/// (`leeway_data::write::header`), when it diverged, why (the columns then
/// hold the samples before), the disturbances held and the warnings.
type Simulated<'py> = (
    Vec<(String, Bound<'py, PyArray1<f64>>)>,
    Option<String>,
    Held,
    Vec<String>,
);

/// `leeway simulate` of `model` with `theta` on the input frame: `x0` gives
/// or overrides initial values, `disturbances` constant unmeasured
/// components (`zero`: all not given are zero), the others the estimate's
/// `means` when θ is an estimate (see [`held`]); `disturbance_std`,
/// `correlation_time`, `noise` and `seed` as `--disturbance-std`,
/// `--correlation-time`, `--noise` and `--seed`. The GIL is released while
/// the frame is read and simulated.
#[pyfunction]
#[pyo3(signature = (model, frame, theta, x0, disturbances, zero=false, means=None, step=None, disturbance_std=Vec::new(), correlation_time=Vec::new(), noise=Vec::new(), seed=0))]
#[allow(clippy::too_many_arguments)]
pub fn simulate_columns<'py>(
    py: Python<'py>,
    model: &Model,
    frame: FrameArg<'py>,
    theta: Vec<f64>,
    x0: Vec<(String, f64)>,
    disturbances: Vec<(String, f64)>,
    zero: bool,
    means: Option<Vec<(String, f64)>>,
    step: Option<f64>,
    disturbance_std: Vec<(String, f64)>,
    correlation_time: Vec<(String, f64)>,
    noise: Vec<(String, f64)>,
    seed: u64,
) -> PyResult<Simulated<'py>> {
    let ir = &model.ir;
    check_theta(ir, &theta)?;
    let options = load_options(ir, step, None, None)?;
    let x0 = initial_values(ir, &x0)?;
    let (dist, named, warning) = held(ir, &disturbances, zero, means.as_deref(), "theta")?;
    let noise = self::noise(ir, &disturbance_std, &correlation_time, &noise)?;
    let frames = borrow_frames(std::slice::from_ref(&frame))?;
    let frame = &frames[0];
    let (header, columns, diverged) = py.detach(|| -> Result<_, Failure> {
        // The columns read in place, located by positional row.
        let read = |e: DataError| Failure::data(&e);
        let experiment = column_name(ir, "experiment");
        let mut table = Columns::new(
            frame.name,
            &frame.columns,
            frame.experiment.map(|l| (experiment.as_str(), l)),
        )
        .map_err(read)?;
        let input = read_input(&mut table, ir, &options, &x0, &NAMES).map_err(read)?;
        let interpreter = Interpreter::new(ir.clone());
        let e = &input.experiment;
        // As the CLI: with dead times the output starts `d_max` rows in.
        let lead = leeway_model::delay::dead_times(ir, &e.name, e.h)
            .map_err(|d| {
                Failure::option(
                    d.to_string(),
                    Some("declare the dead time in steps, or in seconds that are a whole number of the input's sample time".into()),
                )
            })?
            .max;
        let t0 = match lead {
            0 => input.t0,
            d => input.t0 + d as f64 * e.h,
        };
        // As the CLI: the samples before a divergence; without noise, the
        // plain simulation.
        let written = if noise.is_quiet() {
            simulate_written(&interpreter, &theta, e, Disturbances::Constant(&dist))
        } else {
            simulate_noisy(&interpreter, &theta, e, &dist, &noise, seed)
        };
        let (result, finite) = (written.experiment, written.samples);
        let diverged = written.diverged.then(|| {
            let t = t0 + finite as f64 * e.h;
            format!(
                "the simulation diverged at sample {finite} (time {t}): the states left the finite numbers; the {finite} rows before are returned"
            )
        });
        Ok((
            write::header(ir, 1),
            write::columns(ir, &result, t0),
            diverged,
        ))
    })?;
    let columns = header
        .into_iter()
        .zip(columns)
        .map(|(name, c)| (name, PyArray1::from_vec(py, c)))
        .collect();
    Ok((columns, diverged, named, warning.into_iter().collect()))
}

pub(crate) fn check_theta(ir: &Ir, theta: &[f64]) -> Result<(), Failure> {
    if theta.len() != ir.parameters.len() {
        return Err(Failure::params(format!(
            "θ has {} values, model `{}` {} parameters",
            theta.len(),
            ir.name,
            ir.parameters.len()
        )));
    }
    if let Some((p, v)) = ir
        .parameters
        .iter()
        .zip(theta)
        .find(|(_, v)| !v.is_finite())
    {
        return Err(Failure::params(format!(
            "θ[{:?}] = {v} is not a finite number",
            p.name
        )));
    }
    Ok(())
}

/// One row of validation fits: which θ, the experiment, its samples,
/// whether the simulation diverged, and the fit per output (the states,
/// then the heading when integrated; `None` when undefined).
type FitRow = (usize, String, usize, bool, Vec<Option<f64>>);

/// What `leeway validate` reports: the outputs (table columns), a row per θ
/// and experiment, per θ the mean fit per output, the warnings, and per θ
/// the disturbances held.
type Fits = (
    Vec<String>,
    Vec<FitRow>,
    Vec<Vec<Option<f64>>>,
    Vec<String>,
    Vec<Held>,
);

/// `leeway validate` of `model` with each θ on the frames' experiments
/// (loaded as `leeway.estimate` loads them). `names` names each θ in
/// warnings. The GIL is released while loading and simulating.
#[pyfunction]
#[pyo3(signature = (model, frames, thetas, names, disturbances, zero=false, means=Vec::new(), step=None, time_tolerance=0.05, resample=None))]
#[allow(clippy::too_many_arguments)]
pub fn validate_fits(
    py: Python<'_>,
    model: &Model,
    frames: Vec<FrameArg<'_>>,
    thetas: Vec<Vec<f64>>,
    names: Vec<String>,
    disturbances: Vec<(String, f64)>,
    zero: bool,
    means: Vec<Option<Vec<(String, f64)>>>,
    step: Option<f64>,
    time_tolerance: f64,
    resample: Option<f64>,
) -> PyResult<Fits> {
    let ir = &model.ir;
    for theta in &thetas {
        check_theta(ir, theta)?;
    }
    let options = load_options(ir, step, Some(time_tolerance), resample)?;
    let (mut dist, mut named, mut held_warnings) = (Vec::new(), Vec::new(), Vec::new());
    for (m, name) in names.iter().enumerate() {
        let estimated = means.get(m).and_then(Option::as_deref);
        let (values, n, w) = held(ir, &disturbances, zero, estimated, name)?;
        dist.push(values);
        named.push(n);
        held_warnings.extend(w);
    }
    let frames = borrow_frames(&frames)?;
    let fits = py.detach(|| -> Result<Fits, Failure> {
        let (experiments, _notes) = data::load(ir, &frames, &options)?;
        let sources: Vec<&dyn Source> = experiments.iter().map(|e| e as &dyn Source).collect();
        let mut warnings = held_warnings;
        warnings.extend(unit_warnings(ir, &sources));
        warnings.extend(heading_warnings(ir, &heading_gains(ir, &sources)));
        let interpreter = Interpreter::new(ir.clone());
        let comparison = compare(&interpreter, &thetas, &names, &experiments, &dist);
        warnings.extend(comparison.warnings);
        let rows = comparison
            .validations
            .iter()
            .enumerate()
            .flat_map(|(m, validations)| {
                experiments
                    .iter()
                    .zip(validations)
                    .map(move |(e, v)| (m, e.name.clone(), e.len(), v.diverged(), v.outputs()))
            })
            .collect();
        let (outputs, means) = (comparison.outputs, comparison.means);
        Ok((outputs, rows, means, warnings, named))
    })?;
    Ok(fits)
}
