//! End-to-end tests of `leeway check`: the built binary, its exit codes,
//! its text on stdout/stderr and the JSON contract of docs/json.md.

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// Runs `leeway ARGS` from the workspace root, so paths read `examples/models/..`.
fn leeway(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_leeway"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .env_remove("NO_COLOR")
        .output()
        .expect("run leeway")
}

fn code(o: &Output) -> i32 {
    o.status.code().expect("exit code")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &Output) -> Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("stdout is not JSON ({e}): {}", stdout(o)))
}

fn no_panic(o: &Output) {
    assert!(!stderr(o).contains("panicked"), "{}", stderr(o));
}

#[test]
fn identifiable_model_exits_0() {
    let o = leeway(&["check", "examples/models/ship.som"]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("Φ: θ regressors (17 parameters)"), "{out}");
    assert!(
        out.contains("identifiable from one experiment of any sign pattern"),
        "{out}"
    );
    assert!(!stderr(&o).contains("error"), "{}", stderr(&o));
    // Piped output carries no colour codes.
    assert!(!stderr(&o).contains('\u{1b}') && !out.contains('\u{1b}'));
}

#[test]
fn valid_but_unidentifiable_model_exits_1() {
    let o = leeway(&["check", "examples/models/ship_iv2.som"]);
    no_panic(&o);
    assert_eq!(code(&o), 1);
    let err = stderr(&o);
    assert!(err.contains("error[unidentifiable-combination]: θ is not identifiable: `X_uu` and `W_uu` enter only as X_uu + W_uu"), "{err}");
    assert!(
        err.contains("┌─ examples/models/ship_iv2.som:16:44"),
        "{err}"
    );
    assert!(stdout(&o).contains("NOT identifiable from any set of experiments"));
}

#[test]
fn aggregate_makes_ship_iv2_exit_0() {
    let o = leeway(&["check", "--aggregate", "examples/models/ship_iv2.som"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(stdout(&o).contains("X_uu estimates X_uu + W_uu"));
    assert!(stderr(&o).contains("warning[aggregated-combination]"));
}

#[test]
fn syntax_and_semantic_errors_exit_2() {
    for (file, expect) in [
        (
            "examples/models/broken/syntax-power.som",
            "error[syntax]: expected a declaration or an operator, found `^`",
        ),
        (
            "examples/models/broken/order-too-high.som",
            "error[order-too-high]",
        ),
        (
            "examples/models/broken/common-input-term.som",
            "`X_t` and `W_t`",
        ),
    ] {
        let o = leeway(&["check", file]);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{file}");
        assert!(stderr(&o).contains(expect), "{file}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!("`{file}` was not checked")),
            "{}",
            stderr(&o)
        );
        assert!(
            stdout(&o).is_empty(),
            "{file}: nothing on stdout for an invalid model"
        );
    }
}

#[test]
fn missing_file_exits_2_naming_the_path() {
    let o = leeway(&["check", "no/such/model.som"]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    assert_eq!(
        stderr(&o).trim(),
        "error[io]: cannot read `no/such/model.som`: no such file"
    );
    let o = leeway(&["check", "--json", "no/such/model.som"]);
    assert_eq!(code(&o), 2);
    let v = json(&o);
    assert_eq!(v["errors"][0]["code"], "io");
    assert_eq!(
        v["errors"][0]["message"],
        "cannot read `no/such/model.som`: no such file"
    );
    let o = leeway(&["check", "examples/models"]);
    assert_eq!(code(&o), 2, "a directory is not a model");
    no_panic(&o);
}

#[test]
fn usage_errors_exit_2_and_help_exits_0() {
    assert_eq!(code(&leeway(&[])), 2);
    assert_eq!(code(&leeway(&["check"])), 2);
    assert_eq!(code(&leeway(&["check", "--frobnicate", "x.som"])), 2);
    let help = leeway(&["check", "--help"]);
    assert_eq!(code(&help), 0);
    assert!(
        stdout(&help).contains("--pattern <SPEC>"),
        "{}",
        stdout(&help)
    );
}

#[test]
fn patterns_select_the_experiments() {
    let one = leeway(&[
        "check",
        "examples/models/rov.som",
        "--pattern",
        "water.v:+,r:+",
    ]);
    assert_eq!(code(&one), 1, "{}", stderr(&one));
    assert!(
        stderr(&one).contains("`Y_vr` and `Y_rv` enter only as Y_vr + Y_rv"),
        "{}",
        stderr(&one)
    );
    let same = leeway(&[
        "check",
        "examples/models/rov.som",
        "--pattern",
        "r:+",
        "--pattern",
        "water.v:-,r:-",
    ]);
    assert_eq!(
        code(&same),
        1,
        "same sign(water.v)·sign(r) in both experiments"
    );
    let two = leeway(&[
        "check",
        "examples/models/rov.som",
        "--pattern",
        "r:+",
        "--pattern",
        "r:-",
    ]);
    assert_eq!(code(&two), 0, "{}", stderr(&two));
    assert!(
        stdout(&two).contains("identifiable from 2 experiments"),
        "{}",
        stdout(&two)
    );
    let bad = leeway(&["check", "examples/models/rov.som", "--pattern", "water.w:+"]);
    assert_eq!(code(&bad), 2);
    assert_eq!(
        stderr(&bad).trim(),
        "error[invalid-pattern]: --pattern `water.w:+`: `water.w` is not a sign argument of this model; its sign arguments are water.u, water.v, r"
    );
    let bad_json = leeway(&[
        "check",
        "--json",
        "examples/models/rov.som",
        "--pattern",
        "r",
    ]);
    assert_eq!(code(&bad_json), 2);
    assert_eq!(json(&bad_json)["errors"][0]["code"], "invalid-pattern");
}

/// Every key of the contract of docs/json.md, with its type.
fn assert_contract(v: &Value) {
    for key in [
        "model",
        "outputs",
        "parameters",
        "identifiable",
        "regressors",
        "nuisance",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert!(v["model"].is_string() || v["model"].is_null());
    assert!(
        v["outputs"]
            .as_array()
            .is_some_and(|a| a.iter().all(Value::is_string))
    );
    assert!(
        v["parameters"]
            .as_array()
            .is_some_and(|a| a.iter().all(Value::is_string))
    );
    assert!(v["identifiable"].is_boolean());
    for r in v["regressors"].as_array().expect("regressors") {
        for key in ["parameter", "output", "expression"] {
            assert!(r[key].is_string(), "regressor {key}: {r}");
        }
    }
    let n = &v["nuisance"];
    assert!(n["before"].is_u64() && n["after"].is_u64());
    for k in n["kept"].as_array().expect("kept") {
        assert!(k["name"].is_string() && k["estimates"].is_string(), "{k}");
    }
    assert!(v["required_sign_patterns"].is_array());
    assert!(v["omitted"].is_u64(), "omitted: {v}");
    for key in ["notes", "errors"] {
        for d in v[key].as_array().unwrap_or_else(|| panic!("{key}")) {
            for f in ["code", "message", "severity"] {
                assert!(d[f].is_string(), "{key}.{f}: {d}");
            }
            assert!(d["location"].is_string() || d["location"].is_null());
        }
    }
}

#[test]
fn json_of_the_ship() {
    let o = leeway(&["check", "--json", "examples/models/ship.som"]);
    assert_eq!(code(&o), 0);
    let v = json(&o);
    assert_contract(&v);
    assert_eq!(v["model"], "Ship");
    assert_eq!(v["outputs"], serde_json::json!(["u", "v", "r"]));
    assert_eq!(v["parameters"].as_array().map(Vec::len), Some(17));
    assert_eq!(v["identifiable"], true);
    let regressors = v["regressors"].as_array().expect("regressors");
    let per_output = |o: &str| regressors.iter().filter(|r| r["output"] == o).count();
    assert_eq!(
        (per_output("u"), per_output("v"), per_output("r")),
        (5, 6, 6)
    );
    let x_uu = regressors
        .iter()
        .find(|r| r["parameter"] == "X_uu")
        .expect("X_uu");
    assert_eq!(x_uu["expression"], "s[water.u]*u^2");
    assert_eq!(x_uu["term"], "water.u*|water.u|");
    assert_eq!(regressors.iter().filter(|r| r["kind"] == "phi2").count(), 3);
    assert_eq!(
        (
            v["nuisance"]["before"].as_u64(),
            v["nuisance"]["after"].as_u64()
        ),
        (Some(32), Some(24))
    );
    assert_eq!(
        v["required_sign_patterns"],
        serde_json::json!([{"water.u": "+", "water.v": "+"}])
    );
    assert_eq!(v["errors"], serde_json::json!([]));
    assert_eq!(
        v["notes"].as_array().map(Vec::len),
        Some(3),
        "three common state terms"
    );
}

#[test]
fn json_of_an_unidentifiable_model() {
    let o = leeway(&["check", "--json", "examples/models/ship_iv2.som"]);
    assert_eq!(code(&o), 1);
    let v = json(&o);
    assert_contract(&v);
    assert_eq!(v["identifiable"], false);
    assert_eq!(v["required_sign_patterns"], serde_json::json!([]));
    let errors = v["errors"].as_array().expect("errors");
    assert_eq!(errors.len(), 3);
    assert_eq!(errors[0]["code"], "unidentifiable-combination");
    assert_eq!(errors[0]["location"], "examples/models/ship_iv2.som:16:44");
    let separations = v["separations"].as_array().expect("separations");
    assert!(
        separations
            .iter()
            .any(|s| s["parameters"] == serde_json::json!(["N_uv", "W_uv"])
                && s["sign_patterns"].is_null())
    );
}

#[test]
fn json_on_a_syntax_error_is_still_json() {
    let o = leeway(&["check", "--json", "examples/models/broken/syntax-power.som"]);
    assert_eq!(code(&o), 2);
    let v = json(&o);
    assert_contract(&v);
    assert_eq!(v["model"], Value::Null);
    assert_eq!(v["identifiable"], false);
    let e = &v["errors"][0];
    assert_eq!(e["code"], "syntax");
    assert_eq!(
        e["location"],
        "examples/models/broken/syntax-power.som:9:25"
    );
    assert_eq!(
        (e["line"].as_u64(), e["column"].as_u64()),
        (Some(9), Some(25))
    );
    assert!(e["help"].as_str().is_some_and(|h| h.contains("powers")));
    // A semantic error keeps the model's name.
    let o = leeway(&[
        "check",
        "--json",
        "examples/models/broken/missing-equation.som",
    ]);
    assert_eq!(code(&o), 2);
    assert_eq!(json(&o)["model"], "Broken");
}

#[test]
fn json_of_the_rov() {
    let o = leeway(&["check", "--json", "examples/models/rov.som"]);
    assert_eq!(code(&o), 0);
    let v = json(&o);
    assert_contract(&v);
    assert_eq!(
        v["required_sign_patterns"],
        serde_json::json!([
            {"water.u": "+", "water.v": "+"},
            {"water.u": "+", "water.v": "-"}
        ])
    );
    insta::assert_snapshot!(stdout(&o));
}

/// Nine independent moduli (issue "Hardened against every input", item 3):
/// identifiable from all + then all − (exit 0), not "not identifiable".
#[test]
fn nine_independent_moduli_exit_0_with_two_experiments() {
    let dir = crate::common::Scratch::new("nine");
    let path = dir.path("nine.som");
    let mut src = String::from("model Nine {\n    step 0.1\n    state ");
    src += &(0..9)
        .map(|i| format!("x{i}"))
        .collect::<Vec<_>>()
        .join(", ");
    src += "\n    input t\n";
    for i in 0..9 {
        src += &format!("    der x{i} = A{i}*x{i} + D{i}*|x{i}| + B{i}*t\n");
    }
    src += "}\n";
    std::fs::write(&path, src).expect("write model");
    let file = path.to_string_lossy().into_owned();
    let o = leeway(&["check", &file]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(
        stdout(&o).contains("identifiable from 2 experiments"),
        "{}",
        stdout(&o)
    );
    let v = json(&leeway(&["check", "--json", &file]));
    assert_eq!(v["verdict"], "identifiable");
    assert!(v["search_cut"].is_null());
    let required = v["required_sign_patterns"].as_array().expect("array");
    assert_eq!(required.len(), 2);
    assert!(
        required[0]
            .as_object()
            .expect("map")
            .values()
            .all(|s| s == "+")
    );
    assert!(
        required[1]
            .as_object()
            .expect("map")
            .values()
            .all(|s| s == "-")
    );
}

/// A search cut by its budget: verdict `undecided`, exit 0 (θ is proven
/// identifiable from the experiments named), never exit 1.
#[test]
fn a_cut_search_is_undecided_and_exits_0() {
    let o = leeway(&["check", "--json", "examples/models/broken/search-cut.som"]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stdout(&o));
    let v = json(&o);
    assert_contract(&v);
    assert_eq!(v["identifiable"], true);
    assert_eq!(v["verdict"], "undecided");
    assert!(
        v["search_cut"]
            .as_str()
            .is_some_and(|s| s.contains("13 interacting sign arguments")),
        "{}",
        v["search_cut"]
    );
    assert_eq!(v["warnings"][0]["code"], "search-cut");
    let o = leeway(&["check", "examples/models/ship_iv2.som", "--json"]);
    assert_eq!(code(&o), 1);
    assert_eq!(json(&o)["verdict"], "not-identifiable");
    let o = leeway(&["check", "examples/models/ship.som", "--json"]);
    assert_eq!(json(&o)["verdict"], "identifiable");
}

/// A scratch file under the target directory, unique to this test.
fn scratch(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("check-limits");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write scratch file");
    path
}

fn check_path(path: &Path, json: bool) -> Output {
    let p = path.to_str().expect("utf-8 path");
    if json {
        leeway(&["check", "--json", p])
    } else {
        leeway(&["check", p])
    }
}

#[test]
fn a_non_utf8_model_is_one_located_error() {
    // Regression: no line:col and no hint.
    let path = scratch(
        "latin1.som",
        b"model M {\n    state u // caf\xe9\n    der u = X*u\n}\n",
    );
    let o = check_path(&path, false);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(
        err.contains("error[not-utf8]: the model file is not UTF-8 text: byte 0xe9"),
        "{err}"
    );
    assert!(err.contains("latin1.som:2:19"), "{err}");
    assert!(err.contains("help: save the file as UTF-8"), "{err}");
    assert_eq!(err.matches("error[").count(), 1, "{err}");
    let v = json(&check_path(&path, true));
    assert_eq!(v["errors"][0]["code"], "not-utf8");
    assert_eq!(v["errors"][0]["line"], 2);
    assert_eq!(v["errors"][0]["column"], 19);
}

#[test]
fn control_bytes_are_escaped_with_a_caret() {
    let path = scratch("nul.som", b"model M {\n    state u\0\n    der u = X*u\n}\n");
    let o = check_path(&path, false);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(!err.contains('\0'), "{err:?}");
    assert!(
        err.contains("error[syntax]: expected a declaration, found `\\u{0}`"),
        "{err}"
    );
    assert!(err.contains("nul.som:2:12"), "{err}");
    assert!(err.contains("2 │     state u\\u{0}"), "{err}");
    assert!(err.contains("  │            ^"), "{err}");
}

#[test]
fn an_oversized_model_is_refused_before_it_is_read() {
    // Regression: a 6.7 GB file took 6.6 GB of memory. A sparse 8 GiB file is
    // refused from its metadata (reading it would take seconds and gigabytes).
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("check-limits");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join("huge.som");
    let f = std::fs::File::create(&path).expect("create");
    f.set_len(8 << 30).expect("sparse file");
    let start = std::time::Instant::now();
    let o = check_path(&path, false);
    assert!(start.elapsed() < std::time::Duration::from_secs(5));
    let _ = std::fs::remove_file(&path);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(err.contains("error[file-too-large]: the model file is 8589934592 bytes; at most 1048576 are accepted"), "{err}");
}

#[test]
fn floods_are_capped() {
    // Regression: `state u` 4,000 times on one line gave 257 MB of stderr.
    let src = format!("model M {{ {}\n der u = X*u }}\n", "state u ".repeat(4000));
    let o = check_path(&scratch("dup.som", src.as_bytes()), false);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    // The line is printed once: one diagnostic marks the first 8 and counts the rest.
    assert!(err.len() < 2 * 1024, "{} bytes:\n{err}", err.len());
    assert_eq!(
        err.matches("error[duplicate-declaration]").count(),
        1,
        "{err}"
    );
    assert_eq!(err.matches("\n1 │").count(), 1, "{err}");
    assert!(
        err.contains("`u` is declared twice (3999 times on this line)"),
        "{err}"
    );
    assert!(
        err.contains("… and 3991 more on this line, not marked"),
        "{err}"
    );
    assert!(
        err.ends_with("was not checked: 3999 errors\n"),
        "{}",
        &err[err.len() - 300..]
    );
    let v = json(&check_path(&scratch("dup.som", src.as_bytes()), true));
    assert_eq!(v["errors"].as_array().map(Vec::len), Some(50));
    assert_eq!(v["omitted"], 3949);
    // `X*(u+v)` with 12 factors (117 bytes) gave 4,097 errors and 1.5 MB.
    let src = format!(
        "model M {{ state u, v\n der u = X*{}\n der v = Y*v }}\n",
        ["(u+v)"; 12].join("*")
    );
    let o = check_path(&scratch("f12.som", src.as_bytes()), false);
    let err = stderr(&o);
    assert_eq!(err.matches("error[").count(), 1, "{err}");
    assert!(
        err.contains("note: 4095 more terms of this expression have the same problem"),
        "{err}"
    );
    // 500 parameters of one regressor: one short message (it was 96 KB).
    let terms: Vec<String> = (0..499).map(|i| format!("P{i}*u")).collect();
    let src = format!(
        "model W {{\n state u\n input t\n der u = B*t + {}\n}}\n",
        terms.join(" + ")
    );
    let path = scratch("wide.som", src.as_bytes());
    let o = check_path(&path, false);
    assert_eq!(code(&o), 1);
    let err = stderr(&o);
    assert!(err.len() < 2 * 1024, "{} bytes:\n{err}", err.len());
    assert!(err.contains("`P7` and 491 more enter only as"), "{err}");
    let v = json(&check_path(&path, true));
    let message = v["errors"][0]["message"].as_str().unwrap_or_default();
    assert!(message.len() < 300, "{message}");
    assert_eq!(
        v["unidentifiable"][0]["parameters"]
            .as_array()
            .map(Vec::len),
        Some(499)
    );
}

/// 100 unmeasured media (each its own drag in every equation) and 10⁴
/// plain states with moduli: exact verdicts (no search cut), short notes.
/// Their time is measured on the release binary (docs/performance.md), not here.
#[test]
fn large_models_get_exact_verdicts_and_short_reports() {
    let n = 100;
    let mut src = String::from(
        "model Media {\n step 0.1\n state u, v, r\n input tau1, tau2, tau3\n heading psi integrates r\n",
    );
    for i in 0..n {
        src += &format!(" disturbance d{i} unmeasured earth(n{i}, e{i})\n m{i} = relative(d{i})\n");
    }
    let sum =
        |f: &dyn Fn(usize) -> String| (0..n).map(|i| format!(" + {}", f(i))).collect::<String>();
    src += &format!(
        " der u = X_u*u + X_tau*tau1{}\n",
        sum(&|i| format!("U{i}*m{i}.u*|m{i}.u|"))
    );
    src += &format!(
        " der v = Y_v*v + Y_tau*tau2{}\n",
        sum(&|i| format!("V{i}*m{i}.v*|m{i}.v|"))
    );
    src += &format!(
        " der r = N_r*r + N_tau*tau3{}\n}}\n",
        sum(&|i| format!("R{i}*m{i}.u*|m{i}.v|"))
    );
    let v = json(&check_path(&scratch("media.som", src.as_bytes()), true));
    assert_eq!(v["verdict"], "identifiable", "{}", v["search_cut"]);
    assert_eq!(
        v["required_sign_patterns"].as_array().map(Vec::len),
        Some(n)
    );

    let n = 10_000;
    let states: Vec<String> = (0..n).map(|i| format!("x{i}")).collect();
    let mut src = format!("model S {{\n state {}\n", states.join(", "));
    for i in 0..n {
        src += &format!(" der x{i} = A{i}*x{i} + D{i}*|x{i}|\n");
    }
    src += "}\n";
    let o = check_path(&scratch("states.som", src.as_bytes()), false);
    no_panic(&o);
    assert_eq!(code(&o), 0);
    let err = stderr(&o);
    assert!(err.len() < 8 * 1024, "{} bytes", err.len());
    assert!(
        err.contains("note[required-experiments]: θ is identifiable from 2 experiments"),
        "{err}"
    );
    let out = stdout(&o);
    assert!(
        out.starts_with("model S: 10000 states (x0, x1, x2, x3, x4, x5, x6, x7, … (9992 more))"),
        "{}",
        &out[..200]
    );
}

/// A candidate model: `check --json` carries the lines the text prints —
/// the candidates, the full set's verdict and the exchangeable candidates
/// (two candidates for one regressor, a candidate duplicating a required
/// term); a model without candidates has `candidates: null`.
#[test]
fn json_carries_the_candidates_and_the_exchangeable_ones() {
    let dir = crate::common::Scratch::new("check-candidates");
    let src = "model M {\n    state u, v\n    input tau\n    der u = X_u*u + ?X_a*u*|u| + ?X_b*|u|*u + X_t*tau + ?X_v*v\n    der v = Y_v*v + Y_u*u + ?Y_w*u\n}\n";
    let model = dir.write("cand.som", src);
    let o = leeway(&["check", "--json", &model]);
    no_panic(&o);
    let v = json(&o);
    assert_contract(&v);
    assert_eq!(
        v["candidates"],
        serde_json::json!({
            "candidates": ["X_a", "X_b", "X_v", "Y_w"],
            "full_set": "not-identifiable",
            "exchangeable": [
                {"candidate": "X_b", "stands_for": "X_a"},
                {"candidate": "Y_w", "stands_for": "Y_u"}
            ],
            "refused": null
        })
    );
    assert_eq!(v["candidates"]["full_set"], v["verdict"]);
    let text = stdout(&leeway(&["check", &model]));
    assert!(
        text.contains("candidates: 4 (X_a, X_b, X_v, Y_w)\n  the full candidate set: not-identifiable\n  exchangeable: `X_b` can stand for `X_a` (select keeps `X_a`)\n  exchangeable: `Y_w` can stand for `Y_u` (select keeps `Y_u`)\n"),
        "{text}"
    );
    // A candidate beside another parameter in one term: refused, said in both.
    let shared = dir.write(
        "shared.som",
        "model M {\n    state u\n    input t\n    der u = (X + ?Y)*u + Z*t\n}\n",
    );
    let v = json(&leeway(&["check", "--json", &shared]));
    assert_eq!(v["candidates"]["candidates"], serde_json::json!([]));
    let refused = v["candidates"]["refused"].as_str().unwrap_or_default();
    assert!(
        refused.starts_with("4:13: a term of `u` with candidate `Y` also holds `X` and `Y`"),
        "{refused}"
    );
    assert!(stdout(&leeway(&["check", &shared])).contains(&format!("candidates: {refused}\n")));
    let v = json(&leeway(&["check", "--json", "examples/models/rov.som"]));
    assert!(v["candidates"].is_null(), "{}", v["candidates"]);
}
