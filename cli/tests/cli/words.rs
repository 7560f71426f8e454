//! End-to-end tests of the words a newcomer meets: warnings of two lines at
//! most (the full text under `--verbose` and in JSON), a help line and
//! `--strict` for a sign assumption the data break, a parameter multiplying
//! a difference, coded file errors, help texts, an unwritable `--out`.

use crate::common::{
    SHIP, Scratch, code, csv_text, estimation_csv, json, leeway, no_panic, ship, stderr, stdout,
};
use leeway_scenarios::study;

/// Longest line a warning may print (the headline with its `warning: `).
const WIDTH: usize = 120;

/// Every warning of `err` (a `warning:` line and its `= ...` lines): at most
/// two lines without `--verbose`, none wider than [`WIDTH`].
fn assert_short_warnings(err: &str) {
    let mut lines = err.lines().peekable();
    while let Some(line) = lines.next() {
        if !line.starts_with("warning") {
            continue;
        }
        let mut block = vec![line];
        while let Some(next) = lines.next_if(|l| l.starts_with("  = ")) {
            block.push(next);
        }
        assert!(
            block.len() <= 2,
            "a warning of {} lines:\n{}",
            block.len(),
            block.join("\n")
        );
        for l in &block {
            assert!(
                l.chars().count() <= WIDTH,
                "a warning line of {} characters:\n{l}",
                l.chars().count()
            );
        }
    }
}

#[test]
fn quick_start_and_study_warnings_fit_two_lines() {
    let dir = Scratch::new("words-short");
    let model = ship();
    let zigzag = csv_text(&model, &[&study::validation_experiment(&model, 600)]);
    for (name, text) in [
        ("low.csv", estimation_csv(3000, 1.0, 1)),
        ("high.csv", estimation_csv(3000, 10.0, 1)),
        ("zigzag.csv", zigzag),
    ] {
        let data = dir.write(name, &text);
        let o = leeway(&["estimate", SHIP, "--data", &data]);
        no_panic(&o);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        assert_short_warnings(&stderr(&o));
        // The low wind's warnings, in full only when asked.
        if name == "low.csv" {
            let err = stderr(&o);
            assert!(
                err.contains("warning: `W_uu` held at 0: the wind barely varies"),
                "{err}"
            );
            assert!(!err.contains("its column equals"), "{err}");
            let verbose = stderr(&leeway(&["estimate", SHIP, "--data", &data, "--verbose"]));
            assert!(
                verbose.contains("= detail: W_uu is not separately excited: its column equals"),
                "{verbose}"
            );
            let j = json(&leeway(&["estimate", SHIP, "--data", &data, "--json"]));
            let full = j["warnings"].as_array().cloned().unwrap_or_default();
            let summaries = j["warning_summaries"]
                .as_array()
                .cloned()
                .unwrap_or_default();
            assert_eq!(full.len(), summaries.len());
            assert!(!full.is_empty());
            for (w, s) in full.iter().zip(&summaries) {
                assert_eq!(w, &s["detail"], "{s}");
                assert!(s["summary"].as_str().is_some_and(|t| !t.is_empty()), "{s}");
            }
            assert_eq!(summaries[0]["code"], "not-excited");
            assert_eq!(summaries[0]["can_bias"], true);
        }
    }
}

#[test]
fn a_zigzag_whose_sway_changes_sign_says_what_to_do_and_fails_under_strict() {
    let dir = Scratch::new("words-zigzag");
    let model = ship();
    let data = dir.write(
        "zigzag.csv",
        &csv_text(&model, &[&study::validation_experiment(&model, 600)]),
    );
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let err = stderr(&o);
    let mut lines = err.lines();
    let headline = lines
        .find(|l| l.contains("water.v changes sign"))
        .unwrap_or_else(|| panic!("no A7 warning:\n{err}"));
    assert!(headline.contains("can be badly biased"), "{headline}");
    let help = lines.next().unwrap_or_default();
    assert!(
        help.starts_with("  = help: split the run where water.v changes sign")
            && help.contains("--strict"),
        "{help}"
    );
    let strict = leeway(&["estimate", SHIP, "--data", &data, "--strict"]);
    assert_eq!(code(&strict), 1, "{}", stderr(&strict));
    assert!(
        stderr(&strict).contains("error[sign-violation]"),
        "{}",
        stderr(&strict)
    );
}

#[test]
fn strict_fails_on_a_parameter_held_for_lack_of_excitation() {
    let dir = Scratch::new("words-strict");
    let data = dir.write("low.csv", &estimation_csv(3000, 1.0, 1));
    let o = leeway(&["estimate", SHIP, "--data", &data, "--strict"]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains(
            "error[biasing-warning]: --strict: a warning can bias the estimate: `W_uu` held at 0"
        ),
        "{err}"
    );
    let j = json(&leeway(&[
        "estimate", SHIP, "--data", &data, "--strict", "--json",
    ]));
    assert_eq!(j["errors"][0]["code"], "biasing-warning");
}

#[test]
fn nuisance_status_is_a_word_with_its_reason_once() {
    let dir = Scratch::new("words-status");
    let data = dir.write("low.csv", &estimation_csv(3000, 1.0, 1));
    let out = stdout(&leeway(&["estimate", SHIP, "--data", &data]));
    let nuisance = out.split("nuisance parameters").nth(1).unwrap_or_default();
    let nuisance = nuisance.split("\n\n").next().unwrap_or_default();
    assert!(!nuisance.contains("dropped (structurally"), "{nuisance}");
    assert_eq!(
        nuisance.matches("dropped: structurally dependent").count(),
        1,
        "{nuisance}"
    );
}

#[test]
fn a_parameter_multiplying_a_difference_shows_the_difference() {
    let o = leeway(&["check", "tests/models/catamaran.som"]);
    no_panic(&o);
    let out = stdout(&o);
    let regressors = out
        .split("Φ: θ regressors")
        .nth(1)
        .and_then(|s| s.split("\n\n").next())
        .unwrap_or_default();
    insta::assert_snapshot!("catamaran_regressors", regressors);
    let j = json(&leeway(&["check", "tests/models/catamaran.som", "--json"]));
    let n_t = j["regressors"]
        .as_array()
        .and_then(|r| r.iter().find(|x| x["parameter"] == "N_T"))
        .cloned()
        .unwrap_or_default();
    assert_eq!(n_t["term"], "T_p - T_s", "{n_t}");
    assert_eq!(n_t["expression"], "T_p - T_s", "{n_t}");
}

#[test]
fn file_errors_have_their_code_and_help_texts_say_what_is_read() {
    let o = leeway(&["check", "nope.som"]);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).starts_with("error[io]: cannot read `nope.som`"),
        "{}",
        stderr(&o)
    );
    let help = stdout(&leeway(&["estimate", "--help"]));
    assert!(help.contains("CSV or Parquet"), "{help}");
    let help = stdout(&leeway(&["reproduce", "--help"]));
    assert!(
        help.contains("[default: 1000,2000,3000,4000,5000]"),
        "{help}"
    );
}

#[test]
fn an_unwritable_out_fails_before_the_study() {
    let start = std::time::Instant::now();
    let o = leeway(&["reproduce", "--out", "/proc/leeway-cannot-write"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("error[io]"), "{}", stderr(&o));
    // Nothing of the study ran: no table on stdout, and quickly.
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    assert!(start.elapsed().as_secs() < 20);
}

#[test]
fn validate_on_one_experiment_has_no_mean() {
    let dir = Scratch::new("words-one");
    let model = ship();
    let data = dir.write(
        "val.csv",
        &csv_text(&model, &[&study::validation_experiment(&model, 300)]),
    );
    let params = dir.write("theta.json", &crate::common::true_params());
    let o = leeway(&["validate", SHIP, "--params", &params, "--data", &data]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    assert!(!out.contains("mean"), "{out}");
}
