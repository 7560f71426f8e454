//! The generated code, pretty-printed and snapshot-tested: review it by eye.
//! The embedded IR JSON is elided from the snapshots (its content is the IR,
//! snapshot-tested in leeway-structure; its exactness is checked at expansion).

use leeway_codegen::{Source, expand};
use leeway_structure::Options;
use proc_macro2::Span;

fn models_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models")
}

/// The expansion as formatted Rust, with the IR's JSON literal elided.
fn pretty(text: &str, label: &str, options: &Options) -> String {
    let tokens = expand(&Source { text, label, tracked: Some("/path/to/model.som") }, options, Span::call_site());
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

fn example(name: &str, options: &Options) -> String {
    let path = models_dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    pretty(&text, &format!("examples/models/{name}"), options)
}

#[test]
fn ship() {
    insta::assert_snapshot!(example("ship.som", &Options::default()));
}

#[test]
fn ship_iv2_aggregated() {
    insta::assert_snapshot!(example("ship_iv2.som", &Options { aggregate: true, patterns: None }));
}
