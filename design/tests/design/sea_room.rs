//! Sea room (issue 47): each run's nominal track over ground, the mean
//! current's drift included; a run that leaves the plan's trial area makes
//! the design say it cannot keep the track inside.

use crate::common::survey_boat;
use leeway_design::design::design;

#[test]
fn a_track_beyond_the_trial_area_is_said_and_not_a_plan() {
    let (boat, mut c, options) = survey_boat(600.0);
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

#[test]
fn a_box_area_bounds_each_side_and_a_box_without_the_start_is_an_error() {
    let (boat, mut c, options) = survey_boat(600.0);
    let open = design(&boat, &c, &options).expect("a design");
    // The tide (0.2, 0.1) m/s carries the boat north and east.
    let t = open.experiments[0].track.as_ref().expect("track");
    let north = t.positions.iter().map(|p| p[0]).fold(f64::MIN, f64::max);
    assert!(north > 50.0, "{north}");
    // A channel open to the north and south, wide enough: a plan.
    c.area_box = Some(leeway_design::plan::AreaBox {
        north: [f64::NEG_INFINITY, f64::INFINITY],
        east: [-5000.0, 5000.0],
    });
    assert!(design(&boat, &c, &options).expect("a design").feasible);
    // Its northern side short of the track: not a plan, and said so.
    c.area_box = Some(leeway_design::plan::AreaBox {
        north: [-5000.0, 0.5 * north],
        east: [-5000.0, 5000.0],
    });
    let boxed = design(&boat, &c, &options).expect("a design");
    assert!(!boxed.feasible);
    assert!(
        boxed
            .sea_room
            .iter()
            .any(|s| s.contains("m north of its start, beyond the area's")),
        "{:?}",
        boxed.sea_room
    );
    // A box is read from the plan; one that leaves out the start is an
    // error at its key.
    let file = format!(
        "{}/tests/fixtures/survey_boat.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(file).expect("the plan");
    let plan = |area: &str| {
        leeway_design::plan::parse(&format!("{text}\n[area]\n{area}\n"), false)
            .and_then(|p| p.conditions(leeway_model::model::Model::ir(&boat)))
    };
    let read = plan("north = [-200, 400]").expect("a box");
    assert_eq!(
        read.area_box.map(|b| (b.north, b.east[0].is_infinite())),
        Some(([-200.0, 400.0], true))
    );
    let e = plan("east = [100, 400]").expect_err("the start outside");
    assert_eq!(e.key.as_deref(), Some("area.east"));
    assert!(
        e.message.contains("does not hold the start"),
        "{}",
        e.message
    );
    assert!(plan("north = [1, 2, 3]").is_err());
}
