//! Every example model is designed, or the design says why no plan can be.

use crate::common::{conditions, designed, model};
use leeway_design::design::{DesignOptions, design};
use leeway_design::plan::parse;
use leeway_model::model::Model;

#[test]
fn every_example_with_a_plan_gets_a_feasible_design() {
    for (m, plan) in [
        ("examples/models/rov.som", "examples/plans/rov.toml"),
        ("examples/models/blimp.som", "examples/plans/blimp.toml"),
        (
            "examples/models/hovercraft.som",
            "examples/plans/hovercraft.toml",
        ),
        ("examples/models/tanker.som", "examples/plans/tanker.toml"),
        (
            "examples/models/ship.som",
            "examples/plans/ship-low-wind.toml",
        ),
        (
            "examples/models/ship.som",
            "examples/plans/ship-high-wind.toml",
        ),
        ("tests/models/catamaran.som", "tests/plans/catamaran.toml"),
    ] {
        let model = model(m);
        let d = designed(&model, plan, 1500, 0);
        assert!(d.feasible, "{plan}: {:?} {:?}", d.shortfalls, d.families);
        let p = d.prediction.as_ref().expect("prediction");
        assert!(
            p.worst_relative.is_finite() && p.worst_relative > 0.0,
            "{plan}"
        );
        assert!(
            d.experiments
                .iter()
                .flat_map(|e| &e.held)
                .all(|h| h.min_margin >= 0.0),
            "{plan}"
        );
    }
}

#[test]
fn the_catamaran_is_designed_for_the_centring_that_identifies_its_constant() {
    let m = model("tests/models/catamaran.som");
    let d = designed(&m, "tests/plans/catamaran.toml", 1500, 0);
    // X_0 is annihilated by per-experiment centring: an astern run and
    // uncentred instruments identify it (the answer `check` gives).
    assert_eq!(d.centring, "none");
    let patterns: Vec<&str> = d.experiments.iter().map(|e| e.pattern.as_str()).collect();
    assert_eq!(patterns, ["{+water.u +water.v}", "{-water.u +water.v}"]);
    assert!(
        d.assumptions.iter().any(|a| a.contains("--centring none")),
        "{:?}",
        d.assumptions
    );
}

#[test]
fn the_high_wind_ship_needs_iv3() {
    let m = model("examples/models/ship.som");
    let d = designed(&m, "examples/plans/ship-high-wind.toml", 1500, 0);
    let by = |name: &str| d.methods.iter().find(|s| s.method == name).expect("method");
    assert!(by("iv3").holds);
    let iv2 = by("iv2");
    assert!(!iv2.holds);
    // The 14 m/s wind is far beyond the ship's 4 m/s: air.u crosses zero.
    let air_u = iv2
        .arguments
        .iter()
        .find(|a| a.argument == "air.u")
        .expect("air.u");
    assert!(air_u.min_margin < -5.0, "{air_u:?}");
}

#[test]
fn a_windy_day_for_the_blimp_is_explained_not_planned() {
    let m = model("examples/models/blimp.som");
    let mut c = conditions(&m, "examples/plans/blimp.toml", Some(1500)).expect("plan");
    // A 1.6 m/s breeze, gusting: the blimp's sway never clears it.
    c.mean = vec![1.5, 0.5];
    c.std = vec![0.3, 0.3];
    c.uncertainty = vec![0.5, 0.5];
    let d = design(
        &m,
        &c,
        &DesignOptions {
            pilot: 0,
            ..Default::default()
        },
    )
    .expect("design");
    assert!(!d.feasible);
    assert!(
        d.shortfalls
            .iter()
            .any(|s| s.argument == "air.v" && s.short_by > 0.0),
        "{:?}",
        d.shortfalls
    );
    assert!(
        d.proposals.iter().any(|p| p.contains("measure wind")),
        "{:?}",
        d.proposals
    );
}

#[test]
fn models_no_trial_can_serve_are_refused_with_the_reason() {
    let ship_iv2 = model("examples/models/ship_iv2.som");
    let c = conditions(&ship_iv2, "examples/plans/ship-iv2.toml", Some(1000)).expect("plan");
    let e = design(&ship_iv2, &c, &DesignOptions::default()).expect_err("not identifiable");
    assert_eq!(e.code, "not-identifiable");
    // A rotation measured entry by entry cannot be predicted along a trial.
    let barge = model("tests/models/barge.som");
    let plan = parse(
        "[inputs.f]\nrange = [-1, 1]\n[inputs.g]\nrange = [-1, 1]\n",
        false,
    )
    .expect("plan");
    let e = plan.conditions(barge.ir()).expect_err("measured rotation");
    assert_eq!(e.code, "cannot-design");
    assert!(e.message.contains("rotation"), "{e:?}");
}

#[test]
fn plan_errors_name_the_key_and_the_model_s_names() {
    let rov = model("examples/models/rov.som");
    let cases = [
        (
            "[inputs.tau_q]\nrange = [0, 1]\n",
            "inputs.tau_q",
            "tau_x, tau_y, tau_n",
        ),
        (
            "[inputs.tau_x]\nrange = [1, 0]\n",
            "inputs.tau_x.range",
            "low < high",
        ),
        (
            "[disturbances.current]\nstd = -1\n",
            "disturbances.current.std",
            "≥ 0",
        ),
        (
            "[disturbances.current]\nmean = [1, 2, 3]\n",
            "3 values",
            "one per component",
        ),
        (
            "[disturbances.current]\nsensor_noise = 0.1\n",
            "sensor_noise",
            "measured",
        ),
        ("[noise]\nq = 0.1\n", "noise.q", "u, v, r, psi"),
        ("[budget]\ntime = 10\nsamples = 100\n", "both", "not both"),
        (
            "[inputs.tau_x]\nrange = [0, 1]\n",
            "tau_y",
            "range = [low, high]",
        ),
    ];
    let inputs = "[inputs.tau_x]\nrange = [-1, 1]\n[inputs.tau_y]\nrange = [-1, 1]\n[inputs.tau_n]\nrange = [-1, 1]\n";
    for (case, message, hint) in cases {
        // Every input's range, unless the case is about inputs.
        let text = if case.contains("[inputs.") {
            case.to_string()
        } else {
            format!("{inputs}{case}")
        };
        let text = text.as_str();
        let e = parse(text, false)
            .and_then(|p| p.conditions(rov.ir()))
            .expect_err(text);
        assert_eq!(e.code, "plan", "{text}");
        assert!(
            e.message.contains(message) || e.hint.contains(message),
            "{text}: {e:?}"
        );
        assert!(
            e.hint.contains(hint) || e.message.contains(hint),
            "{text}: {e:?}"
        );
    }
    // A model without a step needs the plan's.
    let raft = model("tests/models/raft.som");
    let plan = parse(
        "[inputs.f]\nrange = [-1, 1]\n[inputs.g]\nrange = [-1, 1]\n",
        false,
    )
    .expect("plan");
    let e = plan.conditions(raft.ir()).expect_err("no step");
    assert!(e.hint.contains("step = "), "{e:?}");
}
