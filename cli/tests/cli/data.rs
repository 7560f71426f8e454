//! End-to-end tests of real-log data handling: `#` comment lines, time-stamp
//! jitter and `--time-tolerance`, `--resample`, units declared in the model's
//! `data { }`, the aggregate rows of the `estimate` table, and `validate` with
//! several parameter files (the binary on synthetic ship data).

use leeway_model::Interpreter;
use leeway_scenarios::study;
use serde_json::Value;

use crate::common::*;

fn rows_of(text: &str) -> Vec<Vec<String>> {
    text.lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

fn join(rows: &[Vec<String>]) -> String {
    rows.iter().map(|r| r.join(",") + "\n").collect()
}

/// The ship's data (its time column, step 1 as the model's) with stamps
/// jittered by `jitter(k)` seconds.
fn with_time(text: &str, jitter: impl Fn(usize) -> f64) -> String {
    let mut rows = rows_of(text);
    assert_eq!(rows[0][0], "time");
    for (k, row) in rows.iter_mut().enumerate().skip(1) {
        let t = (k - 1) as f64 + jitter(k - 1);
        row[0] = format!("{t:?}");
    }
    join(&rows)
}

fn files_in(dir: &Scratch) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(&dir.0)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().to_string())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

#[test]
fn comment_lines_are_skipped_counted_and_shown_with_physical_row_numbers() {
    let dir = Scratch::new("comments");
    let text = estimation_csv(2000, 1.0, 5);
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    lines.insert(0, "# logger: test rig v2".to_string());
    lines.insert(0, "# vessel: Ship".to_string());
    lines.insert(500, "   # operator note: buoy passed".to_string());
    let commented = lines.join("\n") + "\n";
    let data = dir.write("log.csv", &commented);
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(
        stdout(&o).contains(&format!(
            "data              {data}: 3 comment lines skipped"
        )),
        "{}",
        stdout(&o)
    );
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    let v = json(&o);
    assert_eq!(v["data_files"][0]["comment_lines"], 3, "{v}");
    assert_eq!(v["data_files"][0]["file"], data.as_str());
    // A bad cell after the comments is located on the line an editor shows:
    // line 1000 of the file (3 comments + header above data row 996).
    let mut bad = lines.clone();
    let mut cells: Vec<String> = bad[999].split(',').map(str::to_string).collect();
    cells[1] = "n/a".to_string();
    bad[999] = cells.join(",");
    let data = dir.write("bad.csv", &(bad.join("\n") + "\n"));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).contains(&format!("{data}:1000:2 (u)")),
        "{}",
        stderr(&o)
    );
}

#[test]
fn jitter_within_the_tolerance_is_accepted_and_reported_beyond_it_located() {
    let dir = Scratch::new("jitter");
    let text = estimation_csv(2000, 1.0, 6);
    // ±2 % of the 1 s step, alternating.
    let jittered = with_time(&text, |k| if k % 2 == 0 { 0.0 } else { 0.02 });
    let data = dir.write("jit.csv", &jittered);
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    let dev = v["data_files"][0]["experiments"][0]["max_step_deviation"]
        .as_f64()
        .unwrap_or(f64::NAN);
    assert!(dev > 0.015 && dev < 0.025, "{v}");
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert!(
        stdout(&o).contains(
            "time steps deviate up to 2.00 % from the nominal step (within --time-tolerance)"
        ),
        "{}",
        stdout(&o)
    );
    // Tighter than the jitter: the worst step beyond it, located, with the way out.
    let o = leeway(&[
        "estimate",
        SHIP,
        "--data",
        &data,
        "--time-tolerance",
        "0.01",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(
        err.starts_with(&format!("error[data]: {data}:"))
            && err.contains(":1 (time): inconsistent sample time"),
        "{err}"
    );
    assert!(err.contains("2.0 % off the nominal (mean) step"), "{err}");
    assert!(
        err.contains("--time-tolerance") && err.contains("--resample"),
        "{err}"
    );
    // The tolerance is a fraction in (0, 0.5).
    for bad in ["5", "0.5", "0", "-0.1", "x"] {
        let o = leeway(&[
            "estimate",
            SHIP,
            "--data",
            &data,
            &format!("--time-tolerance={bad}"),
        ]);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{bad}");
        assert!(
            stderr(&o).contains("not a fraction in (0, 0.5)"),
            "{}",
            stderr(&o)
        );
    }
    // Resampling a log without time stamps is a located error.
    let untimed: Vec<Vec<String>> = rows_of(&text)
        .into_iter()
        .map(|r| r[1..].to_vec())
        .collect();
    let plain = dir.write("plain.csv", &join(&untimed));
    let o = leeway(&["estimate", SHIP, "--data", &plain, "--resample", "1"]);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).contains(&format!("{plain}:1: --resample needs a time column")),
        "{}",
        stderr(&o)
    );
    // With a time column, resampled at the model's step: said in the output.
    let o = leeway(&["estimate", SHIP, "--data", &data, "--resample", "1"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(
        stdout(&o).contains("experiment `jit` resampled from 2000 rows to 2000 samples"),
        "{}",
        stdout(&o)
    );
    let o = leeway(&["estimate", SHIP, "--data", &data, "--resample", "0.5"]);
    assert_eq!(code(&o), 2);
    assert!(
        stderr(&o).contains("--resample 0.5 conflicts"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn declared_units_are_converted_and_shown() {
    let dir = Scratch::new("units");
    let source = std::fs::read_to_string(root().join(SHIP)).unwrap_or_default();
    let with_units = source.replacen(
        "    nominal {",
        "    data { psi = \"heading_deg\" in deg, r in deg/s }\n    nominal {",
        1,
    );
    let model = dir.write("ship_deg.som", &with_units);
    // High wind: every parameter excited, so the estimate is well conditioned
    // and the last-bit differences of converted values do not show.
    let text = estimation_csv(3000, 10.0, 7);
    let mut rows = rows_of(&text);
    let col = |name: &str| rows[0].iter().position(|h| h == name).unwrap_or(0);
    let (psi, r) = (col("psi"), col("r"));
    rows[0][psi] = "heading_deg".to_string();
    for row in rows.iter_mut().skip(1) {
        for c in [psi, r] {
            let v: f64 = row[c].parse().unwrap_or(f64::NAN);
            row[c] = format!("{:?}", v.to_degrees());
        }
    }
    let deg = dir.write("deg.csv", &join(&rows));
    let rad = dir.write("rad.csv", &text);
    let a = json(&leeway(&["estimate", &model, "--data", &deg, "--json"]));
    let b = json(&leeway(&["estimate", SHIP, "--data", &rad, "--json"]));
    assert_eq!(a["errors"], Value::Array(Vec::new()), "{a}");
    assert_eq!(a["data_units"]["psi"], "deg");
    assert_eq!(a["data_units"]["r"], "deg/s");
    // Degrees converted on load give the radians' estimate (to rounding).
    for (name, x) in a["estimates"].as_object().cloned().unwrap_or_default() {
        let (x, y) = (
            x.as_f64().unwrap_or(f64::NAN),
            b["estimates"][&name].as_f64().unwrap_or(f64::NAN),
        );
        assert!(
            (x - y).abs() <= 1e-6 * y.abs().max(1e-6),
            "{name}: {x} vs {y}"
        );
    }
    // No heading-unit warning: the check runs on converted values.
    let warnings = a["warnings"].to_string();
    assert!(!warnings.contains("does not integrate"), "{warnings}");
    let o = leeway(&["estimate", &model, "--data", &deg]);
    let out = stdout(&o);
    assert!(
        out.contains("psi: column heading_deg in deg, converted to rad"),
        "{out}"
    );
    assert!(
        out.contains("r: column r in deg/s, converted to rad/s"),
        "{out}"
    );
    // An unknown unit: the model's located error, exit 2.
    let broken = dir.write(
        "ship_bad.som",
        &source.replacen(
            "    nominal {",
            "    data { r in degrees/s }\n    nominal {",
            1,
        ),
    );
    let o = leeway(&["estimate", &broken, "--data", &rad]);
    no_panic(&o);
    assert_eq!(code(&o), 2);
    let err = stderr(&o);
    assert!(
        err.contains("error[unknown-unit]: unknown unit `degrees/s` for `r`"),
        "{err}"
    );
    assert!(err.contains("ship_bad.som:"), "{err}");
    assert!(
        err.contains("help: units for the yaw rate the heading integrates: rad/s, deg/s"),
        "{err}"
    );
}

#[test]
fn aggregates_are_marked_on_their_own_rows() {
    let dir = Scratch::new("aggregates");
    let data = dir.write("calm.csv", &estimation_csv(2000, 1.0, 8));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    let line = out
        .lines()
        .position(|l| l.trim_start().starts_with("N_uv ") && l.trim_end().ends_with("aggregate"))
        .unwrap_or_else(|| panic!("no aggregate row for N_uv:\n{out}"));
    let next = out.lines().nth(line + 1).unwrap_or_default();
    assert!(
        next.trim_start().starts_with("= N_uv + ") && next.contains("W_uv"),
        "{next}"
    );
    let v = json(&leeway(&["estimate", SHIP, "--data", &data, "--json"]));
    let n_uv = v["parameters"]
        .as_array()
        .and_then(|p| p.iter().find(|c| c["name"] == "N_uv"))
        .cloned()
        .unwrap_or_default();
    assert!(
        n_uv["aggregate"]
            .as_str()
            .is_some_and(|a| a.contains("W_uv")),
        "{n_uv}"
    );
    // The contract's fields stay.
    assert!(n_uv["status"].is_string() && n_uv["estimates"].is_string());
}

#[test]
fn validate_compares_several_parameter_files_and_writes_only_when_asked() {
    let dir = Scratch::new("compare");
    let model = ship();
    let val = study::validation_experiment(&model, 400);
    let val2 = study::validation_experiment(&model, 300);
    let mut second = val2.clone();
    second.name = "second".to_string();
    let mut first = val.clone();
    first.name = "first".to_string();
    let data = dir.write("val.csv", &csv_text(&model, &[&first, &second]));
    let truth = dir.write("truth.json", &true_params());
    let est = leeway(&[
        "estimate",
        SHIP,
        "--data",
        &dir.write("run.csv", &estimation_csv(3000, 1.0, 9)),
        "--json",
    ]);
    let est = dir.write("iv3.json", &stdout(&est));
    let before = files_in(&dir);
    let o = leeway(&[
        "validate", SHIP, "--params", &truth, "--params", &est, "--data", &data, "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    // Nothing written without --plot.
    assert_eq!(files_in(&dir), before);
    let v = json(&o);
    // The first file's results stay at the top level, as with one file.
    assert_eq!(v["params"], truth.as_str());
    assert_eq!(v["experiments"].as_array().map(Vec::len), Some(2));
    assert_eq!(v["plot"], Value::Null);
    let models = v["models"].as_array().cloned().unwrap_or_default();
    assert_eq!(models.len(), 2);
    assert_eq!(models[0]["name"], "truth");
    assert_eq!(models[1]["name"], "iv3");
    assert_eq!(models[0]["experiments"], v["experiments"]);
    for m in &models {
        for o in ["u", "v", "r", "psi"] {
            let per: Vec<f64> = m["experiments"]
                .as_array()
                .map(|es| {
                    es.iter()
                        .map(|e| {
                            if o == "psi" {
                                &e["heading_fit"]
                            } else {
                                &e["fit"][o]
                            }
                            .as_f64()
                            .unwrap_or(f64::NAN)
                        })
                        .collect()
                })
                .unwrap_or_default();
            let mean = m["mean"][o].as_f64().unwrap_or(f64::NAN);
            assert!((mean - (per[0] + per[1]) / 2.0).abs() < 1e-9, "{o}: {m}");
        }
    }
    // The true θ on noise-free data: a perfect fit.
    assert!(
        (v["mean"]["u"].as_f64().unwrap_or(0.0) - 100.0).abs() < 1e-6,
        "{v}"
    );
    // Text: a block per file, a mean row; the plot only where asked, one line per file.
    let plot = dir.path("cmp.svg").display().to_string();
    let o = leeway(&[
        "validate", SHIP, "--params", &truth, "--params", &est, "--data", &data, "--plot", &plot,
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains(&format!("truth ({truth})")) && out.contains(&format!("iv3 ({est})")),
        "{out}"
    );
    assert_eq!(out.matches("\n  mean ").count(), 2, "{out}");
    assert!(
        out.contains("  experiment  samples  u       v       r       psi"),
        "{out}"
    );
    let svg = std::fs::read_to_string(&plot).unwrap_or_default();
    for label in [
        "\ntruth\n",
        "\niv3\n",
        "\nmeasured\n",
        "\nsecond\n",
        "psi: mean fit over 2 experiments",
    ] {
        assert!(svg.contains(label), "`{label}` missing from the SVG");
    }
}

/// The tanker zigzag campaign (`leeway_scenarios::zigzag`) written as a logger would:
/// comment lines, jittered time stamps, the rudder in degrees.
fn tanker_log(dir: &Scratch, noisy: bool) -> (String, Vec<String>, Vec<String>) {
    let source = std::fs::read_to_string(root().join("examples/models/tanker.som"))
        .unwrap_or_default()
        .replace(
            "    nominal {",
            "    data { delta in deg }\n\n    nominal {",
        );
    let model_path = dir.write("tanker-raw.som", &source);
    let c = leeway_structure::compile(&source, &Default::default());
    let model = Interpreter::new(c.ir.expect("the tanker compiles"));
    let campaign = leeway_scenarios::zigzag::campaign(&leeway_scenarios::zigzag::CampaignOptions {
        noise: noisy.then(leeway_scenarios::zigzag::Noise::default),
        ..Default::default()
    });
    let write = |runs: &[leeway_scenarios::zigzag::Run]| -> Vec<String> {
        runs.iter()
            .map(|run| {
                let mut e = run
                    .experiment(leeway_model::Model::ir(&model))
                    .expect("run");
                for d in &mut e.inputs[0] {
                    *d = d.to_degrees();
                }
                let text = with_time(&csv_text(&model, &[&e]), |k| {
                    0.5 * k as f64 + 0.001 * (((k * 37) % 3) as f64 - 1.0)
                });
                let logged = format!(
                    "# tanker 1:35, zigzag {}\n# rudder in degrees\n{text}",
                    run.name
                );
                dir.write(&format!("{}.csv", run.name), &logged)
            })
            .collect()
    };
    (
        model_path,
        write(&campaign.train),
        write(&campaign.validation),
    )
}

fn data_args(files: &[String]) -> Vec<&str> {
    files.iter().flat_map(|f| ["--data", f.as_str()]).collect()
}

/// The model an engineer writes, on logs as a logger writes them: it
/// compiles as written, estimates with default options (uncentred
/// instruments, constants estimated, summed experiments), says so, and its
/// free-run fit on held-out runs beats least squares's under noise.
#[test]
fn the_tanker_estimates_from_raw_logs_with_default_options() {
    let dir = Scratch::new("tanker");
    let (model, train, validation) = tanker_log(&dir, true);
    let check = leeway(&["check", &model]);
    assert_eq!(code(&check), 0, "{}", stderr(&check));
    assert!(stdout(&check).contains("instrument centring: none"));
    let mut args = vec!["estimate", model.as_str()];
    args.extend(data_args(&train));
    let o = leeway(&args);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = stdout(&o);
    for part in [
        "X_0",
        "centring          none (the default for this model)",
        "combination       summed",
        "2 comment lines skipped",
        "delta: column delta in deg, converted to rad",
    ] {
        assert!(out.contains(part), "`{part}` missing:\n{out}");
    }
    assert!(stderr(&o).contains("cross zero; their moduli are evaluated pointwise"));
    let mut fits = Vec::new();
    for method in ["iv3", "ls"] {
        let mut args = vec!["estimate", model.as_str(), "--method", method, "--json"];
        args.extend(data_args(&train));
        let o = leeway(&args);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        let params = dir.write(&format!("{method}.json"), &stdout(&o));
        let mut args = vec!["validate", model.as_str(), "--params", &params, "--json"];
        args.extend(data_args(&validation));
        let v = leeway(&args);
        assert_eq!(code(&v), 0, "{}", stderr(&v));
        fits.push(json(&v)["mean"]["u"].as_f64().unwrap_or(f64::NAN));
    }
    assert!(
        fits[0] > 85.0 && fits[0] >= fits[1] + 10.0,
        "surge iv3, ls: {fits:?}"
    );

    // Per-experiment centring annihilates the constants: refused, naming the way out.
    let mut args = vec!["estimate", model.as_str(), "--centring", "experiment"];
    args.extend(data_args(&train));
    let o = leeway(&args);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("error[unidentifiable]") && err.contains("`X_0`"),
        "{err}"
    );
    assert!(err.contains("--centring none"), "{err}");
}

/// A constant force on a craft in a current: `check` refuses it under the
/// default per-experiment centring and names the centring that keeps it.
#[test]
fn check_names_the_centring_that_keeps_a_constant() {
    let dir = Scratch::new("constant");
    let model = dir.write(
        "current.som",
        "model S {\n    state u, v, r\n    input tau\n    heading psi integrates r\n    disturbance current unmeasured earth(north, east)\n    water = relative(current)\n    der u = X_u*water.u + X_t*tau + X_0\n    der v = Y_v*water.v\n    der r = N_r*r\n}\n",
    );
    let o = leeway(&["check", &model]);
    assert_eq!(code(&o), 1);
    let err = stderr(&o);
    assert!(
        err.contains("`X_0` is a constant term, annihilated by per-experiment centring"),
        "{err}"
    );
    assert!(err.contains(&format!("{model}:7:37")), "{err}");
    assert!(err.contains("`--centring none`"), "{err}");
    let o = leeway(&["check", &model, "--centring", "none"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
}

/// Scales the named columns of a CSV text by `f` (other columns as written).
fn scale_columns(text: &str, names: &[&str], f: f64) -> String {
    let mut rows = rows_of(text);
    let idx: Vec<usize> = names
        .iter()
        .filter_map(|n| rows[0].iter().position(|h| h == n))
        .collect();
    for row in rows.iter_mut().skip(1) {
        for &i in &idx {
            let v: f64 = row[i].parse().unwrap_or(f64::NAN);
            row[i] = format!("{:e}", v * f);
        }
    }
    join(&rows)
}

#[test]
fn blank_lines_and_quoted_line_breaks_keep_physical_row_numbers() {
    let dir = Scratch::new("blank-rows");
    let text = estimation_csv(400, 1.0, 5);
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // Rows 1..: a blank line after row 10 (physical line 12), a bad cell on
    // the data row that was line 100 before it.
    let bad: Vec<String> = lines[99].split(',').map(str::to_string).collect();
    lines[99] = format!("{},zzz,{}", bad[0], bad[2..].join(","));
    lines.insert(11, String::new());
    lines.insert(12, "   ".to_string());
    let data = dir.write("blank.csv", &(lines.join("\n") + "\n"));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("{data}:102:2 (u): `zzz` is not a number")),
        "{}",
        stderr(&o)
    );
    // Without the bad cell: the blank lines are reported, not skipped silently.
    lines[101] = text.lines().nth(99).unwrap_or_default().to_string();
    let data = dir.write("blank.csv", &(lines.join("\n") + "\n"));
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert_eq!(json(&o)["data_files"][0]["blank_lines"], 2);
    // A quoted cell holding two line breaks on row 5 moves later rows down by two.
    let mut rows = rows_of(&text);
    for (k, row) in rows.iter_mut().enumerate() {
        row.push(match k {
            0 => "note".to_string(),
            5 => "\"rudder\nstuck,\nfreed\"".to_string(),
            _ => "ok".to_string(),
        });
    }
    rows[50][3] = "oops".to_string();
    let data = dir.write("quoted.csv", &join(&rows));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("{data}:53:4 (r): `oops` is not a number")),
        "{}",
        stderr(&o)
    );
}

#[test]
fn too_few_samples_names_the_file_and_json_names_the_model() {
    let dir = Scratch::new("few");
    let text = estimation_csv(400, 1.0, 5);
    let short: String = text.lines().take(13).map(|l| format!("{l}\n")).collect();
    let data = dir.write("short.csv", &short);
    let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    assert_eq!(code(&o), 2, "{}", stdout(&o));
    let v = json(&o);
    assert_eq!(v["model"], "Ship", "{v}");
    let e = &v["errors"][0];
    assert_eq!(e["code"], "too-few-samples", "{v}");
    let message = e["message"].as_str().unwrap_or_default();
    assert!(
        message.contains(&format!("`short` in {data}: 12 samples")),
        "{message}"
    );
}

#[test]
fn a_gross_outlier_is_named_by_row_not_taken_for_a_rank_verdict() {
    let dir = Scratch::new("outlier");
    let text = estimation_csv(2000, 1.0, 5);
    for v in ["1e6", "-3e9", "1e300"] {
        let mut rows = rows_of(&text);
        rows[700][1] = v.to_string();
        let data = dir.write("spike.csv", &join(&rows));
        for method in ["ls", "iv3"] {
            let o = leeway(&["estimate", SHIP, "--data", &data, "--method", method]);
            assert_eq!(code(&o), 2, "{}", stderr(&o));
            assert!(
                stderr(&o).contains(&format!("{data}:701:2 (u): `u` = ")),
                "{}",
                stderr(&o)
            );
            assert!(stderr(&o).contains("gross outlier"), "{}", stderr(&o));
        }
    }
    // A whole column so large that squares overflow: a located data error
    // from the first pass, not "not excited".
    let huge = scale_columns(&text, &["u"], 1e200);
    let data = dir.write("huge.csv", &huge);
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("non-finite-data"), "{}", stderr(&o));
    assert!(stderr(&o).contains(&format!("{data}:")), "{}", stderr(&o));
    assert!(!stderr(&o).contains("not excited"), "{}", stderr(&o));
}

/// The gap of the spread rule: a sensor stuck at one value (the anemometer's
/// north component) with one spike is still named by its row, by `estimate`
/// and `validate` alike.
#[test]
fn a_stuck_sensor_with_a_spike_is_named_by_row() {
    let dir = Scratch::new("stuck");
    let text = estimation_csv(2000, 1.0, 5);
    let mut rows = rows_of(&text);
    let col = rows[0]
        .iter()
        .position(|h| h == "wind_n")
        .unwrap_or_else(|| panic!("{:?}", rows[0]));
    for row in rows.iter_mut().skip(1) {
        row[col] = "10".to_string();
    }
    rows[700][col] = "1e300".to_string();
    let data = dir.write("stuck.csv", &join(&rows));
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    let expected = format!(
        "{data}:701:{} (wind_n): `wind_n` = 1e300 is a gross outlier",
        col + 1
    );
    assert!(stderr(&o).contains(&expected), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("the column is constant"),
        "{}",
        stderr(&o)
    );
    let params = dir.write("theta.json", &true_params());
    let o = leeway(&[
        "validate",
        SHIP,
        "--params",
        &params,
        "--data",
        &data,
        "--no-plot",
    ]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains(&expected), "{}", stderr(&o));
}

#[test]
fn the_same_data_in_other_units_give_the_same_verdict() {
    let dir = Scratch::new("units-scale");
    let text = estimation_csv(3000, 1.0, 5);
    let velocities = ["u", "v", "wind_n", "wind_e"];
    for method in ["ls", "iv3"] {
        let reference = {
            let data = dir.write("x1.csv", &text);
            let o = leeway(&[
                "estimate", SHIP, "--data", &data, "--method", method, "--json",
            ]);
            assert_eq!(code(&o), 0, "{}", stderr(&o));
            json(&o)
        };
        let statuses = |v: &Value| -> Vec<String> {
            v["parameters"]
                .as_array()
                .map(|a| {
                    a.iter()
                        // Estimated or held is the verdict; which estimated
                        // columns carry a held one (`aggregate`) depends on
                        // the numeric combination, which a unit scales.
                        .map(|p| {
                            let status = p["status"].as_str().unwrap_or("");
                            let status = if status == "aggregate" {
                                "estimated"
                            } else {
                                status
                            };
                            format!("{} {status}", p["name"])
                        })
                        .collect()
                })
                .unwrap_or_default()
        };
        for f in [1e-8, 1e-4, 1e4, 1e8] {
            let data = dir.write("scaled.csv", &scale_columns(&text, &velocities, f));
            let o = leeway(&[
                "estimate", SHIP, "--data", &data, "--method", method, "--json",
            ]);
            assert_eq!(code(&o), 0, "{method} × {f}: {}", stdout(&o));
            let v = json(&o);
            assert_eq!(statuses(&v), statuses(&reference), "{method} × {f}");
            // Linear terms do not change with the velocity unit (for IV the
            // instruments' nominal simulation is not rescaled, so only the
            // verdict must match).
            let tol = if method == "ls" { 1e-6 } else { 1e-2 };
            for p in ["X_u", "Y_v", "N_r"] {
                let (a, b) = (
                    v["estimates"][p].as_f64().unwrap_or(f64::NAN),
                    reference["estimates"][p].as_f64().unwrap_or(f64::NAN),
                );
                assert!(
                    (a - b).abs() <= tol * b.abs().max(1e-3),
                    "{method} × {f}: {p} {a} vs {b}"
                );
            }
        }
    }
}

#[test]
fn every_numeric_option_is_bounded_with_an_error_naming_it() {
    let dir = Scratch::new("bounds");
    let data = dir.write("d.csv", &estimation_csv(200, 1.0, 5));
    let params = dir.write("p.json", &true_params());
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["reproduce", "--n", "10,1000000000000"], "--n"),
        (vec!["reproduce", "--n", "1000001"], "--n"),
        (vec!["reproduce", "--runs", "10001"], "--runs"),
        (
            vec!["reproduce", "--runs", "200", "--n", "1000000"],
            "--runs",
        ),
        (vec!["reproduce", "--threads", "100000"], "--threads"),
        (vec!["reproduce", "--threads", "0"], "--threads"),
        (
            vec![
                "estimate",
                SHIP,
                "--data",
                &data,
                "--max-refinements",
                "101",
            ],
            "--max-refinements",
        ),
        (
            vec!["estimate", SHIP, "--data", &data, "--lags", "1001"],
            "--lags",
        ),
        (
            vec!["estimate", SHIP, "--data", &data, "--refine-subsample", "0"],
            "--refine-subsample",
        ),
        (
            vec![
                "estimate",
                SHIP,
                "--data",
                &data,
                "--refine-subsample",
                "1.5",
            ],
            "--refine-subsample",
        ),
        (
            vec![
                "estimate",
                SHIP,
                "--data",
                &data,
                "--refine-subsample",
                "nan",
            ],
            "--refine-subsample",
        ),
        (
            vec!["estimate", SHIP, "--data", &data, "--lags", "0"],
            "--lags",
        ),
        (
            vec!["estimate", SHIP, "--data", &data, "--step", "1e7"],
            "--step",
        ),
        (
            vec!["estimate", SHIP, "--data", &data, "--step", "1e-9"],
            "--step",
        ),
        (
            vec!["estimate", SHIP, "--data", &data, "--time-tolerance", "0.7"],
            "--time-tolerance",
        ),
        (
            vec!["estimate", SHIP, "--data", &data, "--resample", "1e300"],
            "--resample",
        ),
        (
            vec![
                "validate", SHIP, "--params", &params, "--data", &data, "--step", "inf",
            ],
            "--step",
        ),
        (
            vec![
                "simulate", SHIP, "--params", &params, "--input", &data, "--x0", "u=1e13",
            ],
            "--x0",
        ),
        (
            vec![
                "simulate",
                SHIP,
                "--params",
                &params,
                "--input",
                &data,
                "--disturbance",
                "north=1e300",
            ],
            "--disturbance",
        ),
    ];
    for (args, option) in cases {
        let started = std::time::Instant::now();
        let o = leeway(&args);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(option), "{args:?}: {}", stderr(&o));
        assert!(
            started.elapsed().as_secs() < 10,
            "{args:?} took {:?}",
            started.elapsed()
        );
    }
    // A resampling step at odds with the model's step is refused before any work.
    let o = leeway(&[
        "estimate",
        SHIP,
        "--data",
        &data,
        "--step",
        "1",
        "--resample",
        "1e-6",
    ]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
}

#[test]
fn too_few_samples_after_resampling_still_names_the_file() {
    // Regression: under --resample the experiments are held in memory, and
    // the error named them without their file.
    let dir = Scratch::new("few-resampled");
    let text = estimation_csv(400, 1.0, 5);
    let short: String = text.lines().take(13).map(|l| format!("{l}\n")).collect();
    let data = dir.write("short.csv", &short);
    let o = leeway(&["estimate", SHIP, "--data", &data, "--resample", "1"]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stdout(&o));
    assert!(
        stderr(&o).contains(&format!("`short` in {data}: 12 samples")),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_file_with_carriage_return_line_ends_reads_as_with_line_feeds() {
    // Regression: files written with lone CRs (classic Mac OS tools) were
    // one long line, refused as "missing column".
    let (dir, other) = (Scratch::new("cr-only"), Scratch::new("lf-only"));
    let text = estimation_csv(1500, 1.0, 9);
    // The same file name: the experiment is named after it.
    let lf = other.write("log.csv", &format!("# a logger's comment\n{text}"));
    let cr = dir.write(
        "log.csv",
        &format!("# a logger's comment\n{text}").replace('\n', "\r"),
    );
    let a = leeway(&["estimate", SHIP, "--data", &lf, "--json"]);
    let b = leeway(&["estimate", SHIP, "--data", &cr, "--json"]);
    assert_eq!(code(&a), 0, "{}", stderr(&a));
    assert_eq!(code(&b), 0, "{}", stderr(&b));
    assert_eq!(stdout(&b).replace(&cr, &lf), stdout(&a));
    // Rows are still named by their physical line.
    let mut broken = format!("# a logger's comment\n{text}").replace('\n', "\r");
    let at = broken.match_indices('\r').nth(40).map_or(0, |(i, _)| i + 1);
    broken.insert_str(at, "oops");
    let bad = dir.write("bad.csv", &broken);
    let o = leeway(&["estimate", SHIP, "--data", &bad]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("{bad}:42:1 (time)")),
        "{}",
        stderr(&o)
    );
}

#[test]
fn an_overflowing_nominal_value_is_a_located_error_not_a_panic() {
    // Regression: one nominal value of 1e305 panicked in nalgebra's SVD.
    let dir = Scratch::new("nominal-overflow");
    let data = dir.write("log.csv", &estimation_csv(1500, 1.0, 5));
    for value in ["1e305", "5e307", "1.7e308", "-1e200"] {
        let nominal = dir.write(
            "nominal.json",
            &true_params().replace("\"X_u\": -0.05", &format!("\"X_u\": {value}")),
        );
        for initial in ["delayed", "nominal"] {
            let o = leeway(&[
                "estimate",
                SHIP,
                "--data",
                &data,
                "--nominal",
                &nominal,
                "--initial",
                initial,
                "--json",
            ]);
            no_panic(&o);
            assert_eq!(code(&o), 2, "{value}: {}", stdout(&o));
            let v = json(&o);
            assert_eq!(v["errors"][0]["code"], "invalid-nominal", "{v}");
            assert!(
                v["errors"][0]["message"]
                    .as_str()
                    .is_some_and(|m| m.contains("`X_u`")),
                "{v}"
            );
        }
    }
    // The same from the model's own nominal { } block.
    let source = std::fs::read_to_string(root().join(SHIP)).unwrap_or_else(|e| panic!("{e}"));
    let model = source.replacen("N_r = -0.15", "N_r = 1e305", 1);
    assert_ne!(model, source, "the ship has a nominal block");
    let model = dir.write("ship.som", &model);
    let o = leeway(&["estimate", &model, "--data", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("`N_r`") && stderr(&o).contains("nominal { }"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn validate_calls_a_fit_below_zero_what_it_is() {
    // Regression: a model whose simulation fits at −299 % was reported
    // without a word.
    let dir = Scratch::new("below-mean");
    let data = dir.write("log.csv", &estimation_csv(1500, 1.0, 5));
    let wrong = dir.write(
        "wrong.json",
        &true_params().replace("\"N_tau\": 0.0003", "\"N_tau\": -0.0003"),
    );
    let o = leeway(&[
        "validate", SHIP, "--data", &data, "--params", &wrong, "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    let fit = v["mean"]["r"].as_f64().unwrap_or(f64::NAN);
    assert!(fit < 0.0, "{v}");
    assert!(
        v["warnings"].as_array().is_some_and(|w| w.iter().any(|w| w
            .as_str()
            .is_some_and(|w| w.contains("`r` at") && w.contains("worse than the data's mean")))),
        "{v}"
    );
}

/// Files are opened side by side, one a core: the experiments keep the
/// order the files were given in, the estimate is the same bytes on every
/// run, and every failing file is reported in the order given, however the
/// threads finished.
#[test]
fn files_opened_side_by_side_keep_their_order_in_estimates_and_errors() {
    let dir = Scratch::new("side-by-side");
    let files: Vec<String> = (0..6u64)
        .map(|i| {
            let rows = 300 + 97 * i as usize;
            dir.write(&format!("run{i}.csv"), &estimation_csv(rows, 1.0, 40 + i))
        })
        .collect();
    let estimate = |given: &[String]| {
        let mut args = vec!["estimate", SHIP, "--method", "ls", "--json"];
        args.extend(data_args(given));
        let o = leeway(&args);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        stdout(&o)
    };
    let order = |text: &str| -> Vec<String> {
        let v: Value = serde_json::from_str(text).unwrap_or_default();
        let files = v["data_files"].as_array().cloned().unwrap_or_default();
        files
            .iter()
            .filter_map(|f| f["file"].as_str().map(str::to_string))
            .collect()
    };
    let first = estimate(&files);
    assert_eq!(order(&first), files, "{first}");
    assert_eq!(estimate(&files), first);
    let reversed: Vec<String> = files.iter().rev().cloned().collect();
    assert_eq!(order(&estimate(&reversed)), reversed);

    // A bad cell near the end of a long file and a missing column in a
    // short one: both reported, in the order given.
    let mut lines: Vec<String> = estimation_csv(3000, 1.0, 7)
        .lines()
        .map(str::to_string)
        .collect();
    let at = lines.len() - 3;
    let mut cells: Vec<String> = lines[at].split(',').map(str::to_string).collect();
    cells[1] = "oops".into();
    lines[at] = cells.join(",");
    let long_bad = dir.write("long-bad.csv", &(lines.join("\n") + "\n"));
    let short_bad = dir.write("short-bad.csv", "t,u\n0,1\n");
    let given = [
        files[0].clone(),
        long_bad.clone(),
        files[1].clone(),
        short_bad.clone(),
    ];
    let mut args = vec!["estimate", SHIP, "--json"];
    args.extend(data_args(&given));
    let o = leeway(&args);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stdout(&o));
    let errors = json(&o)["errors"].as_array().cloned().unwrap_or_default();
    let located: Vec<String> = errors.iter().map(|e| e["location"].to_string()).collect();
    assert_eq!(errors.len(), 2, "{located:?}");
    assert!(
        located[0].contains(&format!("{long_bad}:{}", at + 1)),
        "{located:?}"
    );
    assert!(located[1].contains(&short_bad), "{located:?}");
}
