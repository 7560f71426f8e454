//! Designs of several runs (issue 47): one steady speed with per-experiment
//! centring leaves the surge drag's level confounded with the current's
//! mean; the design tries the same sign pattern at other speeds with pooled
//! centring within the budget and says why it chose what it chose.

use crate::common::{conditions, model};
use leeway_design::design::{DesignOptions, design};

#[test]
fn the_survey_boat_is_designed_for_two_speeds_and_pooled_centring() {
    let boat = model("design/tests/fixtures/survey_boat.som");
    let mut c = conditions(&boat, "design/tests/fixtures/survey_boat.toml", None)
        .expect("the survey boat's plan");
    c.budget = leeway_design::bounds::BudgetRule::Time(900.0);
    // The nominal θ as the truth: the runs are the subject here.
    c.prior = 0.0;
    let options = DesignOptions {
        pilot: 0,
        ..Default::default()
    };
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
