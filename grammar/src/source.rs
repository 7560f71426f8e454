//! Model files as bytes → text. No IO: the caller reads at most
//! [`MAX_SOURCE_BYTES`]` + 1` bytes (checking the file's size first, so a huge
//! file is never read whole) and hands them here; a file that is too large or
//! not UTF-8 gives one located diagnostic and the text to render it against.

use crate::ast::Span;
use crate::diagnostic::data::Diagnostic;

/// Largest model file accepted, in bytes.
pub const MAX_SOURCE_BYTES: usize = 1 << 20;

/// A model file refused before parsing: the diagnostic, and the text it
/// points into (invalid bytes replaced by `�`, which the caret marks).
#[derive(Clone, Debug)]
pub struct Refused {
    /// What to render the diagnostic against.
    pub text: String,
    /// One error: `file-too-large` or `not-utf8`.
    pub diagnostic: Diagnostic,
}

/// The `file-too-large` error for a file of `size` bytes (or more).
pub fn too_large(size: u64) -> Diagnostic {
    Diagnostic::error(
        "file-too-large",
        format!("the model file is {size} bytes; at most {MAX_SOURCE_BYTES} are accepted"),
    )
    .with_primary(Span::new(0, 0), "")
    .with_help("a model file holds one craft's equations; pass the model, not a data file, and split generated text")
}

/// The text of a model file read as bytes (at most [`MAX_SOURCE_BYTES`] are
/// accepted), or why not: too large, or not UTF-8 — located at the first
/// invalid byte.
pub fn decode(bytes: Vec<u8>) -> Result<String, Box<Refused>> {
    if bytes.len() > MAX_SOURCE_BYTES {
        let diagnostic = Diagnostic::error(
            "file-too-large",
            format!("the model file holds more than {MAX_SOURCE_BYTES} bytes"),
        )
        .with_primary(Span::new(0, 0), "")
        .with_help("a model file holds one craft's equations; pass the model, not a data file, and split generated text");
        return Err(Box::new(Refused {
            text: String::new(),
            diagnostic,
        }));
    }
    match String::from_utf8(bytes) {
        Ok(text) => Ok(text),
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let bad = e.as_bytes().get(at).copied().unwrap_or(0);
            // The valid prefix is kept as it is, so `at` is also where the
            // first `�` starts in the lossy text.
            let text = String::from_utf8_lossy(e.as_bytes()).into_owned();
            let width = '\u{fffd}'.len_utf8();
            let diagnostic = Diagnostic::error(
                "not-utf8",
                format!("the model file is not UTF-8 text: byte 0x{bad:02x} cannot start or continue a character"),
            )
            .with_primary(Span::new(at, at + width), "not UTF-8")
            .with_help("save the file as UTF-8 (names and numbers are ASCII; comments may hold any UTF-8 text)");
            Err(Box::new(Refused { text, diagnostic }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnostic::location::line_col;
    use crate::diagnostic::render::{RenderStyle, render};

    #[test]
    fn invalid_utf8_is_located_at_its_first_byte() {
        let bytes = b"model M {\n    state u // caf\xe9\n    der u = X*u\n}\n".to_vec();
        let r = decode(bytes).err().unwrap_or_else(|| panic!("accepted"));
        let span = r.diagnostic.primary_span().unwrap_or_default();
        assert_eq!(line_col(&r.text, span.start), (2, 19));
        let text = render(&[r.diagnostic], "m.som", &r.text, RenderStyle::Plain);
        assert_eq!(
            text,
            "error[not-utf8]: the model file is not UTF-8 text: byte 0xe9 cannot start or continue a character\n  ┌─ m.som:2:19\n  │\n2 │     state u // caf\u{fffd}\n  │                   ^ not UTF-8\n  │\n  = help: save the file as UTF-8 (names and numbers are ASCII; comments may hold any UTF-8 text)\n\n"
        );
        assert_eq!(
            decode(b"model M {}".to_vec()).ok().as_deref(),
            Some("model M {}")
        );
        let big = decode(vec![b' '; MAX_SOURCE_BYTES + 1])
            .err()
            .map(|r| r.diagnostic.code);
        assert_eq!(big.as_deref(), Some("file-too-large"));
    }
}
