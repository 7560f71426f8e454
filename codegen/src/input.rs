//! The macros' arguments and what they are expanded from: the invocation's
//! place, the model's source, the literal with its options.

use leeway_structure::CompileOptions;
use std::path::PathBuf;
use syn::parse::{Parse, ParseStream};
use syn::{LitStr, Token};

/// Where an `include_model!` call sits, as the compiler reports it.
#[derive(Clone, Debug, Default)]
pub struct Invocation {
    /// The invoking source file (`proc_macro::Span::local_file`), if the
    /// compiler names one; possibly relative to the compiler's directory.
    pub invoking_file: Option<PathBuf>,
    /// `CARGO_MANIFEST_DIR`: the base when the invoking file is unknown.
    pub manifest_dir: Option<PathBuf>,
}

/// A model's source text and how to name it.
#[derive(Clone, Copy, Debug)]
pub struct Source<'a> {
    /// The `.som` text.
    pub text: &'a str,
    /// The name diagnostics show: the path as the user wrote it, or `<inline>`.
    pub label: &'a str,
    /// The model file's absolute path, included with `include_str!` so that
    /// editing the file rebuilds the crate; `None` for inline models.
    pub tracked: Option<&'a str>,
}

/// The macros' arguments: a string literal (the path, or the model itself),
/// then optional flags.
#[derive(Clone)]
pub struct MacroInput {
    /// The literal; every error is reported on its span.
    pub literal: LitStr,
    /// `aggregate`: when θ is not identifiable, keep its identifiable
    /// combinations (a warning, like `leeway check --aggregate`) instead of
    /// failing.
    pub aggregate: bool,
}

impl Parse for MacroInput {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        if !input.peek(LitStr) {
            return Err(input.error(
                "expected a string literal: the path of a `.som` file for `include_model!(\"models/ship.som\")`, \
                 the model itself for `inline_model!(r#\"model A { … }\"#)`",
            ));
        }
        let literal: LitStr = input.parse()?;
        let mut aggregate = false;
        while !input.is_empty() {
            input.parse::<Token![,]>()?;
            if input.is_empty() {
                break;
            }
            let flag: syn::Ident = input.parse()?;
            if flag == "aggregate" {
                aggregate = true;
            } else {
                return Err(syn::Error::new(
                    flag.span(),
                    format!(
                        "unknown option `{flag}`: the only option is `aggregate` (estimate the identifiable \
                         combinations when θ is not identifiable)"
                    ),
                ));
            }
        }
        Ok(MacroInput { literal, aggregate })
    }
}

impl MacroInput {
    /// The compiler options the flags ask for.
    pub(crate) fn options(&self) -> CompileOptions {
        CompileOptions {
            aggregate: self.aggregate,
            patterns: None,
            centring: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quote::quote;

    #[test]
    fn options_parse() {
        let i: MacroInput = syn::parse_quote!("a.som", aggregate,);
        assert!(i.aggregate);
        let i: MacroInput = syn::parse_quote!("a.som");
        assert!(!i.aggregate);
        let e = syn::parse2::<MacroInput>(quote!("a.som", aggregated))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("unknown option `aggregated`"), "{e}");
        let e = syn::parse2::<MacroInput>(quote!(ship))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("expected a string literal"), "{e}");
    }
}
