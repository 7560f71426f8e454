//! The editor's commands end to end: `leeway fmt` (rewrite, `--check`,
//! a file that does not parse) and `leeway lsp` driven by a real client,
//! headless Neovim (Debian's `neovim`; .ci/run installs it, and
//! `LEEWAY_REQUIRE_NVIM=1` there makes its absence a failure).

use crate::common::{Scratch, leeway};
use std::process::Command;

/// A model that parses but does not compile (a cubic term), laid out badly.
const BROKEN: &str = "// a broken model: Q multiplies a cubic term — ψ
model   Broken{ state u
input t   der u = X_u*u+Q * u*u*u +T*t
nominal{X_u=-0.2}}
";

#[test]
fn fmt_rewrites_checks_and_refuses() {
    let dir = Scratch::new("fmt");
    let messy = dir.write("messy.som", BROKEN);
    let tidy = dir.write("tidy.som", &leeway_format::format(BROKEN).expect("parses"));
    let bad = dir.write("bad.som", "model M { state u der u = u^2 }\n");

    let check = leeway(&["fmt", "--check", &messy, &tidy]);
    assert_eq!(check.status.code(), Some(1));
    assert_eq!(String::from_utf8_lossy(&check.stdout), format!("{messy}\n"));
    assert_eq!(
        std::fs::read_to_string(&messy).ok().as_deref(),
        Some(BROKEN),
        "--check writes nothing"
    );

    let fmt = leeway(&["fmt", &messy, &bad]);
    assert_eq!(fmt.status.code(), Some(2), "a file that does not parse");
    let stderr = String::from_utf8_lossy(&fmt.stderr);
    assert!(
        stderr.contains("bad.som:1:28") && stderr.contains("was not formatted: it does not parse"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(&messy).ok(),
        std::fs::read_to_string(&tidy).ok()
    );
    assert_eq!(leeway(&["fmt", "--check", &messy]).status.code(), Some(0));
}

#[test]
fn neovim_receives_diagnostics_hover_and_format() {
    let nvim = Command::new("nvim").arg("--version").output();
    if nvim.is_err() {
        assert!(
            std::env::var_os("LEEWAY_REQUIRE_NVIM").is_none(),
            "LEEWAY_REQUIRE_NVIM is set but `nvim` is not installed"
        );
        eprintln!("skipped: `nvim` is not installed (apt-get install neovim); CI runs this test");
        return;
    }
    let dir = Scratch::new("nvim");
    let model = dir.write("broken.som", BROKEN);
    let out = dir.path("held.txt");
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../editors/neovim/e2e.lua");
    let run = Command::new("nvim")
        .args(["--headless", "--clean", "-n", "-u", "NONE", "-c"])
        .arg(format!("luafile {}", script.display()))
        .env("LEEWAY", env!("CARGO_BIN_EXE_leeway"))
        .env("MODEL", &model)
        .env("OUT", &out)
        // `u` of `state u` on line 2 (0-based 1), column 23 (0-based 22).
        .env("HOVER", "1:22")
        .env("HOME", &dir.0)
        .output()
        .expect("nvim runs");
    let held = std::fs::read_to_string(&out).unwrap_or_else(|_| {
        panic!(
            "Neovim wrote nothing: {}",
            String::from_utf8_lossy(&run.stderr)
        )
    });
    insta::assert_snapshot!(held);
}
