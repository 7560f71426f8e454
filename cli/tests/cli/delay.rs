//! Dead times on the command line: `leeway simulate` of a model with dead
//! times starts its output at the longest one, `leeway estimate` reports the
//! equations each experiment drops, and `--scan-delay` finds a dead time
//! (its curve in text and JSON), a bad range being one usage error.

use crate::common::{Scratch, code, json, leeway, no_panic, stderr, stdout};

const THRUSTER: &str = "tests/models/thruster.som";

/// An input a level held for 5 to 60 samples, then another of either sign
/// (a fixed linear congruential sequence: no randomness in the test).
fn input_csv(n: usize) -> String {
    let mut state: u64 = 0x5eed;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as f64 / (1u64 << 31) as f64
    };
    let mut columns = [Vec::new(), Vec::new()];
    for (c, scale) in columns.iter_mut().zip([20.0, 10.0]) {
        while c.len() < n {
            let level = scale * (2.0 * next() - 1.0);
            let run = 5 + (next() * 56.0) as usize;
            c.extend(std::iter::repeat_n(level, run));
        }
    }
    let mut text = "time,tau_x,tau_n,u,r\n".to_string();
    for (k, (a, b)) in columns[0].iter().zip(&columns[1]).take(n).enumerate() {
        let x0 = if k == 0 { "0" } else { "" };
        text.push_str(&format!("{:.1},{a},{b},{x0},{x0}\n", k as f64 * 0.1));
    }
    text
}

/// Simulated data of the thruster with its true dead times (10 and 3
/// samples), measured with seeded noise.
fn data(dir: &Scratch) -> String {
    let input = dir.write("in.csv", &input_csv(1200));
    let params = dir.write(
        "true.json",
        r#"{"X_u": -0.2, "X_uu": -0.05, "X_tau": 0.05, "N_r": -0.3, "N_tau": 0.02}"#,
    );
    let out = dir.path("data.csv").display().to_string();
    let o = leeway(&[
        "simulate",
        THRUSTER,
        "--params",
        &params,
        "--input",
        &input,
        "--noise",
        "u=0.02,r=0.005",
        "--seed",
        "3",
        "--out",
        &out,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap_or_default();
    // The simulation starts at the longest dead time: 10 samples, 1 s in.
    assert!(
        text.lines().nth(1).is_some_and(|l| l.starts_with("1.0,")),
        "{text:.200}"
    );
    assert_eq!(text.lines().count(), 1 + 1200 - 10);
    out
}

#[test]
fn scan_delay_finds_the_dead_time_and_reports_its_curve() {
    let dir = Scratch::new("scan-delay");
    let data = data(&dir);
    let o = leeway(&[
        "estimate",
        THRUSTER,
        "--data",
        &data,
        "--scan-delay",
        "tau_x=0..1.2s",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("dead time of tau_x (scanned by fit)"),
        "{text}"
    );
    let chosen: Vec<&str> = text.lines().filter(|l| l.contains("<- chosen")).collect();
    assert_eq!(chosen.len(), 1, "{text}");
    assert!(chosen[0].trim_start().starts_with("10 "), "{text}");
    assert!(
        text.contains("dropped at start  data: 11 equations (dead time 10, method 1)"),
        "{text}"
    );
    let o = leeway(&[
        "estimate",
        THRUSTER,
        "--data",
        &data,
        "--scan-delay",
        "tau_x=0..12",
        "--scan-by",
        "residual",
        "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let j = json(&o);
    let scan = &j["delay_scan"];
    assert_eq!(scan["input"], "tau_x");
    assert_eq!(scan["by"], "residual");
    assert_eq!(scan["samples"], 10);
    assert_eq!(scan["curve"].as_array().map(Vec::len), Some(13));
    assert_eq!(j["diagnostics"]["dropped_at_start"][0]["equations"], 11);
    let x_tau = j["estimates"]["X_tau"].as_f64().unwrap_or(f64::NAN);
    assert!((x_tau - 0.05).abs() < 0.0025, "X_tau = {x_tau}");
    // Without a scan, the JSON has no `delay_scan`.
    let o = leeway(&["estimate", THRUSTER, "--data", &data, "--json"]);
    assert!(json(&o).get("delay_scan").is_none());
}

#[test]
fn a_bad_scan_range_is_one_usage_error() {
    let dir = Scratch::new("scan-delay-bad");
    let data = dir.write("d.csv", "time,u,r,tau_x,tau_n\n0,0,0,0,0\n");
    for (range, says) in [
        ("tau_x=0..500", "a scan tries at most 200"),
        ("u=0..3", "`u` is not an input of the model"),
        (
            "tau_x=0..0.25s",
            "0.25 s is no whole number of sample times of 0.1 s",
        ),
        ("tau_x", "is not `INPUT=LO..HI`"),
    ] {
        let o = leeway(&["estimate", THRUSTER, "--data", &data, "--scan-delay", range]);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{range}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains(says), "{range}: {err}");
        assert_eq!(err.matches("error").count(), 1, "{range}: {err}");
    }
}

#[test]
fn a_dead_time_in_seconds_that_the_data_cannot_sample_is_a_located_error() {
    let dir = Scratch::new("delay-seconds");
    let model = dir.write(
        "m.som",
        "model M { state u input a delay a 0.25 s der u = X*u + A*a nominal { X = -0.1, A = 1 } }",
    );
    let mut csv = "time,u,a\n".to_string();
    for k in 0..40 {
        csv.push_str(&format!("{:.1},{},{}\n", k as f64 * 0.1, k % 3, k % 5));
    }
    let data = dir.write("d.csv", &csv);
    let o = leeway(&["estimate", &model, "--data", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("error[invalid-delay]"), "{err}");
    assert!(err.contains("d.csv"), "{err}");
    assert!(err.contains("2.500 sample times of 0.1 s"), "{err}");
    // At 0.05 s the same dead time is 5 samples: the data load.
    let mut csv = "time,u,a\n".to_string();
    for k in 0..40 {
        csv.push_str(&format!("{:.2},{},{}\n", k as f64 * 0.05, k % 3, k % 5));
    }
    let data = dir.write("d05.csv", &csv);
    let o = leeway(&["estimate", &model, "--data", &data, "--json"]);
    no_panic(&o);
    assert!(!stderr(&o).contains("invalid-delay"), "{}", stderr(&o));
    let j = json(&o);
    assert!(
        j["errors"]
            .as_array()
            .is_none_or(|e| e.iter().all(|e| e["code"] != "invalid-delay")),
        "{j}"
    );
}
