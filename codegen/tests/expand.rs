//! The generated code, pretty-printed and snapshot-tested: review it by eye.
//! The embedded IR JSON is elided from the snapshots (its content is the IR,
//! snapshot-tested in leeway-structure; its exactness is checked at expansion).

use leeway_codegen::{Source, expand};
use leeway_structure::CompileOptions;
use proc_macro2::Span;
use std::path::Path;

fn models_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models")
}

/// The expansion as formatted Rust, with the IR's JSON literal elided.
fn pretty(text: &str, label: &str, options: &CompileOptions) -> String {
    let tokens = expand(
        &Source {
            text,
            label,
            tracked: Some("/path/to/model.som"),
        },
        options,
        Span::call_site(),
    );
    let file: syn::File = match syn::parse2(tokens.clone()) {
        Ok(f) => f,
        Err(e) => panic!("the expansion is not valid Rust ({e}):\n{tokens}"),
    };
    let code = prettyplease::unparse(&file);
    let mut out = String::new();
    for line in code.lines() {
        match line.find("const IR_JSON: &str = \"") {
            Some(i) => {
                out.push_str(&line[..i]);
                out.push_str("const IR_JSON: &str = \"…\";");
            }
            None => out.push_str(line),
        }
        out.push('\n');
    }
    out
}

fn example(name: &str, options: &CompileOptions) -> String {
    let path = models_dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    pretty(&text, &format!("examples/models/{name}"), options)
}

#[test]
fn ship() {
    insta::assert_snapshot!(example("ship.som", &CompileOptions::default()));
}

#[test]
fn ship_iv2_aggregated() {
    insta::assert_snapshot!(example(
        "ship_iv2.som",
        &CompileOptions {
            aggregate: true,
            patterns: None,
            centring: None,
        }
    ));
}

fn fixture(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/models")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    pretty(
        &text,
        &format!("tests/models/{name}"),
        &CompileOptions::default(),
    )
}

/// Body-frame media (`d[c]` shares), `next` equations, `|input|`, a
/// coefficient of exactly 1/3 rounded once.
#[test]
fn raft() {
    insta::assert_snapshot!(fixture("raft.som"));
}

/// A measured rotation with a structural zero and three components.
#[test]
fn sub() {
    insta::assert_snapshot!(fixture("sub.som"));
}

/// A broken model: one `compile_error!` with the rendered snippet, and the
/// fallback items (the parameters still read) so user code type-checks.
#[test]
fn broken_model_fallback() {
    let text = "model Boat {\n    state u, v\n    input tau\n    der u = X_u*u + X_uvr*u*v*u + X_tau*tau\n    der v = Y_v*v\n}\n";
    insta::assert_snapshot!(pretty(text, "models/boat.som", &CompileOptions::default()));
}
