//! A plan's numbers are in the unit the model's data use (issue 47): a
//! rudder read `in deg` is planned in degrees, or in radians with
//! `unit = "rad"` — the same runs either way — and a range that is absurd
//! for an angle (beyond ±180°) is refused with the likely slip named.

use leeway_design::design::{DesignOptions, design};
use leeway_design::plan::{locate, parse};
use leeway_design::report::Design;
use leeway_model::Interpreter;
use leeway_model::model::Model;

const BOAT: &str = r#"
model Boat {
    step 0.1
    state u, r
    input tau, delta
    data { delta = "rudder_deg" in deg }
    der u = X_u*u + X_uu*u*|u| + X_tau*tau
    der r = N_r*r + N_d*delta*u
    nominal { X_u = -0.3, X_uu = -0.1, X_tau = 0.01, N_r = -0.8, N_d = 0.4 }
}"#;

fn boat() -> Interpreter {
    let c = leeway_structure::compile(BOAT, &Default::default());
    Interpreter::new(c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics)))
}

fn planned(rudder: &str) -> Result<Design, leeway_design::error::DesignError> {
    let text = format!(
        "[inputs.tau]\nrange = [0, 400]\n[inputs.delta]\n{rudder}\n[budget]\nsamples = 2000\n"
    );
    let model = boat();
    let options = DesignOptions {
        pilot: 0,
        ..Default::default()
    };
    parse(&text, false)
        .and_then(|p| p.conditions(model.ir()))
        .and_then(|c| design(&model, &c, &options))
        .map_err(|e| locate(e, &text, false))
}

#[test]
fn a_plan_in_degrees_and_the_same_plan_in_radians_give_the_same_runs() {
    let deg = planned("range = [-35, 35]").expect("degrees");
    let rad = planned(&format!(
        "range = [{}, {}]\nunit = \"rad\"",
        -35f64.to_radians(),
        35f64.to_radians()
    ))
    .expect("radians");
    assert_eq!(deg.runs.len(), rad.runs.len());
    for (a, b) in deg.runs.iter().zip(&rad.runs) {
        assert_eq!(a.inputs.len(), b.inputs.len());
        for (x, y) in a.inputs.iter().flatten().zip(b.inputs.iter().flatten()) {
            assert!((x - y).abs() <= 1e-12 * x.abs().max(1.0), "{x} vs {y}");
        }
    }
    // The rudder stays within ±35° in the model's unit (rad inside), and
    // the report gives it in degrees, saying so.
    let limit = 35f64.to_radians() * (1.0 + 1e-12);
    for run in &deg.runs {
        assert!(run.inputs.iter().all(|u| u[1].abs() <= limit));
    }
    let delta = &deg.experiments[0].inputs["delta"];
    assert_eq!(delta.unit.as_deref(), Some("deg"));
    assert!(
        delta.offset.abs() + delta.amplitude <= 35.0 + 1e-9,
        "{delta:?}"
    );
}

#[test]
fn an_angle_beyond_half_a_turn_names_the_likely_slip() {
    let e = planned("range = [-35, 35]\nunit = \"rad\"")
        .map(|_| ())
        .expect_err("±35 rad");
    assert_eq!(e.key.as_deref(), Some("inputs.delta.range"), "{e:?}");
    assert_eq!((e.line, e.column), (Some(4), Some(9)), "{e:?}");
    assert!(e.message.contains("beyond ±180°"), "{e:?}");
    assert!(e.hint.contains("unit = \"deg\""), "{e:?}");
    let e = planned("range = [-35, 35]\nunit = \"m/s\"")
        .map(|_| ())
        .expect_err("a speed");
    assert!(e.message.contains("is not an angle"), "{e:?}");
}

#[test]
fn a_prior_beyond_a_third_is_refused_at_its_line() {
    let text = "prior = 0.6\n[inputs.tau]\nrange = [0, 400]\n[inputs.delta]\nrange = [-35, 35]\n";
    let model = boat();
    let e = parse(text, false)
        .and_then(|p| p.conditions(model.ir()))
        .map(|_| ())
        .map_err(|e| locate(e, text, false))
        .expect_err("prior 0.6");
    assert_eq!(e.key.as_deref(), Some("prior"), "{e:?}");
    assert_eq!((e.line, e.column), (Some(1), Some(9)), "{e:?}");
    assert!(e.message.contains("not a fraction from 0 to 0.35"), "{e:?}");
    let c = parse(
        "prior = 0.3\n[inputs.tau]\nrange = [0, 400]\n[inputs.delta]\nrange = [-35, 35]\n",
        false,
    )
    .and_then(|p| p.conditions(model.ir()))
    .expect("prior 0.3");
    assert_eq!(c.prior, 0.3);
    assert!(
        !c.assumptions.iter().any(|a| a.contains("θ known")),
        "{:?}",
        c.assumptions
    );
}
