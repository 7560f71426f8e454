// An inline model's diagnostics count lines from the literal's first line.
leeway::inline_model!(
    r#"model Drift {
    state u
    der u = X_u*u + X_uu*u*|u|)
}"#
);

fn main() {}
