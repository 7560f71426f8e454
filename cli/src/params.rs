//! Parameter files (`--params`, `--nominal`): the output of
//! `leeway estimate --json` (its `estimates` object is read) or a plain
//! `{"name": value}` object. Every model parameter must be given exactly once
//! and every name must be a model parameter: nothing is silently ignored or
//! filled in. Problems are located at `file:line:column` of the offending key.

use crate::files::{MAX_PARAMS_BYTES, read_text};
use crate::problem::{Failure, Problem};
use leeway_model::given::{
    disturbance_slots, estimated_unmeasured, given_value_ok, parameter_names,
};
use leeway_structure::grammar::line_col;
use leeway_structure::ir::Ir;
use serde_json::Value;
use std::path::Path;

/// θ in the model's parameter order, read from `path` (given with `flag`).
pub fn read(path: &Path, ir: &Ir, flag: &str) -> Result<Vec<f64>, Failure> {
    Ok(read_file(path, ir, flag)?.theta)
}

/// A parameter file: θ and, from an estimate's document, the disturbance
/// means it found.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterFile {
    /// θ in the model's parameter order.
    pub theta: Vec<f64>,
    /// Per disturbance component of the model, the estimate's mean (`None`
    /// where it has none); `None` for a file that is not an estimate.
    pub means: Option<Vec<Option<f64>>>,
}

/// θ and the disturbance means read from `path` (given with `flag`).
pub fn read_file(path: &Path, ir: &Ir, flag: &str) -> Result<ParameterFile, Failure> {
    let file = path.display().to_string();
    let text = read_text(path, &format!("the {flag} file"), MAX_PARAMS_BYTES)?;
    parse(&file, &text, ir, flag).map_err(Failure::Problems)
}

/// Parses a parameter file's text; `file` names it in problems.
pub fn parse(file: &str, text: &str, ir: &Ir, flag: &str) -> Result<ParameterFile, Vec<Problem>> {
    let help = format!(
        "{flag} takes the output of `leeway estimate --json` or an object {{\"name\": value}} with one number per parameter"
    );
    let invalid = |e: serde_json::Error| {
        vec![
            Problem::error("invalid-params", format!("not valid JSON: {e}"))
                .at(json_place(file, text, &e))
                .help(&help),
        ]
    };
    let document: Value = serde_json::from_str(text).map_err(invalid)?;
    let Value::Object(top) = &document else {
        return Err(vec![
            Problem::error("invalid-params", "the file is not a JSON object")
                .at(file)
                .help(&help),
        ]);
    };
    // An estimate document: read its `estimates`; otherwise the object itself.
    // Entries are re-read in file order with duplicates kept, so a repeated
    // name is reported rather than silently overwritten.
    let places = Places { file, text };
    if let (Some(Value::Object(estimates)), Some(Value::Array(errors))) =
        (top.get("estimates"), top.get("errors"))
        && estimates.is_empty()
        && !errors.is_empty()
    {
        let why = errors[0]["message"].as_str().unwrap_or("see its `errors`");
        return Err(vec![
            Problem::error(
                "invalid-params",
                format!("the file is the output of an estimate that failed: {why}"),
            )
            .at(file)
            .help("give the output of an estimate that succeeded (exit 0)"),
        ]);
    }
    if matches!(top.get("estimates"), Some(Value::Object(_))) {
        let doc: EstimateDocument = serde_json::from_str(text).map_err(invalid)?;
        let start = key_offset(text, 0, "estimates", true);
        let theta = theta_of(ir, &doc.estimates.0, start, &places, &help);
        let means = disturbance_means(ir, top.get("disturbances"), &places);
        match (theta, means) {
            (Ok(theta), Ok(means)) => Ok(ParameterFile {
                theta,
                means: Some(means),
            }),
            (theta, means) => Err([theta.err(), means.err()]
                .into_iter()
                .flatten()
                .flatten()
                .collect()),
        }
    } else {
        let entries: Entries = serde_json::from_str(text).map_err(invalid)?;
        let theta = theta_of(ir, &entries.0, text.find('{'), &places, &help)?;
        Ok(ParameterFile { theta, means: None })
    }
}

/// The disturbance means of an estimate document's `disturbances`
/// (`{"current": {"north": {"mean": 0.19, ...}}}`), per component of the
/// model; a component the model does not have unmeasured is a problem (the
/// file belongs to another model), a null or absent mean is `None`.
fn disturbance_means(
    ir: &Ir,
    value: Option<&Value>,
    places: &Places<'_>,
) -> Result<Vec<Option<f64>>, Vec<Problem>> {
    let at = places.at(key_offset(places.text, 0, "disturbances", true));
    let problem = |message: String| {
        vec![
            Problem::error("invalid-params", message)
                .at(&at)
                .help(leeway_model::given::components_hint(ir)),
        ]
    };
    let mut named = Vec::new();
    match value {
        None | Some(Value::Null) => {}
        Some(Value::Object(media)) => {
            for (medium, components) in media {
                let Value::Object(components) = components else {
                    return Err(problem(format!("`disturbances.{medium}` is not an object")));
                };
                for (component, entry) in components {
                    let name = format!("{medium}.{component}");
                    match entry.get("mean") {
                        Some(Value::Null) => {}
                        Some(m) if m.as_f64().is_some_and(given_value_ok) => {
                            named.push((name, m.as_f64().unwrap_or_default()));
                        }
                        _ => {
                            return Err(problem(format!(
                                "`disturbances.{name}.mean` is not a finite number"
                            )));
                        }
                    }
                }
            }
        }
        Some(_) => return Err(problem("`disturbances` is not an object".into())),
    }
    let named: Vec<(&str, f64)> = named.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    let given = estimated_unmeasured(ir, &named);
    disturbance_slots(ir, &given).map_err(|p| {
        problem(format!(
            "the estimate's disturbance `{}` does not fit model `{}`: {}",
            given[p.index].0, ir.name, p.reason
        ))
    })
}

/// Where a parameter file's entries are, as `file:line:col`.
struct Places<'a> {
    file: &'a str,
    text: &'a str,
}

impl Places<'_> {
    fn at(&self, offset: Option<usize>) -> String {
        match offset {
            Some(o) => {
                let (l, c) = line_col(self.text, o);
                format!("{}:{l}:{c}", self.file)
            }
            None => self.file.to_string(),
        }
    }
}

/// θ from a file's entries (`start`: where they begin): every parameter
/// exactly once ([`parameter_names`]) and finite; each problem at its entry.
fn theta_of(
    ir: &Ir,
    entries: &[(String, Value)],
    start: Option<usize>,
    places: &Places<'_>,
    help: &str,
) -> Result<Vec<f64>, Vec<Problem>> {
    let names: Vec<&str> = ir.parameters.iter().map(|p| p.name.as_str()).collect();
    let matched = parameter_names(ir, entries.iter().map(|(k, _)| k.as_str()));
    // Each entry's place, found in file order.
    let mut from = start.unwrap_or(0);
    let at: Vec<String> = entries
        .iter()
        .map(|(key, _)| {
            let offset = key_offset(places.text, from, key, false);
            if let Some(o) = offset {
                from = o + key.len();
            }
            places.at(offset)
        })
        .collect();
    let mut theta = vec![f64::NAN; names.len()];
    let mut problems = Vec::new();
    for (k, (key, value)) in entries.iter().enumerate() {
        let problem = |message: String| Problem::error("invalid-params", message).at(&at[k]);
        if matched.unknown.contains(&k) {
            problems.push(
                problem(format!(
                    "unknown parameter `{key}`: model `{}` has no such parameter",
                    ir.name
                ))
                .help(format!(
                    "the parameters are {}",
                    leeway_structure::grammar::join_capped(&names, ", ")
                )),
            );
        } else if let Some(&(_, first)) = matched.twice.iter().find(|(i, _)| *i == k) {
            problems.push(
                problem(format!(
                    "parameter `{key}` is given twice (first at {})",
                    at[first]
                ))
                .help("keep one value per parameter"),
            );
        } else if let Some(i) = matched.slots[k] {
            match value.as_f64() {
                Some(v) if v.is_finite() => theta[i] = v,
                _ => problems.push(
                    problem(format!("`{key}` is {value}, not a number"))
                        .help("give every parameter a finite number"),
                ),
            }
        }
    }
    if !matched.missing.is_empty() {
        let missing: Vec<String> = matched
            .missing
            .iter()
            .map(|&p| format!("`{}`", names[p]))
            .collect();
        let plural = if missing.len() == 1 { "" } else { "s" };
        problems.push(
            Problem::error(
                "invalid-params",
                format!(
                    "missing parameter{plural} {}: every parameter of model `{}` needs a value",
                    leeway_structure::grammar::join_capped(&missing, ", "),
                    ir.name
                ),
            )
            .at(places.at(start))
            .help(help),
        );
    }
    if problems.is_empty() {
        Ok(theta)
    } else {
        Err(problems)
    }
}

/// The entries of a JSON object in file order, duplicates kept.
struct Entries(Vec<(String, Value)>);

impl<'de> serde::Deserialize<'de> for Entries {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Entries, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Entries;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a JSON object")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Entries, A::Error> {
                let mut v = Vec::new();
                while let Some(entry) = map.next_entry::<String, Value>()? {
                    v.push(entry);
                }
                Ok(Entries(v))
            }
        }
        d.deserialize_map(Visitor)
    }
}

/// The part of an `estimate --json` document a parameter file needs.
#[derive(serde::Deserialize)]
struct EstimateDocument {
    estimates: Entries,
}

/// The byte offset of `"key"` used as an object key (followed by `:`) at or
/// after `from`; with `object`, only where its value is an object.
fn key_offset(text: &str, from: usize, key: &str, object: bool) -> Option<usize> {
    let quoted = serde_json::to_string(key).ok()?;
    let mut search = from;
    while let Some(found) = text.get(search..)?.find(&quoted) {
        let at = search + found;
        let rest = text[at + quoted.len()..].trim_start();
        if let Some(after) = rest.strip_prefix(':')
            && (!object || after.trim_start().starts_with('{'))
        {
            return Some(at);
        }
        search = at + quoted.len();
    }
    None
}

/// `file:line:column` of a JSON error as an editor shows it: serde_json's
/// column 0 (a line end read, as in a string broken by one) is the
/// previous line's end, where the line end is.
fn json_place(file: &str, text: &str, e: &serde_json::Error) -> String {
    match (e.line(), e.column()) {
        (line @ 2.., 0) => {
            let previous = text.split('\n').nth(line - 2).unwrap_or("");
            format!("{file}:{}:{}", line - 1, previous.chars().count() + 1)
        }
        (line, column) => format!("{file}:{}:{}", line.max(1), column.max(1)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ir() -> Ir {
        let src = "model M { step 1 state x input u der x = a*x + b*u nominal { a = -1 } }";
        let c = leeway_structure::compile(src, &Default::default());
        c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics))
    }

    #[test]
    fn plain_and_estimate_documents_are_read_in_model_order() {
        let ir = ir();
        assert_eq!(
            parse("p.json", r#"{"b": 2.5, "a": -1}"#, &ir, "--params").map_err(|p| p.len()),
            Ok(ParameterFile {
                theta: vec![-1.0, 2.5],
                means: None
            })
        );
        let doc = r#"{"method": "iv3", "nuisance": [{"estimates": "E[a]"}],
            "estimates": {"a": -0.5, "b": 0.25}, "std_errors": {"a": null, "b": 0.1}}"#;
        assert_eq!(
            parse("e.json", doc, &ir, "--params")
                .map(|p| p.theta)
                .map_err(|p| p.len()),
            Ok(vec![-0.5, 0.25])
        );
    }

    #[test]
    fn an_estimate_documents_disturbance_means_are_read_by_component() {
        let src = "model M { step 1 state x input u disturbance current unmeasured body(x: c) \
                   water = relative(current) der x = a*water.x + b*u }";
        let c = leeway_structure::compile(src, &Default::default());
        let ir = c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics));
        let doc = |d: &str| format!(r#"{{"estimates": {{"a": -1, "b": 2}}, "disturbances": {d}}}"#);
        let read = |d: &str| parse("e.json", &doc(d), &ir, "--params");
        assert_eq!(
            read(r#"{"current": {"c": {"mean": 0.25, "std_error": null}}}"#)
                .map(|p| p.means)
                .map_err(|p| p.len()),
            Ok(Some(vec![Some(0.25)]))
        );
        assert_eq!(
            read(r#"{"current": {"c": {"mean": null}}}"#)
                .map(|p| p.means)
                .map_err(|p| p.len()),
            Ok(Some(vec![None]))
        );
        let problems = read(r#"{"wind": {"c": {"mean": 1}}}"#)
            .err()
            .unwrap_or_default();
        assert_eq!(problems.len(), 1);
        assert_eq!(problems[0].location.as_deref(), Some("e.json:1:34"));
        assert!(
            problems[0]
                .message
                .contains("`wind.c` does not fit model `M`"),
            "{}",
            problems[0].message
        );
    }

    #[test]
    fn a_string_broken_by_a_line_end_is_located_at_that_line_end() {
        let problems = parse("p.json", "{\"a\": 1, \"b\n\": 2}", &ir(), "--params")
            .err()
            .unwrap_or_default();
        assert_eq!(problems[0].location.as_deref(), Some("p.json:1:12"));
    }

    #[test]
    fn a_value_reads_to_its_bits() {
        // serde_json's default parser reads this one an ulp off.
        let read = parse(
            "p.json",
            r#"{"a": -9.285898019307274000e-148, "b": 1}"#,
            &ir(),
            "--params",
        )
        .map(|p| p.theta[0].to_bits());
        assert_eq!(read.ok(), Some((-9.285_898_019_307_274e-148_f64).to_bits()));
    }

    #[test]
    fn a_failed_estimate_is_named_as_such() {
        let doc = r#"{"estimates": {}, "errors": [{"message": "θ is not identifiable"}]}"#;
        let problems = parse("e.json", doc, &ir(), "--params")
            .err()
            .unwrap_or_default();
        assert_eq!(
            problems[0].message,
            "the file is the output of an estimate that failed: θ is not identifiable"
        );
    }

    #[test]
    fn unknown_missing_and_non_numeric_entries_are_located() {
        let ir = ir();
        let text = "{\n  \"d\": 2,\n  \"a\": 1,\n  \"c\": \"x\",\n  \"a\": 3\n}";
        let problems = parse("p.json", text, &ir, "--params")
            .err()
            .unwrap_or_default();
        let shown: Vec<String> = problems
            .iter()
            .map(|p| format!("{} {}", p.location.clone().unwrap_or_default(), p.message))
            .collect();
        assert_eq!(
            shown,
            [
                "p.json:2:3 unknown parameter `d`: model `M` has no such parameter",
                "p.json:4:3 unknown parameter `c`: model `M` has no such parameter",
                "p.json:5:3 parameter `a` is given twice (first at p.json:3:3)",
                "p.json:1:1 missing parameter `b`: every parameter of model `M` needs a value",
            ]
        );
        let problems = parse("p.json", "{\"a\": null, \"b\": 1}", &ir, "--params")
            .err()
            .unwrap_or_default();
        assert_eq!(problems.len(), 1);
        assert_eq!(problems[0].message, "`a` is null, not a number");
        let problems = parse("p.json", "{\"a\": 1,", &ir, "--params")
            .err()
            .unwrap_or_default();
        assert!(problems[0].message.starts_with("not valid JSON"));
        assert_eq!(problems[0].location.as_deref(), Some("p.json:1:8"));
        let problems = parse("p.json", "[1, 2]", &ir, "--params")
            .err()
            .unwrap_or_default();
        assert_eq!(problems[0].message, "the file is not a JSON object");
    }
}
