//! The constant unmeasured disturbances `simulate` and `validate` hold:
//! `--disturbance NAME=VALUE,...` or `--disturbance zero`, else the means of
//! the estimate given as `--params`, else zero — the last with a warning,
//! since a simulation without the current an estimate found fits worse and
//! looks like a wrong model.

use crate::params::ParameterFile;
use crate::problem::Problem;
use leeway_model::given::{
    HeldDisturbances, MAX_GIVEN_VALUE, Origin, components_hint, disturbance_slots, given_value_ok,
    held_disturbances,
};
use leeway_model::number::short_number;
use leeway_model::warning::Warning;
use leeway_structure::grammar::{and_list, join_capped};
use leeway_structure::ir::Ir;
use std::path::Path;

/// What `--disturbance` said: values by component (`None`: not given), and
/// whether the user asked for zero (`--disturbance zero`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Given {
    values: Vec<Option<f64>>,
    zero: bool,
}

/// Parses `--disturbance NAME=VALUE,...` (by `north` or `current.north`;
/// measured components come from the data) or `--disturbance zero`.
pub fn given(ir: &Ir, specs: &[String]) -> Result<Given, Problem> {
    let hint = format!(
        "{}; `--disturbance zero` holds them all at zero",
        components_hint(ir)
    );
    let bad = |item: &str, why: String| {
        Problem::error("invalid-option", format!("--disturbance `{item}`: {why}")).help(&hint)
    };
    let items: Vec<&str> = specs
        .iter()
        .flat_map(|spec| spec.split(','))
        .map(str::trim)
        .collect();
    // An empty item says nothing: a trailing comma or `--disturbance ''`
    // is more likely a value lost on the way than a choice.
    if let Some(spec) = specs
        .iter()
        .find(|s| s.split(',').any(|i| i.trim().is_empty()))
    {
        return Err(bad(
            spec,
            "an empty item (a trailing or doubled comma, or an empty value)".into(),
        ));
    }
    let zero = items.iter().any(|i| i.eq_ignore_ascii_case("zero"));
    let mut named = Vec::with_capacity(items.len());
    for item in items.iter().filter(|i| !i.eq_ignore_ascii_case("zero")) {
        let Some((name, value)) = item.split_once('=') else {
            return Err(bad(
                item,
                "expected NAME=VALUE (e.g. current.north=0.2) or `zero`".into(),
            ));
        };
        let value = value.trim();
        let v = match value.parse::<f64>() {
            Ok(v) if given_value_ok(v) => v,
            Ok(v) if v.is_finite() => {
                return Err(bad(
                    item,
                    format!("`{value}` exceeds {MAX_GIVEN_VALUE:e} in magnitude"),
                ));
            }
            _ => return Err(bad(item, format!("`{value}` is not a finite number"))),
        };
        named.push((name.trim(), v, *item));
    }
    let pairs: Vec<(&str, f64)> = named.iter().map(|&(n, v, _)| (n, v)).collect();
    let values = disturbance_slots(ir, &pairs).map_err(|p| bad(named[p.index].2, p.reason))?;
    Ok(Given { values, zero })
}

/// The disturbances held while simulating with the parameter file at
/// `path`, and the warning when an unmeasured medium is zero by default.
pub fn held(
    ir: &Ir,
    given: &Given,
    file: &ParameterFile,
    path: &Path,
) -> (HeldDisturbances, Option<Warning>) {
    let none = vec![None; ir.components.len()];
    let estimated = file.means.as_deref().unwrap_or(&none);
    let held = held_disturbances(ir, &given.values, given.zero, estimated);
    let (media, components) = held.defaulted(ir);
    let warning = (!media.is_empty()).then(|| {
        let why = if file.means.is_some() {
            "the estimate there has no mean for it"
        } else {
            "the file holds no disturbance means (it is not `leeway estimate --json` output)"
        };
        let plural = if media.len() == 1 { "is" } else { "are" };
        let summary = format!(
            "the {} {plural} taken as zero while simulating with `{}`",
            and_list(media.iter().map(|m| format!("`{m}`"))),
            path.display(),
        );
        let values: Vec<String> = components.iter().map(|c| format!("{c}=VALUE")).collect();
        let help = format!(
            "give --disturbance {} (an estimate's means), or --disturbance zero",
            join_capped(&values, ",")
        );
        let detail = format!("{summary}: {why}; {help}");
        Warning::new("disturbance-zero", summary, help, detail)
    });
    (held, warning)
}

/// One line saying what was held: `current.north = 0.185 (estimate), ...`.
pub fn described(ir: &Ir, held: &HeldDisturbances) -> Option<String> {
    let named = held.named(ir);
    (!named.is_empty()).then(|| {
        named
            .iter()
            .map(|(n, v, o)| format!("{n} = {} ({})", short_number(*v), o.as_str()))
            .collect::<Vec<_>>()
            .join(", ")
    })
}

/// The JSON shape of what was held: `{"current.north": {"value", "from"}}`.
pub fn json(ir: &Ir, held: &HeldDisturbances) -> crate::output::Ordered<HeldJson> {
    crate::output::Ordered(
        held.named(ir)
            .into_iter()
            .map(|(n, value, o)| (n, HeldJson { value, from: o }))
            .collect(),
    )
}

/// One held component in JSON.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HeldJson {
    value: f64,
    #[serde(serialize_with = "origin_str")]
    from: Origin,
}

fn origin_str<S: serde::Serializer>(o: &Origin, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(o.as_str())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ship() -> Ir {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/models/ship.som");
        let c = leeway_structure::compile(
            &std::fs::read_to_string(path).unwrap_or_default(),
            &Default::default(),
        );
        c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics))
    }

    fn file(means: Option<Vec<Option<f64>>>) -> ParameterFile {
        ParameterFile {
            theta: Vec::new(),
            means,
        }
    }

    #[test]
    fn the_estimates_means_unless_given_else_zero_with_a_warning() {
        let ir = ship();
        let p = Path::new("p.json");
        let estimate = file(Some(vec![Some(0.185), Some(-0.114), None, None]));
        let (h, w) = held(&ir, &Given::default(), &estimate, p);
        assert_eq!(h.values, vec![0.185, -0.114, 0.0, 0.0]);
        assert!(w.is_none());
        assert_eq!(
            described(&ir, &h).as_deref(),
            Some("current.north = 0.185 (estimate), current.east = -0.114 (estimate)")
        );
        let one = given(&ir, &["current.east=0.3".into()]).unwrap_or_default();
        let (h, w) = held(&ir, &one, &estimate, p);
        assert_eq!(h.values[..2].to_vec(), vec![0.185, 0.3]);
        assert!(w.is_none());
        let zero = given(&ir, &["zero".into()]).unwrap_or_default();
        let (h, w) = held(&ir, &zero, &estimate, p);
        assert_eq!(h.values[..2].to_vec(), vec![0.0, 0.0]);
        assert!(w.is_none());
        let (h, w) = held(&ir, &Given::default(), &file(None), p);
        assert_eq!(h.values, vec![0.0; 4]);
        let w = w.unwrap_or_else(|| Warning::plain("none", ""));
        assert_eq!(
            (w.summary.as_str(), w.help.as_str()),
            (
                "the `current` is taken as zero while simulating with `p.json`",
                "give --disturbance current.north=VALUE,current.east=VALUE (an estimate's means), or --disturbance zero"
            )
        );
        assert!(w.detail.contains("the file holds no disturbance means"));
    }

    #[test]
    fn bad_values_name_the_item() {
        let ir = ship();
        let e = given(&ir, &["north=x".into()]).err().map(|p| p.message);
        assert_eq!(
            e.as_deref(),
            Some("--disturbance `north=x`: `x` is not a finite number")
        );
        let e = given(&ir, &["wind_n=1".into()]).err().map(|p| p.message);
        assert!(e.is_some_and(|m| m.contains("is measured")));
        // Nothing said is refused, never read as "no disturbance given".
        for empty in ["", "north=0.1,", "north=0.1,,east=0"] {
            let e = given(&ir, &[empty.into()]).err().map(|p| p.message);
            assert!(e.is_some_and(|m| m.contains("an empty item")), "{empty:?}");
        }
        assert!(given(&ir, &[]).is_ok());
    }
}
