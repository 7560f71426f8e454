// The path must be a string literal.
leeway::include_model!(models::ship);

fn main() {}
