//! A simulated experiment written to CSV reads back bit for bit.

use leeway_data::{LoadOptions, parse_csv, write_csv};
use leeway_model::Interpreter;
use leeway_scenarios::study;
use leeway_structure::ir::Ir;

fn ship() -> Ir {
    let path = format!("{}/../examples/models/ship.som", env!("CARGO_MANIFEST_DIR"));
    let c = leeway_structure::compile(
        &std::fs::read_to_string(path).unwrap_or_default(),
        &Default::default(),
    );
    c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics))
}

#[test]
fn a_written_experiment_reads_back_bit_for_bit() {
    let ir = ship();
    let model = Interpreter::new(ir.clone());
    let (e, _) = study::estimation_experiment(&model, &study::InputDesign::default(), 1.0, 50, 3);
    let mut buf = Vec::new();
    write_csv(&ir, &[&e], 0.0, &mut buf).unwrap_or_else(|err| panic!("{err}"));
    let text = String::from_utf8_lossy(&buf).into_owned();
    assert!(
        text.starts_with("time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n"),
        "{text}"
    );
    let back = parse_csv("run3.csv", &buf, &ir, &LoadOptions::default())
        .unwrap_or_else(|err| panic!("{err}"));
    assert_eq!(back, vec![e]);
}
