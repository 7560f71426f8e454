//! Every file the CLI reads is read within a bound: `/dev/zero` (no line
//! end, no end at all) as a data file, a simulation's input, a manifest, a
//! manifest's source, a plan, a parameter file or a model is one located
//! error, exit 2, in a few MiB and seconds; a pipe is read as a stream (a
//! CSV file through a FIFO, or `<(zcat log.csv.gz)`).

use crate::common::{SHIP, Scratch, code, root, stderr, true_params};
use std::io::Read;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Resident memory past which a run is stopped, MiB: what reading a file
/// with a bound costs is far below, a file read whole (5.7 GB in 8 s
/// before) far above.
const RSS_MIB: u64 = 400;
/// Time past which a run is stopped, s.
const SECONDS: u64 = 60;

/// The resident memory of process `pid`, KiB (0 when it has gone).
fn rss_kib(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

/// Runs `leeway ARGS` from the workspace root, watched: stopped past
/// [`RSS_MIB`] of resident memory or [`SECONDS`]. Its output, and the peak
/// resident memory seen (MiB); `None` when it had to be stopped.
fn watched(args: &[&str]) -> (Option<Output>, u64) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_leeway"))
        .args(args)
        .current_dir(root())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run leeway");
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let started = Instant::now();
    let mut peak = 0;
    let status = loop {
        if let Ok(Some(status)) = child.try_wait() {
            break Some(status);
        }
        peak = peak.max(rss_kib(child.id()));
        if peak > RSS_MIB << 10 || started.elapsed() > Duration::from_secs(SECONDS) {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let (stdout, stderr) = (
        out.join().unwrap_or_default(),
        err.join().unwrap_or_default(),
    );
    let output = status.map(|status| Output {
        status,
        stdout,
        stderr,
    });
    (output, peak >> 10)
}

/// `leeway ARGS` refused with exit 2 and a message holding each of `says`,
/// within the bounds.
fn refused(args: &[&str], says: &[&str]) {
    let (o, peak) = watched(args);
    let o = o.unwrap_or_else(|| panic!("{args:?}: stopped at {peak} MiB (or {SECONDS} s)"));
    assert_eq!(code(&o), 2, "{args:?}: {}", stderr(&o));
    for s in says {
        assert!(
            stderr(&o).contains(s),
            "{args:?}: no {s:?} in\n{}",
            stderr(&o)
        );
    }
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
}

#[test]
fn dev_zero_as_any_file_is_one_located_error_in_bounded_memory() {
    if !Path::new("/dev/zero").exists() {
        eprintln!("no /dev/zero here: skipped");
        return;
    }
    let dir = Scratch::new("readers-zero");
    let line = ["/dev/zero:1", "a line longer than 1 MiB"];
    refused(&["estimate", SHIP, "--data", "/dev/zero"], &line);
    let input = dir.write("in.csv", "tau1,tau2,tau3\n1,2,3\n");
    let x0 = "u=4,v=0,r=0,psi=0";
    let params = dir.write("p.json", &true_params());
    refused(
        &[
            "simulate",
            SHIP,
            "--params",
            params.as_str(),
            "--input",
            "/dev/zero",
            "--x0",
            x0,
        ],
        &line,
    );
    refused(
        &[
            "simulate",
            SHIP,
            "--params",
            "/dev/zero",
            "--input",
            input.as_str(),
            "--x0",
            x0,
        ],
        &["/dev/zero", "larger than 64 MiB"],
    );
    refused(
        &["design", "examples/models/rov.som", "--plan", "/dev/zero"],
        &["/dev/zero", "larger than 1 MiB"],
    );
    refused(&["check", "/dev/zero"], &["more than 1048576 bytes"]);
    // A manifest that is /dev/zero, and one naming it as a source.
    let zero = dir.path("zero.toml");
    std::os::unix::fs::symlink("/dev/zero", &zero).expect("a link");
    let zero = zero.display().to_string();
    refused(&["estimate", SHIP, "--data", &zero], &["larger than 1 MiB"]);
    let signals: String = [
        "u", "v", "r", "psi", "tau1", "tau2", "tau3", "wind_n", "wind_e",
    ]
    .iter()
    .map(|s| format!("{s} = \"nav:{s}\"\n"))
    .collect();
    let manifest = dir.write(
        "log.toml",
        &format!("[sources.nav]\nfile = \"/dev/zero\"\ntime = \"t\"\n[signals]\n{signals}"),
    );
    refused(
        &["estimate", SHIP, "--data", &manifest],
        &["log.toml:1:1", "source `nav` is a device, not a file"],
    );
}

#[test]
fn a_csv_file_through_a_pipe_is_read_as_a_stream() {
    let dir = Scratch::new("readers-pipe");
    let fifo = dir.path("pipe.csv");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("no mkfifo here: skipped");
        return;
    }
    // A header, then a line of 2 MiB: the error names the pipe's line 2,
    // so the stream was read from its first byte, once.
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut text = b"time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n".to_vec();
            text.extend(std::iter::repeat_n(b'0', 2 << 20));
            let w = std::fs::OpenOptions::new().write(true).open(&fifo);
            w.and_then(|mut w| std::io::Write::write_all(&mut w, &text))
        })
    };
    let fifo = fifo.display().to_string();
    let (o, peak) = watched(&["estimate", SHIP, "--data", &fifo]);
    let o = o.unwrap_or_else(|| panic!("stopped at {peak} MiB (or {SECONDS} s): the pipe waits"));
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("{fifo}:2"))
            && stderr(&o).contains("a line longer than 1 MiB"),
        "{}",
        stderr(&o)
    );
    // The writer is done (leeway stops reading at the limit: the rest of
    // the line may be refused by the closed pipe).
    let _ = writer.join();
}
