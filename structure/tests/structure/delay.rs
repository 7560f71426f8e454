//! Dead times: `delay input N steps` and `delay input T s` in the IR, and
//! `delay` still free as a name elsewhere.

use leeway_structure::ir::{Delay, Lag};
use leeway_structure::{CompileOptions, compile};

fn delays(source: &str) -> Vec<Delay> {
    let c = compile(source, &CompileOptions::default());
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    c.ir.expect("an IR").delays
}

#[test]
fn steps_and_seconds_resolve_against_the_step() {
    let d = delays(
        "model M { step 0.1 state u, v input a, b
           delay b 1.2 s
           delay a 3 steps
           der u = X*u + A*a  der v = Y*v + B*b }",
    );
    assert_eq!(
        d,
        vec![
            Delay {
                input: 1,
                lag: Lag::Samples(12)
            },
            Delay {
                input: 0,
                lag: Lag::Samples(3)
            },
        ]
    );
}

#[test]
fn seconds_without_a_step_wait_for_the_data() {
    let d = delays("model M { state u input a delay a 0.5 s der u = X*u + A*a }");
    assert_eq!(
        d,
        vec![Delay {
            input: 0,
            lag: Lag::Seconds(0.5)
        }]
    );
    let ir = compile(
        "model M { state u input a delay a 0.5 s der u = X*u + A*a }",
        &CompileOptions::default(),
    )
    .ir
    .expect("an IR");
    assert_eq!(ir.dead_times(0.1), Ok(vec![5]));
    assert!(ir.dead_times(0.3).is_err(), "0.5 s is no multiple of 0.3 s");
}

#[test]
fn delay_stays_a_name_and_no_delay_leaves_the_ir_json_as_it_was() {
    let source = "model M { state u input a der u = delay*u + A*a }";
    let c = compile(source, &CompileOptions::default());
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    let ir = c.ir.expect("an IR");
    assert_eq!(ir.parameters[0].name, "delay");
    let json = serde_json::to_string(&ir).expect("json");
    assert!(!json.contains("delays"), "{json}");
}
