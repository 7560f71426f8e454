//! The ROV (paper Remark 1): two experiments, the sign patterns `check`
//! requires, offsets that hold them, a yaw rate that changes sign.

use crate::common::{designed, model};
use leeway_design::document::json;
use leeway_design::trial::margins;
use leeway_model::model::Model;
use leeway_structure::identify::{Analysis, pattern_text};
use leeway_structure::ir::PredictorKind;

const ROV: &str = "examples/models/rov.som";
const PLAN: &str = "examples/plans/rov.toml";

#[test]
fn the_runs_are_the_patterns_check_requires_and_keep_their_signs() {
    let m = model(ROV);
    let d = designed(&m, PLAN, 3000, 10);
    let ir = m.ir();
    let required = Analysis::new(ir, PredictorKind::Measured)
        .required_patterns()
        .expect("identifiable");
    let wanted: Vec<String> = required
        .iter()
        .map(|p| pattern_text(ir, p, PredictorKind::Measured))
        .collect();
    let got: Vec<&str> = d.experiments.iter().map(|e| e.pattern.as_str()).collect();
    assert_eq!(got, wanted);
    assert_eq!(got, ["{+water.u +water.v}", "{+water.u -water.v}"]);
    assert!(d.feasible, "{:?}", d.shortfalls);
    for (e, run) in d.experiments.iter().enumerate() {
        for h in &run.held {
            assert!(h.min_margin >= 0.0, "experiment {e}: {h:?}");
            assert!(h.steady_margin > 0.0, "experiment {e}: {h:?}");
        }
        // r is evaluated pointwise: Y_vr and Y_rv need it on both sides.
        let r = &run.pointwise[0];
        assert_eq!(r.state, "r");
        assert!((0.05..0.95).contains(&r.negative_fraction), "{r:?}");
    }
    // Along the nominal run from heading 0, every held argument stays
    // beyond its band at every sample (the files and figure show these).
    for ((truth, run), held) in d.nominal.iter().zip(&d.runs).zip(&d.held) {
        for m in margins(&m, truth, &run.inputs, held) {
            assert!(
                m.iter().all(|v| *v >= 0.0),
                "{:?}",
                m.iter().copied().fold(f64::INFINITY, f64::min)
            );
        }
    }
}

#[test]
fn the_inputs_stay_within_their_ranges_and_rates() {
    let m = model(ROV);
    let d = designed(&m, PLAN, 3000, 0);
    let c = d.conditions.as_ref().expect("conditions");
    for run in &d.runs {
        for (i, l) in c.limits.iter().enumerate() {
            let mut last = run.inputs[0][i];
            for u in &run.inputs {
                assert!((l.low..=l.high).contains(&u[i]), "{} outside {l:?}", u[i]);
                assert!(
                    (u[i] - last).abs() <= l.per_sample * (1.0 + 1e-12),
                    "rate {l:?}"
                );
                last = u[i];
            }
        }
    }
}

#[test]
fn predicted_errors_scale_as_one_over_the_root_of_the_run_length() {
    let m = model(ROV);
    let c = crate::common::conditions(&m, PLAN, Some(3000)).expect("plan");
    let options = leeway_design::design::DesignOptions {
        pilot: 0,
        target: Some(0.05),
        ..Default::default()
    };
    let d = leeway_design::design::design(&m, &c, &options).expect("design");
    let p = d.prediction.as_ref().expect("prediction");
    let at = |samples: usize| {
        p.curve
            .iter()
            .find(|c| c.samples == samples)
            .expect("curve point")
    };
    for (a, b) in at(3000).std_errors.iter().zip(&at(12_000).std_errors) {
        if let (Some(a), Some(b)) = (a, b) {
            assert!((b / a - 0.5).abs() < 1e-12, "{a} {b}");
        }
    }
    // The target's run length meets the target, and no shorter one does.
    let t = p.target.as_ref().expect("target");
    let samples = t.samples.expect("within the bound");
    let worst = at(samples).worst_relative;
    assert!(
        worst <= 0.05 * (1.0 + 1e-9) && worst > 0.05 * (1.0 - 1e-3),
        "{worst}"
    );
    assert_eq!(t.within_budget, samples <= 3000);
}

#[test]
fn a_design_is_the_same_at_any_thread_count() {
    let m = model(ROV);
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| json(&designed(&m, PLAN, 2000, 8), None))
    };
    assert_eq!(run(1), run(2));
}
