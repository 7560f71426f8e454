//! The deliberately broken models of `examples/models/broken/`, one per
//! diagnostic class. Each file states what it expects inline, under the
//! offending line (carets under the primary span):
//!
//! ```text
//!     der u = X_uu*water.u^2 + X_t*tau
//! //                      ^ error[syntax]: expected a declaration or an operator, found `^`
//! ```
//!
//! The test compiles each file and checks that exactly the annotated errors
//! and warnings are reported, at those places, with those messages; the full
//! rendered diagnostics are snapshotted. A last test checks that every error
//! code the compiler can emit has a broken model here.

use leeway_structure::grammar::{Diagnostic, RenderStyle, Severity, line_col, render};
use leeway_structure::{CompileOptions, compile};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// One expectation: severity, code, message, line, and the column range
/// `[start, end)` of the carets (1-based, in characters).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Expected {
    line: usize,
    start: usize,
    end: usize,
    severity: String,
    code: String,
    message: String,
}

/// Parses an annotation line `//   ^^^ error[code]: message`.
fn annotation(line: &str) -> Option<(usize, usize, String, String, String)> {
    let rest = line.strip_prefix("//")?;
    let carets_at = rest.find('^')?;
    if !rest[..carets_at].chars().all(|c| c == ' ') {
        return None;
    }
    let after = &rest[carets_at..];
    let width = after.chars().take_while(|c| *c == '^').count();
    let tail = after[width..].strip_prefix(' ')?;
    let (severity, tail) = tail.split_once('[')?;
    let (code, tail) = tail.split_once(']')?;
    let message = tail.strip_prefix(": ")?;
    // Columns count characters; `//` and the spaces before the carets are ASCII.
    let start = 2 + carets_at + 1;
    Some((
        start,
        start + width,
        severity.to_string(),
        code.to_string(),
        message.to_string(),
    ))
}

fn expectations(source: &str) -> Vec<Expected> {
    let mut out = Vec::new();
    let mut target = 0;
    for (i, line) in source.lines().enumerate() {
        match annotation(line) {
            Some((start, end, severity, code, message)) => {
                assert!(
                    target > 0,
                    "annotation on line {} has no line above it",
                    i + 1
                );
                out.push(Expected {
                    line: target,
                    start,
                    end,
                    severity,
                    code,
                    message,
                });
            }
            None => target = i + 1,
        }
    }
    out.sort();
    out
}

/// What the compiler reported, in the same shape. A span running past its
/// first line is drawn to the end of that line; an empty span as one caret.
fn reported(source: &str, d: &Diagnostic) -> Expected {
    let span = d
        .primary_span()
        .unwrap_or_else(|| panic!("{} has no location: {d:?}", d.code));
    assert!(
        span.start <= span.end && span.end <= source.len(),
        "{}: span {span:?} outside the source",
        d.code
    );
    let (line, start) = line_col(source, span.start);
    let (end_line, end_col) = line_col(source, span.end);
    let end = if end_line == line {
        end_col.max(start + 1)
    } else {
        let text = source.lines().nth(line - 1).unwrap_or_default();
        text.trim_end().chars().count() + 1
    };
    let severity = match d.severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Note => "note",
    };
    Expected {
        line,
        start,
        end,
        severity: severity.into(),
        code: d.code.clone(),
        message: d.message.clone(),
    }
}

fn broken_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models/broken")
}

fn check(path: &Path) -> String {
    let source =
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let name = format!(
        "broken/{}",
        path.file_name().unwrap_or_default().to_string_lossy()
    );
    let expected = expectations(&source);
    assert!(
        !expected.is_empty(),
        "{name}: a broken model states what it expects"
    );
    let c = compile(&source, &CompileOptions::default());
    let mut actual: Vec<Expected> = c
        .diagnostics
        .iter()
        .filter(|d| d.severity != Severity::Note)
        .map(|d| reported(&source, d))
        .collect();
    actual.sort();
    assert_eq!(
        actual, expected,
        "{name}: reported (left) vs annotated (right)"
    );
    if c.has_errors() {
        assert!(
            c.ir.is_none() || c.only_unidentifiable(),
            "{name}: an invalid model yields no IR"
        );
    }
    render(&c.diagnostics, &name, &source, RenderStyle::Plain)
}

#[test]
fn broken_models_report_what_they_annotate() {
    insta::glob!("../../../examples/models/broken", "*.som", |path| {
        insta::assert_snapshot!(check(path));
    });
}

/// Every `Diagnostic::error("code", ..)` in the library code of grammar/ and
/// structure/ (unit tests excluded).
fn error_codes_in_source() -> BTreeSet<String> {
    codes_in_source(&["Diagnostic::error("])
}

/// Every `.rs` file under `dir`, its subfolders included, in a fixed order.
fn rust_files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(d) = pending.pop() {
        for entry in std::fs::read_dir(&d).expect("source dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                pending.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The string literals right after any of `calls` in the library code.
fn codes_in_source(calls: &[&str]) -> BTreeSet<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut codes = BTreeSet::new();
    for dir in ["grammar/src", "structure/src"] {
        for path in rust_files(&root.join(dir)) {
            let text = std::fs::read_to_string(&path).expect("read source");
            if text.contains("#![cfg(test)]") {
                continue; // a module of test helpers
            }
            let library = text.split("#[cfg(test)]").next().unwrap_or_default();
            for call in calls {
                for (i, _) in library.match_indices(call) {
                    let rest = library[i + call.len()..].trim_start();
                    if let Some(lit) = rest.strip_prefix('"')
                        && let Some(end) = lit.find('"')
                    {
                        codes.insert(lit[..end].to_string());
                    }
                }
            }
        }
    }
    codes
}

#[test]
fn every_error_code_has_a_broken_model() {
    let codes = error_codes_in_source();
    assert!(codes.len() > 30, "found only {codes:?}");
    let mut covered = BTreeSet::new();
    for entry in std::fs::read_dir(broken_dir()).expect("broken dir") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "som") {
            let source = std::fs::read_to_string(&path).expect("read");
            covered.extend(expectations(&source).into_iter().map(|e| e.code));
        }
    }
    // A model over 1 MiB does not belong in the repository; grammar's unit
    // tests cover `file-too-large`; a file that is not UTF-8 (`not-utf8`)
    // cannot carry an inline expectation.
    let elsewhere = BTreeSet::from(["file-too-large".to_string(), "not-utf8".to_string()]);
    let missing: Vec<&String> = codes
        .iter()
        .filter(|c| !covered.contains(*c) && !elsewhere.contains(*c))
        .collect();
    assert!(
        missing.is_empty(),
        "error codes without a broken model: {missing:?}"
    );
}

#[test]
fn annotations_parse() {
    let src =
        "model M {\n    der u = X*u^2\n//             ^ error[syntax]: expected x, found `^`\n}\n";
    let e = expectations(src);
    assert_eq!(
        e,
        vec![Expected {
            line: 2,
            start: 16,
            end: 17,
            severity: "error".into(),
            code: "syntax".into(),
            message: "expected x, found `^`".into()
        }]
    );
    // The caret sits under the `^` of `u^2`, which `line_col` places at column 16 too.
    assert_eq!(line_col(src, src.find("^2").unwrap_or(0)), (2, 16));
    // Prose comments and code are not annotations.
    assert_eq!(annotation("// Powers: u^2 is written u*u"), None);
    assert_eq!(annotation("    der u = X*u"), None);
}

/// docs/language.md has a `#### \`code\`` section for every diagnostic the
/// compiler (and the CLI) can emit.
#[test]
fn every_diagnostic_code_is_documented() {
    let docs_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/language.md");
    let docs = std::fs::read_to_string(&docs_path).expect("docs/language.md");
    let documented: BTreeSet<String> = docs
        .lines()
        .filter_map(|l| l.strip_prefix("#### `"))
        .filter_map(|l| l.split('`').next())
        .map(str::to_string)
        .collect();
    let mut codes = codes_in_source(&[
        "Diagnostic::error(",
        "Diagnostic::warning(",
        "Diagnostic::note(",
    ]);
    codes.extend(["io".to_string(), "invalid-pattern".to_string()]);
    assert!(codes.len() > 40, "{codes:?}");
    let missing: Vec<&String> = codes.difference(&documented).collect();
    assert!(
        missing.is_empty(),
        "codes without a section in docs/language.md: {missing:?}"
    );
    let stale: Vec<&String> = documented.difference(&codes).collect();
    assert!(
        stale.is_empty(),
        "docs/language.md documents codes nobody emits: {stale:?}"
    );
}
