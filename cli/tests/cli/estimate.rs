//! End-to-end tests of `leeway estimate`, `simulate` and `validate`: the
//! built binary on synthetic ship data written as CSV by the tests themselves
//! (the paper's study, fixed seeds), every malformed-CSV class with its
//! location and exit code 2, the JSON contract of docs/json.md, the parameter
//! file round trip and the heading's unit check.

use leeway_scenarios::study;
use serde_json::Value;

use crate::common::*;

#[test]
fn estimate_prints_the_json_contract() {
    let dir = Scratch::new("contract");
    let data = dir.write("run.csv", &estimation_csv(5000, 10.0, 201));
    let o = leeway(&[
        "estimate", SHIP, "--data", &data, "--method", "iv3", "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    for key in [
        "method",
        "estimates",
        "std_errors",
        "disturbances",
        "sign_patterns",
        "diagnostics",
        "warnings",
        "errors",
        "nuisance",
        "parameters",
        "model",
    ] {
        assert!(v.get(key).is_some(), "missing `{key}`: {v}");
    }
    assert_eq!(v["method"], "iv3");
    assert_eq!(v["model"], "Ship");
    assert_eq!(v["errors"], serde_json::json!([]));
    let estimates = v["estimates"].as_object().cloned().unwrap_or_default();
    let names: Vec<&String> = estimates.keys().collect();
    assert_eq!(names.len(), 17);
    // Model order, not alphabetical.
    let text = stdout(&o);
    let at = |key: &str| text.find(&format!("\"{key}\":")).unwrap_or(usize::MAX);
    assert!(at("X_u") < at("X_vr") && at("X_vr") < at("N_r"), "{text}");
    // The thrust gains are the best-determined parameters: within 10 % of θ0.
    for (name, truth) in [("X_tau", 0.02), ("Y_tau", 0.02), ("N_tau", 0.0003)] {
        let est = v["estimates"][name].as_f64().unwrap_or(f64::NAN);
        assert!((est - truth).abs() < 0.1 * truth, "{name} = {est}");
        assert!(v["std_errors"][name].as_f64().is_some_and(|s| s > 0.0));
    }
    // The current's mean (0.2, 0.2) within three standard errors.
    for c in ["north", "east"] {
        let m = &v["disturbances"]["current"][c];
        let (mean, se) = (
            m["mean"].as_f64().unwrap_or(f64::NAN),
            m["std_error"].as_f64().unwrap_or(f64::NAN),
        );
        assert!((mean - 0.2).abs() < 3.0 * se, "current.{c}: {mean} ± {se}");
    }
    // The covariance of θ: rows and columns in the model's order, symmetric,
    // its diagonal the squared standard errors (√ of it, bit for bit).
    let cov = v["covariance"].as_object().cloned().unwrap_or_default();
    assert_eq!(cov.keys().collect::<Vec<_>>(), names);
    for (a, row) in &cov {
        let row = row.as_object().cloned().unwrap_or_default();
        assert_eq!(row.keys().collect::<Vec<_>>(), names);
        for (b, value) in &row {
            assert_eq!(value, &v["covariance"][b][a], "{a}, {b}");
        }
        match (row[a].as_f64(), v["std_errors"][a].as_f64()) {
            (Some(var), Some(se)) => assert_eq!(var.max(0.0).sqrt().to_bits(), se.to_bits(), "{a}"),
            (var, se) => assert!(var.is_none() && se.is_none(), "{a}: {var:?} {se:?}"),
        }
    }
    let patterns = v["sign_patterns"].as_array().cloned().unwrap_or_default();
    assert_eq!(patterns.len(), 1);
    assert_eq!(patterns[0]["experiment"], "run");
    assert_eq!(patterns[0]["pattern"]["water.u"], "+");
    assert!(patterns[0]["arguments"][0]["minority_fraction"].is_number());
    let d = &v["diagnostics"];
    for key in [
        "rank",
        "condition_number",
        "refinements",
        "converged",
        "instruments",
        "centring",
        "unexcited",
        "aggregates",
        "heading_gains",
    ] {
        assert!(d.get(key).is_some(), "diagnostics.{key}: {d}");
    }
    assert!(
        d["centring"]
            .as_str()
            .is_some_and(|s| s.contains("per experiment"))
    );
    let gain = d["heading_gains"]["run"].as_f64().unwrap_or(f64::NAN);
    assert!((gain - 1.0).abs() < 0.05, "heading gain {gain}");
    // The estimate's own simulation on its data: a fit per state, none diverged.
    let own = &d["own_simulation"];
    let states: Vec<&str> = own["fits"]
        .as_array()
        .map(|a| a.iter().filter_map(|f| f["state"].as_str()).collect())
        .unwrap_or_default();
    assert_eq!(states, ["u", "v", "r"], "{own}");
    assert!(own["mean_fit"].as_f64().is_some_and(|f| f > 0.0), "{own}");
    assert_eq!(own["diverged"], serde_json::json!([]), "{own}");
    let nuisance = v["nuisance"].as_array().cloned().unwrap_or_default();
    assert!(
        nuisance
            .iter()
            .any(|n| n["name"] == "rho[north,X_u]" && n["estimates"] == "E[north]*X_u")
    );
}

#[test]
fn estimate_prints_tables_and_warnings_for_people() {
    let dir = Scratch::new("text");
    let data = dir.write("low.csv", &estimation_csv(3000, 1.0, 7));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    for part in [
        "Ship: iv3 estimate from 1 experiment (2998 equations)",
        "name   estimate",
        "std error  status",
        "X_tau",
        "nuisance parameters",
        "rho[north,X_u]",
        "unmeasured disturbance means (paper Corollary 1)",
        "current.north",
        "sign patterns",
        "low  water.u + (other sign 0%)",
        "condition number",
        "refinements",
        "centring",
        "unexcited         W_uu is not separately excited",
        "aggregate",
    ] {
        assert!(out.contains(part), "`{part}` missing:\n{out}");
    }
    // Low wind: the wind parameters are held, and stderr says so.
    let err = stderr(&o);
    assert!(
        err.contains("warning: `W_uu` held at 0: the wind barely varies"),
        "{err}"
    );
    assert!(!out.contains('\u{1b}') && !err.contains('\u{1b}'));
    // The JSON says "aggregate" where the text does (it said "estimated").
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    let v = json(&o);
    let parameters = v["parameters"].as_array().cloned().unwrap_or_default();
    let sums: Vec<_> = parameters
        .iter()
        .filter(|p| !p["aggregate"].is_null())
        .collect();
    assert!(!sums.is_empty(), "{parameters:?}");
    for p in &sums {
        assert_eq!(p["status"], "aggregate", "{p}");
        assert_eq!(p["estimates"], p["aggregate"], "{p}");
        assert!(
            !p["estimates"].as_str().unwrap_or("").contains("- -"),
            "{p}"
        );
    }
    assert!(
        parameters
            .iter()
            .filter(|p| p["status"] == "estimated")
            .all(|p| p["aggregate"].is_null())
    );
}

/// `--refine-subsample`: the refinement on the first fifth of a long run
/// settles there and the refinement over all samples goes on from it, in
/// the JSON and in the text.
#[test]
fn estimate_refines_on_a_subsample_when_asked() {
    let dir = Scratch::new("subsample");
    let data = dir.write("long.csv", &estimation_csv(20000, 10.0, 201));
    let o = leeway(&[
        "estimate",
        SHIP,
        "--data",
        &data,
        "--refine-subsample",
        "0.2",
        "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    let d = &v["diagnostics"];
    assert_eq!(
        d["subsample"],
        serde_json::json!({"fraction": 0.2, "samples": 4000, "refinements": d["subsample"]["refinements"], "used": true}),
        "{d}"
    );
    assert_eq!(d["converged"].as_bool(), Some(true), "{d}");
    let o = leeway(&[
        "estimate",
        SHIP,
        "--data",
        &data,
        "--refine-subsample",
        "0.2",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("subsample         the first 0.2 of every experiment (4000 samples)")
            && out.contains("settled; the refinement over all samples went on from it")
            && out.contains("first simulation: the estimate refined on the subsample"),
        "{out}"
    );
    // Without the flag, the JSON has no `subsample`.
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    assert!(json(&o)["diagnostics"].get("subsample").is_none());
}

/// A small valid file: 30 samples with a time column, then mutated per class.
fn small_csv() -> Vec<Vec<String>> {
    estimation_csv(30, 1.0, 3)
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

fn join(rows: &[Vec<String>]) -> String {
    rows.iter().map(|r| r.join(",") + "\n").collect()
}

#[test]
fn every_malformed_csv_gives_its_located_error_and_exit_2() {
    let dir = Scratch::new("malformed");
    let good = small_csv();
    assert_eq!(
        good[0].join(","),
        "time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e"
    );
    let mutate = |f: &dyn Fn(&mut Vec<Vec<String>>)| {
        let mut rows = good.clone();
        f(&mut rows);
        join(&rows)
    };
    let cases: Vec<(&str, String, String)> = vec![
        (
            "missing-column",
            mutate(&|r| {
                r.iter_mut().for_each(|row| {
                    row.remove(6);
                })
            }),
            ":1: missing column `tau2`".to_string(),
        ),
        (
            "non-numeric",
            mutate(&|r| r[4][2] = "abc".to_string()),
            ":5:3 (v): `abc` is not a number".to_string(),
        ),
        (
            "nan",
            mutate(&|r| r[6][1] = "NaN".to_string()),
            ":7:2 (u): `NaN` is not a finite number".to_string(),
        ),
        (
            "inf",
            mutate(&|r| r[9][5] = "-inf".to_string()),
            ":10:6 (tau1): `-inf` is not a finite number".to_string(),
        ),
        (
            "empty-cell",
            mutate(&|r| r[7][3] = String::new()),
            ":8:4 (r): empty cell".to_string(),
        ),
        (
            "too-few-samples",
            mutate(&|r| r.truncate(6)),
            ":2: experiment `too-few-samples` has 5 samples; at least 10 are needed".to_string(),
        ),
        (
            "inconsistent-time",
            mutate(&|r| r[8][0] = "6.5".to_string()),
            ":9:1 (time): inconsistent sample time".to_string(),
        ),
        (
            "step-mismatch",
            mutate(&|r| {
                for (k, row) in r.iter_mut().enumerate().skip(1) {
                    row[0] = format!("{:?}", 0.5 * (k - 1) as f64);
                }
            }),
            ":2:1 (time): the data are sampled every 0.5 s but the model declares step 1"
                .to_string(),
        ),
        (
            "non-contiguous-experiment",
            mutate(&|r| {
                for (k, row) in r.iter_mut().enumerate() {
                    let name = match k {
                        0 => "experiment",
                        1..=12 => "a",
                        13..=24 => "b",
                        _ => "a",
                    };
                    row.insert(0, name.to_string());
                }
            }),
            ":26:1 (experiment): experiment `a` resumes after another experiment started"
                .to_string(),
        ),
        (
            "duplicate-header",
            mutate(&|r| r[0][9] = "u".to_string()),
            ":1:10: column `u` appears twice (columns 2 and 10)".to_string(),
        ),
        (
            "row-length",
            mutate(&|r| r[11].push("1.0".to_string())),
            ":12: malformed row".to_string(),
        ),
    ];
    for (name, text, expect) in &cases {
        let file = dir.write(&format!("{name}.csv"), text);
        let o = leeway(&["estimate", SHIP, "--data", &file]);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{name}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.starts_with(&format!("error[data]: {file}{expect}")),
            "{name}: expected `{file}{expect}` in\n{err}"
        );
        assert!(err.contains("  = help: "), "{name}: a hint\n{err}");
        assert!(stdout(&o).is_empty(), "{name}: nothing on stdout");
        // The same location in the JSON document, with empty results.
        let o = leeway(&["estimate", SHIP, "--data", &file, "--json"]);
        assert_eq!(code(&o), 2, "{name}");
        let v = json(&o);
        let location = v["errors"][0]["location"].as_str().unwrap_or_default();
        assert!(
            format!(
                "{location}: {}",
                v["errors"][0]["message"].as_str().unwrap_or_default()
            )
            .starts_with(&format!("{file}{expect}")),
            "{name}: {v}"
        );
        assert_eq!(v["errors"][0]["code"], "data");
        assert_eq!(v["estimates"], serde_json::json!({}));
    }
    // Unreadable files: missing, a directory, bytes that are not UTF-8.
    let missing = dir.path("missing.csv").display().to_string();
    let folder = dir.path("folder");
    std::fs::create_dir_all(&folder).unwrap_or_else(|e| panic!("{e}"));
    let folder = folder.display().to_string();
    let mut bytes = join(&good).into_bytes();
    bytes[60] = 0xff;
    let binary = dir.path("binary.csv");
    std::fs::write(&binary, bytes).unwrap_or_else(|e| panic!("{e}"));
    let binary = binary.display().to_string();
    for (file, expect) in [
        (
            &missing,
            format!("error[data]: {missing}: cannot read the file"),
        ),
        (
            &folder,
            format!("error[data]: {folder}: cannot read the file"),
        ),
        (&binary, format!("error[data]: {binary}:2")),
    ] {
        let o = leeway(&["estimate", SHIP, "--data", file]);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{file}");
        assert!(stderr(&o).starts_with(&expect), "{}", stderr(&o));
    }
    // Several bad files: every one is reported.
    let a = dir.path("nan.csv").display().to_string();
    let o = leeway(&["estimate", SHIP, "--data", &a, "--data", &missing]);
    assert_eq!(code(&o), 2);
    assert_eq!(
        stderr(&o).matches("error[data]").count(),
        2,
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_heading_in_degrees_gives_the_gain_warning() {
    let dir = Scratch::new("degrees");
    let mut rows: Vec<Vec<String>> = estimation_csv(2000, 1.0, 11)
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    for row in rows.iter_mut().skip(1) {
        let psi: f64 = row[4].parse().unwrap_or(f64::NAN);
        row[4] = format!("{:?}", psi.to_degrees());
    }
    let data = dir.write("deg.csv", &join(&rows));
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    no_panic(&o);
    let v = json(&o);
    let warnings = v["warnings"].as_array().cloned().unwrap_or_default();
    let w = warnings
        .iter()
        .filter_map(Value::as_str)
        .find(|w| w.contains("does not integrate"))
        .unwrap_or_else(|| panic!("no heading warning: {v}"));
    assert!(
        w.starts_with("experiment `deg`: the heading `psi` does not integrate `r`: Δpsi/h ≈ "),
        "{w}"
    );
    // The measured gain: 180/π ≈ 57.3 for degrees (whatever the step sizes).
    let gain: f64 = w
        .split("(gain ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|g| g.parse().ok())
        .unwrap_or(f64::NAN);
    assert!((gain - 57.3).abs() < 1.0, "{w}");
    assert!(w.contains("the heading is in degrees"), "{w}");
    // The same data in radians: no such warning.
    let data = dir.write("rad.csv", &estimation_csv(2000, 1.0, 11));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(!stderr(&o).contains("does not integrate"), "{}", stderr(&o));
}

#[test]
fn data_that_cannot_support_the_model_exit_1() {
    let dir = Scratch::new("unsupported");
    // IV2 at 10 m/s wind: the air-relative velocity changes sign around the
    // circle (paper A7); with --strict that is an error, exit 1.
    let data = dir.write("windy.csv", &estimation_csv(3000, 10.0, 500));
    let o = leeway(&[
        "estimate",
        SHIP,
        "--data",
        &data,
        "--method",
        "iv2",
        "--aggregate",
        "--strict",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.starts_with("error[sign-violation]: experiment `windy`: air.u has sign"),
        "{err}"
    );
    assert!(err.contains("%") && err.contains("  = help: "), "{err}");
    // Without --strict: a warning with the figure, exit 0.
    let o = leeway(&[
        "estimate",
        SHIP,
        "--data",
        &data,
        "--method",
        "iv2",
        "--aggregate",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: experiment `windy`: air.u changes sign ("));
    // Wind unmeasured: X_uu and W_uu enter only as their sum; exit 1 unless aggregated.
    let o = leeway(&[
        "estimate",
        "examples/models/ship_iv2.som",
        "--data",
        &data,
        "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 1, "{}", stdout(&o));
    let v = json(&o);
    assert_eq!(v["errors"][0]["code"], "unidentifiable");
    assert!(
        v["errors"][0]["help"]
            .as_str()
            .is_some_and(|h| h.contains("--aggregate"))
    );
    let o = leeway(&[
        "estimate",
        "examples/models/ship_iv2.som",
        "--data",
        &data,
        "--aggregate",
        "--method",
        "iv2",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    // Data that excite nothing (all zeros): a clear error naming the cause, exit 1.
    let mut zeros = String::from("time,u,v,r,tau1,tau2,tau3,psi,wind_n,wind_e\n");
    for k in 0..200 {
        zeros.push_str(&format!("{k},0,0,0,0,0,0,0,0,0\n"));
    }
    let data = dir.write("zeros.csv", &zeros);
    for method in ["ls", "iv3"] {
        let o = leeway(&[
            "estimate",
            SHIP,
            "--data",
            &data,
            "--method",
            method,
            "--aggregate",
        ]);
        no_panic(&o);
        assert_eq!(code(&o), 1, "{method}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("error[rank-deficient]"),
            "{method}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn model_parameter_file_and_option_errors_exit_2() {
    let dir = Scratch::new("errors");
    let data = dir.write("run.csv", &estimation_csv(200, 1.0, 5));
    // A model that does not compile: its rendered diagnostics, like `check`.
    let o = leeway(&[
        "estimate",
        "examples/models/broken/order-too-high.som",
        "--data",
        &data,
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).contains("error[order-too-high]"),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("┌─ examples/models/broken/order-too-high.som:"));
    assert!(stderr(&o).contains("nothing was estimated"));
    let o = leeway(&["estimate", "no/such.som", "--data", &data, "--json"]);
    assert_eq!(code(&o), 2);
    assert_eq!(json(&o)["errors"][0]["code"], "io");
    // --nominal with an unknown and a missing name, located.
    let nominal = dir.write("nominal.json", "{\n  \"X_u\": -0.1,\n  \"X_foo\": 1\n}\n");
    let o = leeway(&["estimate", SHIP, "--data", &data, "--nominal", &nominal]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "error[invalid-params]: {nominal}:3:3: unknown parameter `X_foo`"
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!("{nominal}:1:1: missing parameters `X_vr`")),
        "{err}"
    );
    // Option errors.
    let o = leeway(&["estimate", SHIP, "--data", &data, "--step", "0.5"]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains("--step 0.5 conflicts with the model's `step 1`"));
    for bad in [
        vec!["--method", "iv4"],
        vec!["--combine", "averaged"],
        vec!["--centring", "median"],
        vec!["--lags", "0"],
        vec!["--step", "-1"],
    ] {
        let mut args = vec!["estimate", SHIP, "--data", &data];
        args.extend(bad.iter());
        let o = leeway(&args);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{bad:?}");
    }
}

#[test]
fn estimate_then_validate_round_trips_the_parameters() {
    let dir = Scratch::new("roundtrip");
    let model = ship();
    let data = dir.write("run.csv", &estimation_csv(5000, 10.0, 202));
    let val = study::validation_experiment(&model, 1000);
    let val_file = dir.write("val.csv", &csv_text(&model, &[&val]));
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let est = dir.write("est.json", &stdout(&o));
    // The validation run is calm (no current): held at the estimate's
    // current (the default) the surge fit drops; `--disturbance zero` says so.
    let o = leeway(&[
        "validate", SHIP, "--params", &est, "--data", &val_file, "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let held = json(&o)["mean"]["u"].as_f64().unwrap_or(f64::NAN);
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &est,
        "--data",
        &val_file,
        "--json",
        "--disturbance",
        "zero",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    assert!(
        held < v["mean"]["u"].as_f64().unwrap_or(f64::NAN) - 10.0,
        "{held}: {v}"
    );
    let fit = &v["experiments"][0]["fit"];
    for output in ["u", "v", "r"] {
        let f = fit[output].as_f64().unwrap_or(f64::NAN);
        // IV3 from 5000 noisy samples at 10 m/s wind, on noise-free validation data.
        assert!(f > 85.0, "fit of {output}: {f} ({v})");
    }
    // No file is written unless asked: the directory holds what it held.
    assert_eq!(v["plot"], serde_json::Value::Null);
    assert!(!dir.path("val-validation.svg").exists());
    // Asked for, the plot has a panel per output and the integrated heading,
    // the legend naming the parameter file.
    let plot = dir.path("val.svg");
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &est,
        "--data",
        &val_file,
        "--plot",
        &plot.display().to_string(),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let svg = std::fs::read_to_string(&plot).unwrap_or_default();
    for label in [
        "u: fit", "v: fit", "r: fit", "psi: fit", "measured", "\nest\n", "time (s)",
    ] {
        assert!(
            svg.contains(label),
            "`{label}` missing from the SVG:\n{svg}"
        );
    }
    // The true θ as a plain object: the simulation reproduces the noise-free data.
    let truth = dir.write("truth.json", &true_params());
    let png = dir.path("fit.png").display().to_string();
    let o = leeway(&[
        "validate", SHIP, "--params", &truth, "--data", &val_file, "--plot", &png,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("experiment  samples  u       v       r"),
        "{out}"
    );
    assert!(
        out.contains("val         1000     100.00  100.00  100.00"),
        "{out}"
    );
    assert!(out.contains(&format!("plot: {png}")));
    assert!(
        std::fs::read(&png)
            .unwrap_or_default()
            .starts_with(b"\x89PNG")
    );
    // A plot that cannot be written: exit 2, the fits still printed.
    let nowhere = dir.path("no/such/dir/fit.svg").display().to_string();
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &truth,
        "--data",
        &val_file,
        "--plot",
        &nowhere,
        "--disturbance",
        "zero",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    assert!(
        stdout(&o).contains("100.00  100.00  100.00"),
        "{}",
        stdout(&o)
    );
    assert!(
        stderr(&o).starts_with(&format!("error[io]: cannot draw `{nowhere}`")),
        "{}",
        stderr(&o)
    );
    // A parameter file missing a name, or naming an unknown one: exit 2.
    let partial = dir.write("partial.json", "{\"X_u\": -0.05}");
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &partial,
        "--data",
        &val_file,
        "--no-plot",
    ]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains("missing parameters"), "{}", stderr(&o));
}

/// `validate` takes every estimate leeway writes: IV2 treats a measured
/// wind as unmeasured and reports its mean, which the validation (taking
/// the wind from the data) leaves aside. And one refused parameter file is
/// reported without voiding the comparison of the others (exit 2).
#[test]
fn validate_takes_an_iv2_estimate_and_survives_a_refused_file() {
    let dir = Scratch::new("iv2-validate");
    let model = ship();
    let data = dir.write("run.csv", &estimation_csv(3000, 10.0, 203));
    let val = study::validation_experiment(&model, 500);
    let val_file = dir.write("val.csv", &csv_text(&model, &[&val]));
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    assert_eq!(code(&o), 0, "{}", stdout(&o));
    // IV2 (the augmented predictor) reports a measured medium's mean beside
    // the unmeasured ones when it can solve for it, as on the survey boat.
    let mut document = json(&o);
    document["disturbances"]["wind"] = serde_json::json!({
        "wind_n": {"mean": 7.1, "std_error": 0.2},
        "wind_e": {"mean": 6.9, "std_error": 0.2}
    });
    let iv2 = dir.write("iv2.json", &document.to_string());
    let o = leeway(&[
        "validate", SHIP, "--params", &iv2, "--data", &val_file, "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stdout(&o));
    let v = json(&o);
    assert!(
        v["disturbances"].get("wind").is_none()
            || v["models"][0]["disturbances"].get("wind").is_none(),
        "{v}"
    );
    let bad = dir.write("bad.json", "{\"X_u\": 1}\n");
    let o = leeway(&[
        "validate", SHIP, "--params", &bad, "--params", &iv2, "--data", &val_file, "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stdout(&o));
    let v = json(&o);
    assert_eq!(v["models"].as_array().map(Vec::len), Some(1), "{v}");
    assert_eq!(v["models"][0]["name"], "iv2");
    assert_eq!(v["params"], iv2.as_str());
    assert!(
        v["errors"][0]["location"]
            .as_str()
            .is_some_and(|l| l.contains("bad.json")),
        "{v}"
    );
    let o = leeway(&[
        "validate", SHIP, "--params", &bad, "--params", &iv2, "--data", &val_file,
    ]);
    assert_eq!(code(&o), 2);
    assert!(stdout(&o).contains("iv2"), "{}", stdout(&o));
    assert!(stderr(&o).contains("bad.json"), "{}", stderr(&o));
}

#[test]
fn simulate_writes_a_data_file_that_validates() {
    let dir = Scratch::new("simulate");
    let model = ship();
    let val = study::validation_experiment(&model, 400);
    // An input file: time and inputs (and the measured wind); initial state by --x0.
    let full = csv_text(&model, &[&val]);
    let input: String = full
        .lines()
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            let mut keep = vec![cells[0]];
            keep.extend(&cells[5..]);
            keep.join(",") + "\n"
        })
        .collect();
    assert!(input.starts_with("time,tau1,tau2,tau3,wind_n,wind_e\n"));
    let input = dir.write("in.csv", &input);
    let truth = dir.write("truth.json", &true_params());
    let o = leeway(&[
        "simulate",
        SHIP,
        "--params",
        &truth,
        "--input",
        &input,
        "--x0",
        "u=4,v=0,r=0,psi=0",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.starts_with("time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n0.0,4.0,0.0,0.0,0.0,"),
        "{}",
        &out[..out.len().min(300)]
    );
    assert_eq!(out.lines().count(), 401);
    // The same model, θ, input and start as the validation data: the same states.
    let numbers = |text: &str| -> Vec<f64> {
        text.lines()
            .skip(1)
            .flat_map(|l| l.split(',').map(|c| c.parse::<f64>().unwrap_or(f64::NAN)))
            .collect::<Vec<_>>()
    };
    let (sim, data) = (numbers(&out), numbers(&full));
    assert_eq!(sim.len(), data.len());
    for (k, (a, b)) in sim.iter().zip(&data).enumerate() {
        assert!(
            (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
            "cell {k}: {a} vs {b}"
        );
    }
    // Written to a file, it is data that `validate` reads: fit 100.
    let sim = dir.path("sim.csv").display().to_string();
    let o = leeway(&[
        "simulate",
        SHIP,
        "--params",
        &truth,
        "--input",
        &input,
        "--x0",
        "u=4,v=0,r=0,psi=0",
        "--out",
        &sim,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(stdout(&o).is_empty());
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &truth,
        "--data",
        &sim,
        "--no-plot",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(
        stdout(&o).contains("100.00  100.00  100.00"),
        "{}",
        stdout(&o)
    );
    // Without an initial state: a located error naming both ways to give it.
    let o = leeway(&["simulate", SHIP, "--params", &truth, "--input", &input]);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(
        err.contains(&format!("{input}:1: no initial value for `u`"))
            && err.contains("--x0 u=VALUE"),
        "{err}"
    );
    // A destabilised model diverges: exit 1, the rows before are written.
    let unstable = dir.write(
        "unstable.json",
        &true_params().replace("\"X_u\": -0.05", "\"X_u\": 5.0"),
    );
    let o = leeway(&[
        "simulate",
        SHIP,
        "--params",
        &unstable,
        "--input",
        &input,
        "--x0",
        "u=4,v=0,r=0,psi=0",
        "--disturbance",
        "zero",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with("error[diverged]: the simulation diverged at sample"),
        "{}",
        stderr(&o)
    );
    let rows = stdout(&o).lines().count();
    assert!(rows > 2 && rows < 401, "{rows} rows");
    assert!(!stdout(&o).contains("NaN"));
}

/// What a person reads, for review: the tables of `estimate` and `validate`
/// on fixed-seed data (paths replaced by `[dir]`).
#[test]
fn text_output_snapshots() {
    let dir = Scratch::new("snapshots");
    let model = ship();
    let data = dir.write("ship.csv", &estimation_csv(2000, 10.0, 42));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let here = dir.0.display().to_string();
    insta::assert_snapshot!("estimate_stdout", stdout(&o));
    insta::assert_snapshot!("estimate_stderr", stderr(&o).replace(&here, "[dir]"));
    let est = dir.write(
        "est.json",
        &stdout(&leeway(&["estimate", SHIP, "--data", &data, "--json"])),
    );
    let val = dir.write(
        "val.csv",
        &csv_text(&model, &[&study::validation_experiment(&model, 600)]),
    );
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &est,
        "--data",
        &val,
        "--disturbance",
        "zero",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    insta::assert_snapshot!("validate_stdout", stdout(&o).replace(&here, "[dir]"));
}

/// A new craft's first hour: validating the estimate's own output holds the
/// current it found (the fit its own simulation reported, the fit the means
/// given by hand give); a plain parameter file holds zero and says so.
#[test]
fn validate_holds_the_disturbance_means_of_the_estimate_it_is_given() {
    let dir = Scratch::new("catamaran");
    let data = dir.write("runs.csv", &catamaran_csv(3000, 7));
    let o = leeway(&[
        "estimate",
        CATAMARAN,
        "--data",
        &data,
        "--json",
        "--centring",
        "none",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let est = dir.write("est.json", &stdout(&o));
    let e = json(&o);
    // One answer on the constant force: `check` and `estimate` (default
    // centring, per experiment) name the same centring and experiments.
    let way = "θ is identifiable with `--centring none` or `pooled` from experiments with sign patterns {+water.u +water.v}, {-water.u +water.v}";
    let check = leeway(&["check", CATAMARAN]);
    let default = leeway(&["estimate", CATAMARAN, "--data", &data]);
    assert_eq!(code(&default), 1, "{}", stderr(&default));
    for o in [&check, &default] {
        assert!(
            stdout(o).contains(way) || stderr(o).contains(way),
            "{}{}",
            stdout(o),
            stderr(o)
        );
    }
    let mean = |c: &str| {
        e["disturbances"]["current"][c]["mean"]
            .as_f64()
            .unwrap_or(f64::NAN)
    };
    let (north, east) = (mean("north"), mean("east"));
    // The current found, within a few standard errors of (0.2, −0.1).
    assert!(
        (north - 0.2).abs() < 0.05 && (east + 0.1).abs() < 0.05,
        "{north} {east}"
    );
    let fits = |v: &Value| -> Vec<f64> {
        ["u", "v", "r", "psi"]
            .iter()
            .map(|s| v["mean"][s].as_f64().unwrap_or(f64::NAN))
            .collect()
    };
    let validate = |extra: &[&str]| {
        let mut args = vec!["validate", CATAMARAN, "--data", &data, "--json"];
        args.extend(extra);
        let o = leeway(&args);
        no_panic(&o);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        json(&o)
    };
    // Without options: the estimate's means, said in JSON, no warning.
    let held = validate(&["--params", &est]);
    assert_eq!(held["warnings"], serde_json::json!([]), "{held}");
    assert_eq!(
        held["models"][0]["disturbances"],
        serde_json::json!({
            "current.north": {"value": north, "from": "estimate"},
            "current.east": {"value": east, "from": "estimate"},
        })
    );
    // The fit the estimate's own simulation reported for u, v, r.
    let own = &e["diagnostics"]["own_simulation"]["fits"];
    for (k, state) in ["u", "v", "r"].iter().enumerate() {
        let reported = own[k]["fit"].as_f64().unwrap_or(f64::NAN);
        assert_eq!(own[k]["state"], *state);
        assert!(
            (fits(&held)[k] - reported).abs() < 1e-9,
            "{state}: {held} vs {own}"
        );
    }
    // The same means given by hand: the same fits, bit for bit.
    let given = format!("current.north={north:?},current.east={east:?}");
    let by_hand = validate(&["--params", &est, "--disturbance", &given]);
    assert_eq!(fits(&by_hand), fits(&held));
    assert_eq!(
        by_hand["models"][0]["disturbances"]["current.east"]["from"],
        "given"
    );
    // θ as a plain file: the current is zero, with a warning saying how to
    // give it; `--disturbance zero` asks for that and silences it.
    let plain = serde_json::to_string(&e["estimates"]).unwrap_or_default();
    let plain = dir.write("plain.json", &plain);
    let zero = validate(&["--params", &plain]);
    let warnings = zero["warnings"].to_string();
    assert!(
        warnings.contains("the `current` is taken as zero while simulating with")
            && warnings.contains("--disturbance current.north=VALUE,current.east=VALUE"),
        "{warnings}"
    );
    assert_eq!(
        zero["models"][0]["disturbances"]["current.north"]["from"],
        "default"
    );
    let asked = validate(&["--params", &plain, "--disturbance", "zero"]);
    assert_eq!(asked["warnings"], serde_json::json!([]));
    assert_eq!(fits(&asked), fits(&zero));
    // Without the current the fit drops: what made a newcomer doubt the model.
    assert!(fits(&zero)[0] < fits(&held)[0] - 5.0, "{zero} vs {held}");
    // The text output says what was held.
    let o = leeway(&["validate", CATAMARAN, "--data", &data, "--params", &est]);
    assert!(
        stdout(&o).contains(&format!(
            "disturbances held: current.north = {} (estimate)",
            (north * 1e4).round() / 1e4
        )),
        "{}",
        stdout(&o)
    );
}

#[test]
fn validate_resid_reports_the_residual_tests() {
    let dir = Scratch::new("resid");
    let model = ship();
    let data = dir.write("run.csv", &estimation_csv(600, 1.0, 7));
    let truth = dir.write("truth.json", &true_params());
    let o = leeway(&[
        "validate", SHIP, "--params", &truth, "--data", &data, "--resid",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let text = stdout(&o);
    for label in [
        "truth: free-run simulation errors, N = 599, lags 1..25",
        "verdict: independent of the inputs",
        "Ljung-Box Q",
        "tau1",
    ] {
        assert!(text.contains(label), "`{label}` missing:\n{text}");
    }
    // The true parameters pass the verdict (the one-step test refused
    // them: with measurement noise their one-step error is MA(1)).
    assert!(!text.contains("NO"), "the true model is refused:\n{text}");
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &truth,
        "--data",
        &data,
        "--resid",
        "--resid-lags",
        "10",
        "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    let tests = &v["residuals"][0]["tests"];
    assert_eq!(v["residuals"][0]["name"], "truth");
    assert_eq!(tests["lags"], 10);
    assert_eq!(tests["samples"], 599);
    assert_eq!(tests["errors"], "simulation");
    let states = tests["states"].as_array().cloned().unwrap_or_default();
    assert_eq!(states.len(), leeway_model::Model::ir(&model).states.len());
    assert_eq!(
        states[0]["autocorrelation"].as_array().map(Vec::len),
        Some(10)
    );
    assert_eq!(
        states[0]["inputs"][0]["correlation"]
            .as_array()
            .map(Vec::len),
        Some(21)
    );
    // Without `--resid` there is no `residuals` field; its lags alone are a usage error.
    let o = leeway(&[
        "validate", SHIP, "--params", &truth, "--data", &data, "--json",
    ]);
    assert!(json(&o).get("residuals").is_none());
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &truth,
        "--data",
        &data,
        "--resid-lags",
        "5",
    ]);
    assert_eq!(code(&o), 2);
    // More lags than samples: a located option error, exit 2.
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &truth,
        "--data",
        &data,
        "--resid",
        "--resid-lags",
        "900",
        "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    assert_eq!(json(&o)["errors"][0]["code"], "invalid-option");
}
