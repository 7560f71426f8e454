//! Property test of CSV layouts through `leeway estimate`: blank lines (empty,
//! spaces, CR), comment lines (indented too), quoted cells holding line breaks
//! and commas, CRLF line ends, empty and non-numeric cells, rows with a cell
//! too many or too few. Whatever the layout: no panic, exit 0, 1 or 2, and
//! every data error located at a physical line of the file that holds the
//! offending text. `PROPTEST_CASES=1000` for a longer run (CI runs 24).

use proptest::prelude::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A valid ship log of `n` rows: time, states, heading, inputs, wind, note.
fn base_rows(n: usize) -> Vec<Vec<String>> {
    let mut rows = vec![
        "time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e,note"
            .split(',')
            .map(str::to_string)
            .collect::<Vec<_>>(),
    ];
    for k in 0..n {
        let t = k as f64;
        let vals = [
            t,
            5.0 + (0.1 * t).sin(),
            0.2 * (0.07 * t).cos(),
            0.02 * (0.05 * t).sin(),
            0.3 * t,
            100.0 + 10.0 * (0.13 * t).sin(),
            5.0 * (0.11 * t).cos(),
            200.0 * (0.05 * t).sin(),
            1.0 + 0.1 * (0.3 * t).sin(),
            -0.5 + 0.1 * (0.2 * t).cos(),
        ];
        let mut row: Vec<String> = vals.iter().map(|v| format!("{v:?}")).collect();
        row.push("ok".to_string());
        rows.push(row);
    }
    rows
}

#[derive(Clone, Debug)]
enum Edit {
    Blank(usize, &'static str),
    Comment(usize, &'static str),
    Quoted(usize, &'static str),
    Empty(usize, usize),
    Text(usize, usize, &'static str),
    ExtraCell(usize),
    MissingCell(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let row = 0usize..80;
    let col = 0usize..10;
    prop_oneof![
        (
            row.clone(),
            prop::sample::select(vec!["", "  ", "\t", " \r"])
        )
            .prop_map(|(r, s)| Edit::Blank(r, s)),
        (
            row.clone(),
            prop::sample::select(vec!["# note", "   # pause", "#,1,2"])
        )
            .prop_map(|(r, s)| Edit::Comment(r, s)),
        (
            row.clone(),
            prop::sample::select(vec!["\"a\nb\"", "\"x,\n\n# y\"", "\"q \"\"z\"\"\n\""])
        )
            .prop_map(|(r, s)| Edit::Quoted(r, s)),
        (row.clone(), col.clone()).prop_map(|(r, c)| Edit::Empty(r, c)),
        (
            row.clone(),
            col,
            prop::sample::select(vec!["abc", "1.2.3", "NaN", "--1", "0x10"])
        )
            .prop_map(|(r, c, s)| Edit::Text(r, c, s)),
        row.clone().prop_map(Edit::ExtraCell),
        row.prop_map(Edit::MissingCell),
    ]
}

fn set(row: &mut [String], column: usize, text: &str) {
    if let Some(cell) = row.get_mut(column) {
        *cell = text.to_string();
    }
}

/// The file text: the edited rows, extra lines, line ends.
fn layout(edits: &[Edit], crlf: bool) -> String {
    let mut rows = base_rows(80);
    // Extra lines to insert before a data row index, in order.
    let mut before: Vec<(usize, String)> = Vec::new();
    for e in edits {
        match e {
            Edit::Blank(r, s) => before.push((*r, (*s).to_string())),
            Edit::Comment(r, s) => before.push((*r, (*s).to_string())),
            // A cell a `MissingCell` edit removed stays removed.
            Edit::Quoted(r, s) => set(&mut rows[r + 1], 10, s),
            Edit::Empty(r, c) => set(&mut rows[r + 1], *c, ""),
            Edit::Text(r, c, s) => set(&mut rows[r + 1], *c, s),
            Edit::ExtraCell(r) => rows[r + 1].push("9".to_string()),
            Edit::MissingCell(r) => {
                rows[r + 1].pop();
            }
        }
    }
    let end = if crlf { "\r\n" } else { "\n" };
    let mut text = String::new();
    for (i, row) in rows.iter().enumerate() {
        for (_, line) in before.iter().filter(|(r, _)| i > 0 && *r + 1 == i) {
            text.push_str(line);
            text.push_str(end);
        }
        text.push_str(&row.join(","));
        text.push_str(end);
    }
    text
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(24),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn any_layout_is_read_or_refused_at_its_physical_line(
        edits in prop::collection::vec(edit(), 0..6),
        crlf in any::<bool>(),
        id in any::<u64>(),
    ) {
        let text = layout(&edits, crlf);
        let dir = std::env::temp_dir();
        let path = dir.join(format!("leeway-layout-{}-{id}.csv", std::process::id()));
        std::fs::write(&path, &text).unwrap_or_else(|e| panic!("{e}"));
        let started = std::time::Instant::now();
        let o = Command::new(env!("CARGO_BIN_EXE_leeway"))
            .args(["estimate", "examples/models/ship.som", "--method", "ls", "--json", "--data"])
            .arg(&path)
            .current_dir(root())
            .output()
            .expect("run leeway");
        let _ = std::fs::remove_file(&path);
        if std::env::var_os("LEEWAY_LAYOUT_LOG").is_some() {
            eprintln!(
                "layout-case exit {} {} ms",
                o.status.code().unwrap_or(-1),
                started.elapsed().as_millis()
            );
        }
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        prop_assert!(!stderr.contains("panicked"), "{}", stderr);
        let code = o.status.code().unwrap_or(-1);
        prop_assert!([0, 1, 2].contains(&code), "exit {code}: {stderr}");
        prop_assert!(started.elapsed().as_secs() < 20);
        let v: Value = serde_json::from_slice(&o.stdout).unwrap_or(Value::Null);
        let file = path.display().to_string();
        let lines: Vec<&str> = text.split('\n').collect();
        for e in v["errors"].as_array().into_iter().flatten() {
            if e["code"] != "data" {
                continue;
            }
            let location = e["location"].as_str().unwrap_or_default();
            let message = e["message"].as_str().unwrap_or_default();
            let rest = location.strip_prefix(&format!("{file}:"));
            prop_assert!(rest.is_some(), "unlocated: {location}: {message}");
            let rest = rest.unwrap_or_default();
            let line: usize = rest.split(':').next().and_then(|s| s.parse().ok()).unwrap_or(0);
            prop_assert!(line >= 1 && line <= lines.len(), "{location}: {message}");
            let held = lines[line - 1];
            prop_assert!(!held.trim().is_empty() && !held.trim_start().starts_with('#'),
                "{location} is a blank or comment line: {message}");
            // The offending text quoted by the message is on that line.
            if let Some(raw) = message
                .strip_prefix('`')
                .filter(|m| m.contains("` is not a"))
                .and_then(|m| m.split('`').next())
            {
                prop_assert!(held.contains(raw), "{location}: `{raw}` not on line {line} `{held}`");
            }
            if message == "empty cell" {
                prop_assert!(held.contains(",,") || held.starts_with(',') || held.trim_end().ends_with(','),
                    "{location}: no empty cell on `{held}`");
            }
        }
    }
}
