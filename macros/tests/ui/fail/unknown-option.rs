// The only option is `aggregate`.
leeway::include_model!("../../../../examples/models/ship_iv2.som", aggregated);

fn main() {}
