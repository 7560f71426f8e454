//! Time per request on the largest example and on a generated 500-line
//! model (figures for the closing note; no timed assertion):
//! `cargo test -p leeway-lsp --test latency -- --ignored --nocapture` (the
//! test profile: opt-level 1).

mod support;

use serde_json::json;
use std::fmt::Write;
use std::path::Path;
use std::time::{Duration, Instant};
use support::{Client, URI};

/// A model of `n` decoupled surge-like states, two lines per equation,
/// with a current: about 2n + 20 lines.
fn generated(n: usize) -> String {
    let mut s = String::from("// generated for timing\nmodel Big {\n    step 0.1\n");
    let states: Vec<String> = (0..n).map(|i| format!("x{i}")).collect();
    let _ = writeln!(s, "    state {}", states.join(", "));
    let _ = writeln!(s, "    input t");
    let _ = writeln!(
        s,
        "    disturbance current unmeasured body({})",
        states
            .iter()
            .map(|x| format!("{x}: c{x}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(s, "    water = relative(current)");
    for i in 0..n {
        let _ = writeln!(
            s,
            "    der x{i} = A{i}*water.x{i} + B{i}*water.x{i}*|water.x{i}|"
        );
        let _ = writeln!(s, "          + C{i}*t");
    }
    s.push_str("}\n");
    s
}

fn time(c: &mut Client, method: &str, params: serde_json::Value, runs: u32) -> Duration {
    let t = Instant::now();
    for _ in 0..runs {
        let _ = c.request(method, params.clone());
    }
    t.elapsed() / runs
}

fn measure(name: &str, text: &str) {
    let mut c = Client::start();
    let t = Instant::now();
    c.open(text);
    let _ = c.diagnostics(1);
    let open = t.elapsed();
    // A keystroke: one character typed at the end of line 3, then its diagnostics.
    let t = Instant::now();
    let runs = 20;
    for v in 0..runs {
        let ch = if v % 2 == 0 { " " } else { "" };
        let range = json!({"start": {"line": 2, "character": 4}, "end": {"line": 2, "character": 4 + (v % 2)}});
        c.notify("textDocument/didChange", json!({"textDocument": {"uri": URI, "version": v + 2}, "contentChanges": [{"range": range, "text": ch}]}));
        let _ = c.diagnostics(v as i32 + 2);
    }
    let keystroke = t.elapsed() / runs;
    let line = text.lines().position(|l| l.contains("der ")).unwrap_or(0) as u32;
    let at = c.at(line, 12);
    let hover = time(&mut c, "textDocument/hover", at.clone(), 20);
    let definition = time(&mut c, "textDocument/definition", at.clone(), 20);
    let completion = time(&mut c, "textDocument/completion", at, 20);
    // On the line's first parameter (no `nominal` entry in the generated
    // model: the refactors are offered, each compiled before it is).
    let on = text.lines().nth(line as usize).unwrap_or("");
    let col = on.find('=').map_or(0, |i| i + 2) as u32;
    let range =
        json!({"start": {"line": line, "character": col}, "end": {"line": line, "character": col}});
    let actions = time(
        &mut c,
        "textDocument/codeAction",
        json!({"textDocument": {"uri": URI}, "range": range, "context": {"diagnostics": []}}),
        5,
    );
    let formatting = time(
        &mut c,
        "textDocument/formatting",
        json!({"textDocument": {"uri": URI}, "options": {"tabSize": 4, "insertSpaces": true}}),
        20,
    );
    println!(
        "{name} ({} lines): open→diagnostics {open:?}, keystroke→diagnostics {keystroke:?}, hover {hover:?}, definition {definition:?}, completion {completion:?}, code actions {actions:?}, formatting {formatting:?}",
        text.lines().count()
    );
    c.stop();
}

#[test]
#[ignore = "figures for the closing note, run by hand"]
fn latency_per_request() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models");
    let largest = std::fs::read_dir(&dir)
        .expect("examples")
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "som"))
        .max_by_key(|e| e.metadata().map(|m| m.len()).unwrap_or(0))
        .expect("an example");
    let text = std::fs::read_to_string(largest.path()).expect("readable");
    measure(&largest.file_name().to_string_lossy(), &text);
    measure("generated", &generated(240));
}
