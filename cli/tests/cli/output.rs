//! Output that cannot be written: stdout on a full disk (`> /dev/full`) is
//! an `io` error with exit 2 for every command, a closed pipe a quiet exit
//! 141, never a panic; files are never written through a symbolic link;
//! `simulate` on an input no longer than the dead time is a located error.

use crate::common::{SHIP, Scratch, code, estimation_csv, leeway, no_panic, root, stderr, stdout};
use std::process::{Command, Output, Stdio};

const THRUSTER: &str = "tests/models/thruster.som";
const FULL: &str = "error[io]: cannot write the output to stdout: No space left on device\n";

/// Runs `leeway ARGS` from the workspace root with stdout on `out`.
fn leeway_into(args: &[&str], out: impl Into<Stdio>) -> Output {
    Command::new(env!("CARGO_BIN_EXE_leeway"))
        .args(args)
        .current_dir(root())
        .env("NO_COLOR", "1")
        .stdout(out)
        .output()
        .expect("run leeway")
}

/// `leeway ARGS > /dev/full` (`None` where there is no /dev/full).
fn into_full(args: &[&str]) -> Option<Output> {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .ok()?;
    let o = leeway_into(args, full);
    no_panic(&o);
    Some(o)
}

/// Exit 2 and the one line saying why, after what the command said itself.
fn assert_full(o: &Output) {
    assert_eq!(code(o), 2, "{}", stderr(o));
    let err = stderr(o);
    assert!(err.ends_with(FULL), "{err}");
    assert_eq!(err.matches("error[io]").count(), 1, "{err}");
}

/// The thruster's θ and an input of `n` samples (dead times 10 and 3).
fn thruster(dir: &Scratch, n: usize) -> (String, String) {
    let mut csv = "time,tau_x,tau_n,u,r\n".to_string();
    for k in 0..n {
        let x0 = if k == 0 { "0,0" } else { "," };
        csv.push_str(&format!("{:.1},{},{},{x0}\n", k as f64 * 0.1, k % 7, k % 3));
    }
    (
        dir.write("in.csv", &csv),
        dir.write(
            "theta.json",
            r#"{"X_u": -0.2, "X_uu": -0.05, "X_tau": 0.05, "N_r": -0.3, "N_tau": 0.02}"#,
        ),
    )
}

fn rov_plan(dir: &Scratch) -> String {
    let text = std::fs::read_to_string(root().join("examples/plans/rov.toml")).expect("plan");
    dir.write("rov.toml", &text.replace("time = 1200", "time = 100"))
}

#[test]
fn check_on_a_full_disk_is_an_io_error() {
    let Some(o) = into_full(&["check", SHIP]) else {
        return;
    };
    assert_full(&o);
    let Some(o) = into_full(&["check", SHIP, "--json"]) else {
        return;
    };
    assert_full(&o);
}

#[test]
fn simulate_on_a_full_disk_is_an_io_error() {
    let dir = Scratch::new("out-simulate-full");
    let (input, params) = thruster(&dir, 50);
    let Some(o) = into_full(&["simulate", THRUSTER, "--params", &params, "--input", &input]) else {
        return;
    };
    assert_full(&o);
    // `--out` on a full disk was already one; it stays one.
    let o = leeway(&[
        "simulate",
        THRUSTER,
        "--params",
        &params,
        "--input",
        &input,
        "--out",
        "/dev/full",
    ]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o)
            .contains("error[io]: /dev/full: cannot write `/dev/full`: No space left on device"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn estimate_json_on_a_full_disk_is_an_io_error() {
    let dir = Scratch::new("out-estimate-full");
    let data = dir.write("run.csv", &estimation_csv(2000, 1.0, 7));
    let Some(o) = into_full(&["estimate", SHIP, "--data", &data, "--json"]) else {
        return;
    };
    assert_full(&o);
}

#[test]
fn design_on_a_full_disk_is_an_io_error() {
    let dir = Scratch::new("out-design-full");
    let plan = rov_plan(&dir);
    let args = [
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
    ];
    let Some(o) = into_full(&args) else {
        return;
    };
    assert_full(&o);
    let Some(o) = into_full(&[&args[..], &["--json"]].concat()) else {
        return;
    };
    assert_full(&o);
}

#[test]
fn a_closed_pipe_is_a_quiet_exit_141() {
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    let o = leeway_into(&["check", SHIP], writer);
    no_panic(&o);
    assert_eq!(code(&o), 141, "{}", stderr(&o));
    assert!(!stderr(&o).contains("error"), "{}", stderr(&o));
}

#[cfg(unix)]
#[test]
fn design_out_refuses_a_symbolic_link_in_the_directory() {
    let dir = Scratch::new("out-design-link");
    let plan = rov_plan(&dir);
    let out = dir.path("out");
    std::fs::create_dir_all(&out).expect("out");
    let outside = dir.write("outside.txt", "keep\n");
    // A figure: plotters opens it by name; a text file: see below.
    let link = out.join("design.svg");
    std::os::unix::fs::symlink(&outside, &link).expect("symlink");
    let o = leeway(&[
        "design",
        "examples/models/rov.som",
        "--plan",
        &plan,
        "--pilot",
        "0",
        "--out",
        &out.display().to_string(),
    ]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}{}", stdout(&o), stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&outside).ok().as_deref(),
        Some("keep\n")
    );
    let err = stderr(&o);
    assert!(err.contains("error[io]"), "{err}");
    assert!(err.contains(&link.display().to_string()), "{err}");
    assert!(err.contains("symbolic link"), "{err}");
    assert!(std::fs::symlink_metadata(&link).is_ok_and(|m| m.file_type().is_symlink()));
}

#[cfg(unix)]
#[test]
fn simulate_out_refuses_a_symbolic_link() {
    let dir = Scratch::new("out-simulate-link");
    let (input, params) = thruster(&dir, 50);
    let outside = dir.write("outside.txt", "keep\n");
    let link = dir.path("sim.csv");
    std::os::unix::fs::symlink(&outside, &link).expect("symlink");
    let link = link.display().to_string();
    let args = [
        "simulate", THRUSTER, "--params", &params, "--input", &input, "--out", &link,
    ];
    let o = leeway(&args);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&outside).ok().as_deref(),
        Some("keep\n")
    );
    let err = stderr(&o);
    assert!(err.contains(&format!("cannot write `{link}`")), "{err}");
    assert!(err.contains("symbolic link"), "{err}");
    // A regular file in the way is replaced.
    std::fs::remove_file(&link).expect("unlink");
    std::fs::write(&link, "old\n").expect("old");
    let o = leeway(&args);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let text = std::fs::read_to_string(&link).unwrap_or_default();
    assert!(text.starts_with("time,u,r,tau_x,tau_n\n1.0,"), "{text}");
}

#[test]
fn simulate_on_an_input_no_longer_than_the_dead_time_is_a_located_error() {
    let dir = Scratch::new("out-short-input");
    let (input, params) = thruster(&dir, 10);
    let o = leeway(&["simulate", THRUSTER, "--params", &params, "--input", &input]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(stdout(&o), "");
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "error[too-few-samples]: {input}: the input has 10 samples, no more than the model's longest dead time (of `tau_x`) of 10 samples (1 s)"
        )),
        "{err}"
    );
    assert!(
        err.contains("= help: give an input of more than 10 samples"),
        "{err}"
    );
    // One sample more: one row, at the dead time.
    let (input, params) = thruster(&dir, 11);
    let o = leeway(&["simulate", THRUSTER, "--params", &params, "--input", &input]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert_eq!(stdout(&o).lines().count(), 2, "{}", stdout(&o));
}
