// A valid model whose parameter `self` cannot be a Rust field name.
leeway::include_model!("parameter-not-a-rust-name.som");

fn main() {}
