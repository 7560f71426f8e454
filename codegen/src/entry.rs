//! The two macros' entry points: `include_model!` (the path resolved like
//! `include_str!`, the file read with its size checked) and `inline_model!`.

use crate::expand::expand;
use crate::input::{Invocation, MacroInput, Source};
use crate::message::{compile_error, error_message};
use proc_macro2::TokenStream;
use std::path::{Path, PathBuf};

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
}
