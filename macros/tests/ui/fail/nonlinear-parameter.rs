// error[nonlinear-parameter]: A parameter squared: the model must be linear in θ.
leeway::include_model!("nonlinear-parameter.som");

fn main() {}
