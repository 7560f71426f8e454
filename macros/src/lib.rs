//! leeway-macros: the procedural macros `include_model!` and `inline_model!`,
//! a shell over `leeway-codegen` (which parses the arguments, resolves the
//! path, runs the structure compiler and emits the tokens). Use them through
//! the `leeway` crate, whose documentation describes them.
//!
//! `include_model!` passes its tokens, `Span::call_site().local_file()` and
//! `CARGO_MANIFEST_DIR` to codegen; `inline_model!` passes its tokens. No
//! logic lives here: an `if` in this crate belongs in codegen.

use proc_macro::{Span, TokenStream};

/// Compiles the `.som` model file at the given path — relative to the
/// invoking file, like `include_str!` — into a typed, straight-line
/// `leeway::Model`. See the `leeway` crate.
#[proc_macro]
pub fn include_model(input: TokenStream) -> TokenStream {
    let invocation = leeway_codegen::Invocation {
        invoking_file: Span::call_site().local_file(),
        manifest_dir: std::env::var_os("CARGO_MANIFEST_DIR").map(Into::into),
    };
    leeway_codegen::include_model(input.into(), &invocation).into()
}

/// Compiles a model written in a string literal into a typed, straight-line
/// `leeway::Model`. See the `leeway` crate.
#[proc_macro]
pub fn inline_model(input: TokenStream) -> TokenStream {
    leeway_codegen::inline_model(input.into()).into()
}
