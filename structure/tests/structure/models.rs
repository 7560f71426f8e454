//! Snapshots of the full derived structure of every example model
//! (`examples/models/*.som`): the text of `leeway check`, then the rendered
//! diagnostics. Each snapshot was reviewed against a hand expansion; see
//! `ship_phi_is_the_papers` and `identifiability.rs` for the facts asserted.
//! insta snapshots; CI never writes them (a new or changed one fails).

use leeway_structure::grammar::{RenderStyle, render};
use leeway_structure::{CompileOptions, compile, render as structure};
use std::path::Path;

/// `render::render` of the IR (if any) followed by the plain diagnostics.
fn derived(path: &Path, options: &CompileOptions) -> String {
    let source =
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let name = format!(
        "examples/models/{}",
        path.file_name().unwrap_or_default().to_string_lossy()
    );
    let c = compile(&source, options);
    let mut out = String::new();
    if let Some(ir) = &c.ir {
        out.push_str(&structure::render(ir));
    }
    out.push_str("\n--- diagnostics\n");
    out.push_str(&render(&c.diagnostics, &name, &source, RenderStyle::Plain));
    out
}

fn models() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/models")
}

#[test]
fn structure_of_every_example_model() {
    insta::glob!("../../../examples/models", "*.som", |path| {
        insta::assert_snapshot!(derived(path, &CompileOptions::default()));
    });
}

#[test]
fn ship_iv2_aggregated() {
    let options = CompileOptions {
        aggregate: true,
        patterns: None,
        centring: None,
    };
    insta::assert_snapshot!(derived(&models().join("ship_iv2.som"), &options));
}

#[test]
fn rov_from_one_experiment() {
    // One all-plus experiment (an empty pattern means every sign +).
    let options = CompileOptions {
        aggregate: false,
        patterns: Some(vec![Vec::new()]),
        centring: None,
    };
    insta::assert_snapshot!(derived(&models().join("rov.som"), &options));
}

#[test]
fn every_example_model_compiles() {
    let mut seen = 0;
    for entry in std::fs::read_dir(models()).expect("examples/models") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "som") {
            seen += 1;
            let source = std::fs::read_to_string(&path).expect("read");
            let c = compile(&source, &CompileOptions::default());
            assert!(
                c.ir.is_some(),
                "{} must compile: {:?}",
                path.display(),
                c.diagnostics
            );
            let unexpected: Vec<_> = c
                .diagnostics
                .iter()
                .filter(|d| d.is_error() && d.code != "unidentifiable-combination")
                .collect();
            assert!(unexpected.is_empty(), "{}: {unexpected:?}", path.display());
            assert!(
                c.diagnostics.iter().all(|d| d.code != "unused-declaration"),
                "{}: example models declare nothing they do not use",
                path.display()
            );
        }
    }
    assert!(seen >= 5, "expected the example models, found {seen}");
}
