//! The canonical layout: idempotent on every `.som` of the repository and
//! on randomly edited examples, never changing what a model compiles to,
//! comments (non-ASCII ones too) kept where they were written.

use leeway_format::format;
use leeway_structure::{CompileOptions, compile};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every `.som` under the repository (build output and hidden folders aside).
fn every_model() -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![root()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let path = e.path();
            let name = e.file_name().to_string_lossy().to_string();
            if path.is_dir() {
                if !name.starts_with('.') && name != "target" && name != "node_modules" {
                    stack.push(path);
                }
            } else if name.ends_with(".som") {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// What a model compiles to, without the byte offsets (which formatting
/// moves): the IR as JSON with its spans removed, and each diagnostic's
/// code, severity and message.
fn compiled(source: &str) -> String {
    let c = compile(source, &CompileOptions::default());
    let mut ir = serde_json::to_value(&c.ir).expect("the IR serialises");
    strip_spans(&mut ir);
    let diagnostics: Vec<String> = c
        .diagnostics
        .iter()
        .map(|d| format!("{:?} {} {}", d.severity, d.code, d.message))
        .collect();
    format!("{ir}\n{}", diagnostics.join("\n"))
}

fn strip_spans(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.remove("span");
            m.values_mut().for_each(strip_spans);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_spans),
        _ => {}
    }
}

/// Formats `source` (which parses), checks the layout is a fixed point and
/// compiles as the source does; returns the layout.
fn check_layout(source: &str, what: &str) -> String {
    let once = format(source).unwrap_or_else(|d| panic!("{what}: {d:?}"));
    let twice = format(&once).unwrap_or_else(|d| panic!("{what}, formatted: {d:?}\n{once}"));
    assert_eq!(once, twice, "{what}: formatting twice differs");
    assert_eq!(
        compiled(source),
        compiled(&once),
        "{what}: the formatted model compiles differently\n{once}"
    );
    once
}

#[test]
fn idempotent_and_faithful_on_every_model_of_the_repository() {
    let models = every_model();
    assert!(models.len() > 60, "found only {} models", models.len());
    let mut parsed = 0;
    for path in &models {
        let Ok(source) = std::fs::read_to_string(path) else {
            continue;
        };
        if leeway_grammar::parse(&source).0.is_none() {
            // A fixture of a syntax error: formatting refuses it, untouched.
            assert!(format(&source).is_err());
            continue;
        }
        check_layout(&source, &path.display().to_string());
        parsed += 1;
    }
    assert!(parsed > 50, "only {parsed} models parse");
}

#[test]
fn the_examples_are_formatted() {
    for dir in ["examples/models", "tests/models"] {
        for e in std::fs::read_dir(root().join(dir))
            .expect("the folder exists")
            .flatten()
        {
            let path = e.path();
            if path.extension().is_some_and(|x| x == "som") {
                let source = std::fs::read_to_string(&path).expect("readable");
                assert_eq!(
                    format(&source).ok().as_deref(),
                    Some(source.as_str()),
                    "{}: run `leeway fmt` on it",
                    path.display()
                );
            }
        }
    }
}

#[test]
fn layout_of_a_messy_model() {
    let source = "// En-tête : modèle d'un navire — ψ en degrés
model   Messy{step 0.5;state u,v ; input   t   // poussée (N) – ≈ 1 kN
heading psi integrates v axes( u ,v )
disturbance current unmeasured   earth( n,e )   water=relative( current )


  /* a block comment
     over two lines */
der u = X_u * water.u+X_uu*water.u * | water.u |   /* inline */ + T*t
      - ( A + B ) * u   // après parenthèse
der v = -Y_v*water.v
  // between the terms
  + Y_uv * water.u * water.v
nominal{X_u=-0.2,X_uu= - 0.1 T = 1e-3}
data { psi = \"heading_deg\" in deg , t in kN }
}  // fin
";
    let layout = check_layout(source, "messy");
    insta::assert_snapshot!(layout);
}

/// A few hundred random edits of the examples (insertions of grammar
/// fragments, deletions, truncations): every one that still parses is
/// formatted to a fixed point that compiles as it did. The larger campaign
/// is `lsp/tests`' ignored fuzz (its figures in the closing note).
#[test]
fn idempotent_on_edited_examples() {
    const PIECES: &[&str] = &[
        " ",
        "\n",
        "// c\n",
        "/* é */",
        "+",
        "-",
        "*",
        "|",
        "(",
        ")",
        "x",
        "X_u",
        "water.u",
        ",",
        "0.5",
        "{",
        "}",
        "=",
        "der v = ",
        "nominal { A = 1 }",
        ";",
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(51);
    let examples: Vec<String> = every_model()
        .into_iter()
        .filter(|p| p.starts_with(root().join("examples")))
        .filter_map(|p| std::fs::read_to_string(p).ok())
        .collect();
    let mut parsed = 0;
    for round in 0..300 {
        let mut text = examples[round % examples.len()].clone();
        for _ in 0..rng.random_range(1..4) {
            let mut at = rng.random_range(0..=text.len());
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            match rng.random_range(0..3) {
                0 => text.insert_str(at, PIECES[rng.random_range(0..PIECES.len())]),
                1 => {
                    let mut end = (at + rng.random_range(1..8)).min(text.len());
                    while !text.is_char_boundary(end) {
                        end += 1;
                    }
                    text.replace_range(at..end, "");
                }
                _ => text.truncate(at.max(text.len() * 9 / 10)),
            }
        }
        if leeway_grammar::parse(&text).0.is_some() {
            check_layout(&text, &format!("round {round}:\n{text}"));
            parsed += 1;
        }
    }
    assert!(parsed > 50, "only {parsed} edited models parse");
}

#[test]
fn long_lines_are_broken_at_terms_and_entries() {
    let terms: Vec<String> = (0..12).map(|i| format!("A{i}*water.u*|water.u|")).collect();
    let states: Vec<String> = (0..30).map(|i| format!("state_{i}")).collect();
    let source = format!(
        "model Wide {{\n    state u, {}\n    disturbance current unmeasured body(u: cu)\n    water = relative(current)\n    der u = {}\n    nominal {{ {} }}\n    rotation {{\n        u = [r11]\n    }}\n}}\n",
        states.join(", "),
        terms.join(" + "),
        (0..12)
            .map(|i| format!("A{i} = -0.{i}"))
            .collect::<Vec<_>>()
            .join(", "),
    );
    let layout = check_layout(&source, "wide");
    assert!(
        layout
            .lines()
            .all(|l| l.chars().count() <= leeway_format::WIDTH),
        "{layout}"
    );
    insta::assert_snapshot!(layout);
}

/// A candidate's `?` (`leeway select`) is part of the model: the IR does
/// not hold it, so the layout is compared as text.
#[test]
fn candidates_keep_their_marker() {
    let source = "model Boat {
step 0.1
state u
input t
der u = X_u*u+ ?X_uu * u*|u| +X_t*t
nominal { X_u = -0.1, X_t = 0.01 } }
";
    let layout = check_layout(source, "candidates");
    assert!(layout.contains("?X_uu*u*|u|"), "{layout}");
    assert_eq!(layout.matches('?').count(), 1, "{layout}");
}
