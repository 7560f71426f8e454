// A model identifiable from two experiments, with a note and a warning from
// the structure compiler: neither fails the build, even with warnings denied.
#![deny(warnings)]

use leeway::{Interpreter, Model, Signals, planar_rotation};

leeway::include_model!("two-experiments.som");

fn main() {
    let report = Boat.report();
    assert!(report.identifiable && !report.any_single_pattern);
    assert_eq!(report.required_patterns.len(), 2);
    assert_eq!(BoatParams::NAMES, ["X_u", "X_uu", "W_uu", "X_tau", "Y_v", "N_r"]);
    assert_eq!(Boat::SIGN_ARGS, ["water.u", "air.u"]);

    let theta = BoatParams { X_uu: -0.05, W_uu: -0.01, ..BoatParams::nominal() };
    assert_eq!(BoatParams::from_slice(&theta.to_vec()).ok(), Some(theta));
    assert!(BoatParams::from_slice(&[1.0]).is_err());

    let rotation = planar_rotation(0.5);
    let sig = Signals { states: &[1.0, 0.2, 0.1], inputs: &[3.0, 0.0], rotation: &rotation, disturbances: &[0.1, 0.2, 2.0, -1.0] };
    let interpreter = Interpreter::new(Boat.ir().clone());
    let mut generated = [0.0; Boat::AUGMENTED_LEN];
    let mut interpreted = [0.0; Boat::AUGMENTED_LEN];
    Boat.augmented(&sig, &[1.0, -1.0], &mut generated);
    interpreter.augmented(&sig, &[1.0, -1.0], &mut interpreted);
    assert_eq!(generated.map(f64::to_bits), interpreted.map(f64::to_bits));

    let (mut f, mut next) = ([0.0; 3], [0.0; 3]);
    Boat.step(&theta.to_array(), Boat::STEP.unwrap_or(1.0), &sig, &mut f, &mut next);
    assert!(next.iter().all(|x| x.is_finite()));
}
