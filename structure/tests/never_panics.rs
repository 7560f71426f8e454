//! The parser and the compiler never panic: random text, random bytes and
//! mutations of the example models (deleted, inserted, duplicated and
//! replaced characters and tokens) either compile or yield at least one error
//! located inside the source. `PROPTEST_CASES` sets the number of cases (CI:
//! 2000); the default keeps `cargo test` quick in debug builds.

use leeway_structure::grammar::{RenderStyle, render};
use leeway_structure::{Options, compile, render as structure};
use proptest::prelude::*;
use std::path::Path;

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(48)
}

/// The example models, valid and broken: the seeds of the mutations.
fn seeds() -> &'static [String] {
    static SEEDS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    SEEDS.get_or_init(|| models(true))
}

/// The valid example models only: mutations that keep them valid reach the
/// expansion and the identifiability analysis.
fn valid_seeds() -> &'static [String] {
    static SEEDS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    SEEDS.get_or_init(|| models(false))
}

fn models(with_broken: bool) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models");
    let mut out = Vec::new();
    let dirs = if with_broken {
        vec![root.clone(), root.join("broken")]
    } else {
        vec![root]
    };
    for dir in dirs {
        let mut paths: Vec<_> = std::fs::read_dir(&dir)
            .expect("models dir")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        paths.sort();
        for p in paths
            .into_iter()
            .filter(|p| p.extension().is_some_and(|e| e == "som"))
        {
            out.push(std::fs::read_to_string(&p).expect("read model"));
        }
    }
    out
}

/// Tokens of the language and its near misses, inserted by the mutations.
const TOKENS: &[&str] = &[
    "|",
    "(",
    ")",
    "*",
    "/",
    "+",
    "-",
    "=",
    ",",
    ";",
    "{",
    "}",
    "[",
    "]",
    ":",
    ".",
    "\"",
    "0",
    "1e999",
    "0.5",
    "-2",
    "der",
    "next",
    "state",
    "input",
    "step",
    "heading",
    "integrates",
    "axes(u, v)",
    "rotation",
    "disturbance",
    "measured",
    "unmeasured",
    "earth(a, b)",
    "body(u: c)",
    "relative",
    "nominal",
    "data",
    "model",
    "water.u",
    "|water.v|",
    "air.u",
    "psi",
    "north",
    "X",
    "u",
    "v",
    "r",
    "tau1",
    "//",
    "/*",
    "*/",
    "\n",
    "((",
    "||",
    "u*v*r",
    "water",
    "é",
    "\u{2028}",
    "\0",
    "heading h integrates u",
    "rotation { u = [a, b] }",
    "x = relative(current)",
];

#[derive(Clone, Debug)]
enum Mutation {
    Delete { at: u16, len: u8 },
    InsertChar { at: u16, c: char },
    InsertToken { at: u16, token: usize },
    Duplicate { at: u16, len: u8, to: u16 },
    ReplaceByte { at: u16, byte: u8 },
    SwapLines { a: u16, b: u16 },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<u16>(), 1u8..12).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<u16>(), any::<char>()).prop_map(|(at, c)| Mutation::InsertChar { at, c }),
        (any::<u16>(), 0..TOKENS.len()).prop_map(|(at, token)| Mutation::InsertToken { at, token }),
        (any::<u16>(), 1u8..40, any::<u16>()).prop_map(|(at, len, to)| Mutation::Duplicate {
            at,
            len,
            to
        }),
        (any::<u16>(), any::<u8>()).prop_map(|(at, byte)| Mutation::ReplaceByte { at, byte }),
        (any::<u16>(), any::<u16>()).prop_map(|(a, b)| Mutation::SwapLines { a, b }),
    ]
}

/// A byte offset on a character boundary, `at` scaled to the text's length.
fn offset(text: &str, at: u16) -> usize {
    let mut i = (text.len() * at as usize) / (u16::MAX as usize + 1);
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &mut String, m: &Mutation) {
    match m {
        Mutation::Delete { at, len } => {
            let start = offset(text, *at);
            let end = text[start..]
                .char_indices()
                .nth(*len as usize)
                .map_or(text.len(), |(i, _)| start + i);
            text.replace_range(start..end, "");
        }
        Mutation::InsertChar { at, c } => {
            let i = offset(text, *at);
            text.insert(i, *c);
        }
        Mutation::InsertToken { at, token } => {
            let i = offset(text, *at);
            text.insert_str(i, TOKENS[*token]);
        }
        Mutation::Duplicate { at, len, to } => {
            let start = offset(text, *at);
            let end = text[start..]
                .char_indices()
                .nth(*len as usize)
                .map_or(text.len(), |(i, _)| start + i);
            let piece = text[start..end].to_string();
            let to = offset(text, *to);
            text.insert_str(to, &piece);
        }
        Mutation::ReplaceByte { at, byte } => {
            let i = offset(text, *at);
            let mut bytes = std::mem::take(text).into_bytes();
            if i < bytes.len() {
                bytes[i] = *byte;
            }
            *text = String::from_utf8_lossy(&bytes).into_owned();
        }
        Mutation::SwapLines { a, b } => {
            let mut lines: Vec<&str> = text.split('\n').collect();
            let n = lines.len();
            lines.swap(*a as usize % n, *b as usize % n);
            *text = lines.join("\n");
        }
    }
}

/// Compiles and checks the contract: no panic; every label inside the source
/// on character boundaries; no IR without an error located in the source;
/// an IR only with no errors or only unidentifiable combinations; rendering
/// works on whatever came out.
fn check(source: &str, aggregate: bool) -> Result<(), TestCaseError> {
    let c = compile(
        source,
        &Options {
            aggregate,
            patterns: None,
            centring: None,
        },
    );
    for d in &c.diagnostics {
        for l in &d.labels {
            prop_assert!(
                source.get(l.span.start..l.span.end).is_some(),
                "{}: label {:?} outside the source or off a character boundary",
                d.code,
                l.span
            );
        }
    }
    match &c.ir {
        None => prop_assert!(
            c.diagnostics
                .iter()
                .any(|d| d.is_error() && d.primary_span().is_some()),
            "rejected without a located error: {:?}",
            c.diagnostics
        ),
        Some(ir) => {
            prop_assert!(
                !c.has_errors() || c.only_unidentifiable(),
                "{:?}",
                c.diagnostics
            );
            prop_assert!(!structure::render(ir).is_empty());
        }
    }
    let text = render(&c.diagnostics, "model.som", source, RenderStyle::Plain);
    prop_assert_eq!(text.is_empty(), c.diagnostics.is_empty());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn random_text(text in "[ -~\n\t]{0,400}") {
        check(&text, false)?;
    }

    #[test]
    fn random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        check(&String::from_utf8_lossy(&bytes), false)?;
    }

    #[test]
    fn token_soup(tokens in proptest::collection::vec(0..TOKENS.len(), 0..80), prefix in any::<bool>()) {
        let body: Vec<&str> = tokens.iter().map(|t| TOKENS[*t]).collect();
        let text = if prefix { format!("model M {{ {} }}", body.join(" ")) } else { body.join(" ") };
        check(&text, false)?;
    }

    #[test]
    fn mutated_models(
        seed in any::<prop::sample::Index>(),
        mutations in proptest::collection::vec(mutation(), 1..6),
        aggregate in any::<bool>(),
    ) {
        let mut text = seed.get(seeds()).clone();
        for m in &mutations {
            apply(&mut text, m);
        }
        check(&text, aggregate)?;
    }

    #[test]
    fn mutated_valid_models(
        seed in any::<prop::sample::Index>(),
        mutation in mutation(),
        aggregate in any::<bool>(),
    ) {
        let mut text = seed.get(valid_seeds()).clone();
        apply(&mut text, &mutation);
        check(&text, aggregate)?;
    }
}

#[test]
fn deep_nesting_and_huge_input_are_rejected_not_overflowed() {
    let deep = format!(
        "model M {{ state u der u = X*{}u{} }}",
        "(".repeat(100_000),
        ")".repeat(100_000)
    );
    let c = compile(&deep, &Options::default());
    assert!(
        c.diagnostics.iter().any(|d| d.code == "nesting-too-deep"),
        "{:?}",
        c.diagnostics
    );
    let moduli = format!(
        "model M {{ state u der u = X*u*{}u{} }}",
        "|".repeat(50_000),
        "|".repeat(50_000)
    );
    let c = compile(&moduli, &Options::default());
    assert!(c.has_errors());
    let huge = "// padding\n".repeat(200_000);
    let c = compile(&huge, &Options::default());
    assert_eq!(
        c.diagnostics.first().map(|d| d.code.as_str()),
        Some("file-too-large")
    );
}
