//! Hostile plans and options (issue 49): every count a design derives from
//! a user's numbers is bounded before anything is allocated for it, and a
//! plan reads as it says — a key given twice, a range of three numbers or a
//! field that does nothing is refused at its line and column.

use crate::common::{conditions, model};
use leeway_design::design::{DesignOptions, design};
use leeway_design::error::DesignError;
use leeway_design::plan::{locate, parse};
use leeway_model::model::Model;
use std::time::{Duration, Instant};

const INPUTS: &str = "[inputs.tau_x]\nrange = [-6000, 6000]\n[inputs.tau_y]\nrange = [-6000, 6000]\n[inputs.tau_n]\nrange = [-4000, 4000]\n";

/// The ROV designed under the plan's text (TOML or JSON), its error
/// located as the CLI and Python locate it.
fn refused(text: &str, json: bool) -> DesignError {
    let rov = model("examples/models/rov.som");
    let options = DesignOptions {
        pilot: 0,
        ..Default::default()
    };
    parse(text, json)
        .and_then(|p| p.conditions(rov.ir()))
        .and_then(|c| design(&rov, &c, &options))
        .map(|_| ())
        .map_err(|e| locate(e, text, json))
        .expect_err(text)
}

#[test]
fn a_budget_beyond_the_bound_is_a_located_error_at_once() {
    for (plan, key, at) in [
        ("step = 1e-300\n", "budget.time", (9, 8)),
        ("step = 0.05\n", "budget.time", (9, 8)),
        ("step = 1e-9\n", "budget.time", (9, 8)),
    ] {
        for time in ["1200", "1e308", "1e7"] {
            if plan == "step = 0.05\n" && time == "1200" {
                continue; // a plan within the bound
            }
            let text = format!("{plan}{INPUTS}[budget]\ntime = {time}\n");
            let start = Instant::now();
            let e = refused(&text, false);
            assert!(start.elapsed() < Duration::from_secs(5), "{text}");
            assert_eq!(e.code, "plan", "{text}: {e:?}");
            assert_eq!(e.key.as_deref(), Some(key), "{text}: {e:?}");
            assert_eq!(
                (e.line, e.column),
                (Some(at.0), Some(at.1)),
                "{text}: {e:?}"
            );
            assert!(
                e.message.contains(&format!("budget.time = {time} s")),
                "{e:?}"
            );
            assert!(e.message.contains("more than 10000000 samples"), "{e:?}");
            assert!(
                e.hint.contains("shorten budget.time or lengthen step"),
                "{e:?}"
            );
        }
    }
    // Without a budget, the default 600 s per experiment over the step.
    let text = format!("step = 1e-9\n{INPUTS}");
    let e = refused(&text, false);
    assert_eq!(
        (e.key.as_deref(), e.line, e.column),
        (Some("step"), Some(1), Some(8)),
        "{e:?}"
    );
    // The same bound in a JSON plan, located at its key.
    let text = r#"{"step": 0.05,
 "inputs": {"tau_x": {"range": [-1, 1]}, "tau_y": {"range": [-1, 1]}, "tau_n": {"range": [-1, 1]}},
 "budget": {"time": 1e308}}"#;
    let e = refused(text, true);
    assert_eq!(
        (e.key.as_deref(), e.line),
        (Some("budget.time"), Some(3)),
        "{e:?}"
    );
    assert!(e.message.contains("more than 10000000 samples"), "{e:?}");
}

#[test]
fn too_many_pilot_trials_are_refused() {
    let rov = model("examples/models/rov.som");
    let c = parse(&format!("step = 0.05\n{INPUTS}"), false)
        .and_then(|p| p.conditions(rov.ir()))
        .expect("plan");
    let options = DesignOptions {
        pilot: 1001,
        ..Default::default()
    };
    let e = design(&rov, &c, &options).expect_err("pilot");
    assert_eq!(e.code, "invalid-option");
    assert!(e.message.contains("give 0 to 1000"), "{e:?}");
}

#[test]
fn a_target_beyond_the_bound_says_so() {
    let rov = model("examples/models/rov.som");
    let c = conditions(&rov, "examples/plans/rov.toml", Some(400)).expect("plan");
    let options = DesignOptions {
        pilot: 0,
        target: Some(1e-300),
        ..Default::default()
    };
    let d = design(&rov, &c, &options).expect("design");
    let t = d
        .prediction
        .as_ref()
        .and_then(|p| p.target.as_ref())
        .expect("target");
    assert_eq!((t.samples, t.seconds, t.within_budget), (None, None, false));
    let doc = leeway_design::document::json(&d, None);
    assert!(doc.contains("\"samples\": null"), "{doc}");
}

#[test]
fn a_json_key_given_twice_is_refused_at_every_level() {
    let e = parse("{\"step\": 0.5,\n \"step\": 0.1}", true).expect_err("twice");
    assert_eq!(e.line, Some(2), "{e:?}");
    assert!(e.message.contains("`step` is given twice"), "{e:?}");
    let e = parse(
        "{\"inputs\": {\"f\": {\"range\": [-1, 1],\n  \"range\": [-2, 2]}}}",
        true,
    )
    .expect_err("twice");
    assert_eq!(e.line, Some(2), "{e:?}");
    assert!(
        e.message.contains("`inputs.f.range` is given twice"),
        "{e:?}"
    );
    let e = parse(
        "{\"disturbances\": {\"current\": {\"std\": 1}, \"current\": {\"std\": 2}}}",
        true,
    )
    .expect_err("twice");
    assert!(
        e.message.contains("`disturbances.current` is given twice"),
        "{e:?}"
    );
    // The same key in different objects is not a duplicate.
    parse(
        "{\"inputs\": {\"f\": {\"range\": [-1, 1]}, \"g\": {\"range\": [-1, 1]}}}",
        true,
    )
    .expect("reads");
    // TOML refuses a duplicate by its grammar.
    let e = parse("step = 0.5\nstep = 0.1\n", false).expect_err("twice");
    assert_eq!(e.line, Some(2), "{e:?}");
}

#[test]
fn a_range_is_two_numbers_in_toml_and_json() {
    let e = parse("[inputs.f]\nrange = [-35, 35, 1e308]\n", false).expect_err("three");
    assert_eq!((e.line, e.column), (Some(2), Some(9)), "{e:?}");
    assert!(e.message.contains("has 3"), "{e:?}");
    let e = parse(
        "{\"inputs\": {\"f\":\n {\"range\": [-35, 35, 1e308]}}}",
        true,
    )
    .expect_err("three");
    assert_eq!(e.line, Some(2), "{e:?}");
    assert!(e.message.contains("has 3"), "{e:?}");
    for text in [
        "[inputs.f]\nrange = [1]\n",
        "{\"inputs\": {\"f\": {\"range\": [1]}}}",
    ] {
        let e = parse(text, false).expect_err("one");
        assert!(e.message.contains("has 1"), "{e:?}");
    }
}

#[test]
fn a_correlation_time_without_a_spread_is_refused() {
    let text = format!(
        "step = 0.05\n{INPUTS}[disturbances.current]\nmean = [0.3, 0.1]\ncorrelation_time = 30\n"
    );
    let rov = model("examples/models/rov.som");
    let e = parse(&text, false)
        .and_then(|p| p.conditions(rov.ir()))
        .map_err(|e| locate(e, &text, false))
        .expect_err("no std");
    assert!(e.message.contains("does not vary about its mean"), "{e:?}");
    assert_eq!((e.line, e.column), (Some(10), Some(20)), "{e:?}");
}

#[test]
fn semantic_errors_are_located_at_their_value() {
    let text = format!("step = 0.05\n{INPUTS}[noise]\nq = 0.1\n");
    let rov = model("examples/models/rov.som");
    let e = parse(&text, false)
        .and_then(|p| p.conditions(rov.ir()))
        .map_err(|e| locate(e, &text, false))
        .expect_err("no q");
    assert_eq!((e.line, e.column), (Some(9), Some(5)), "{e:?}");
}
