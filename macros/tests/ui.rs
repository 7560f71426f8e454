//! trybuild ui tests of `include_model!` and `inline_model!`: one failing
//! case per error class, each with its sibling `.som` file and the
//! `.stderr` rustc prints: the model file's `path:line:col`, the source
//! line, the caret and the hint. Models that compile and run are ordinary
//! tests (the facade's `tests/generated.rs`): with only failing cases,
//! trybuild type-checks its dependencies instead of building them.
//!
//! Regenerate the `.stderr` files with
//! `TRYBUILD=overwrite cargo test -p leeway-macros --test ui` and review
//! every change.

#[test]
fn ui() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/fail/*.rs");
}
