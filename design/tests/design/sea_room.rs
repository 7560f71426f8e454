//! Sea room (issue 47): each run's nominal track over ground, the mean
//! current's drift included; a run that leaves the plan's trial area makes
//! the design say it cannot keep the track inside.

use crate::common::{conditions, model};
use leeway_design::design::{DesignOptions, design};

#[test]
fn a_track_beyond_the_trial_area_is_said_and_not_a_plan() {
    let boat = model("design/tests/fixtures/survey_boat.som");
    let mut c = conditions(&boat, "design/tests/fixtures/survey_boat.toml", None).expect("plan");
    c.budget = leeway_design::bounds::BudgetRule::Time(600.0);
    c.prior = 0.0;
    let options = DesignOptions {
        pilot: 0,
        ..Default::default()
    };
    let open = design(&boat, &c, &options).expect("a design");
    assert!(open.feasible && open.sea_room.is_empty());
    let farthest = open
        .experiments
        .iter()
        .map(|e| e.track.as_ref().expect("a planar craft's track").farthest)
        .fold(0.0, f64::max);
    // The current (0.2, 0.1) m/s alone drifts the boat 134 m in 600 s; the
    // runs share the 600 s.
    let seconds = open.seconds;
    let drift = 0.2f64.hypot(0.1) * seconds;
    for e in &open.experiments {
        let t = e.track.as_ref().expect("track");
        let end = t.end[0].hypot(t.end[1]);
        assert!(
            end > 0.3 * drift && end <= t.farthest + 1e-9,
            "{:?} vs drift {drift}",
            t.end
        );
    }
    c.area_radius = Some(0.5 * farthest);
    let tight = design(&boat, &c, &options).expect("a design");
    assert!(!tight.feasible);
    assert!(!tight.sea_room.is_empty());
    assert!(
        tight.sea_room[0].contains("beyond the area's"),
        "{:?}",
        tight.sea_room
    );
    assert!(
        tight
            .proposals
            .iter()
            .any(|p| p.contains("leaves the trial area")),
        "{:?}",
        tight.proposals
    );
    c.area_radius = Some(2.0 * farthest);
    assert!(design(&boat, &c, &options).expect("a design").feasible);
}
