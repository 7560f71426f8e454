//! `leeway design`: the runs it prints and writes, the input files
//! `simulate` replays, exit codes and located plan errors.

use crate::common::{Scratch, code, json, leeway, no_panic, root, stderr, stdout};

/// The ROV's plan with a short budget (tests run short trials).
fn rov_plan(dir: &Scratch) -> String {
    let text = std::fs::read_to_string(root().join("examples/plans/rov.toml")).expect("plan");
    let short = text.replace("time = 1200", "time = 100");
    assert_ne!(text, short);
    dir.write("rov.toml", &short)
}

#[test]
fn design_prints_the_runs_and_writes_files_simulate_replays() {
    let dir = Scratch::new("design-out");
    let plan = rov_plan(&dir);
    let out = dir.path("out").display().to_string();
    let o = leeway(&[
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "5",
        "--out",
        &out,
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}{}", stdout(&o), stderr(&o));
    let text = stdout(&o);
    for line in [
        "design for Rov (iv3, instrument centring experiment): 2 experiments of 50 s (1000 samples at 0.05 s)",
        "experiment 1 {+water.u +water.v}",
        "experiment 2 {+water.u -water.v}",
        "held        water.u > 0",
        "held        water.v < 0",
        "pointwise   r:",
        "predicted standard errors (iv3), 50 s per experiment (half the 95th percentile of |error| of 5 simulated trials)",
        "signs iv3: keeps water.u, water.v on their sides in every nominal run",
    ] {
        assert!(text.contains(line), "missing `{line}` in\n{text}");
    }
    for file in [
        "run-1.csv",
        "run-2.csv",
        "run-1-margins.csv",
        "design.json",
        "design.svg",
        "design.png",
    ] {
        assert!(dir.path("out").join(file).exists(), "{file}");
    }
    // run-1.csv is a simulation input: the nominal model, holding the
    // plan's mean current, replays its nominal states.
    let params = dir.write(
        "nominal.json",
        r#"{"X_u": -0.1, "X_uu": -0.3, "X_vr": 1.0, "X_t": 0.00025, "Y_v": -0.2, "Y_vv": -0.6, "Y_ur": -1.0, "Y_vr": -0.1, "Y_rv": -0.1, "Y_t": 0.00025, "N_r": -0.4, "N_rr": -0.5, "N_uv": 0.05, "N_t": 0.0002}"#,
    );
    let run = dir.path("out").join("run-1.csv").display().to_string();
    let sim = dir.path("sim.csv").display().to_string();
    let o = leeway(&[
        "simulate",
        "examples/models/rov.som",
        "--params",
        &params,
        "--input",
        &run,
        "--disturbance",
        "current.north=0.3,current.east=0.1",
        "--out",
        &sim,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let read = |p: &str| -> Vec<Vec<f64>> {
        std::fs::read_to_string(p)
            .expect("csv")
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.parse().expect("number")).collect())
            .collect()
    };
    let (planned, replayed) = (read(&run), read(&sim));
    assert_eq!(planned.len(), replayed.len());
    // Columns time, u, v, r, psi: the same trajectory up to the rotation's
    // round-off (the simulation re-anchors its heading's rotation).
    for (a, b) in planned.iter().zip(&replayed) {
        for j in 1..5 {
            assert!((a[j] - b[j]).abs() < 1e-6, "{a:?} {b:?}");
        }
    }
}

#[test]
fn design_json_is_the_document() {
    let dir = Scratch::new("design-json");
    let plan = rov_plan(&dir);
    let o = leeway(&[
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--json",
        "--target",
        "5%",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let d = json(&o);
    assert_eq!(d["model"], "Rov");
    assert_eq!(d["feasible"], true);
    assert_eq!(d["experiments"].as_array().map(Vec::len), Some(2));
    assert_eq!(
        d["prediction"]["parameters"].as_array().map(Vec::len),
        Some(14)
    );
    assert_eq!(d["prediction"]["trials"], 0);
    assert_eq!(d["prediction"]["target"]["relative"], 0.05);
    assert!(d["verification"].is_null());
    assert_eq!(d["noise"]["psi"], 0.005);
}

#[test]
fn a_plan_no_craft_can_fly_exits_1_with_what_would_work() {
    let dir = Scratch::new("design-windy");
    let text = std::fs::read_to_string(root().join("examples/plans/blimp.toml")).expect("plan");
    let windy = text
        .replace("mean = [0.5, 0.3]", "mean = [1.5, 0.5]")
        .replace("std = 0.1\n", "std = 0.3\n")
        .replace("time = 1200", "time = 100");
    let plan = dir.write("windy.toml", &windy);
    let o = leeway(&[
        "design",
        "examples/models/blimp.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--verify",
        "5",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 1, "{}", stdout(&o));
    let text = stdout(&o);
    assert!(
        text.contains("no plan within the limits keeps every held sign"),
        "{text}"
    );
    assert!(
        text.contains("measure wind (declare it `measured` and log it)"),
        "{text}"
    );
    assert!(
        text.contains("not verified: the design does not keep its signs"),
        "{text}"
    );
}

#[test]
fn plan_errors_are_located_and_exit_2() {
    let dir = Scratch::new("design-bad");
    let plan = dir.write("bad.toml", "step = 0.05\n[inputs.tau_x]\nrange = [0, \n");
    let o = leeway(&["design", "examples/models/rov.som", "--plan", &plan]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(err.contains(&format!("{plan}:3:")), "{err}");
    assert!(err.contains("docs/design.md"), "{err}");
    let plan = dir.write("unknown.toml", "[inputs.rudder]\nrange = [0, 1]\n");
    let o = leeway(&["design", "examples/models/rov.som", "--plan", &plan]);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).contains("no input named `rudder`"),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("tau_x, tau_y, tau_n"), "{}", stderr(&o));
    let o = leeway(&[
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--target",
        "120%",
    ]);
    assert_eq!(code(&o), 2);
    let o = leeway(&[
        "design",
        "examples/models/ship_iv2.som",
        "--plan",
        "examples/plans/ship-iv2.toml",
    ]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("not identifiable from any set of experiments"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn compare_sets_an_input_of_ones_own_beside_the_design() {
    let dir = Scratch::new("design-compare");
    let plan = rov_plan(&dir);
    let out = dir.path("out").display().to_string();
    let o = leeway(&[
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--out",
        &out,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let run1 = dir.path("out").join("run-1.csv").display().to_string();
    let run2 = dir.path("out").join("run-2.csv").display().to_string();
    let o = leeway(&[
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--compare",
        &run1,
        "--compare",
        &run2,
        "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let d = json(&o);
    // The design's own runs, given back: the same errors per sample.
    for p in d["comparison"]["parameters"]
        .as_array()
        .expect("parameters")
    {
        let ratio = p["ratio"].as_f64().expect("ratio");
        assert!((ratio - 1.0).abs() < 1e-9, "{p}");
    }
}

/// A craft no example has, through the README's steps: check, design,
/// simulate the planned runs as the trial would log them, estimate,
/// validate.
const WORKBOAT: &str = "// A 7 m workboat: one propeller, one rudder, a current nobody measures.
model Workboat {
    step 0.1
    state u, v, r
    input thrust, rudder
    heading psi integrates r
    disturbance current unmeasured earth(north, east)
    water = relative(current)
    der u = X_u*water.u + X_uu*water.u*|water.u| + X_t*thrust
    der v = Y_v*water.v + Y_vv*water.v*|water.v| + Y_ur*water.u*r + Y_d*rudder
    der r = N_r*r + N_v*water.v + N_d*rudder
    nominal { X_u = -0.1, X_uu = -0.05, X_t = 0.002, Y_v = -0.5, Y_vv = -0.3,
              Y_ur = -0.6, Y_d = 0.01, N_r = -0.6, N_v = -0.1, N_d = -0.02 }
}
";

const WORKBOAT_PLAN: &str = "[inputs.thrust]
range = [0, 1000]
rate = 200
[inputs.rudder]
range = [-35, 35]
rate = 10
[disturbances.current]
mean = [0.3, -0.2]
std = 0.03
correlation_time = 20
[noise]
u = 0.02
v = 0.02
r = 0.005
psi = 0.01
[budget]
time = 300
";

#[test]
fn a_new_craft_goes_from_check_to_validate() {
    let dir = Scratch::new("design-workboat");
    let model = dir.write("workboat.som", WORKBOAT);
    let plan = dir.write("plan.toml", WORKBOAT_PLAN);
    let o = leeway(&["check", &model]);
    assert_eq!(code(&o), 0, "{}", stdout(&o));
    let out = dir.path("trial").display().to_string();
    let o = leeway(&[
        "design", &model, "--plan", &plan, "--pilot", "20", "--out", &out, "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let d = json(&o);
    let runs = d["experiments"].as_array().map_or(0, Vec::len);
    assert!(runs >= 1);
    // The trial, as its logger records it: the true craft (here the
    // nominal θ) in a drifting current, with sensor noise.
    let truth = [
        ("X_u", -0.1),
        ("X_uu", -0.05),
        ("X_t", 0.002),
        ("Y_v", -0.5),
        ("Y_vv", -0.3),
        ("Y_ur", -0.6),
        ("Y_d", 0.01),
        ("N_r", -0.6),
        ("N_v", -0.1),
        ("N_d", -0.02),
    ];
    let params = dir.write(
        "truth.json",
        &format!(
            "{{{}}}",
            truth
                .iter()
                .map(|(n, v)| format!("\"{n}\": {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let mut data = Vec::new();
    for k in 1..=runs {
        let input = format!("{out}/run-{k}.csv");
        let logged = dir.path(&format!("logged-{k}.csv")).display().to_string();
        let seed = k.to_string();
        let o = leeway(&[
            "simulate",
            &model,
            "--params",
            &params,
            "--input",
            &input,
            "--disturbance",
            "current.north=0.3,current.east=-0.2",
            "--disturbance-std",
            "current=0.03",
            "--correlation-time",
            "current=20",
            "--noise",
            "u=0.02,v=0.02,r=0.005,psi=0.01",
            "--seed",
            &seed,
            "--out",
            &logged,
        ]);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        data.push(logged);
    }
    let mut args = vec!["estimate", model.as_str(), "--json", "--centring"];
    let centring = d["centring"].as_str().expect("centring").to_string();
    args.push(&centring);
    for f in &data {
        args.push("--data");
        args.push(f);
    }
    let o = leeway(&args);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let est = json(&o);
    let est_path = dir.write("est.json", &stdout(&o));
    // Within five predicted standard errors of the truth (the prediction
    // was made for these runs and this noise; five leaves room for the
    // one trial this is).
    let predicted = d["prediction"]["parameters"]
        .as_array()
        .expect("parameters");
    let names = est["parameters"].as_array().expect("names");
    for (i, (name, value)) in truth.iter().enumerate() {
        assert_eq!(names[i]["name"], *name);
        let got = names[i]["value"].as_f64().expect("θ");
        let sigma = predicted[i]["std_error"].as_f64().expect("σ");
        assert!(
            (got - value).abs() <= 5.0 * sigma,
            "{name}: {got} vs {value} ± {sigma}"
        );
    }
    let o = leeway(&[
        "validate", &model, "--params", &est_path, "--data", &data[0], "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    // Validation holds the current the estimate found, and the yaw rate
    // (no offset to get wrong) fits well; surge and sway fits are measured
    // about their offsets, which a few hundredths of m/s of current error
    // cost dearly (the design's --verify reports them).
    assert_eq!(
        v["models"][0]["disturbances"]["current.north"]["from"],
        "estimate"
    );
    let fit = v["mean"]["r"].as_f64().expect("fit");
    assert!(fit > 80.0, "r: {fit} in {v}");
}

/// The ROV's inputs, for plans that differ elsewhere.
const ROV_INPUTS: &str = "[inputs.tau_x]\nrange = [-6000, 6000]\n[inputs.tau_y]\nrange = [-6000, 6000]\n[inputs.tau_n]\nrange = [-4000, 4000]\n";

#[test]
fn a_budget_beyond_the_bound_is_a_located_error_in_well_under_a_second() {
    let dir = Scratch::new("design-bounds");
    for (name, head, budget, at) in [
        ("tiny-step", "step = 1e-300\n", "time = 1200\n", ":9:8"),
        ("huge-time", "step = 0.05\n", "time = 1e308\n", ":9:8"),
        ("nano-step", "step = 1e-9\n", "time = 1200\n", ":9:8"),
        ("long-time", "step = 0.05\n", "time = 1e7\n", ":9:8"),
    ] {
        let plan = dir.write(
            &format!("{name}.toml"),
            &format!("{head}{ROV_INPUTS}[budget]\n{budget}"),
        );
        let start = std::time::Instant::now();
        let o = leeway(&["design", "examples/models/rov.som", "--plan", &plan]);
        let took = start.elapsed();
        no_panic(&o);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{name}: {err}");
        assert!(err.contains(&format!("{plan}{at}")), "{name}: {err}");
        assert!(err.contains("budget.time = "), "{name}: {err}");
        assert!(err.contains("more than 10000000 samples"), "{name}: {err}");
        assert!(err.contains("lengthen step"), "{name}: {err}");
        // Refused before anything is simulated (the debug build's time).
        assert!(took < std::time::Duration::from_secs(5), "{name}: {took:?}");
    }
}

#[test]
fn a_target_beyond_the_bound_is_said_so() {
    let dir = Scratch::new("design-target-bound");
    let plan = rov_plan(&dir);
    let args = [
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--target",
        "1e-300",
    ];
    let o = leeway(&args);
    no_panic(&o);
    let text = stdout(&o);
    assert_eq!(code(&o), 0, "{text}{}", stderr(&o));
    assert!(
        text.contains("more than 10000000 samples (beyond what leeway plans)"),
        "{text}"
    );
    assert!(!text.contains("18446744073709551615"), "{text}");
    let o = leeway(&[&args[..], &["--json"]].concat());
    let d = json(&o);
    assert!(d["prediction"]["target"]["samples"].is_null(), "{d}");
    assert_eq!(d["prediction"]["target"]["within_budget"], false);
}

#[test]
fn a_plan_reads_as_it_says() {
    let dir = Scratch::new("design-reads");
    let inputs = r#""inputs": {"tau_x": {"range": [-6000, 6000]}, "tau_y": {"range": [-6000, 6000]}, "tau_n": {"range": [-4000, 4000]}}"#;
    for (name, text, at, says) in [
        (
            "top.json",
            format!("{{\"step\": 0.05,\n {inputs},\n \"step\": 1e-9}}"),
            ":3:7",
            "`step` is given twice",
        ),
        (
            // serde refuses a struct's field twice, but a map (inputs,
            // disturbances, noise, nominal) kept the last.
            "nested.json",
            format!("{{{inputs},\n \"noise\": {{\"u\": 0.01,\n  \"u\": 10}}}}"),
            ":3:5",
            "`noise.u` is given twice",
        ),
        (
            "three.json",
            format!("{{{inputs},\n \"step\": 0.05}}")
                .replace("[-6000, 6000]}, \"tau_y\"", "[-35, 35, 1e308]}, \"tau_y\""),
            ":1:",
            "this one has 3",
        ),
        (
            "three.toml",
            ROV_INPUTS.replacen("[-6000, 6000]", "[-35, 35, 1e308]", 1),
            ":2:9",
            "this one has 3",
        ),
    ] {
        let plan = dir.write(name, &text);
        let o = leeway(&["design", "examples/models/rov.som", "--plan", &plan]);
        no_panic(&o);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{name}: {err}");
        assert!(err.contains(&format!("{plan}{at}")), "{name}: {err}");
        assert!(err.contains(says), "{name}: {err}");
    }
}

#[test]
fn compare_errors_name_compare() {
    let dir = Scratch::new("design-compare-name");
    let plan = rov_plan(&dir);
    let missing = dir.path("missing.csv").display().to_string();
    let o = leeway(&[
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--compare",
        &missing,
    ]);
    no_panic(&o);
    let err = stderr(&o);
    assert_eq!(code(&o), 2, "{err}");
    assert!(err.contains("--compare"), "{err}");
    assert!(!err.contains("--input"), "{err}");
}

#[test]
fn a_design_whose_verified_models_fall_short_exits_1_with_what_fails() {
    // The survey boat of issue 47 on 10 minutes at sea: its signs hold, but
    // the models its trials yield cannot simulate the held-out run.
    let dir = Scratch::new("design-short");
    let text = std::fs::read_to_string(root().join("design/tests/fixtures/survey_boat.toml"))
        .expect("plan");
    let plan = dir.write("boat.toml", &text.replace("time = 1800", "time = 600"));
    let o = leeway(&[
        "design",
        "design/tests/fixtures/survey_boat.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--verify",
        "4",
    ]);
    no_panic(&o);
    let text = stdout(&o);
    assert_eq!(code(&o), 1, "{text}");
    assert!(
        text.contains("not a success: the verified models are not what the trial needs"),
        "{text}"
    );
    assert!(
        text.contains("fails: held-out fit more than 10 points below the true model's: u "),
        "{text}"
    );
    assert!(text.contains("would help: "), "{text}");
    // The other runs the design tried were verified too, in turn, and
    // failed: the design's own is the one reported.
    let tried = text
        .split("verified the runs the design tried, in turn:\n")
        .nth(1)
        .unwrap_or_else(|| panic!("{text}"));
    let lines: Vec<&str> = tried.lines().take_while(|l| l.starts_with("  ")).collect();
    assert!(lines.len() >= 2, "{text}");
    assert!(lines.iter().all(|l| l.contains(": fails (")), "{text}");
    assert_eq!(
        lines
            .iter()
            .filter(|l| l.ends_with("— the design above"))
            .count(),
        1,
        "{text}"
    );
}
