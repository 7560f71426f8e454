// error[unidentifiable-combination]: Both media unmeasured: N_uv and W_uv multiply the same regressor u*v, and
leeway::include_model!("unidentifiable-combination.som");

fn main() {}
