//! The fallback expansion of a model that does not compile (after thiserror's
//! `fallback.rs`): the same items as a valid model — the struct, its
//! constants, `<Model>Params` with a field per parameter that could be read,
//! and a `Model` impl whose bodies are never run — so that code using the
//! model type-checks and the user sees the model's errors, not thirty
//! follow-on errors about missing items. The `compile_error!`s emitted beside
//! it guarantee the crate does not build.

use crate::emit::{Shape, declared, names};
use crate::tokens::rust_ident;
use leeway_structure::{grammar, resolve, terms};
use proc_macro2::TokenStream;
use quote::quote;

/// What can be read from a broken model: its name, states, inputs and
/// parameters (the passes collect errors and go on, so these survive most
/// errors); after a syntax error, only the name, by a plain scan.
pub(crate) fn sketch(source: &str) -> Shape {
    let (model, _) = grammar::parse(source);
    match model {
        Some(model) => {
            let mut scratch = Vec::new();
            let r = resolve::resolve(&model, &mut scratch);
            let (params, _) = terms::lower_terms(&r, &mut scratch);
            let idents = |v: &[grammar::Ident]| v.iter().map(|i| i.name.clone()).collect();
            Shape {
                name: r.name.name.clone(),
                states: idents(&r.states),
                inputs: idents(&r.inputs),
                nominal: vec![0.0; params.len()],
                parameters: params.into_iter().map(|p| p.name).collect(),
                ..Shape::default()
            }
        }
        None => Shape {
            name: scan_name(source).unwrap_or_default(),
            ..Shape::default()
        },
    }
}

/// The identifier after the first `model` keyword outside `//` comments.
fn scan_name(source: &str) -> Option<String> {
    let mut words = source.lines().flat_map(|l| {
        l.split("//")
            .next()
            .unwrap_or("")
            .split(|c: char| c.is_whitespace() || c == '{')
    });
    words.find(|w| *w == "model")?;
    words
        .find(|w| !w.is_empty())
        .filter(|w| rust_ident(w).is_some())
        .map(str::to_string)
}

/// The fallback items for `shape`; nothing when not even the model's name is
/// a Rust identifier (the errors then stand alone).
pub(crate) fn expansion(shape: &Shape) -> TokenStream {
    let (Some(names), _) = names(shape) else {
        return TokenStream::new();
    };
    let ty = &names.model;
    let doc = quote!(
        /// The model as declared; its `.som` file has errors (see the compile errors).
    );
    let declared = declared(doc, shape, &names);
    let never = quote!(::core::unreachable!("the model did not compile"));
    quote! {
        #declared

        #[allow(clippy::all, clippy::pedantic, clippy::nursery)]
        impl ::leeway::__private::Model for #ty {
            fn ir(&self) -> &::leeway::__private::Ir {
                #never
            }
            fn basic(&self, _: &::leeway::__private::Signals<'_>, _: &mut [f64]) {
                #never
            }
            fn augmented(&self, _: &::leeway::__private::Signals<'_>, _: &[f64], _: &mut [f64]) {
                #never
            }
            fn measured(&self, _: &::leeway::__private::Signals<'_>, _: &[f64], _: &mut [f64]) {
                #never
            }
            fn rhs(&self, _: &[f64], _: &::leeway::__private::Signals<'_>, _: &mut [f64]) {
                #never
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_syntax_error_keeps_the_name() {
        let s = sketch("// a comment with model Foo\nmodel Boat {\n state u\n der u = X*u +\n}");
        assert_eq!(s.name, "Boat");
        assert!(s.parameters.is_empty());
    }

    #[test]
    fn a_semantic_error_keeps_the_parameters() {
        let s = sketch("model Boat {\n state u, v\n der u = X*u*v*u\n der v = Y*v + Z*w\n}");
        assert_eq!(s.name, "Boat");
        assert_eq!(s.states, ["u", "v"]);
        assert!(s.parameters.iter().any(|p| p == "Y"), "{:?}", s.parameters);
    }

    #[test]
    fn no_name_no_items() {
        assert!(expansion(&sketch("")).is_empty());
        assert!(expansion(&sketch("model self { }")).is_empty());
    }
}
