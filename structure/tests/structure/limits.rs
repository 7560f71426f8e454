//! The language's limits (docs/language.md, Diagnostics): each oversized or
//! extreme input gives one located error, quickly, without exhausting the stack.
//! Every compile runs on a thread with a small stack, so that recursion
//! proportional to the input aborts the test instead of passing by luck on a
//! large main stack, and under a time bound, so that a hang fails it.

use leeway_structure::grammar::{Diagnostic, MAX_LISTED, MAX_OPERANDS, line_col};
use leeway_structure::{CompileOptions, compile};
use std::time::{Duration, Instant};

/// Compiles on a 256 KiB stack (the main thread has 8 MiB, a test thread
/// 2 MiB) and returns the diagnostics, the IR's presence and the time taken.
fn compile_small(source: String) -> (bool, Vec<Diagnostic>, Duration) {
    let handle = std::thread::Builder::new()
        .stack_size(
            std::env::var("STACK_KB")
                .ok()
                .and_then(|v| v.parse::<usize>().ok())
                .unwrap_or(512)
                * 1024,
        )
        .spawn(move || {
            let start = Instant::now();
            let c = compile(&source, &CompileOptions::default());
            let ir = c.ir.is_some();
            (ir, c.diagnostics, start.elapsed())
        })
        .unwrap_or_else(|e| panic!("cannot spawn: {e}"));
    handle
        .join()
        .unwrap_or_else(|_| panic!("the compiler panicked"))
}

/// Exactly one error, with `code` and `message`, at `line:col`.
fn one_error(source: &str, code: &str, message: &str, at: (usize, usize)) {
    let (ir, d, took) = compile_small(source.to_string());
    assert!(!ir);
    assert_eq!(d.len(), 1, "{d:#?}");
    assert_eq!((d[0].code.as_str(), d[0].message.as_str()), (code, message));
    let span = d[0].primary_span().unwrap_or_default();
    assert_eq!(line_col(source, span.start), at);
    assert!(took < Duration::from_secs(2), "took {took:?}");
}

#[test]
fn long_operand_chains_are_one_error() {
    // `X*u` then 7,200 `*1` (14 KB) overflowed the stack in `sum_of_products`;
    // 40,000 operands overflowed in `Expr::clone`.
    for (op, n) in [("*1", 7200), ("+1", 7200), ("/1", 7200), ("*1", 40_000)] {
        let src = format!("model M {{\n state u\n der u = X*u{}\n}}\n", op.repeat(n));
        one_error(
            &src,
            "expression-too-large",
            "this expression has more than 1000 operands",
            (3, 10),
        );
    }
    // 7,200 unary minus overflowed in `build_expr`.
    let src = format!(
        "model M {{\n state u\n der u = X*{}u\n}}\n",
        "-".repeat(7200)
    );
    one_error(
        &src,
        "expression-too-large",
        "more than 8 signs in a row",
        (3, 12),
    );
}

#[test]
fn the_longest_accepted_expressions_compile_on_a_small_stack() {
    // MAX_OPERANDS operands in one product and in one sum: the tree is as deep
    // as the guard allows, and every pass walks it.
    let product = format!(
        "model M {{ state u der u = X*u{} }}",
        "*1".repeat(MAX_OPERANDS - 2)
    );
    let (ir, d, _) = compile_small(product);
    assert!(ir, "{d:#?}");
    let sum = format!(
        "model M {{ state u der u = X*u{} }}",
        "+X*u".repeat((MAX_OPERANDS - 2) / 2)
    );
    let (ir, d, _) = compile_small(sum);
    assert!(ir, "{d:#?}");
    let signs = "model M { state u der u = X*- - - - - - - -u }".to_string();
    let (ir, d, _) = compile_small(signs);
    assert!(ir, "{d:#?}");
}

#[test]
fn literals_out_of_range_are_one_error_each_and_quick() {
    // `1e-9223372036854775808` wrapped `scale.abs()` and then ran forever.
    let src = "model M {\n state u\n der u = 1e-9223372036854775808*X*u\n}\n";
    one_error(
        src,
        "invalid-number",
        "`1e-9223372036854775808` is out of range: a non-zero number must lie between 1e-307 and 1e308 in magnitude",
        (3, 10),
    );
    let src = "model M {\n state u\n der u = X*u\n nominal { X = 1e-9223372036854775808 }\n}\n";
    let (_, d, took) = compile_small(src.to_string());
    assert_eq!(d.len(), 1, "{d:#?}");
    assert_eq!(d[0].code, "invalid-number");
    assert!(took < Duration::from_secs(2));
    // `1e399` and `1e-399` passed `check` and became inf and 0 at evaluation.
    for lit in ["1e399", "1e-399"] {
        let src = format!("model M {{\n state u\n der u = {lit}*X*u\n}}\n");
        let (_, d, _) = compile_small(src);
        assert_eq!(d.len(), 1, "{d:#?}");
        assert!(d[0].message.contains("out of range"));
    }
    // 400,000 digits took 30 s (a quadratic gcd); now one quick error with a short message.
    let src = format!(
        "model M {{\n state u\n der u = {}*X*u\n}}\n",
        "7".repeat(400_000)
    );
    let (_, d, took) = compile_small(src);
    assert_eq!(d.len(), 1, "{d:#?}");
    assert!(
        d[0].message
            .ends_with("at most 40 significant digits are accepted")
            || d[0].message.contains("at most 40 are accepted")
    );
    assert!(d[0].message.len() < 120, "{}", d[0].message);
    assert!(took < Duration::from_secs(2), "took {took:?}");
    // A product of in-range numbers that leaves the f64 range.
    let src = format!(
        "model M {{\n state u\n der u = X*u{}\n}}\n",
        "*1e300".repeat(3)
    );
    let (_, d, _) = compile_small(src);
    assert_eq!(d.len(), 1, "{d:#?}");
    assert_eq!(d[0].code, "invalid-number");
}

/// Messages stay short: one `unidentifiable-combination` of 499 parameters
/// must not be a 96 KB message. Every list in a message, note or help names at most
/// `MAX_LISTED` items and counts the rest; the report's structured fields
/// keep every name.
#[test]
fn lists_in_messages_are_capped() {
    let terms: Vec<String> = (0..499).map(|i| format!("P{i}*u")).collect();
    let src = format!(
        "model W {{\n state u\n input t\n der u = B*t + {}\n}}\n",
        terms.join(" + ")
    );
    let (ir, d, _) = compile_small(src.clone());
    assert!(ir);
    let errors: Vec<&Diagnostic> = d.iter().filter(|d| d.is_error()).collect();
    assert_eq!(errors.len(), 1, "{d:#?}");
    let e = errors[0];
    assert_eq!(e.code, "unidentifiable-combination");
    assert_eq!(
        e.message,
        "θ is not identifiable: `P0`, `P1`, `P2`, `P3`, `P4`, `P5`, `P6`, `P7` and 491 more enter only as P0 + P1 + P2 + P3 + P4 + P5 + P6 + P7 + … (491 more terms)"
    );
    assert!(e.labels.len() <= MAX_LISTED, "{}", e.labels.len());
    for n in &e.notes {
        assert!(n.len() < 300, "{n}");
    }
    assert!(
        e.notes.iter().any(|n| n.contains("u carries no modulus")),
        "{:?}",
        e.notes
    );
    // The structured report keeps the whole group.
    let c = compile(&src, &CompileOptions::default());
    let r = &c.ir.as_ref().expect("an IR").report;
    assert_eq!(r.unidentifiable[0].parameters.len(), 499);
    // A nominal entry that is not a parameter lists at most 8 in its help.
    let src = format!(
        "model W {{\n state u\n input t\n der u = B*t + {}\n nominal {{ Q = 1 }}\n}}\n",
        terms[..99].join(" + ")
    );
    let c = compile(&src, &CompileOptions::default());
    let unknown = c
        .diagnostics
        .iter()
        .find(|d| d.code == "unknown-parameter")
        .expect("unknown-parameter");
    assert!(
        unknown
            .help
            .as_deref()
            .unwrap_or_default()
            .ends_with("P6, … (92 more)"),
        "{:?}",
        unknown.help
    );
}

/// 2,000 independent states each need both signs of their modulus: the
/// `required-experiments` note holds one pair of notes per group for at
/// most `MAX_LISTED` groups, then a count, and names the patterns with at
/// most `MAX_LISTED` signs each (it held 4,000 notes and every sign).
#[test]
fn many_groups_give_a_short_note() {
    let n = 2000;
    let states: Vec<String> = (0..n).map(|i| format!("x{i}")).collect();
    let mut src = format!("model S {{\n state {}\n", states.join(", "));
    for i in 0..n {
        src += &format!(" der x{i} = A{i}*x{i} + D{i}*|x{i}|\n");
    }
    src += "}\n";
    let (ir, d, _) = compile_small(src);
    assert!(ir, "{d:#?}");
    let note = d
        .iter()
        .find(|d| d.code == "required-experiments")
        .expect("required-experiments");
    assert!(note.message.len() < 400, "{}", note.message);
    assert!(
        note.message.contains("… and 1992 more, all +}"),
        "{}",
        note.message
    );
    assert_eq!(note.notes.len(), 2 * MAX_LISTED + 1);
    assert!(
        note.notes[2 * MAX_LISTED].starts_with("… and 1992 more groups like these"),
        "{}",
        note.notes[2 * MAX_LISTED]
    );
}
