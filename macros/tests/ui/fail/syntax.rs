// error[syntax]: A product with two `*` in a row.
leeway::include_model!("syntax.som");

fn main() {}
