// error[common-input-term]: An input-only term in both media: X1*tau and X2*tau cannot be told apart.
leeway::include_model!("common-input-term.som");

fn main() {}
