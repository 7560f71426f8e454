// The inline form: the model in a string literal, comments included.
#![deny(warnings)]

use leeway::{Model, Signals};

leeway::inline_model!(
    r#"
    // A drifting buoy in one dimension.
    model Drift {
        state u
        input f
        next u = A*u + D*u*|u| + B*f   // |u| of a noisy state: a sign argument
        nominal { A = 0.9, B = 0.1 }
    }
    "#
);

fn main() {
    assert_eq!(Drift::SIGN_ARGS, ["u"]);
    assert_eq!(DriftParams::nominal(), DriftParams { A: 0.9, D: 0.0, B: 0.1 });
    let sig = Signals { states: &[-2.0], inputs: &[1.0], rotation: &[], disturbances: &[] };
    let mut phi = [0.0; Drift::BASIC_LEN];
    Drift.basic(&sig, &mut phi);
    assert_eq!(phi, [-2.0, -4.0, 1.0]);
    let mut aug = [0.0; Drift::AUGMENTED_LEN];
    Drift.augmented(&sig, &[-1.0], &mut aug);
    assert_eq!(aug, [-2.0, -4.0, 1.0]);
}
