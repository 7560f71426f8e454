//! Values a user gives by name — θ by parameter, constant disturbance
//! components, initial states — matched against the model once, for the CLI
//! and Python alike; each front end words the problems in its own syntax.

use leeway_structure::ir::Ir;

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
        let found = ir.components.iter().position(|c| {
            let d = &ir.disturbances[c.disturbance].name;
            name == c.name || name == format!("{d}.{}", c.name)
        });
        let Some(i) = found else {
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
    use super::{disturbance_values, parameter_names};

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
}
