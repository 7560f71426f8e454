//! The paper's ship, compiled into Rust at build time: simulate a few steps
//! under current and wind, printing the regressors of each predictor.
//!
//! `cargo run --example ship`

use leeway::{Model, Signals, next_heading, planar_rotation};

// Parsed, expanded and proved identifiable while this file compiles; editing
// the model file rebuilds the example.
leeway::include_model!("models/ship.som");

fn main() {
    let model = Ship;
    let theta = ShipParams {
        X_uu: -0.05,
        Y_vv: -0.1,
        N_vv: -0.01,
        W_uu: -0.002,
        W_vv: -0.004,
        ..ShipParams::nominal()
    };
    let h = Ship::STEP.unwrap_or(1.0);
    println!(
        "{} — {}",
        Ship::NAME,
        if model.report().identifiable {
            "θ identifiable"
        } else {
            "θ NOT identifiable"
        }
    );
    println!(
        "states {:?}, inputs {:?}, sign arguments {:?}\n",
        Ship::STATES,
        Ship::INPUTS,
        Ship::SIGN_ARGS
    );

    // Current (north, east) and wind (wind_n, wind_e), in Ship::COMPONENTS order.
    let disturbances = [0.2, 0.2, 1.0, 1.0];
    let inputs = [20.0, 5.0, 50.0];
    let mut x = [1.0, 0.0, 0.0];
    let mut psi = 0.0;
    let mut f = [0.0; Ship::STATES.len()];
    let mut next = [0.0; Ship::STATES.len()];
    let mut basic = [0.0; Ship::BASIC_LEN];
    let mut measured = [0.0; Ship::MEASURED_LEN];

    for k in 0..5 {
        let rotation = planar_rotation(psi);
        let sig = Signals {
            states: &x,
            inputs: &inputs,
            rotation: &rotation,
            disturbances: &disturbances,
        };
        // The sign pattern of this sample: the sign of each sign argument.
        let signs: Vec<f64> = model
            .ir()
            .sign_args
            .iter()
            .map(|a| {
                let plan = leeway::model::interp::arg_plan(model.ir(), &a.arg);
                if plan.eval(&sig, true) < 0.0 {
                    -1.0
                } else {
                    1.0
                }
            })
            .collect();
        model.basic(&sig, &mut basic);
        model.measured(&sig, &signs, &mut measured);
        println!(
            "k = {k}: x = [{:.4}, {:.4}, {:.4}], psi = {psi:.4}",
            x[0], x[1], x[2]
        );
        for (o, state) in Ship::STATES.iter().enumerate() {
            let row = &basic[o * Ship::BASIC_COLUMNS.len()..(o + 1) * Ship::BASIC_COLUMNS.len()];
            let terms: Vec<String> = Ship::BASIC_COLUMNS
                .iter()
                .zip(row)
                .filter(|(_, v)| **v != 0.0)
                .map(|(name, v)| format!("{name} {v:.4}"))
                .collect();
            println!("  Φ   {state}: {}", terms.join(", "));
        }
        let n = Ship::MEASURED_COLUMNS.len();
        let nonzero = measured.iter().filter(|v| **v != 0.0).count();
        println!(
            "  IV3 regressors: {nonzero} non-zero of {} ({} columns × {} outputs)",
            measured.len(),
            n,
            Ship::STATES.len()
        );

        model.step(&theta.to_array(), h, &sig, &mut f, &mut next);
        psi = next_heading(model.ir(), psi, h, &x);
        x = next;
    }
}
