//! Robot logs read as written (docs/logs.md): topics in files of their own,
//! joined on the model's grid, gaps split and reported, every malformed
//! variant one located error.

use crate::common::{Scratch, code, json, leeway, no_panic, stderr, stdout};
use leeway_scenarios::ferry::{FerryLog, write_ferry_log};

const FERRY: &str = "examples/models/ferry.som";

fn ferry_log(name: &str, aligned: bool) -> Scratch {
    let dir = Scratch::new(name);
    let spec = FerryLog {
        aligned,
        seconds: 600.0,
        closed_loop: (450.0, 520.0),
        ..FerryLog::default()
    };
    write_ferry_log(&dir.0, &spec).unwrap_or_else(|e| panic!("{e}"));
    dir
}

fn estimate_json(data: &str, method: &str) -> serde_json::Value {
    let o = leeway(&[
        "estimate", FERRY, "--data", data, "--method", method, "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    json(&o)
}

#[test]
fn the_topics_joined_give_the_estimate_of_the_same_samples_on_one_grid() {
    let dir = ferry_log("aligned", true);
    for method in ["ls", "iv3"] {
        let joined = estimate_json(&dir.path("ferry.toml").display().to_string(), method);
        let uniform = estimate_json(&dir.path("uniform.csv").display().to_string(), method);
        assert_eq!(joined["parameters"], uniform["parameters"], "{method}");
        let names = |v: &serde_json::Value| v["experiments"].clone();
        assert_eq!(names(&joined), names(&uniform));
    }
}

#[test]
fn the_methods_that_must_agree_say_so_and_a_controller_is_found() {
    let dir = ferry_log("agree", true);
    let data = dir.path("ferry.toml").display().to_string();
    let iv1 = estimate_json(&data, "iv1");
    let iv3 = estimate_json(&data, "iv3");
    assert_eq!(iv1["parameters"], iv3["parameters"]);
    let said = |v: &serde_json::Value| {
        v["notes"].as_array().into_iter().flatten().any(|n| {
            n.as_str()
                .is_some_and(|n| n.starts_with("iv1, iv2 and iv3 give this same estimate"))
        })
    };
    assert!(said(&iv1) && said(&iv3));
    assert!(!said(&estimate_json(&data, "ls")));
    // Dynamic positioning from 450 to 520 s, 44.2 to 114.2 s into `ferry/2`.
    let closed: Vec<&str> = iv3["warnings"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|w| w.as_str())
        .filter(|w| w.contains("the past motion explains"))
        .collect();
    assert_eq!(closed.len(), 1, "{}", iv3["warnings"]);
    assert!(
        closed[0].starts_with("experiment `ferry/2`, samples 600–899 (t = 60 to 89.9 s"),
        "{}",
        closed[0]
    );
}

#[test]
fn every_split_is_reported_with_its_time_range() {
    let dir = ferry_log("realistic", false);
    let manifest = dir.path("ferry.toml").display().to_string();
    let v = estimate_json(&manifest, "ls");
    let e = &v["data_files"][0]["experiments"][0];
    let gaps: Vec<(String, f64, f64)> = e["gaps"]
        .as_array()
        .unwrap_or_else(|| panic!("{e}"))
        .iter()
        .map(|g| {
            (
                g["signal"].as_str().unwrap_or_default().to_string(),
                g["from"].as_f64().unwrap_or_default(),
                g["to"].as_f64().unwrap_or_default(),
            )
        })
        .collect();
    // The allocator's one-second stall and the velocities' 5.8 s hole.
    assert_eq!(gaps.len(), 2, "{gaps:?}");
    assert_eq!(gaps[0].0, "tau_x, tau_y, tau_n");
    assert!(
        gaps[0].1 < 300.0 && gaps[0].2 > 301.0 && gaps[0].2 < 301.3,
        "{gaps:?}"
    );
    assert_eq!(gaps[1].0, "u, v, r");
    assert!(gaps[1].1 <= 400.0 && gaps[1].2 >= 405.8, "{gaps:?}");
    assert_eq!(e["pieces"].as_array().map(Vec::len), Some(3));
    let signals = v["data_files"][0]["signals"].as_array().map(Vec::len);
    assert_eq!(signals, Some(7));
    let o = leeway(&["estimate", FERRY, "--data", &manifest, "--method", "ls"]);
    assert!(
        stdout(&o).contains("split: no samples of u, v, r from t = 399."),
        "{}",
        stdout(&o)
    );
    // A wider limit bridges the stall, never the hole.
    let o = leeway(&[
        "estimate",
        FERRY,
        "--data",
        &manifest,
        "--method",
        "ls",
        "--max-gap",
        "2",
        "--json",
    ]);
    let gaps = json(&o)["data_files"][0]["experiments"][0]["gaps"].clone();
    assert_eq!(gaps.as_array().map(Vec::len), Some(1), "{gaps}");
}

/// Runs the estimate on the ferry log after `edit` and returns its one error.
fn refused(name: &str, edit: impl FnOnce(&Scratch)) -> (String, String) {
    let dir = ferry_log(name, false);
    edit(&dir);
    let manifest = dir.path("ferry.toml").display().to_string();
    let o = leeway(&[
        "estimate", FERRY, "--data", &manifest, "--method", "ls", "--json",
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stdout(&o));
    let v = json(&o);
    let errors = v["errors"].as_array().cloned().unwrap_or_default();
    assert_eq!(errors.len(), 1, "{v}");
    let at = errors[0]["location"]
        .as_str()
        .unwrap_or_default()
        .to_string();
    let message = errors[0]["message"]
        .as_str()
        .unwrap_or_default()
        .to_string();
    (at.replace(&dir.0.display().to_string(), "DIR"), message)
}

fn rewrite(dir: &Scratch, file: &str, f: impl FnOnce(String) -> String) {
    let path = dir.path(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(&path, f(text)).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn stamps_going_backwards_are_located() {
    let (at, message) = refused("backwards", |d| {
        rewrite(d, "twist.csv", |t| {
            let mut lines: Vec<&str> = t.lines().collect();
            lines.swap(100, 101);
            lines.join("\n") + "\n"
        });
    });
    assert_eq!(at, "DIR/twist.csv:102:1 (secs)");
    assert!(message.starts_with("time goes backwards"), "{message}");
}

#[test]
fn a_local_time_column_is_refused_with_the_reason() {
    let (at, message) = refused("local-time", |d| {
        rewrite(d, "ferry.toml", |t| {
            t.replacen(
                "[sources.heading]\nfile = \"heading.csv\"\ntime = [\"secs\", \"nsecs\"]",
                "[sources.heading]\nfile = \"heading.csv\"\ntime = \"time_local\"",
                1,
            )
        });
    });
    assert_eq!(at, "DIR/heading.csv:2:3 (time_local)");
    assert!(message.contains("not an ISO-8601 date"), "{message}");
}

#[test]
fn a_missing_file_column_or_mapping_is_one_error() {
    let (at, message) = refused("missing-file", |d| {
        std::fs::remove_file(d.path("tau.csv")).unwrap_or_else(|e| panic!("{e}"));
    });
    assert!(at.contains("tau.csv"), "{at}: {message}");
    let (at, message) = refused("missing-column", |d| {
        rewrite(d, "ferry.toml", |t| {
            t.replace("\"twist:u\"", "\"twist:surge\"")
        });
    });
    assert_eq!(at, "DIR/twist.csv:1");
    assert!(message.contains("no column `surge`"), "{message}");
    let (at, message) = refused("unmapped", |d| {
        rewrite(d, "ferry.toml", |t| t.replace("tau_n = \"tau:Mz\"\n", ""));
    });
    assert_eq!(at, "DIR/ferry.toml");
    assert!(message.contains("`tau_n` is not mapped"), "{message}");
    let (at, message) = refused("unknown-source", |d| {
        rewrite(d, "ferry.toml", |t| {
            t.replace("\"tau:Mz\"", "\"allocator:Mz\"")
        });
    });
    assert!(at.starts_with("DIR/ferry.toml:"), "{at}");
    assert!(message.contains("`allocator`"), "{message}");
}

#[test]
fn clocks_that_never_overlap_are_refused() {
    let (at, message) = refused("time-zone", |d| {
        // The heading logged two hours late: local time taken for UTC.
        rewrite(d, "heading.csv", |t| {
            t.lines()
                .enumerate()
                .map(|(i, l)| match (i, l.split_once(',')) {
                    (0, _) | (_, None) => l.to_string(),
                    (_, Some((s, rest))) => {
                        format!("{},{rest}", s.parse::<i64>().unwrap_or(0) + 7200)
                    }
                })
                .collect::<Vec<_>>()
                .join("\n")
                + "\n"
        });
    });
    assert_eq!(at, "DIR/ferry.toml");
    assert!(message.contains("never overlap"), "{message}");
}

#[test]
fn a_gap_in_every_topic_splits_the_log() {
    let dir = ferry_log("all-gap", false);
    for file in ["twist.csv", "heading.csv", "tau.csv"] {
        rewrite(&dir, file, |t| {
            t.lines()
                .filter(|l| {
                    let secs = l.split(',').next().and_then(|s| s.parse::<i64>().ok());
                    !secs.is_some_and(|s| {
                        let t = s - leeway_scenarios::ferry::EPOCH_SECONDS;
                        (200..220).contains(&t)
                    })
                })
                .collect::<Vec<_>>()
                .join("\n")
                + "\n"
        });
    }
    let v = estimate_json(&dir.path("ferry.toml").display().to_string(), "ls");
    let gaps = v["data_files"][0]["experiments"][0]["gaps"].clone();
    let covers = gaps.as_array().into_iter().flatten().any(|g| {
        g["from"].as_f64().is_some_and(|f| f < 200.0)
            && g["to"].as_f64().is_some_and(|t| t >= 220.0)
    });
    assert!(covers, "{gaps}");
}

#[test]
fn resampling_one_file_splits_at_its_hole() {
    // The aligned log's own samples, one file, with the velocities' hole.
    let dir = ferry_log("resample-hole", true);
    let text = std::fs::read_to_string(dir.path("uniform.csv")).unwrap_or_else(|e| panic!("{e}"));
    // One experiment whose time column jumps across the hole.
    let joined: String = text
        .lines()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            if cells.len() > 1 && cells[1].starts_with("ferry/") {
                cells[1] = "ferry";
            }
            cells.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let file = dir.write("one.csv", &(joined + "\n"));
    let o = leeway(&[
        "estimate",
        FERRY,
        "--data",
        &file,
        "--method",
        "ls",
        "--resample",
        "0.1",
        "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    let e = &v["data_files"][0]["experiments"][0];
    assert_eq!(e["gaps"].as_array().map(Vec::len), Some(1), "{e}");
    let names: Vec<&str> = v["experiments"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|x| x["name"].as_str())
        .collect();
    assert_eq!(names, ["ferry/1", "ferry/2"]);
}

#[test]
fn the_same_log_as_a_bag_gives_the_same_estimate() {
    let dir = ferry_log("bag", false);
    leeway_scenarios::ferry::write_ferry_bag(&dir.0).unwrap_or_else(|e| panic!("{e}"));
    let files = estimate_json(&dir.path("ferry.toml").display().to_string(), "iv3");
    let bag = estimate_json(&dir.path("ferry-bag.toml").display().to_string(), "iv3");
    let values = |v: &serde_json::Value| -> Vec<f64> {
        v["parameters"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|p| p["value"].as_f64())
            .collect()
    };
    // The heading goes through a quaternion and back: equal to round-off.
    for (a, b) in values(&files).iter().zip(values(&bag)) {
        assert!((a - b).abs() <= 1e-9 * a.abs(), "{a} {b}");
    }
    assert_eq!(values(&files).len(), 12);
    assert_eq!(
        files["data_files"][0]["experiments"][0]["gaps"],
        bag["data_files"][0]["experiments"][0]["gaps"]
    );
    // Without a manifest: the model's data block names the field paths.
    let source = std::fs::read_to_string(crate::common::root().join(FERRY)).unwrap_or_default();
    let paths = "data { u = \"/navigation/twist_body.twist.linear.x\", v = \"/navigation/twist_body.twist.linear.y\", r = \"/navigation/twist_body.twist.angular.z\", psi = \"/imu.orientation\", tau_x = \"/allocator/wrench.wrench.force.x\", tau_y = \"/allocator/wrench.wrench.force.y\", tau_n = \"/allocator/wrench.wrench.torque.z\" }\n    nominal {";
    let model = dir.write("ferry-bag.som", &source.replacen("nominal {", paths, 1));
    let bag_file = dir.path("ferry.mcap").display().to_string();
    let bare = leeway(&["estimate", &model, "--data", &bag_file, "--json"]);
    assert_eq!(code(&bare), 0, "{}", stdout(&bare));
    assert_eq!(values(&json(&bare)), values(&bag));
}

#[test]
fn a_bag_with_a_wrong_path_or_damaged_is_one_located_error() {
    let (at, message) = refused("bag-path", |d| {
        leeway_scenarios::ferry::write_ferry_bag(&d.0).unwrap_or_else(|e| panic!("{e}"));
        let manifest = std::fs::read_to_string(d.path("ferry-bag.toml")).unwrap_or_default();
        std::fs::write(
            d.path("ferry.toml"),
            manifest.replace("wrench.force.x", "wrench.force.q"),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    });
    assert!(at.contains("ferry.mcap"), "{at}: {message}");
    assert!(
        message.contains("force.q") || message.contains("`q`"),
        "{message}"
    );
    let (at, _) = refused("bag-damaged", |d| {
        leeway_scenarios::ferry::write_ferry_bag(&d.0).unwrap_or_else(|e| panic!("{e}"));
        let mut bytes = std::fs::read(d.path("ferry.mcap")).unwrap_or_default();
        let n = bytes.len();
        bytes.truncate(n / 2);
        std::fs::write(d.path("ferry.mcap"), bytes).unwrap_or_else(|e| panic!("{e}"));
        std::fs::rename(d.path("ferry-bag.toml"), d.path("ferry.toml"))
            .unwrap_or_else(|e| panic!("{e}"));
    });
    assert!(at.contains("ferry.mcap"), "{at}");
}

#[test]
fn the_log_as_written_recovers_the_ferry_and_its_dead_time() {
    let dir = ferry_log("truth", false);
    let data = dir.path("ferry.toml").display().to_string();
    let v = estimate_json(&data, "iv3");
    // Model error (the truth is RK4 at 100 Hz, the model Euler at 10 Hz),
    // asynchronous topics, a closed-loop stretch: within 8 % of the truth.
    for (name, truth) in leeway_scenarios::ferry::TRUTH {
        let p = v["parameters"]
            .as_array()
            .into_iter()
            .flatten()
            .find(|p| p["name"] == name);
        let value = p.and_then(|p| p["value"].as_f64()).unwrap_or(f64::NAN);
        let tolerance = if name == "N_rr" || name == "X_vr" {
            0.15
        } else {
            0.08
        };
        assert!(
            (value - truth).abs() <= tolerance * truth.abs(),
            "{name}: {value} against {truth}"
        );
    }
    let o = leeway(&[
        "estimate",
        FERRY,
        "--data",
        &data,
        "--scan-delay",
        "tau_x=0..2s",
        "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert_eq!(
        json(&o)["delay_scan"]["samples"],
        10,
        "{}",
        json(&o)["delay_scan"]
    );
}

/// The relative errors of `v`'s parameters against the raw ferry's truth,
/// with their relative standard errors.
fn raw_errors(v: &serde_json::Value) -> Vec<(&'static str, f64, f64)> {
    leeway_scenarios::raw_ferry::RAW_TRUTH
        .iter()
        .map(|(name, truth)| {
            let p = v["parameters"]
                .as_array()
                .into_iter()
                .flatten()
                .find(|p| p["name"] == *name);
            let of = |key: &str| p.and_then(|p| p[key].as_f64()).unwrap_or(f64::NAN);
            (
                *name,
                (of("value") - truth) / truth.abs(),
                of("std_error") / truth.abs(),
            )
        })
        .collect()
}

#[test]
fn raw_topics_read_by_their_means_recover_the_truth_where_instants_do_not() {
    use leeway_scenarios::raw_ferry::{RawFerry, write_raw_ferry};
    for seed in [1, 2] {
        let dir = Scratch::new(&format!("raw-ferry-{seed}"));
        let spec = RawFerry {
            seed,
            seconds: 1200.0,
            dp: (500.0, 643.0),
        };
        write_raw_ferry(&dir.0, &spec).unwrap_or_else(|e| panic!("{e}"));
        let model = dir.path("raw-ferry.som").display().to_string();
        let run = |manifest: &str| {
            let data = dir.path(manifest).display().to_string();
            let o = leeway(&[
                "estimate", &model, "--data", &data, "--method", "ls", "--json",
            ]);
            assert_eq!(code(&o), 0, "{}", stderr(&o));
            json(&o)
        };
        let means = run("ferry.toml");
        // The window leaves the DP stretch out: two pieces, their spans noted.
        let pieces = &means["data_files"][0]["experiments"][0]["pieces"];
        let spans: Vec<(f64, f64)> = pieces
            .as_array()
            .into_iter()
            .flatten()
            .map(|p| {
                (
                    p["from"].as_f64().unwrap_or(-1.0),
                    p["to"].as_f64().unwrap_or(-1.0),
                )
            })
            .collect();
        assert_eq!(spans, [(0.0, 499.0), (643.0, 1199.0)], "{pieces}");
        let on_grid: Vec<&str> = means["data_files"][0]["signals"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|s| s["on_grid"].as_str())
            .collect();
        // The forces at 50 Hz by their mean over the step, the 5 Hz motion by
        // a centred mean.
        let means_of = |prefix: &str| on_grid.iter().filter(|s| s.starts_with(prefix)).count();
        assert_eq!(means_of("mean over the step of "), 3, "{on_grid:?}");
        assert_eq!(means_of("centred mean over the step of "), 4, "{on_grid:?}");
        // The same topics read at one instant a step (the old rule).
        let manifest = std::fs::read_to_string(dir.path("ferry.toml")).unwrap_or_default();
        let instant = ["u", "v", "r"]
            .iter()
            .fold(manifest, |m, s| {
                m.replace(
                    &format!("{s} = \"nav:{s}\""),
                    &format!("{s} = {{ from = \"nav:{s}\", on_grid = \"instant\" }}"),
                )
            })
            .replace(
                "tau_x = \"tau:Fx\"",
                "tau_x = { from = \"tau:Fx\", on_grid = \"instant\" }",
            )
            .replace(
                "tau_y = \"tau:Fy\"",
                "tau_y = { from = \"tau:Fy\", on_grid = \"instant\" }",
            )
            .replace(
                "tau_n = \"tau:Mz\"",
                "tau_n = { from = \"tau:Mz\", on_grid = \"instant\" }",
            )
            .replace(
                "frame = \"enu\" }",
                "frame = \"enu\", on_grid = \"instant\" }",
            );
        dir.write("instant.toml", &instant);
        let instants = run("instant.toml");
        let (mean_err, instant_err) = (raw_errors(&means), raw_errors(&instants));
        // Within statistical tolerance of the truth: three standard errors,
        // plus 8 % for the model error (the truth is RK4 at 100 Hz, the
        // model one Euler step a second: 5 % on a 10 s time constant); the
        // input gains within 5 %.
        for (name, e, se) in &mean_err {
            let tolerance = if name.ends_with("_t") {
                0.05
            } else {
                3.0 * se + 0.08
            };
            assert!(
                e.abs() <= tolerance,
                "seed {seed}, {name}: {:+.1} % (σ {:.1} %)",
                100.0 * e,
                100.0 * se
            );
        }
        // One sample a step keeps the ripple and the noise as an error in
        // the regressors: the gains shrink.
        let total = |errs: &[(&str, f64, f64)]| errs.iter().map(|(_, e, _)| e.abs()).sum::<f64>();
        assert!(
            total(&mean_err) * 2.0 < total(&instant_err),
            "seed {seed}: {mean_err:?} against {instant_err:?}"
        );
        for ((name, m, _), (_, i, _)) in mean_err.iter().zip(&instant_err) {
            if name.ends_with("_t") {
                assert!(
                    i.abs() > 0.2 && m.abs() < i.abs() / 4.0,
                    "seed {seed}, {name}: {m} against {i}"
                );
            }
        }
    }
}

#[test]
fn several_inputs_are_scanned_one_after_another() {
    let dir = ferry_log("scan-two", false);
    let data = dir.path("ferry.toml").display().to_string();
    let o = leeway(&[
        "estimate",
        FERRY,
        "--data",
        &data,
        "--scan-delay",
        "tau_x=8..12,tau_n=8..12",
        "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = json(&o);
    let scans = v["delay_scans"].as_array().cloned().unwrap_or_default();
    let chosen: Vec<(String, u64)> = scans
        .iter()
        .map(|s| {
            (
                s["input"].as_str().unwrap_or_default().to_string(),
                s["samples"].as_u64().unwrap_or(0),
            )
        })
        .collect();
    assert_eq!(
        chosen,
        [("tau_x".into(), 10), ("tau_n".into(), 10)],
        "{scans:?}"
    );
    assert_eq!(v["delay_scan"]["input"], "tau_n");
    // An input scanned twice is one usage error before any work.
    let o = leeway(&[
        "estimate",
        FERRY,
        "--data",
        &data,
        "--scan-delay",
        "tau_x=8..12",
        "--scan-delay",
        "tau_x=0..2",
    ]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("scanned twice"), "{}", stderr(&o));
}

#[test]
fn check_lists_the_declared_dead_times() {
    let o = leeway(&["check", FERRY]);
    assert!(
        stdout(&o).contains(
            "dead times: tau_x 10 samples (1 s), tau_y 10 samples (1 s), tau_n 10 samples (1 s)"
        ),
        "{}",
        stdout(&o)
    );
}

#[test]
fn keep_windows_from_the_command_line_and_options_given_twice_must_agree() {
    let dir = ferry_log("keep", false);
    let data = dir.path("ferry.toml").display().to_string();
    let o = leeway(&[
        "estimate", FERRY, "--data", &data, "--method", "ls", "--keep", "0..250", "--keep",
        "420..", "--json",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let pieces = json(&o)["data_files"][0]["experiments"][0]["pieces"].clone();
    let spans: Vec<(f64, f64)> = pieces
        .as_array()
        .into_iter()
        .flatten()
        .map(|p| {
            (
                p["from"].as_f64().unwrap_or(-1.0),
                p["to"].as_f64().unwrap_or(-1.0),
            )
        })
        .collect();
    // The velocities' hole (400–405.8 s) lies between the windows.
    assert_eq!(spans.len(), 2, "{pieces}");
    assert_eq!(spans[0], (0.0, 250.0), "{pieces}");
    assert!(spans[1].0 == 420.0 && spans[1].1 > 590.0, "{pieces}");
    // A window beyond the log: one error naming it.
    let o = leeway(&["estimate", FERRY, "--data", &data, "--keep", "5000.."]);
    assert_ne!(code(&o), 0);
    no_panic(&o);
    assert!(stderr(&o).contains("--keep (window 1)"), "{}", stderr(&o));
    assert!(stderr(&o).contains("keeps nothing"), "{}", stderr(&o));
    // --max-gap against the manifest's own limit: an error, never a silent pick.
    rewrite(&dir, "ferry.toml", |t| {
        t.replace(
            "experiment = \"ferry\"",
            "experiment = \"ferry\"\nmax_gap = 2.0",
        )
    });
    let o = leeway(&["estimate", FERRY, "--data", &data, "--max-gap", "1"]);
    assert_ne!(code(&o), 0);
    assert!(
        stderr(&o).contains("conflicts with the manifest's gap limit"),
        "{}",
        stderr(&o)
    );
    // The same limit in both places agrees.
    let o = leeway(&[
        "estimate",
        FERRY,
        "--data",
        &data,
        "--max-gap",
        "2",
        "--method",
        "ls",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    // --keep with the manifest's own windows, and on one data file.
    rewrite(&dir, "ferry.toml", |t| t + "[[keep]]\nfrom = 0\nto = 300\n");
    let o = leeway(&["estimate", FERRY, "--data", &data, "--keep", "0..100"]);
    assert_ne!(code(&o), 0);
    assert!(stderr(&o).contains("[[keep]] windows"), "{}", stderr(&o));
    let csv = dir.path("tau.csv").display().to_string();
    let o = leeway(&["estimate", FERRY, "--data", &csv, "--keep", "0..100"]);
    assert_ne!(code(&o), 0);
    assert!(stderr(&o).contains("one data file"), "{}", stderr(&o));
}
