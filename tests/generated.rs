//! Models the macros compile, and that run, with warnings denied: the
//! structure compiler's notes and warnings never fail a build. (The ui
//! tests, `macros/tests/ui.rs`, hold the failing cases; these were its passing
//! ones, moved here so that trybuild only type-checks, and these compile
//! with the other tests.)
#![deny(warnings)]

/// The inline form: the model in a string literal, comments included.
mod inline {
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

    #[test]
    fn drift_compiles_and_evaluates() {
        assert_eq!(Drift::SIGN_ARGS, ["u"]);
        assert_eq!(
            DriftParams::nominal(),
            DriftParams {
                A: 0.9,
                D: 0.0,
                B: 0.1
            }
        );
        let sig = Signals {
            states: &[-2.0],
            inputs: &[1.0],
            rotation: &[],
            disturbances: &[],
        };
        let mut phi = [0.0; Drift::BASIC_LEN];
        Drift.basic(&sig, &mut phi);
        assert_eq!(phi, [-2.0, -4.0, 1.0]);
        let mut aug = [0.0; Drift::AUGMENTED_LEN];
        Drift.augmented(&sig, &[-1.0], &mut aug);
        assert_eq!(aug, [-2.0, -4.0, 1.0]);
    }
}

/// A model identifiable from two experiments, with a note and a warning from
/// the structure compiler: neither fails the build.
mod two_experiments {
    use leeway::{Interpreter, Model, Signals, planar_rotation};

    leeway::include_model!("generated/two-experiments.som");

    #[test]
    fn boat_compiles_with_a_note_and_a_warning() {
        let report = Boat.report();
        assert!(report.identifiable && !report.any_single_pattern);
        assert_eq!(report.required_patterns.len(), 2);
        assert_eq!(
            BoatParams::NAMES,
            ["X_u", "X_uu", "W_uu", "X_tau", "Y_v", "N_r"]
        );
        assert_eq!(Boat::SIGN_ARGS, ["water.u", "air.u"]);

        let theta = BoatParams {
            X_uu: -0.05,
            W_uu: -0.01,
            ..BoatParams::nominal()
        };
        assert_eq!(BoatParams::from_slice(&theta.to_vec()).ok(), Some(theta));
        assert!(BoatParams::from_slice(&[1.0]).is_err());

        let rotation = planar_rotation(0.5);
        let sig = Signals {
            states: &[1.0, 0.2, 0.1],
            inputs: &[3.0, 0.0],
            rotation: &rotation,
            disturbances: &[0.1, 0.2, 2.0, -1.0],
        };
        let interpreter = Interpreter::new(Boat.ir().clone());
        let mut generated = [0.0; Boat::AUGMENTED_LEN];
        let mut interpreted = [0.0; Boat::AUGMENTED_LEN];
        Boat.augmented(&sig, &[1.0, -1.0], &mut generated);
        interpreter.augmented(&sig, &[1.0, -1.0], &mut interpreted);
        assert_eq!(generated.map(f64::to_bits), interpreted.map(f64::to_bits));

        let (mut f, mut next) = ([0.0; 3], [0.0; 3]);
        Boat.step(
            &theta.to_array(),
            Boat::STEP.unwrap_or(1.0),
            &sig,
            &mut f,
            &mut next,
        );
        assert!(next.iter().all(|x| x.is_finite()));
    }
}
