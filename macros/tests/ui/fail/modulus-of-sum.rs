// error[modulus-of-sum]: |u + v| is no declared relative velocity.
leeway::include_model!("modulus-of-sum.som");

fn main() {}
