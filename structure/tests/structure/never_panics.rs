//! The parser and the compiler never panic: random text, random bytes and
//! mutations of the example models (deleted, inserted, duplicated and
//! replaced characters and tokens) either compile or yield at least one error
//! located inside the source. `PROPTEST_CASES` sets the number of cases (CI:
//! 2000); the default keeps `cargo test` quick in debug builds.

use leeway_structure::grammar::{RenderStyle, render};
use leeway_structure::{CompileOptions, compile, render as structure};
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
        &CompileOptions {
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
    // No flood: at most 50 diagnostics, each line cut to a window.
    prop_assert!(text.len() < 256 * 1024, "{} bytes rendered", text.len());
    Ok(())
}

/// [`check`] on a thread with a 256 KiB stack and a time bound: recursion
/// proportional to the input aborts, a hang fails.
fn check_small_stack(source: String, aggregate: bool) -> Result<(), TestCaseError> {
    let handle = std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(move || {
            let start = std::time::Instant::now();
            let r = check(&source, aggregate);
            (r, start.elapsed())
        })
        .map_err(|e| TestCaseError::fail(format!("spawn: {e}")))?;
    let (r, took) = handle
        .join()
        .map_err(|_| TestCaseError::fail("the compiler panicked"))?;
    prop_assert!(took < std::time::Duration::from_secs(5), "took {took:?}");
    r
}

/// One operand or operator piece of a long expression.
fn piece() -> impl Strategy<Value = &'static str> {
    prop::sample::select(vec![
        "*1", "*u", "+X*u", "-Y*v", "/2", "*(u+v)", "*|u|", "*-", "*- -", "+(", ")", "*|(", "|)",
        "*1e-300", "*9e307", "*0.5", "+1", "*X", "*((u))",
    ])
}

/// Long expressions around the operand limit, with signs, parentheses and moduli.
fn long_expression() -> impl Strategy<Value = String> {
    (prop::collection::vec(piece(), 0..200), 1usize..8).prop_map(|(pieces, repeat)| {
        let body: String = pieces.concat().repeat(repeat);
        format!("model M {{\n state u, v\n der u = X*u{body}\n der v = Y*v\n}}\n")
    })
}

/// Wide models: many states, each with a few terms, some with a medium.
fn wide_model() -> impl Strategy<Value = String> {
    (1usize..400, any::<bool>(), 0usize..4).prop_map(|(n, medium, shape)| {
        let mut s = String::from("model W {\n state ");
        s.push_str(&(0..n).map(|i| format!("x{i}")).collect::<Vec<_>>().join(", "));
        s.push_str("\n input t\n");
        if medium && n >= 2 {
            s.push_str(" heading psi integrates x1\n disturbance c unmeasured earth(north, east)\n w = relative(c)\n");
        }
        for i in 0..n {
            let term = match (shape + i) % 4 {
                0 => format!("A{i}*x{i}"),
                1 => format!("A{i}*x{i} + B{i}*x{i}*|x{i}|"),
                2 => format!("A{i}*x{i} + K{i}*t"),
                _ => format!("A{i}*x{i} + 1.5e-3*C{i}*x{i}*x0"),
            };
            let term = if medium && i < 2 && n >= 2 { format!("{term} + D{i}*w.x{i}") } else { term };
            s.push_str(&format!(" der x{i} = {term}\n"));
        }
        s.push_str("}\n");
        s
    })
}

/// Number literals: long mantissas, huge and tiny exponents, in equations and `nominal`.
fn literal() -> impl Strategy<Value = String> {
    (
        "[0-9]{0,60}",
        any::<bool>(),
        "[0-9]{0,60}",
        prop::option::of(any::<i64>()),
        any::<bool>(),
    )
        .prop_map(|(int, dot, frac, exp, nominal)| {
            let mut lit = int;
            if dot || lit.is_empty() {
                lit.push('.');
                lit.push_str(&frac);
                if lit == "." {
                    lit.push('5');
                }
            }
            if let Some(e) = exp {
                lit.push_str(&format!(
                    "e{}",
                    e % 1000 * if e % 7 == 0 { 1 << 40 } else { 1 }
                ));
            }
            if nominal {
                format!("model M {{ state u der u = X*u nominal {{ X = -{lit} }} }}")
            } else {
                format!("model M {{ state u der u = {lit}*X*u*{lit} }}")
            }
        })
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
    fn long_expressions(source in long_expression()) {
        check_small_stack(source, false)?;
    }

    #[test]
    fn wide_models(source in wide_model()) {
        check_small_stack(source, false)?;
    }

    #[test]
    fn literals(source in literal()) {
        check_small_stack(source, false)?;
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
    let c = compile(&deep, &CompileOptions::default());
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
    let c = compile(&moduli, &CompileOptions::default());
    assert!(c.has_errors());
    let huge = "// padding\n".repeat(200_000);
    let c = compile(&huge, &CompileOptions::default());
    assert_eq!(
        c.diagnostics.first().map(|d| d.code.as_str()),
        Some("file-too-large")
    );
}
