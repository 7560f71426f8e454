// Absolute paths are rejected: the crate would build on one machine only.
leeway::include_model!("/models/ship.som");

fn main() {}
