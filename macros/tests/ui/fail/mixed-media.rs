// error[mixed-media]: One term relative to two media at once.
leeway::include_model!("mixed-media.som");

fn main() {}
