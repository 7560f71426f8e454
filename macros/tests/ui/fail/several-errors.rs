// error[several-errors]: Every error is reported, not only the first.
leeway::include_model!("several-errors.som");

fn main() {}
