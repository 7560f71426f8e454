// The path is resolved next to this file, like `include_str!`.
leeway::include_model!("no-such-model.som");

fn main() {}
