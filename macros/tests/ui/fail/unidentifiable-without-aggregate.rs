// The paper's ship with the wind unmeasured is identifiable only up to
// aggregates: without `aggregate`, every combination is an error.
leeway::include_model!("../../../../examples/models/ship_iv2.som");

fn main() {}
