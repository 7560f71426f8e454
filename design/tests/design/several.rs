//! Designs of several runs (issue 47): one steady speed with per-experiment
//! centring leaves the surge drag's level confounded with the current's
//! mean; the design tries the same sign pattern at other speeds with pooled
//! centring within the budget and says why it chose what it chose.

use crate::common::survey_boat;
use leeway_design::design::{DesignOptions, design};

#[test]
fn the_survey_boat_is_designed_for_two_speeds_and_pooled_centring() {
    // The nominal θ as the truth: the runs are the subject here.
    let (boat, c, options) = survey_boat(900.0);
    let d = design(&boat, &c, &options).expect("a design");
    let one = &d.runs_tried[0];
    assert_eq!(
        (one.runs, one.centring.as_str()),
        (1, "experiment"),
        "{:?}",
        d.runs_tried
    );
    assert_eq!(one.seconds, 900.0);
    let chosen: Vec<_> = d.runs_tried.iter().filter(|o| o.chosen).collect();
    assert_eq!(chosen.len(), 1, "{:?}", d.runs_tried);
    let chosen = chosen[0];
    assert!(
        chosen.runs >= 2 && chosen.centring == "pooled",
        "{chosen:?}"
    );
    // Within the budget: the runs share the 900 s.
    assert!(
        chosen.runs as f64 * chosen.seconds <= 900.0 + 1e-9,
        "{chosen:?}"
    );
    assert_eq!(d.experiments.len(), chosen.runs);
    assert_eq!(d.centring, "pooled");
    let (w1, wk) = (
        one.worst_relative.expect("one run's prediction"),
        chosen.worst_relative.expect("the chosen prediction"),
    );
    assert!(wk < 0.8 * w1, "{w1} → {wk}");
    assert!(
        d.runs_reason.contains("confounded with the medium's mean"),
        "{}",
        d.runs_reason
    );
    // The runs are at different speeds.
    let u: Vec<f64> = d.experiments.iter().map(|e| e.steady["u"]).collect();
    assert!((u[0] - u[1]).abs() > 0.1, "{u:?}");
    // The rudder never leaves its range in the model's unit (rad inside).
    let limit = 35f64.to_radians() * (1.0 + 1e-12);
    for run in &d.runs {
        assert!(
            run.inputs
                .iter()
                .all(|x| x[1].abs() <= limit && (0.0..=400.0).contains(&x[0]))
        );
    }
}

#[test]
fn the_survey_boat_tries_the_mirrored_turn_and_is_judged_over_its_envelope() {
    // The nominal θ as the truth: the runs are the subject here.
    let (boat, c, options) = survey_boat(900.0);
    let d = design(&boat, &c, &options).expect("a design");
    // One pattern suffices, so the turn to the other side is tried beside
    // the first, the budget shared.
    let mirrored = d
        .runs_tried
        .iter()
        .find(|o| o.differ_by.as_deref() == Some("sign pattern"))
        .unwrap_or_else(|| panic!("{:?}", d.runs_tried));
    assert_eq!(
        (mirrored.runs, mirrored.seconds),
        (2, 450.0),
        "{mirrored:?}"
    );
    assert_eq!(mirrored.centring, "pooled");
    // It designs as an option of its own, its runs on either side of v.
    let forced = DesignOptions {
        runs: Some((
            2,
            leeway_structure::identify::Centring::Pooled,
            leeway_design::report::DifferBy::SignPattern,
        )),
        ..options.clone()
    };
    let m = design(&boat, &c, &forced).expect("the mirrored design");
    let v: Vec<f64> = m.experiments.iter().map(|e| e.steady["v"]).collect();
    assert!(v[0] * v[1] < 0.0, "{v:?}");
    assert_ne!(m.experiments[0].pattern, m.experiments[1].pattern);
    assert!(
        m.runs_tried
            .iter()
            .filter(|o| o.chosen)
            .all(|o| o.key() == forced.runs)
    );
    // The held-out run is a manoeuvre over the inputs' ranges, not the
    // designed run's small excursions: the rudder to both sides, beyond
    // half its range, and the thrust over most of its.
    let held_out = d.validation.as_ref().expect("a held-out run");
    let column = |i: usize| held_out.inputs.iter().map(move |x| x[i]);
    let rudder = |f: fn(f64, f64) -> f64, start| column(1).fold(start, f).to_degrees();
    assert!(rudder(f64::max, f64::MIN) > 17.5 && rudder(f64::min, f64::MAX) < -17.5);
    let thrust = column(0).fold(f64::MIN, f64::max) - column(0).fold(f64::MAX, f64::min);
    assert!(thrust > 200.0, "{thrust}");
}
