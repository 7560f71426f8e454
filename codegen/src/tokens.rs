//! Small token helpers: Rust identifiers from model names, exact float and
//! index literals, doc attributes.

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;
use std::str::FromStr;

/// Names that cannot be Rust identifiers even as raw identifiers.
const NOT_RAW: [&str; 5] = ["self", "Self", "super", "crate", "_"];

/// A Rust identifier spelled exactly as `name`, raw (`r#type`) for a
/// keyword; `None` when Rust has no such identifier (`self`, `_`, `2x`).
pub(crate) fn rust_ident(name: &str) -> Option<Ident> {
    let shaped = name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !shaped || NOT_RAW.contains(&name) {
        return None;
    }
    if syn::parse_str::<Ident>(name).is_ok() {
        Some(Ident::new(name, Span::call_site()))
    } else {
        // A keyword (`type`, `fn`, `async`): legal as a raw identifier.
        Some(Ident::new_raw(name, Span::call_site()))
    }
}

/// An `f64` expression with exactly the value `v`: the shortest decimal that
/// round-trips (Rust parses float literals correctly rounded), negated with a
/// unary minus (exact), the named constants for non-finite values.
pub(crate) fn float(v: f64) -> TokenStream {
    if v.is_nan() {
        return quote!(::core::f64::NAN);
    }
    if v.is_infinite() {
        return if v > 0.0 {
            quote!(::core::f64::INFINITY)
        } else {
            quote!(::core::f64::NEG_INFINITY)
        };
    }
    let magnitude = v.abs();
    // `{:?}` writes `0.5`, `1.0`, `1e-7`, `1e300`: all valid float literals.
    let lit = Literal::from_str(&format!("{magnitude:?}"))
        .unwrap_or_else(|_| Literal::f64_unsuffixed(magnitude));
    if v.is_sign_negative() {
        quote!(-#lit)
    } else {
        quote!(#lit)
    }
}

/// An unsuffixed integer literal (`3`, not `3usize`), for indices and lengths.
pub(crate) fn index(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

/// `#[doc = " ..."]` lines (with the space a `///` comment has).
pub(crate) fn doc(lines: &[String]) -> TokenStream {
    lines
        .iter()
        .map(|l| {
            let l = if l.is_empty() {
                String::new()
            } else {
                format!(" {l}")
            };
            quote!(#[doc = #l])
        })
        .collect()
}

/// Escapes text for a doc comment: brackets, angle brackets and stars
/// outside backtick code spans would otherwise read as links, HTML or
/// emphasis to rustdoc.
pub(crate) fn doc_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut in_code = false;
    for c in text.chars() {
        if c == '`' {
            in_code = !in_code;
        }
        if !in_code && matches!(c, '[' | ']' | '<' | '>' | '*') {
            out.push('\\');
        }
        out.push(c);
    }
    out
}

/// `"a", "b"` as a `[&str; N]` expression.
pub(crate) fn str_array<S: AsRef<str>>(items: &[S]) -> TokenStream {
    let items = items.iter().map(AsRef::as_ref);
    quote!([#(#items),*])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_spelled_as_written() {
        assert_eq!(
            rust_ident("X_uu").map(|i| i.to_string()),
            Some("X_uu".to_string())
        );
        assert_eq!(
            rust_ident("type").map(|i| i.to_string()),
            Some("r#type".to_string())
        );
        assert_eq!(rust_ident("self"), None);
        assert_eq!(rust_ident("_"), None);
        assert_eq!(rust_ident("2x"), None);
        assert_eq!(rust_ident("a.b"), None);
    }

    #[test]
    fn float_literals_round_trip_exactly() {
        for v in [
            0.5,
            1.0,
            -0.2,
            0.00015,
            1e-7,
            -1e300,
            5e-324,
            0.1 + 0.2,
            -0.0,
            123456789.125,
            f64::MAX,
        ] {
            let text = float(v).to_string().replace(' ', "");
            let parsed: f64 = text.parse().unwrap_or(f64::NAN);
            assert_eq!(parsed.to_bits(), v.to_bits(), "{v} written as {text}");
        }
        assert_eq!(
            float(f64::NAN).to_string().replace(' ', ""),
            "::core::f64::NAN"
        );
        assert_eq!(
            float(f64::NEG_INFINITY).to_string().replace(' ', ""),
            "::core::f64::NEG_INFINITY"
        );
    }

    #[test]
    fn doc_text_is_escaped_outside_code() {
        assert_eq!(
            doc_escape("rho[north] `s[water.u]` <inline>"),
            "rho\\[north\\] `s[water.u]` \\<inline\\>"
        );
    }
}
