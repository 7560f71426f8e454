//! Values a user gives by name — θ by parameter, constant disturbance
//! components, initial states, the noises of a simulation — matched against
//! the model once, for the CLI and Python alike; each front end words the
//! problems in its own syntax.

use crate::number::short_number;
use leeway_structure::ir::{Ir, Rotation};

/// Largest magnitude of a value given by hand (initial states, disturbance
/// components): squares of larger values approach f64's range inside the
/// regressors.
pub const MAX_GIVEN_VALUE: f64 = 1e12;

/// Whether `v` is a value leeway takes by hand: finite, at most
/// [`MAX_GIVEN_VALUE`] in magnitude.
pub fn given_value_ok(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_GIVEN_VALUE
}

/// A name given that does not fit the model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NameProblem {
    /// The index of the name among those given.
    pub index: usize,
    /// What is wrong, naming it (`` `x` is not a disturbance component ``).
    pub reason: String,
}

/// The unmeasured disturbance components (`current.north`), what a hint lists.
pub fn unmeasured_components(ir: &Ir) -> Vec<String> {
    ir.components
        .iter()
        .filter(|c| !ir.disturbances[c.disturbance].measured)
        .map(|c| format!("{}.{}", ir.disturbances[c.disturbance].name, c.name))
        .collect()
}

/// The hint for a disturbance component that does not fit.
pub fn components_hint(ir: &Ir) -> String {
    let unmeasured = unmeasured_components(ir);
    if unmeasured.is_empty() {
        format!("model `{}` has no unmeasured disturbance", ir.name)
    } else {
        format!(
            "the unmeasured components are {}",
            leeway_structure::grammar::join_capped(&unmeasured, ", ")
        )
    }
}

/// Constant unmeasured disturbance components by name (`north` or
/// `current.north`), in the model's component order, the others zero. A
/// name that is not a component, a measured component (its values come
/// from the data) or one given twice is a problem. The values themselves
/// are checked by the caller (see [`given_value_ok`]).
pub fn disturbance_values(ir: &Ir, given: &[(&str, f64)]) -> Result<Vec<f64>, NameProblem> {
    Ok(disturbance_slots(ir, given)?
        .into_iter()
        .map(|v| v.unwrap_or(0.0))
        .collect())
}

/// Unmeasured disturbance components by name, as [`disturbance_values`]
/// reads them, in the model's component order: `None` where not given.
pub fn disturbance_slots(ir: &Ir, given: &[(&str, f64)]) -> Result<Vec<Option<f64>>, NameProblem> {
    let mut values = vec![None; ir.components.len()];
    for (index, &(name, v)) in given.iter().enumerate() {
        let problem = |reason: String| NameProblem { index, reason };
        let Some(i) = component_named(ir, name) else {
            return Err(problem(format!("`{name}` is not a disturbance component")));
        };
        if ir.disturbances[ir.components[i].disturbance].measured {
            return Err(problem(format!(
                "`{name}` is measured: its values come from the data"
            )));
        }
        if values[i].is_some() {
            return Err(problem(format!("`{name}` is given twice")));
        }
        values[i] = Some(v);
    }
    Ok(values)
}

/// An estimate's disturbance means without the components `ir` measures:
/// IV2 (the augmented predictor) estimates the mean of a measured medium
/// too, and a simulation takes a measured medium's values from the data.
pub fn estimated_unmeasured<'a>(ir: &Ir, means: &[(&'a str, f64)]) -> Vec<(&'a str, f64)> {
    means
        .iter()
        .filter(|(name, _)| {
            component_named(ir, name)
                .is_none_or(|i| !ir.disturbances[ir.components[i].disturbance].measured)
        })
        .copied()
        .collect()
}

/// Where the constant value of an unmeasured disturbance component in a
/// simulation comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Given by the user (`--disturbance`, `disturbances=`).
    Given,
    /// The mean an estimate found (its parameter file or object).
    Estimate,
    /// Zero because nothing gave it: the user must be warned.
    Default,
}

impl Origin {
    /// The word in JSON and tables.
    pub fn as_str(self) -> &'static str {
        match self {
            Origin::Given => "given",
            Origin::Estimate => "estimate",
            Origin::Default => "default",
        }
    }
}

/// The constant unmeasured disturbances a simulation holds, each with where
/// it comes from.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldDisturbances {
    /// Per component of the model (measured ones 0: they come from the data).
    pub values: Vec<f64>,
    /// Per component: `None` for a measured one.
    pub origins: Vec<Option<Origin>>,
}

impl HeldDisturbances {
    /// The unmeasured components as `(current.north, value, origin)`.
    pub fn named(&self, ir: &Ir) -> Vec<(String, f64, Origin)> {
        ir.components
            .iter()
            .zip(self.values.iter().zip(&self.origins))
            .filter_map(|(c, (&v, o))| {
                o.map(|o| {
                    let d = &ir.disturbances[c.disturbance].name;
                    (format!("{d}.{}", c.name), v, o)
                })
            })
            .collect()
    }

    /// The unmeasured media (`current`) with a component zero by default,
    /// and those components: what the warning names.
    pub fn defaulted(&self, ir: &Ir) -> (Vec<String>, Vec<String>) {
        let mut media: Vec<String> = Vec::new();
        let mut components = Vec::new();
        for (c, o) in ir.components.iter().zip(&self.origins) {
            if *o == Some(Origin::Default) {
                let d = &ir.disturbances[c.disturbance].name;
                if !media.contains(d) {
                    media.push(d.clone());
                }
                components.push(format!("{d}.{}", c.name));
            }
        }
        (media, components)
    }
}

/// The disturbances a simulation holds: per unmeasured component the value
/// given (from [`disturbance_slots`]), else the estimate's mean, else zero
/// by default; `zero` (the user asked for no disturbance) makes every
/// component not given a given zero.
pub fn held_disturbances(
    ir: &Ir,
    given: &[Option<f64>],
    zero: bool,
    estimated: &[Option<f64>],
) -> HeldDisturbances {
    let mut values = vec![0.0; ir.components.len()];
    let mut origins = vec![None; ir.components.len()];
    for (i, c) in ir.components.iter().enumerate() {
        if ir.disturbances[c.disturbance].measured {
            continue;
        }
        let (v, o) = match (
            given.get(i).copied().flatten(),
            estimated.get(i).copied().flatten(),
        ) {
            (Some(v), _) => (v, Origin::Given),
            (None, _) if zero => (0.0, Origin::Given),
            (None, Some(v)) => (v, Origin::Estimate),
            (None, None) => (0.0, Origin::Default),
        };
        values[i] = v;
        origins[i] = Some(o);
    }
    HeldDisturbances { values, origins }
}

/// The component `name` stands for, `north` or `current.north`.
fn component_named(ir: &Ir, name: &str) -> Option<usize> {
    ir.components.iter().position(|c| {
        let d = &ir.disturbances[c.disturbance].name;
        name == c.name || name == format!("{d}.{}", c.name)
    })
}

/// The components a name stands for, measured or not: one component
/// (`north` or `current.north`, as [`disturbance_slots`] reads it) or every
/// component of a medium (`current`); empty when it is neither.
pub fn named_components(ir: &Ir, name: &str) -> Vec<usize> {
    match component_named(ir, name) {
        Some(i) => vec![i],
        None => (0..ir.components.len())
            .filter(|&i| ir.disturbances[ir.components[i].disturbance].name == name)
            .collect(),
    }
}

/// The option of a noisy simulation a value was given to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseOption {
    /// How much a disturbance component varies about its mean.
    DisturbanceStd,
    /// How slowly it varies.
    CorrelationTime,
    /// How noisy a sensor is.
    Sensor,
}

impl NoiseOption {
    /// The names the option takes, as a hint lists them.
    pub fn hint(self, ir: &Ir) -> String {
        let media = |measured_only: bool| -> Vec<String> {
            ir.disturbances
                .iter()
                .filter(|d| d.measured || !measured_only)
                .map(|d| d.name.clone())
                .collect()
        };
        let components = |measured_only: bool| -> Vec<String> {
            ir.components
                .iter()
                .filter(|c| ir.disturbances[c.disturbance].measured || !measured_only)
                .map(|c| format!("{}.{}", ir.disturbances[c.disturbance].name, c.name))
                .collect()
        };
        let join = |names: &[String]| leeway_structure::grammar::join_capped(names, ", ");
        match self {
            NoiseOption::DisturbanceStd | NoiseOption::CorrelationTime => {
                if ir.components.is_empty() {
                    return format!("model `{}` has no disturbance", ir.name);
                }
                format!(
                    "the disturbance components are {}; a medium's name ({}) stands for all its components",
                    join(&components(false)),
                    join(&media(false))
                )
            }
            NoiseOption::Sensor => {
                let mut signals = ir.states.clone();
                if let Rotation::Planar { heading, .. } = &ir.rotation {
                    signals.push(heading.clone());
                }
                signals.extend(components(true));
                let measured = media(true);
                let media = if measured.is_empty() {
                    String::new()
                } else {
                    format!(
                        "; a measured medium's name ({}) stands for all its components",
                        join(&measured)
                    )
                };
                format!("the measured signals are {}{media}", join(&signals))
            }
        }
    }
}

/// A noise given that does not fit the model or is out of bounds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NoiseProblem {
    /// The option it was given to.
    pub option: NoiseOption,
    /// The index of the value among those given to that option.
    pub index: usize,
    /// What is wrong (`` `x` is not a disturbance component or medium ``).
    pub reason: String,
}

/// The noises of a simulation as plain numbers in the model's order: how
/// much each disturbance component varies about its mean and how slowly,
/// and the std of each sensor. Drawing them is `leeway-scenarios`' work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SimulationNoise {
    /// Std of each disturbance component about its mean (0: constant).
    pub disturbance_std: Vec<f64>,
    /// Correlation time of each component, s (0: independent samples).
    pub correlation_time: Vec<f64>,
    /// Measurement noise std of each state.
    pub states: Vec<f64>,
    /// Measurement noise std of the heading.
    pub heading: f64,
    /// Sensor noise std of each measured component (unmeasured ones 0).
    pub sensors: Vec<f64>,
}

impl SimulationNoise {
    /// True when nothing is random: every std zero.
    pub fn is_quiet(&self) -> bool {
        self.heading == 0.0
            && [&self.disturbance_std, &self.states, &self.sensors]
                .iter()
                .all(|v| v.iter().all(|s| *s == 0.0))
    }
}

/// The noises given by name (see [`NoiseOption::hint`] for the names): a
/// std or time per component or medium, measured or not; a sensor's std per
/// state, the heading, or a measured component or medium. Every value is
/// finite, at least 0 and at most [`MAX_GIVEN_VALUE`]; a component is given
/// at most once per option; a correlation time names a component with a
/// std (else it would change nothing).
pub fn simulation_noise(
    ir: &Ir,
    disturbance_std: &[(&str, f64)],
    correlation_time: &[(&str, f64)],
    sensors: &[(&str, f64)],
) -> Result<SimulationNoise, NoiseProblem> {
    let n_comp = ir.components.len();
    let std = per_component(ir, NoiseOption::DisturbanceStd, disturbance_std)?;
    let time = per_component(ir, NoiseOption::CorrelationTime, correlation_time)?;
    for (index, (name, _)) in correlation_time.iter().enumerate() {
        if named_components(ir, name).iter().all(|&c| std[c].is_none()) {
            return Err(NoiseProblem {
                option: NoiseOption::CorrelationTime,
                index,
                reason: format!(
                    "`{name}` has no standard deviation given: its correlation time would change nothing"
                ),
            });
        }
    }
    let mut noise = SimulationNoise {
        disturbance_std: std.iter().map(|v| v.unwrap_or(0.0)).collect(),
        correlation_time: time.iter().map(|v| v.unwrap_or(0.0)).collect(),
        states: vec![0.0; ir.states.len()],
        heading: 0.0,
        sensors: vec![0.0; n_comp],
    };
    sensor_noise(ir, sensors, &mut noise)?;
    Ok(noise)
}

/// Why a std or time is out of bounds, if it is.
fn out_of_bounds(option: NoiseOption, v: f64) -> Option<String> {
    let what = match option {
        NoiseOption::CorrelationTime => {
            "a correlation time is at least 0 s (0: independent samples)"
        }
        _ => "a standard deviation is at least 0",
    };
    if !v.is_finite() {
        Some(format!("{v} is not a finite number"))
    } else if v < 0.0 {
        Some(format!("{} is negative: {what}", short_number(v)))
    } else if v > MAX_GIVEN_VALUE {
        Some(format!("{} exceeds {MAX_GIVEN_VALUE:e}", short_number(v)))
    } else {
        None
    }
}

/// Values by component or medium, each component at most once.
fn per_component(
    ir: &Ir,
    option: NoiseOption,
    given: &[(&str, f64)],
) -> Result<Vec<Option<f64>>, NoiseProblem> {
    let mut values = vec![None; ir.components.len()];
    let mut by: Vec<Option<&str>> = vec![None; ir.components.len()];
    for (index, &(name, v)) in given.iter().enumerate() {
        let problem = |reason: String| NoiseProblem {
            option,
            index,
            reason,
        };
        if let Some(why) = out_of_bounds(option, v) {
            return Err(problem(why));
        }
        let components = named_components(ir, name);
        if components.is_empty() {
            return Err(problem(format!(
                "`{name}` is not a disturbance component or medium of model `{}`",
                ir.name
            )));
        }
        for c in components {
            if let Some(earlier) = by[c] {
                return Err(problem(given_twice(ir, c, earlier, name)));
            }
            (values[c], by[c]) = (Some(v), Some(name));
        }
    }
    Ok(values)
}

/// The reason a component is given twice: `` `north` is given twice ``, or
/// `` `current.north` is given twice: by `north` and by `current` ``.
fn given_twice(ir: &Ir, c: usize, earlier: &str, name: &str) -> String {
    if earlier == name {
        return format!("`{name}` is given twice");
    }
    let comp = &ir.components[c];
    let full = format!("{}.{}", ir.disturbances[comp.disturbance].name, comp.name);
    format!("`{full}` is given twice: by `{earlier}` and by `{name}`")
}

/// Sensor noise by state, heading, or measured component or medium, each
/// at most once, into `noise`.
fn sensor_noise(
    ir: &Ir,
    given: &[(&str, f64)],
    noise: &mut SimulationNoise,
) -> Result<(), NoiseProblem> {
    let heading = match &ir.rotation {
        Rotation::Planar { heading, .. } => Some(heading.as_str()),
        _ => None,
    };
    let (mut states, mut heading_given) = (vec![false; ir.states.len()], false);
    let mut components: Vec<Option<&str>> = vec![None; ir.components.len()];
    for (index, &(name, v)) in given.iter().enumerate() {
        let problem = |reason: String| NoiseProblem {
            option: NoiseOption::Sensor,
            index,
            reason,
        };
        let twice = || problem(format!("`{name}` is given twice"));
        if let Some(why) = out_of_bounds(NoiseOption::Sensor, v) {
            return Err(problem(why));
        }
        if let Some(o) = ir.states.iter().position(|s| s == name) {
            if std::mem::replace(&mut states[o], true) {
                return Err(twice());
            }
            noise.states[o] = v;
            continue;
        }
        if heading == Some(name) {
            if std::mem::replace(&mut heading_given, true) {
                return Err(twice());
            }
            noise.heading = v;
            continue;
        }
        let named = named_components(ir, name);
        if named.is_empty() {
            return Err(problem(format!(
                "`{name}` is not a state, the heading or a measured disturbance of model `{}`",
                ir.name
            )));
        }
        for c in named {
            if !ir.disturbances[ir.components[c].disturbance].measured {
                return Err(problem(format!(
                    "`{name}` is not measured: no sensor records it"
                )));
            }
            if let Some(earlier) = components[c] {
                return Err(problem(given_twice(ir, c, earlier, name)));
            }
            (noise.sensors[c], components[c]) = (v, Some(name));
        }
    }
    Ok(())
}

/// How names given for θ match the model's parameters.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ParameterNames {
    /// Per name given, the parameter's index (`None`: unknown, or given before).
    pub slots: Vec<Option<usize>>,
    /// Names that are not parameters (indices among those given).
    pub unknown: Vec<usize>,
    /// Names given again, with the index of their first.
    pub twice: Vec<(usize, usize)>,
    /// Parameters not given (indices among the model's parameters).
    pub missing: Vec<usize>,
}

impl ParameterNames {
    /// Whether every parameter is given exactly once and nothing else is.
    pub fn complete(&self) -> bool {
        self.unknown.is_empty() && self.twice.is_empty() && self.missing.is_empty()
    }
}

/// Matches names given for θ against the model's parameters: every
/// parameter exactly once, nothing else.
pub fn parameter_names<'a>(ir: &Ir, names: impl IntoIterator<Item = &'a str>) -> ParameterNames {
    let mut first: Vec<Option<usize>> = vec![None; ir.parameters.len()];
    let mut out = ParameterNames::default();
    for (index, name) in names.into_iter().enumerate() {
        match ir.parameters.iter().position(|p| p.name == name) {
            None => {
                out.unknown.push(index);
                out.slots.push(None);
            }
            Some(p) => match first[p] {
                Some(earlier) => {
                    out.twice.push((index, earlier));
                    out.slots.push(None);
                }
                None => {
                    first[p] = Some(index);
                    out.slots.push(Some(p));
                }
            },
        }
    }
    out.missing = (0..ir.parameters.len())
        .filter(|&p| first[p].is_none())
        .collect();
    out
}

#[cfg(test)]
mod tests {
    use super::{
        NoiseOption, NoiseProblem, SimulationNoise, disturbance_values, parameter_names,
        simulation_noise,
    };

    fn ir() -> leeway_structure::ir::Ir {
        let path = format!("{}/../examples/models/ship.som", env!("CARGO_MANIFEST_DIR"));
        let source = std::fs::read_to_string(path).unwrap_or_default();
        let c = leeway_structure::compile(&source, &Default::default());
        c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics))
    }

    #[test]
    fn every_parameter_once_and_nothing_else() {
        let ir = ir();
        let names: Vec<&str> = ir
            .parameters
            .iter()
            .rev()
            .map(|p| p.name.as_str())
            .collect();
        let m = parameter_names(&ir, names.iter().copied());
        assert!(m.complete());
        assert_eq!(m.slots[0], Some(ir.parameters.len() - 1));
        let m = parameter_names(&ir, ["X_u", "c", "X_u"]);
        assert_eq!(m.unknown, vec![1]);
        assert_eq!(m.twice, vec![(2, 0)]);
        assert_eq!(m.missing.len(), ir.parameters.len() - 1);
        assert!(!m.complete());
    }

    #[test]
    fn disturbance_components_by_name() {
        let ir = ir();
        assert_eq!(
            disturbance_values(&ir, &[("current.east", 0.3), ("north", 0.1)]),
            Ok(vec![0.1, 0.3, 0.0, 0.0])
        );
        let e = disturbance_values(&ir, &[("north", 0.1), ("current.north", 0.2)]);
        assert_eq!(
            e.map_err(|p| (p.index, p.reason)),
            Err((1, "`current.north` is given twice".to_string()))
        );
        let e = disturbance_values(&ir, &[("wind.x", 0.1)]);
        assert!(e.is_err_and(|p| p.reason.contains("not a disturbance component")));
        let e = disturbance_values(&ir, &[("wind_n", 0.1)]);
        assert!(e.is_err_and(|p| p.reason.contains("is measured")));
    }

    #[test]
    fn noises_by_component_medium_state_or_heading() {
        let ir = ir();
        let noise = simulation_noise(
            &ir,
            &[("current", 0.03), ("wind.wind_e", 0.5)],
            &[("north", 60.0)],
            &[("u", 0.01), ("psi", 0.005), ("wind", 0.2)],
        );
        assert_eq!(
            noise,
            Ok(SimulationNoise {
                disturbance_std: vec![0.03, 0.03, 0.0, 0.5],
                correlation_time: vec![60.0, 0.0, 0.0, 0.0],
                states: vec![0.01, 0.0, 0.0],
                heading: 0.005,
                sensors: vec![0.0, 0.0, 0.2, 0.2],
            })
        );
        assert!(noise.is_ok_and(|n| !n.is_quiet()));
        assert!(simulation_noise(&ir, &[("current", 0.0)], &[], &[]).is_ok_and(|n| n.is_quiet()));
    }

    #[test]
    fn noises_that_do_not_fit_name_the_option_and_the_item() {
        let ir = ir();
        let problem = |std: &[(&str, f64)], time: &[(&str, f64)], sensors: &[(&str, f64)]| {
            simulation_noise(&ir, std, time, sensors).err()
        };
        let at = |option, index, reason: &str| {
            Some(NoiseProblem {
                option,
                index,
                reason: reason.to_string(),
            })
        };
        use NoiseOption::*;
        assert_eq!(
            problem(&[("north", 0.1), ("tide", 0.1)], &[], &[]),
            at(
                DisturbanceStd,
                1,
                "`tide` is not a disturbance component or medium of model `Ship`"
            )
        );
        assert_eq!(
            problem(&[("north", -0.1)], &[], &[]),
            at(
                DisturbanceStd,
                0,
                "-0.1 is negative: a standard deviation is at least 0"
            )
        );
        assert_eq!(
            problem(&[("current", 0.1), ("current.east", 0.2)], &[], &[]),
            at(
                DisturbanceStd,
                1,
                "`current.east` is given twice: by `current` and by `current.east`"
            )
        );
        assert_eq!(
            problem(&[("north", 0.1)], &[("north", -1.0)], &[]),
            at(
                CorrelationTime,
                0,
                "-1 is negative: a correlation time is at least 0 s (0: independent samples)"
            )
        );
        assert_eq!(
            problem(&[("north", 0.1)], &[("east", 5.0)], &[]),
            at(
                CorrelationTime,
                0,
                "`east` has no standard deviation given: its correlation time would change nothing"
            )
        );
        assert_eq!(
            problem(&[], &[], &[("current.north", 0.1)]),
            at(
                Sensor,
                0,
                "`current.north` is not measured: no sensor records it"
            )
        );
        assert_eq!(
            problem(&[], &[], &[("u", 0.1), ("w", 0.1)]),
            at(
                Sensor,
                1,
                "`w` is not a state, the heading or a measured disturbance of model `Ship`"
            )
        );
        assert_eq!(
            problem(&[], &[], &[("u", f64::INFINITY)]),
            at(Sensor, 0, "inf is not a finite number")
        );
        assert_eq!(
            problem(&[], &[], &[("u", 2e12)]),
            at(Sensor, 0, "2e12 exceeds 1e12")
        );
        assert_eq!(
            problem(&[], &[], &[("psi", 0.1), ("psi", 0.2)]),
            at(Sensor, 1, "`psi` is given twice")
        );
        assert_eq!(
            Sensor.hint(&ir),
            "the measured signals are u, v, r, psi, wind.wind_n, wind.wind_e; a measured medium's name (wind) stands for all its components"
        );
        assert_eq!(
            DisturbanceStd.hint(&ir),
            "the disturbance components are current.north, current.east, wind.wind_n, wind.wind_e; a medium's name (current, wind) stands for all its components"
        );
    }
}
