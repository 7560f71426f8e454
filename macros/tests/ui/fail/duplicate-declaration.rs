// error[duplicate-declaration]: `tau` declared twice.
leeway::include_model!("duplicate-declaration.som");

fn main() {}
