//! Random edits through `didChange` on the example models: insertions of
//! language fragments and non-ASCII text, deletions, truncations, ranges
//! past line ends and inside surrogate pairs; after each, a request. The
//! server must answer every request, publish the diagnostics of the text
//! the client holds, and never panic. A cheap seeded run here; the larger
//! campaign with its timings is `fuzz_campaign` (ignored, run by hand).

mod support;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};
use std::collections::BTreeSet;
use std::path::Path;
use std::time::{Duration, Instant};
use support::{Client, URI, utf16_position};

const PIECES: &[&str] = &[
    " ",
    "\n",
    "// ψ\n",
    "/* 😀 */",
    "/*",
    "*/",
    "+",
    "-",
    "*",
    "/",
    "|",
    "(",
    ")",
    "x",
    "X_u",
    "water.u",
    ",",
    "0.5",
    "1e-3",
    "{",
    "}",
    "=",
    "der v = ",
    "nominal { A = 1 }",
    ";",
    "\"",
    "model",
    "state",
    "é",
    "😀",
    "\r\n",
    "\t",
];

/// The client's copy of an edit, with its own reading of positions: a
/// column past the line's end is its end, one inside a surrogate pair
/// lands before the character.
fn offset(text: &str, line: u32, character: u32) -> usize {
    let mut start = 0;
    for _ in 0..line {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => return text.len(),
        }
    }
    let end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let mut units = 0;
    for (i, c) in text[start..end].char_indices() {
        units += c.len_utf16() as u32;
        if units > character {
            return start + i;
        }
    }
    end
}

fn examples() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models");
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("examples")
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "som"))
        .filter_map(|e| std::fs::read_to_string(e.path()).ok())
        .collect();
    v.sort();
    v
}

/// A random position: mostly inside the text, sometimes past a line's end
/// or the last line, sometimes inside a character's UTF-16 units.
fn position(rng: &mut ChaCha8Rng, text: &str) -> (u32, u32) {
    let lines = text.matches('\n').count() as u32 + 1;
    let mut byte = rng.random_range(0..=text.len());
    while !text.is_char_boundary(byte) {
        byte -= 1;
    }
    let (l, c) = utf16_position(text, byte);
    match rng.random_range(0..10) {
        0 => (l, c + rng.random_range(1..200)),
        1 => (lines + rng.random_range(0..3), rng.random_range(0..5)),
        2 => (l, c + 1), // inside a surrogate pair when one starts here
        _ => (l, c),
    }
}

/// Statistics of one campaign: how many edits and requests, the slowest
/// answer, the parse failures seen.
struct Figures {
    edits: usize,
    requests: usize,
    slowest: Duration,
    total: Duration,
    unparsed: usize,
    formatted: usize,
    /// Definitions and references found on a text that does not parse
    /// (answered from the last version that parsed).
    stale_found: usize,
}

fn campaign(seed: u64, edits: usize) -> Figures {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let examples = examples();
    let mut figures = Figures {
        edits: 0,
        requests: 0,
        slowest: Duration::ZERO,
        total: Duration::ZERO,
        unparsed: 0,
        formatted: 0,
        stale_found: 0,
    };
    let mut c = Client::start();
    let mut text = examples[0].clone();
    c.open(&text);
    let _ = c.diagnostics(1);
    let mut version = 1;
    for n in 0..edits {
        if n % 8 == 7 {
            // Start again from an example: piled-up edits rarely parse.
            text = examples[rng.random_range(0..examples.len())].clone();
            version += 1;
            c.notify("textDocument/didChange", json!({"textDocument": {"uri": URI, "version": version}, "contentChanges": [{"text": text}]}));
        }
        let (a, b) = (position(&mut rng, &text), position(&mut rng, &text));
        let (start, end) = if a <= b { (a, b) } else { (b, a) };
        let new_text: String = match rng.random_range(0..4) {
            0 | 1 => PIECES[rng.random_range(0..PIECES.len())].to_string(),
            2 => String::new(),
            _ => text.chars().rev().take(rng.random_range(0..20)).collect(),
        };
        let (start, end) = if rng.random_range(0..20) == 0 {
            // Truncate: everything from a position on.
            (start, (u32::MAX, 0))
        } else {
            (start, end)
        };
        let from = offset(&text, start.0, start.1);
        let to = offset(&text, end.0, end.1).max(from);
        text.replace_range(from..to, &new_text);
        version += 1;
        c.notify(
            "textDocument/didChange",
            json!({"textDocument": {"uri": URI, "version": version},
                   "contentChanges": [{"range": {"start": {"line": start.0, "character": start.1},
                                                 "end": {"line": end.0, "character": end.1}},
                                       "text": new_text}]}),
        );
        figures.edits += 1;
        let (l, ch) = position(&mut rng, &text);
        let method = [
            "textDocument/hover",
            "textDocument/definition",
            "textDocument/completion",
            "textDocument/formatting",
            "textDocument/documentSymbol",
            "textDocument/references",
            "textDocument/codeAction",
        ][rng.random_range(0..7)];
        let mut params = c.at(l, ch);
        params["range"] =
            json!({"start": {"line": l, "character": ch}, "end": {"line": l, "character": ch}});
        params["context"] = json!({"diagnostics": []});
        params["options"] = json!({"tabSize": 4, "insertSpaces": true});
        if method == "textDocument/references" {
            params["context"] = json!({"includeDeclaration": true});
        }
        let t = Instant::now();
        let answer = c.try_request(method, params);
        let took = t.elapsed();
        figures.requests += 1;
        figures.total += took;
        figures.slowest = figures.slowest.max(took);
        assert!(answer.is_ok(), "{method} failed: {answer:?}");
        assert!(c.alive(), "the server stopped");
        if method == "textDocument/formatting" {
            match leeway_format::format(&text) {
                Ok(layout) => {
                    let edits = answer.clone().unwrap_or(Value::Null);
                    let got = edits
                        .get(0)
                        .and_then(|e| e["newText"].as_str())
                        .map_or(text.clone(), str::to_string);
                    assert_eq!(got, layout, "formatting after edit {n}");
                    assert_eq!(
                        leeway_format::format(&layout).ok().as_deref(),
                        Some(layout.as_str()),
                        "idempotent on the fuzzed model"
                    );
                    figures.formatted += 1;
                }
                Err(_) => figures.unparsed += 1,
            }
        }
        if method == "textDocument/definition" || method == "textDocument/references" {
            // Every location holds the same name, in this text (also when
            // the answer comes from the last version that parsed).
            let at = |p: &Value| {
                let n = |k: &str| p[k].as_u64().map_or(0, |x| x as u32);
                offset(&text, n("line"), n("character"))
            };
            let names: BTreeSet<&str> = answer
                .as_ref()
                .ok()
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .map(|l| &text[at(&l["range"]["start"])..at(&l["range"]["end"])])
                .collect();
            assert!(names.len() <= 1, "{method} after edit {n}: {names:?}");
            if !names.is_empty() && leeway_grammar::parse(&text).0.is_none() {
                figures.stale_found += 1;
            }
            assert!(
                names
                    .iter()
                    .all(|s| !s.is_empty() && s.chars().all(|c| c.is_alphanumeric() || c == '_')),
                "{method} after edit {n}: {names:?}"
            );
        }
        if n % 25 == 0 {
            // The server holds the client's text: its diagnostics are check's on it.
            let published = c.diagnostics(version);
            let codes: Vec<&str> = published
                .iter()
                .filter_map(|d| d["code"].as_str())
                .filter(|c| *c != "identifiability")
                .collect();
            let compiled = leeway_structure::compile(&text, &Default::default());
            let want: Vec<&str> = compiled
                .diagnostics
                .iter()
                .map(|d| d.code.as_str())
                .collect();
            assert_eq!(
                codes, want,
                "edit {n}: the server's text differs from the client's:\n{text}"
            );
        }
    }
    c.stop();
    figures
}

#[test]
fn survives_random_edits() {
    let f = campaign(51, 300);
    assert_eq!(f.requests, 300);
}

#[test]
#[ignore = "the campaign for the closing note: cargo test -p leeway-lsp --test fuzz -- --ignored --nocapture"]
fn fuzz_campaign() {
    let mut slowest = Duration::ZERO;
    let (mut edits, mut requests, mut total) = (0, 0, Duration::ZERO);
    let (mut unparsed, mut formatted, mut stale) = (0, 0, 0);
    for seed in 0..20 {
        let f = campaign(seed, 2_000);
        slowest = slowest.max(f.slowest);
        edits += f.edits;
        requests += f.requests;
        total += f.total;
        unparsed += f.unparsed;
        formatted += f.formatted;
        stale += f.stale_found;
    }
    println!(
        "{edits} edits, {requests} requests, mean answer {:?}, slowest {slowest:?}, formatted (to a fixed point) {formatted} edited models, refused {unparsed} that do not parse; {stale} definitions/references found from the last version that parsed",
        total / requests as u32
    );
}
