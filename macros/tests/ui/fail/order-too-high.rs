// error[order-too-high]: u*v*r is beyond second order. Code that uses the
// model still type-checks against the fallback items, so the model's error
// is the only one.
use leeway::{Model, Signals};

leeway::include_model!("order-too-high.som");

fn main() {
    let theta = BoatParams { X_u: -0.2, ..BoatParams::nominal() };
    let sig = Signals { states: &[1.0, 0.0, 0.0], inputs: &[1.0], rotation: &[], disturbances: &[] };
    let mut phi = [0.0; Boat::BASIC_LEN];
    Boat.basic(&sig, &mut phi);
    let mut f = [0.0; Boat::STATES.len()];
    Boat.rhs(&theta.to_array(), &sig, &mut f);
}
