// error[missing-equation]: The state `v` has no equation.
leeway::include_model!("missing-equation.som");

fn main() {}
