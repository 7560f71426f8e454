//! One model source → the macro's items: the model's, or the fallback's
//! beside a `compile_error!` per error; warnings go into the documentation.
//! For a model file, `const _: &str = include_str!("<absolute path>")` makes
//! editing the model rebuild the crate.

use crate::emit;
use crate::fallback;
use crate::input::Source;
use crate::message::{compile_error, error_message, for_macro};
use leeway_structure::grammar::{Diagnostic, Severity};
use leeway_structure::{CompileOptions, compile};
use proc_macro2::{Span, TokenStream};
use quote::quote;

/// The expansion of one model source: the model's items, or the fallback
/// items, plus a `compile_error!` at `span` per error; warnings and notes go
/// into the model's documentation and never fail the build.
pub fn expand(source: &Source, options: &CompileOptions, span: Span) -> TokenStream {
    let compilation = compile(source.text, options);
    let (errors, remarks): (Vec<&Diagnostic>, Vec<&Diagnostic>) =
        compilation.diagnostics.iter().partition(|d| d.is_error());
    let mut out = TokenStream::new();
    for d in &errors {
        out.extend(compile_error(
            &error_message(&for_macro(d), source.label, source.text),
            span,
        ));
    }
    if let Some(path) = source.tracked {
        out.extend(quote!(
            const _: &str = ::core::include_str!(#path);
        ));
    }
    // An aggregated combination is stated in the identifiability paragraph already.
    let remarks: Vec<String> = remarks
        .iter()
        .filter(|d| d.code != "aggregated-combination")
        .map(|d| {
            let severity = if d.severity == Severity::Warning {
                "warning"
            } else {
                "note"
            };
            format!("{severity}[{}]: {}", d.code, d.message)
        })
        .collect();
    let items = match &compilation.ir {
        Some(ir) => match emit::model(ir, source.label, &remarks) {
            Ok(items) => items,
            Err(messages) => {
                for m in messages {
                    out.extend(compile_error(&m, span));
                }
                fallback::expansion(&emit::Shape::of(ir))
            }
        },
        None => fallback::expansion(&fallback::sketch(source.text)),
    };
    out.extend(items);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_broken_model_expands_to_errors_and_a_fallback() {
        let src = "model A {\n  state u\n  der u = X*u*u*u\n}\n";
        let out = expand(
            &Source {
                text: src,
                label: "a.som",
                tracked: None,
            },
            &CompileOptions::default(),
            Span::call_site(),
        )
        .to_string();
        assert_eq!(out.matches("compile_error").count(), 1, "{out}");
        assert!(out.contains("struct A"), "{out}");
        assert!(out.contains("struct AParams"), "{out}");
        assert!(out.contains("unreachable"), "{out}");
    }

    #[test]
    fn model_names_rust_cannot_use_are_errors() {
        for name in ["f64", "self", "_"] {
            let src = format!("model {name} {{\n  state u\n  der u = X*u\n}}\n");
            let out = expand(
                &Source {
                    text: &src,
                    label: "a.som",
                    tracked: None,
                },
                &CompileOptions::default(),
                Span::call_site(),
            )
            .to_string();
            assert!(out.contains("cannot be a Rust type name"), "{name}: {out}");
            assert!(!out.contains("struct"), "{name}: {out}");
        }
    }

    #[test]
    fn a_valid_model_has_no_errors_and_tracks_its_file() {
        let src = "model A {\n  state u\n  input f\n  der u = X*u + F*f\n}\n";
        let out = expand(
            &Source {
                text: src,
                label: "a.som",
                tracked: Some("/m/a.som"),
            },
            &CompileOptions::default(),
            Span::call_site(),
        )
        .to_string();
        assert!(!out.contains("compile_error"), "{out}");
        assert!(out.contains("include_str ! (\"/m/a.som\")"), "{out}");
        assert!(!out.contains("unreachable"), "{out}");
    }
}
