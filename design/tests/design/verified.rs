//! A design judged by its verification in the library (issue 47): when the
//! verified models fall short, the other runs the design tried are
//! designed and verified in turn, and every caller — CLI, JSON, Python —
//! gets the same record; when they pass, nothing else is tried.

use crate::common::{conditions, model};
use leeway_design::design::{DesignOptions, design};
use leeway_design::verified::design_verified;

#[test]
fn a_failing_verdict_verifies_the_other_runs_the_design_tried() {
    // The survey boat on 150 s at sea: its models fall short whatever
    // its runs (the CLI's exit-1 test), so every option is verified.
    let boat = model("design/tests/fixtures/survey_boat.som");
    let mut c = conditions(&boat, "design/tests/fixtures/survey_boat.toml", None)
        .expect("the survey boat's plan");
    c.budget = leeway_design::bounds::BudgetRule::Time(150.0);
    let options = DesignOptions {
        pilot: 0,
        ..Default::default()
    };
    let searched = design(&boat, &c, &options).expect("a design");
    let tried = searched
        .runs_tried
        .iter()
        .filter(|o| o.worst_relative.is_some())
        .count();
    assert!(tried >= 2, "{:?}", searched.runs_tried);
    let out = design_verified(&boat, &c, &options, Some(2), &|| ()).expect("a design");
    let v = out.verification.expect("verified");
    assert!(!v.verdict.passed, "{:?}", v.verdict);
    // Every option the search scored was verified, the search's first.
    assert_eq!(v.runs_verified.len(), tried, "{:?}", v.runs_verified);
    let chosen = searched
        .runs_tried
        .iter()
        .find(|o| o.chosen)
        .expect("chosen");
    let first = &v.runs_verified[0];
    assert_eq!(
        (first.runs, first.centring.as_str()),
        (chosen.runs, chosen.centring.as_str())
    );
    for r in &v.runs_verified {
        assert_eq!(r.passed, Some(false), "{r:?}");
        assert!(!r.failures.is_empty(), "{r:?}");
    }
    // None passes: the design reported is the search's own, taken once.
    assert!(first.taken, "{:?}", v.runs_verified);
    assert_eq!(v.runs_verified.iter().filter(|r| r.taken).count(), 1);
    assert_eq!(out.design.seconds, searched.seconds);
    assert_eq!(out.design.runs.len(), searched.runs.len());
    // The JSON document carries the record.
    let doc: serde_json::Value =
        serde_json::from_str(&leeway_design::document::json(&out.design, Some(&v))).expect("json");
    assert_eq!(
        doc["verification"]["runs_verified"]
            .as_array()
            .map(Vec::len),
        Some(tried)
    );
}

#[test]
fn a_passing_verdict_tries_nothing_else() {
    let m = model("examples/models/hovercraft.som");
    let c = conditions(&m, "examples/plans/hovercraft.toml", Some(1500)).expect("plan");
    let options = DesignOptions {
        pilot: 0,
        ..Default::default()
    };
    let out = design_verified(&m, &c, &options, Some(4), &|| ()).expect("a design");
    let v = out.verification.expect("verified");
    assert!(v.verdict.passed, "{:?}", v.verdict);
    assert!(v.runs_verified.is_empty(), "{:?}", v.runs_verified);
    // Without trials nothing is verified.
    let plain = design_verified(&m, &c, &options, None, &|| ()).expect("a design");
    assert!(plain.verification.is_none());
}
