// error[unknown-name]: `water.w`: the relative velocity has no component `w`.
leeway::include_model!("unknown-name.som");

fn main() {}
