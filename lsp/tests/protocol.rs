//! The protocol, scripted in process: initialize, open, change, hover,
//! definition, references, symbols, completion, formatting, shutdown on
//! every example model and every broken fixture; the diagnostics equal to
//! `leeway check`'s, their ranges in UTF-16 columns.

mod support;

use leeway_grammar::Severity;
use leeway_structure::{CompileOptions, compile};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use support::{Client, URI, utf16_position};

fn models() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models");
    let mut found = Vec::new();
    for dir in [root.clone(), root.join("broken")] {
        for e in std::fs::read_dir(dir).expect("examples").flatten() {
            if e.path().extension().is_some_and(|x| x == "som") {
                found.push(e.path());
            }
        }
    }
    found.sort();
    found
}

fn range_of(text: &str, start: usize, end: usize) -> Value {
    let (l0, c0) = utf16_position(text, start);
    let (l1, c1) = utf16_position(text, end);
    json!({"start": {"line": l0, "character": c0}, "end": {"line": l1, "character": c1}})
}

/// What the server must publish for `text`: check's diagnostics (code,
/// severity, first line, range of the primary label), then the verdict.
fn expected(text: &str) -> Vec<(String, u64, String, Value)> {
    let c = compile(text, &CompileOptions::default());
    let (model, _) = leeway_grammar::parse(text);
    let name = model.as_ref().map(|m| m.name.span);
    let mut out: Vec<(String, u64, String, Value)> = c
        .diagnostics
        .iter()
        .map(|d| {
            let at = d.primary_span().or(name).unwrap_or_default();
            let severity = match d.severity {
                Severity::Error => 1,
                Severity::Warning => 2,
                Severity::Note => 3,
            };
            (
                d.code.clone(),
                severity,
                d.message.clone(),
                range_of(text, at.start, at.end),
            )
        })
        .collect();
    if let (Some(ir), Some(at)) = (&c.ir, name) {
        let verdict = leeway_structure::render::verdict(ir);
        // The verdict itself first: not the section's title, not the centring.
        let first = verdict
            .lines()
            .map(str::trim)
            .find(|l| {
                !l.is_empty()
                    && !l.starts_with("Identifiability of")
                    && !l.starts_with("instrument centring")
            })
            .unwrap_or("")
            .to_string();
        out.push((
            "identifiability".into(),
            3,
            first,
            range_of(text, at.start, at.end),
        ));
    }
    out
}

fn received(published: &[Value]) -> Vec<(String, u64, String, Value)> {
    published
        .iter()
        .map(|d| {
            let message = d["message"].as_str().unwrap_or("");
            (
                d["code"].as_str().unwrap_or("").to_string(),
                d["severity"].as_u64().unwrap_or(0),
                message.lines().next().unwrap_or("").to_string(),
                d["range"].clone(),
            )
        })
        .collect()
}

/// Applies the server's whole-document edits.
fn apply_edits(text: &str, edits: &Value) -> String {
    match edits.as_array().map(Vec::as_slice) {
        Some([]) | None => text.to_string(),
        Some([edit]) => {
            assert_eq!(edit["range"]["start"], json!({"line": 0, "character": 0}));
            edit["newText"].as_str().expect("text").to_string()
        }
        Some(more) => panic!("{} edits", more.len()),
    }
}

#[test]
fn scripted_session_on_every_example_and_broken_fixture() {
    let all = models();
    assert!(all.len() > 50);
    for path in all {
        let what = path.display().to_string();
        let text = std::fs::read_to_string(&path).expect("readable");
        let mut c = Client::start();
        c.open(&text);
        let published = c.diagnostics(1);
        assert_eq!(received(&published), expected(&text), "{what}: on open");
        // Every label but the one the range shows is a related location
        // (both terms of a conflict, every member of a combination).
        let compiled = compile(&text, &CompileOptions::default());
        for (d, p) in compiled.diagnostics.iter().zip(&published) {
            let at = d.primary_span();
            let others = d
                .labels
                .iter()
                .filter(|l| !(l.primary && Some(l.span) == at))
                .count();
            let related = p["relatedInformation"].as_array().map_or(0, Vec::len);
            assert_eq!(related, others, "{what}: related locations of `{}`", d.code);
        }

        // An edit: a non-ASCII comment line at the top shifts every range by a line.
        let header = "// ψ ≈ 1 😀 (UTF-16: the emoji counts two)\n";
        c.notify(
            "textDocument/didChange",
            json!({"textDocument": {"uri": URI, "version": 2},
                   "contentChanges": [{"range": {"start": {"line": 0, "character": 0},
                                                 "end": {"line": 0, "character": 0}},
                                       "text": header}]}),
        );
        let edited = format!("{header}{text}");
        assert_eq!(
            received(&c.diagnostics(2)),
            expected(&edited),
            "{what}: after a change"
        );

        let (model, _) = leeway_grammar::parse(&edited);
        let ir = compile(&edited, &CompileOptions::default()).ir;
        if let Some(ir) = &ir {
            // Hover on every term: its regressors.
            for t in &ir.terms {
                let (l, ch) = utf16_position(&edited, t.span.start);
                let h = c.request("textDocument/hover", c.at(l, ch));
                let md = h["contents"]["value"].as_str().unwrap_or("");
                assert!(
                    md.contains(&format!("**term** `{}`", t.text)),
                    "{what}: hover on `{}`:\n{md}",
                    t.text
                );
                assert!(md.contains("Φ "), "{what}: no Φ column in\n{md}");
            }
        }
        if let Some(model) = &model {
            // Definition of every name used in an equation: a declaration of it.
            let uses = names_in_equations(model);
            for (name, start) in uses {
                let (l, ch) = utf16_position(&edited, start);
                let found = c.request("textDocument/definition", c.at(l, ch));
                let spots = found.as_array().cloned().unwrap_or_default();
                assert!(!spots.is_empty(), "{what}: no definition of `{name}`");
                for s in spots {
                    let r = &s["range"];
                    let line = edited
                        .lines()
                        .nth(r["start"]["line"].as_u64().unwrap_or(0) as usize)
                        .unwrap_or("");
                    let col = r["start"]["character"].as_u64().unwrap_or(0) as usize;
                    let at: String = String::from_utf16_lossy(
                        &line
                            .encode_utf16()
                            .skip(col)
                            .take(name.encode_utf16().count())
                            .collect::<Vec<_>>(),
                    );
                    assert_eq!(at, name, "{what}: definition of `{name}`");
                }
            }
            let symbols = c.request(
                "textDocument/documentSymbol",
                json!({"textDocument": {"uri": URI}}),
            );
            assert_eq!(symbols[0]["name"], json!(model.name.name));
        }
        let items = c.request("textDocument/completion", c.at(0, 0));
        assert!(
            items
                .as_array()
                .is_some_and(|a| a.iter().any(|i| i["label"] == "nominal"))
        );

        let edits = c.try_request(
            "textDocument/formatting",
            json!({"textDocument": {"uri": URI}, "options": {"tabSize": 4, "insertSpaces": true}}),
        );
        match leeway_format::format(&edited) {
            Ok(layout) => assert_eq!(
                apply_edits(&edited, &edits.expect("edits")),
                layout,
                "{what}"
            ),
            // No edit for a file that does not parse (its diagnostics say why).
            Err(_) => assert_eq!(edits, Ok(Value::Null), "{what}"),
        }
        c.stop();
    }
}

/// Every name written in an equation, with its byte offset.
fn names_in_equations(model: &leeway_grammar::ModelSyntax) -> Vec<(String, usize)> {
    use leeway_grammar::{Expr, Item};
    let mut out = Vec::new();
    for item in &model.items {
        if let Item::Equation { rhs, .. } = item {
            let mut stack = vec![rhs];
            while let Some(e) = stack.pop() {
                match e {
                    Expr::Path(p) => out.push((p.base.name.clone(), p.base.span.start)),
                    Expr::Abs(x, _) | Expr::Neg(x, _) | Expr::Paren(x, _) => stack.push(x),
                    Expr::Binary { lhs, rhs, .. } => {
                        stack.push(lhs);
                        stack.push(rhs);
                    }
                    Expr::Number(_) => {}
                }
            }
        }
    }
    out
}

#[test]
fn utf16_columns_after_a_non_ascii_comment() {
    // The error is on `Q*u*u*u` (order too high), after a comment with a
    // character outside the BMP on the same line.
    let text = "model M {\n    state u\n    der u = /* 😀é */ A*u + Q*u*u*u\n}\n";
    let mut c = Client::start();
    c.open(text);
    let d = c.diagnostics(1);
    let error = d.iter().find(|d| d["severity"] == 1).expect("an error");
    let byte = text.find("Q*u*u*u").expect("there");
    // 4 + "der u = " (8) + "/* " (3) + 😀 (2 units) + "é */ " (5) + "A*u + " (6) = 28.
    assert_eq!(utf16_position(text, byte), (2, 28));
    assert_eq!(error["range"]["start"], json!({"line": 2, "character": 28}));
    // A hover at that position lands on `Q`.
    let h = c.request("textDocument/hover", c.at(2, 28));
    assert!(
        h.is_null()
            || h["contents"]["value"]
                .as_str()
                .unwrap_or("")
                .contains("`Q`"),
        "{h}"
    );
    c.stop();
}

#[test]
fn hovers_on_a_parameter_a_signal_and_a_medium() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models/ship.som"),
    )
    .expect("ship");
    let mut c = Client::start();
    c.open(&text);
    let _ = c.diagnostics(1);
    let hover_at = |c: &mut Client, needle: &str, nth: usize| {
        let byte = text.match_indices(needle).nth(nth).expect("in the ship").0;
        let (l, ch) = utf16_position(&text, byte);
        c.request("textDocument/hover", c.at(l, ch))["contents"]["value"]
            .as_str()
            .unwrap_or("")
            .to_string()
    };
    let x_uu = hover_at(&mut c, "X_uu", 0);
    assert!(
        x_uu.contains("**parameter** `X_uu`") && x_uu.contains("- `water.u*|water.u|` in `der u`"),
        "{x_uu}"
    );
    assert!(
        x_uu.contains("nominal value: 0") && x_uu.contains("identified"),
        "{x_uu}"
    );
    assert!(
        x_uu.contains("rho[north,X_uu]") || x_uu.contains("Φρ"),
        "the nuisance columns of the term:\n{x_uu}"
    );
    let current = hover_at(&mut c, "current", 1);
    assert!(
        current.contains("unmeasured, in the earth frame, components north, east"),
        "{current}"
    );
    let tau1 = hover_at(&mut c, "tau1", 1);
    assert!(
        tau1.contains("**input** `tau1`") && tau1.contains("input tau1, tau2, tau3"),
        "{tau1}"
    );
    let refs = {
        let byte = text.find("water.u").expect("there");
        let (l, ch) = utf16_position(&text, byte);
        let mut p = c.at(l, ch);
        p["context"] = json!({"includeDeclaration": true});
        c.request("textDocument/references", p)
    };
    let n = text.matches("water").count();
    assert_eq!(refs.as_array().map(Vec::len), Some(n), "every `water`");
    c.stop();
}

#[test]
fn quick_fix_removes_an_unused_input() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/models/broken/unused-declaration.som");
    let text = std::fs::read_to_string(path).expect("fixture");
    let mut c = Client::start();
    c.open(&text);
    let d = c.diagnostics(1);
    let unused = d
        .iter()
        .find(|d| d["code"] == "unused-declaration")
        .expect("the warning");
    let actions = c.request(
        "textDocument/codeAction",
        json!({"textDocument": {"uri": URI}, "range": unused["range"],
               "context": {"diagnostics": [unused]}}),
    );
    assert_eq!(actions[0]["title"], "remove the unused `rudder`");
    let edit = &actions[0]["edit"]["changes"][URI][0];
    let r = &edit["range"];
    let line = r["start"]["line"].as_u64().expect("line") as usize;
    let (a, b) = (
        r["start"]["character"].as_u64().expect("col") as usize,
        r["end"]["character"].as_u64().expect("col") as usize,
    );
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    lines[line].replace_range(a..b, edit["newText"].as_str().expect("text"));
    assert_eq!(lines[line], "    input tau");
    let fixed = lines.join("\n");
    let c2 = compile(&fixed, &CompileOptions::default());
    assert!(
        c2.diagnostics
            .iter()
            .all(|d| d.code != "unused-declaration")
    );
    c.stop();
}

#[test]
fn semantic_tokens_tell_parameters_from_signals() {
    let text = "model M {\n    state u\n    input t\n    der u = X_u*u + B*t // é\n}\n";
    let mut c = Client::start();
    c.open(text);
    let _ = c.diagnostics(1);
    let got = c.request(
        "textDocument/semanticTokens/full",
        json!({"textDocument": {"uri": URI}}),
    );
    let data: Vec<u64> = got["data"]
        .as_array()
        .expect("data")
        .iter()
        .filter_map(Value::as_u64)
        .collect();
    // (Δline, Δstart, length, type, modifiers): u, t declared; then on line
    // 3: u (the equation's state), X_u (parameter), u, B (parameter), t.
    assert_eq!(
        data,
        vec![
            1, 10, 1, 0, 0, //
            1, 10, 1, 0, 0, //
            1, 8, 1, 0, 0, //
            0, 4, 3, 1, 0, //
            0, 4, 1, 0, 0, //
            0, 4, 1, 1, 0, //
            0, 2, 1, 0, 0,
        ]
    );
    c.stop();
}

/// `text` with one of the server's text edits applied (UTF-16 positions).
fn apply_edit(text: &str, edit: &Value) -> String {
    let at = |p: &Value| {
        let p: lsp_types::Position = serde_json::from_value(p.clone()).expect("position");
        leeway_lsp::text::offset(text, p)
    };
    let (start, end) = (at(&edit["range"]["start"]), at(&edit["range"]["end"]));
    let mut out = text.to_string();
    out.replace_range(start..end, edit["newText"].as_str().expect("text"));
    out
}

/// The code actions for a range, as (title, kind, the edited text).
fn actions_at(c: &mut Client, text: &str, range: Value) -> Vec<(String, String, String)> {
    let found = c.request(
        "textDocument/codeAction",
        json!({"textDocument": {"uri": URI}, "range": range, "context": {"diagnostics": []}}),
    );
    found
        .as_array()
        .expect("actions")
        .iter()
        .map(|a| {
            let edits = a["edit"]["changes"][URI].as_array().expect("edits");
            assert_eq!(edits.len(), 1);
            (
                a["title"].as_str().expect("title").to_string(),
                a["kind"].as_str().expect("kind").to_string(),
                apply_edit(text, &edits[0]),
            )
        })
        .collect()
}

fn warnings(text: &str) -> Vec<String> {
    let c = compile(text, &CompileOptions::default());
    assert!(c.ir.is_some(), "{:?}", c.diagnostics);
    assert!(!c.diagnostics.iter().any(|d| d.severity == Severity::Error));
    c.diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Warning)
        .map(|d| d.message.clone())
        .collect()
}

const BOAT: &str = "model Boat {
    state u, v, r
    input tau, rudder
    delay rudder 1 steps
    heading psi integrates r
    disturbance current unmeasured earth(north, east)
    disturbance wind measured earth(wind_n, wind_e)  // the anemometer
    water = relative(current)
    air = relative(wind)  // not used yet

    der u = X_u*water.u + X_tau*tau
    der v = Y_v*water.v
    der r = N_r*r
}
";

#[test]
fn quick_fixes_remove_an_unused_relative_velocity_then_its_medium() {
    let mut c = Client::start();
    c.open(BOAT);
    let d = c.diagnostics(1);
    let unused = |d: &[Value], what: &str| {
        d.iter()
            .find(|d| {
                d["code"] == "unused-declaration"
                    && d["message"].as_str().expect("message").contains(what)
            })
            .unwrap_or_else(|| panic!("{what}: {d:?}"))["range"]
            .clone()
    };
    // `rudder` is still named by its `delay`: removing it alone would be an
    // error, so no fix is offered.
    assert_eq!(actions_at(&mut c, BOAT, unused(&d, "`rudder`")), []);
    let found = actions_at(&mut c, BOAT, unused(&d, "`air`"));
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, "remove the unused `air`");
    assert_eq!(found[0].1, "quickfix");
    let without_air = &found[0].2;
    assert_eq!(
        *without_air,
        BOAT.replace("    air = relative(wind)  // not used yet\n", "")
    );
    let w = warnings(without_air);
    assert!(!w.iter().any(|m| m.contains("`air`")), "{w:?}");
    assert!(
        w.iter()
            .any(|m| m == "disturbance `wind` has no relative velocity"),
        "{w:?}"
    );

    // The medium no relative velocity sees now, removed in turn.
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": URI, "version": 2},
               "contentChanges": [{"text": without_air}]}),
    );
    let d = c.diagnostics(2);
    let found = actions_at(&mut c, without_air, unused(&d, "`wind`"));
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, "remove the unused `wind`");
    let fixed = &found[0].2;
    assert_eq!(
        *fixed,
        without_air.replace(
            "    disturbance wind measured earth(wind_n, wind_e)  // the anemometer\n",
            ""
        )
    );
    let w = warnings(fixed);
    assert_eq!(w, ["input `rudder` appears in no equation"]);
    c.stop();
}

#[test]
fn refactor_lists_a_parameter_without_nominal_value() {
    let with_block = BOAT.replace(
        "    der r = N_r*r\n",
        "    der r = N_r*r\n    nominal { X_u = -0.2 }\n",
    );
    let mut c = Client::start();
    c.open(&with_block);
    let _ = c.diagnostics(1);
    let at = |text: &str, name: &str| {
        let start = text.find(name).expect("name") + 1;
        range_of(text, start, start)
    };
    // A signal, and a parameter already listed: nothing.
    assert_eq!(actions_at(&mut c, &with_block, at(&with_block, "*tau")), []);
    assert_eq!(
        actions_at(&mut c, &with_block, at(&with_block, " X_u*")),
        []
    );
    let found = actions_at(&mut c, &with_block, at(&with_block, " Y_v*"));
    let titles: Vec<&str> = found.iter().map(|f| f.0.as_str()).collect();
    assert_eq!(
        titles,
        [
            "list `Y_v` in `nominal { }` (0, its value unlisted)",
            "list the 3 parameters without a nominal value in `nominal { }` (0)"
        ]
    );
    assert!(found.iter().all(|f| f.1 == "refactor.rewrite"));
    assert!(
        found[0].2.contains("    nominal { X_u = -0.2, Y_v = 0 }\n"),
        "{}",
        found[0].2
    );
    assert!(
        found[1]
            .2
            .contains("    nominal { X_u = -0.2, X_tau = 0, Y_v = 0, N_r = 0 }\n")
    );
    for (_, _, edited) in &found {
        // Same model, same warnings; the parameter now has its entry.
        assert_eq!(warnings(edited), warnings(&with_block));
        let ir = compile(edited, &CompileOptions::default()).ir.expect("ir");
        let y_v = ir.parameters.iter().find(|p| p.name == "Y_v").expect("Y_v");
        assert_eq!(y_v.nominal, 0.0);
        let (model, _) = leeway_grammar::parse(edited);
        let listed = model.expect("parses").items.iter().any(|i| {
            matches!(i, leeway_grammar::Item::Nominal { entries, .. }
                if entries.iter().any(|(n, _)| n.name == "Y_v"))
        });
        assert!(listed);
    }
    c.stop();

    // Without a block: a new one, indented as the declarations above.
    let mut c = Client::start();
    c.open(BOAT);
    let _ = c.diagnostics(1);
    let found = actions_at(&mut c, BOAT, at(BOAT, " N_r*"));
    assert_eq!(found.len(), 2, "{found:?}");
    assert_eq!(
        found[0].2,
        BOAT.replace(
            "    der r = N_r*r\n",
            "    der r = N_r*r\n    nominal { N_r = 0 }\n"
        )
    );
    assert_eq!(warnings(&found[1].2), warnings(BOAT));
    c.stop();
}

#[test]
fn hover_and_definition_answer_from_the_last_version_that_parsed() {
    let mut c = Client::start();
    c.open(BOAT);
    let _ = c.diagnostics(1);
    // A `+` left hanging at the end of `der v`: the text no longer parses.
    let broken = BOAT.replace("    der v = Y_v*water.v\n", "    der v = Y_v*water.v +\n");
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": URI, "version": 2},
               "contentChanges": [{"text": broken}]}),
    );
    let d = c.diagnostics(2);
    assert!(d.iter().any(|d| d["code"] == "syntax"), "{d:?}");
    let pos = |at: usize| {
        let (l, ch) = utf16_position(&broken, at);
        c_at(l, ch)
    };
    // Before the edit (same place) and after it (shifted by two bytes).
    for name in ["X_u*", "N_r*"] {
        let at = broken.find(name).expect("name");
        let h = c.request("textDocument/hover", pos(at + 1));
        let md = h["contents"]["value"].as_str().expect("a hover");
        assert!(
            md.starts_with("*(as of the last version that parsed)*"),
            "{md}"
        );
        assert!(md.contains(&name[..3]), "{md}");
        assert_eq!(h["range"], range_of(&broken, at, at + 3));
    }
    // The `v` the edit touches: no answer from the old version.
    let v = broken.find("water.v +").expect("edit") + "water.".len();
    assert_eq!(c.request("textDocument/hover", pos(v)), Value::Null);
    // Definition and references of `water`, written before and after the edit.
    let uses: Vec<usize> = broken.match_indices("water").map(|(i, _)| i).collect();
    let defined = c.request("textDocument/definition", pos(uses[2] + 1));
    assert_eq!(defined[0]["range"], range_of(&broken, uses[0], uses[0] + 5));
    let mut p = pos(uses[1]);
    p["context"] = json!({"includeDeclaration": true});
    let refs = c.request("textDocument/references", p);
    let ranges: Vec<&Value> = refs
        .as_array()
        .expect("refs")
        .iter()
        .map(|l| &l["range"])
        .collect();
    let want: Vec<Value> = uses.iter().map(|&i| range_of(&broken, i, i + 5)).collect();
    assert_eq!(ranges, want.iter().collect::<Vec<_>>());
    c.stop();
}

fn c_at(line: u32, character: u32) -> Value {
    json!({"textDocument": {"uri": URI}, "position": {"line": line, "character": character}})
}
