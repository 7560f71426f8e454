//! Diagnostics as `compile_error!` items: the plain rendering without the
//! leading `error`, and hints worded for the macros' options.

use leeway_structure::grammar::{Diagnostic, RenderStyle, render};
use proc_macro2::{Span, TokenStream};
use quote::quote_spanned;

/// `compile_error! { message }` at `span`: braces, no `;`, so it stands as an
/// item beside the others.
pub(crate) fn compile_error(message: &str, span: Span) -> TokenStream {
    quote_spanned!(span=> ::core::compile_error! { #message })
}

/// The message of one diagnostic: its plain rendering (`┌─ path:line:col`,
/// the source line, the caret, notes and help), with the leading `error`
/// dropped because rustc prints `error: ` before the message itself.
pub fn error_message(d: &Diagnostic, label: &str, source: &str) -> String {
    let rendered = render(std::slice::from_ref(d), label, source, RenderStyle::Plain);
    let text = rendered.trim_end();
    match text.strip_prefix("error") {
        Some(rest) if rest.starts_with('[') => match rest.split_once("]: ") {
            Some((code, tail)) => format!("{code}] {tail}"),
            None => rest.to_string(),
        },
        _ => text.to_string(),
    }
}

/// A diagnostic as macro users read it: the compiler's hints name the CLI's
/// `--aggregate`; the macros' equivalent is their `aggregate` option.
pub(crate) fn for_macro(d: &Diagnostic) -> Diagnostic {
    let mut d = d.clone();
    let rewrite = |s: &str| s.replace("with --aggregate", "with the macro's `aggregate` option");
    d.help = d.help.as_deref().map(rewrite);
    d.notes = d.notes.iter().map(|n| rewrite(n)).collect();
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_structure::{CompileOptions, compile};

    #[test]
    fn error_messages_carry_the_rendered_snippet() {
        let src = "model A {\n  state u\n  der u = X*u*u*u\n}\n";
        let c = compile(src, &CompileOptions::default());
        let d = c
            .diagnostics
            .iter()
            .find(|d| d.is_error())
            .expect("an error");
        let m = error_message(d, "models/a.som", src);
        assert!(m.starts_with(&format!("[{}] ", d.code)), "{m}");
        assert!(m.contains("models/a.som:3:"), "{m}");
        assert!(m.contains("der u = X*u*u*u"), "{m}");
        assert!(m.contains('^'), "{m}");
    }
}
