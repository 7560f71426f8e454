//! trybuild ui tests of `include_model!` and `inline_model!`: models that
//! compile (and run), and one failing case per error class, each with its
//! sibling `.som` file and the `.stderr` rustc prints: the model file's
//! `path:line:col`, the source line, the caret and the hint.
//!
//! Regenerate the `.stderr` files with `TRYBUILD=overwrite cargo test --test ui`
//! and review every change.

#[test]
fn ui() {
    let t = trybuild::TestCases::new();
    t.pass("tests/ui/pass/*.rs");
    t.compile_fail("tests/ui/fail/*.rs");
}
