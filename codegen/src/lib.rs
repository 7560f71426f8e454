//! leeway-codegen: a `.som` model → the Rust tokens of `include_model!` and
//! `inline_model!`, as a normal library (the proc-macro crate is a shell over
//! it). It runs the structure compiler and emits, for a model `Ship`, a unit
//! struct `Ship` implementing `leeway::Model` with straight-line regressor
//! code (the evaluation order of `leeway_structure::ir::Entry`, shared with
//! the run-time interpreter, so both agree bit for bit), the typed parameter
//! struct `ShipParams`, typed constants, and the IR embedded as JSON data.
//!
//! Nothing here returns `Err` or panics: every problem becomes a
//! `compile_error!` on the macro's string literal, carrying the rendered
//! diagnostic (`path:line:col`, source line, caret, help), emitted beside a
//! fallback expansion so the user sees the model's errors and nothing else.
//! The only IO is reading the model file of `include_model!`.

mod emit;
mod eval;
mod fallback;
mod tokens;

use leeway_structure::grammar::{Diagnostic, RenderStyle, Severity, render};
use leeway_structure::{CompileOptions, compile};
use proc_macro2::{Span, TokenStream};
use quote::{quote, quote_spanned};
use std::path::{Path, PathBuf};
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
    fn options(&self) -> CompileOptions {
        CompileOptions {
            aggregate: self.aggregate,
            patterns: None,
            centring: None,
        }
    }
}

/// `compile_error! { message }` at `span`: braces, no `;`, so it stands as an
/// item beside the others.
fn compile_error(message: &str, span: Span) -> TokenStream {
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
fn for_macro(d: &Diagnostic) -> Diagnostic {
    let mut d = d.clone();
    let rewrite = |s: &str| s.replace("with --aggregate", "with the macro's `aggregate` option");
    d.help = d.help.as_deref().map(rewrite);
    d.notes = d.notes.iter().map(|n| rewrite(n)).collect();
    d
}

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

/// Resolves the path of `include_model!` like `include_str!`: relative to the
/// invoking file's directory, else to `CARGO_MANIFEST_DIR`. Absolute paths
/// are rejected (as sqlx does): a crate that names a file by an absolute path
/// builds on one machine only.
pub fn resolve_path(written: &str, invocation: &Invocation) -> Result<PathBuf, String> {
    let path = Path::new(written);
    if written.is_empty() {
        return Err(
            "expected the path of a `.som` model file, e.g. `include_model!(\"models/ship.som\")`"
                .to_string(),
        );
    }
    if path.is_absolute() || path.has_root() {
        return Err(format!(
            "absolute model paths are not accepted: `{written}` would build on this machine only; \
             write the path relative to the invoking file, like `include_str!`"
        ));
    }
    let base = match (&invocation.invoking_file, &invocation.manifest_dir) {
        (Some(file), _) => file.parent().map(Path::to_path_buf).unwrap_or_default(),
        (None, Some(dir)) => dir.clone(),
        (None, None) => {
            return Err(format!(
                "cannot resolve `{written}`: the compiler names no invoking file and CARGO_MANIFEST_DIR is not set"
            ));
        }
    };
    Ok(base.join(path))
}

/// `include_model!("models/ship.som")`: reads the file next to the invoking
/// file and expands it; every failure is a `compile_error!` on the literal.
pub fn include_model(input: TokenStream, invocation: &Invocation) -> TokenStream {
    let input: MacroInput = match syn::parse2(input) {
        Ok(i) => i,
        Err(e) => return e.to_compile_error(),
    };
    let written = input.literal.value();
    let span = input.literal.span();
    let path = match resolve_path(&written, invocation) {
        Ok(p) => p,
        Err(e) => return compile_error(&e, span),
    };
    let text = match read_model(&path) {
        Ok(Ok(t)) => t,
        // Too large (checked before reading) or not UTF-8 (located): one rendered error.
        Ok(Err(refused)) => {
            return compile_error(
                &error_message(&refused.diagnostic, &written, &refused.text),
                span,
            );
        }
        Err(e) => {
            let why = match e.kind() {
                std::io::ErrorKind::NotFound => "not found".to_string(),
                _ => e.to_string(),
            };
            return compile_error(
                &format!(
                    "cannot read model file `{written}`: {why} (looked at `{}`; paths are relative to the invoking file, like `include_str!`)",
                    path.display()
                ),
                span,
            );
        }
    };
    let absolute = std::fs::canonicalize(&path)
        .or_else(|_| std::path::absolute(&path))
        .unwrap_or(path);
    let tracked = absolute.to_str();
    if tracked.is_none() {
        return compile_error(
            &format!("the path of model file `{written}` is not valid UTF-8"),
            span,
        );
    }
    expand(
        &Source {
            text: &text,
            label: &written,
            tracked,
        },
        &input.options(),
        span,
    )
}

/// Reads a model file, its size checked before reading: at most
/// `MAX_SOURCE_BYTES + 1` bytes are read, then decoded as UTF-8.
fn read_model(
    path: &std::path::Path,
) -> std::io::Result<Result<String, Box<leeway_structure::grammar::source::Refused>>> {
    use leeway_structure::grammar::{self, source};
    use std::io::Read;
    let file = std::fs::File::open(path)?;
    let size = file.metadata()?.len();
    let limit = grammar::MAX_SOURCE_BYTES as u64;
    if size > limit {
        return Ok(Err(Box::new(source::Refused {
            text: String::new(),
            diagnostic: source::too_large(size),
        })));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes)?;
    Ok(source::decode(bytes))
}

/// `inline_model!(r#"model A { … }"#)`: the model written in a string
/// literal (comments and layout kept, so diagnostics show `<inline>:line:col`
/// counted from the literal's first line).
pub fn inline_model(input: TokenStream) -> TokenStream {
    let input: MacroInput = match syn::parse2(input) {
        Ok(i) => i,
        Err(e) => return e.to_compile_error(),
    };
    let text = input.literal.value();
    expand(
        &Source {
            text: &text,
            label: "<inline>",
            tracked: None,
        },
        &input.options(),
        input.literal.span(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn invocation(file: &str) -> Invocation {
        Invocation {
            invoking_file: Some(PathBuf::from(file)),
            manifest_dir: Some(PathBuf::from("/crate")),
        }
    }

    #[test]
    fn paths_resolve_next_to_the_invoking_file() {
        assert_eq!(
            resolve_path("models/a.som", &invocation("src/main.rs")),
            Ok(PathBuf::from("src/models/a.som"))
        );
        assert_eq!(
            resolve_path("../a.som", &invocation("/w/tests/ui/x.rs")),
            Ok(PathBuf::from("/w/tests/ui/../a.som"))
        );
        let no_file = Invocation {
            invoking_file: None,
            manifest_dir: Some(PathBuf::from("/crate")),
        };
        assert_eq!(
            resolve_path("a.som", &no_file),
            Ok(PathBuf::from("/crate/a.som"))
        );
        assert!(resolve_path("a.som", &Invocation::default()).is_err());
    }

    #[test]
    fn absolute_and_empty_paths_are_rejected() {
        let e = resolve_path("/etc/ship.som", &invocation("src/main.rs"));
        assert!(e.as_ref().is_err_and(|e| e.contains("absolute")), "{e:?}");
        assert!(resolve_path("", &invocation("src/main.rs")).is_err());
    }

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
