//! `leeway select`: a ferry simulated with five of its nine candidate terms
//! true, the chosen model written and read back by `estimate`, and the
//! errors.

use crate::common::*;

const CANDIDATES: &str = "model Ferry {
    step 0.1
    state u, v, r
    input tau_x, tau_y, tau_n

    der u = X_u*u + ?X_uu*u*|u| + ?X_vr*v*r + X_t*tau_x + ?X_r*r
    der v = Y_v*v + ?Y_vv*v*|v| + ?Y_ur*u*r + Y_t*tau_y + ?Y_tn*tau_n
    der r = N_r*r + ?N_rr*r*|r| + ?N_uv*u*v + N_t*tau_n + ?N_ty*tau_y

    nominal { X_u = -0.05, X_t = 6.7e-5, Y_v = -0.15, Y_t = 6e-5, N_r = -0.3, N_t = 2e-5 }
}
";

const TRUTH: &str = r#"{"X_u": -0.05, "X_uu": -0.05, "X_vr": 0.4, "X_t": 6.7e-5, "X_r": 0.0,
 "Y_v": -0.15, "Y_vv": -0.3, "Y_ur": -0.5, "Y_t": 6e-5, "Y_tn": 0.0,
 "N_r": -0.3, "N_rr": 0.0, "N_uv": 0.02, "N_t": 2e-5, "N_ty": 0.0}"#;

/// 3000 samples of piecewise-constant forces (a new level every 5 s) from
/// a small linear congruential generator, the states given on the first row.
fn input(seed: u64) -> String {
    let mut state = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
    let mut uniform = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut text = String::from("time,tau_x,tau_y,tau_n,u,v,r\n");
    let mut level = [0.0; 3];
    for k in 0..3000 {
        if k % 50 == 0 {
            level = [
                20000.0 + 8000.0 * uniform(),
                3000.0 * uniform(),
                15000.0 * uniform(),
            ];
        }
        let states = if k == 0 { "1.0,0.0,0.0" } else { ",," };
        text.push_str(&format!(
            "{},{},{},{},{states}\n",
            k as f64 / 10.0,
            level[0],
            level[1],
            level[2]
        ));
    }
    text
}

/// Run `k` of `model` with θ from `truth` on `inputs` (CSV text), simulated
/// with the tests' noise and seed `k`: the written file's path.
fn simulated(dir: &Scratch, (model, truth): (&str, &str), k: u64, inputs: &str) -> String {
    let inp = dir.write(&format!("in{k}.csv"), inputs);
    let run = dir.path(&format!("run{k}.csv")).display().to_string();
    let seed = k.to_string();
    let o = leeway(&[
        "simulate",
        model,
        "--params",
        truth,
        "--input",
        &inp,
        "--out",
        &run,
        "--noise",
        "u=0.01,v=0.01,r=0.002",
        "--seed",
        &seed,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    run
}

#[test]
fn select_keeps_the_true_candidates_and_writes_a_model_estimate_reads() {
    let dir = Scratch::new("select");
    let model = dir.write("cand.som", CANDIDATES);
    let truth = dir.write("truth.json", TRUTH);
    let mut runs = Vec::new();
    for k in 0..3u64 {
        runs.push(simulated(&dir, (&model, &truth), k, &input(k)));
    }
    let chosen = dir.path("chosen.som").display().to_string();
    let figure = dir.path("selection.png");
    let figure_arg = figure.display().to_string();
    let mut args = vec!["select", model.as_str()];
    for r in &runs {
        args.extend(["--data", r.as_str()]);
    }
    args.extend(["--out", chosen.as_str(), "--plot", &figure_arg, "--json"]);
    let o = leeway(&args);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    // The figure of the criteria against model size is a PNG.
    let png = std::fs::read(&figure).unwrap_or_default();
    assert!(
        png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 10_000,
        "{}",
        png.len()
    );
    let doc = json(&o);
    let kept: Vec<&str> = doc["selection"]["kept"]
        .as_array()
        .map(|a| a.iter().filter_map(|v| v.as_str()).collect())
        .unwrap_or_default();
    assert_eq!(kept, ["X_uu", "X_vr", "Y_vv", "Y_ur", "N_uv"]);
    // Nothing is missing: no suggestion stands out.
    let strongest = doc["selection"]["suggestions"][0]["correlation"]
        .as_f64()
        .unwrap_or(1.0);
    assert!(strongest.abs() < 0.1, "{strongest}");
    let written = std::fs::read_to_string(&chosen).unwrap_or_default();
    assert_eq!(
        written,
        CANDIDATES
            .replace(" + ?X_r*r", "")
            .replace(" + ?Y_tn*tau_n", "")
            .replace(" + ?N_rr*r*|r|", "")
            .replace(" + ?N_ty*tau_y", "")
            .replace('?', "")
    );
    let mut est = vec!["estimate", chosen.as_str()];
    for r in &runs {
        est.extend(["--data", r.as_str()]);
    }
    let o = leeway(&est);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    // Without the true `u*v` of the yaw equation among the candidates, it is
    // the first suggestion.
    let lacking = dir.write("lacking.som", &CANDIDATES.replace(" + ?N_uv*u*v", ""));
    args[1] = lacking.as_str();
    let o = leeway(&args);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let first = &json(&o)["selection"]["suggestions"][0];
    assert_eq!(
        (first["equation"].as_str(), first["term"].as_str()),
        (Some("r"), Some("u*v"))
    );
    assert!(
        first["correlation"].as_f64().unwrap_or(0.0) > 0.3,
        "{first}"
    );
}

#[test]
fn select_refuses_least_squares_and_a_model_without_candidates() {
    let dir = Scratch::new("select-errors");
    let model = dir.write("cand.som", CANDIDATES);
    let truth = dir.write("truth.json", TRUTH);
    let inp = dir.write("in.csv", &input(9));
    let run = dir.path("run.csv").display().to_string();
    let o = leeway(&[
        "simulate", &model, "--params", &truth, "--input", &inp, "--out", &run,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = dir.path("chosen.som").display().to_string();
    let o = leeway(&[
        "select", &model, "--data", &run, "--out", &out, "--method", "ls",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).starts_with("error[invalid-option]: selection needs an IV method"),
        "{}",
        stderr(&o)
    );
    let plain = dir.write("plain.som", &CANDIDATES.replace('?', ""));
    let o = leeway(&["select", &plain, "--data", &run, "--out", &out]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).contains("error[no-candidates]"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.path("chosen.som").exists());
}

/// The text output: after the path, the chosen estimate's warnings and
/// notes on standard error, word for word what `leeway estimate` prints for
/// the written model on the same data — here the chosen model's compiler
/// warning (a false candidate was the only term of input `tau_z`, located in
/// the written file) and the estimator's notes.
#[test]
fn select_prints_the_chosen_estimates_warnings_and_notes_as_estimate_does() {
    let dir = Scratch::new("select-warnings");
    let source = CANDIDATES
        .replace(
            "input tau_x, tau_y, tau_n",
            "input tau_x, tau_y, tau_n, tau_z",
        )
        .replace(" + ?N_ty*tau_y", " + ?N_ty*tau_y + ?N_tz*tau_z");
    let model = dir.write("cand.som", &source);
    let truth = dir.write("truth.json", &TRUTH.replace('}', ", \"N_tz\": 0.0}"));
    let mut data = Vec::new();
    for k in 0..3u64 {
        // A fourth input column, never in the truth: another run's tau_y.
        let levels: Vec<String> = input(k + 10)
            .lines()
            .map(|l| l.split(',').nth(2).unwrap_or("0").to_string())
            .collect();
        let mut text = String::new();
        for (i, l) in input(k).lines().enumerate() {
            let z = if i == 0 { "tau_z" } else { levels[i].as_str() };
            text.push_str(&format!("{l},{z}\n"));
        }
        let run = simulated(&dir, (&model, &truth), k, &text);
        data.extend(["--data".to_string(), run]);
    }
    let chosen = dir.path("chosen.som").display().to_string();
    let mut args = vec!["select", model.as_str()];
    args.extend(data.iter().map(String::as_str));
    args.extend(["--out", chosen.as_str()]);
    let selected = leeway(&args);
    no_panic(&selected);
    assert_eq!(code(&selected), 0, "{}", stderr(&selected));
    assert!(
        !std::fs::read_to_string(&chosen)
            .unwrap_or_default()
            .contains("N_tz")
    );
    let mut est = vec!["estimate", chosen.as_str()];
    est.extend(data.iter().map(String::as_str));
    let estimated = leeway(&est);
    assert_eq!(code(&estimated), 0, "{}", stderr(&estimated));
    let text = stderr(&selected);
    assert_eq!(text, stderr(&estimated));
    assert!(
        text.starts_with(&format!(
            "warning: {chosen}:4:32: warning[unused-declaration]: input `tau_z` appears in no equation\n"
        )),
        "{text}"
    );
    assert!(
        text.contains("\nnote: iv1, iv2 and iv3 give this same estimate on this model"),
        "{text}"
    );
    // `--json`: the same warnings in full, as `estimate --json` lists them.
    args.push("--json");
    let doc = json(&leeway(&args));
    est.push("--json");
    assert_eq!(doc["warnings"], json(&leeway(&est))["warnings"]);
    assert!(
        doc["warnings"][0]
            .as_str()
            .is_some_and(|w| w.contains("input `tau_z` appears in no equation")),
        "{}",
        doc["warnings"]
    );
}
