//! A manifest and its sources are read within bounds: a manifest larger
//! than 1 MiB or without end (`/dev/zero`) is refused without being read
//! whole; a source that is a pipe, a device or a folder is refused before
//! it is opened (never waited on); an error shows nothing of a source but
//! the columns the manifest asked for.

use std::path::Path;
use std::time::{Duration, Instant};

use leeway_data::{DataError, LoadOptions};
use leeway_logs::{load_log, load_path};
use leeway_structure::ir::Ir;

fn model() -> Ir {
    let src = "model M { step 0.1 state u, r input n heading psi integrates r
         der u = X*u + T*n der r = N*r + M*n }";
    leeway_structure::compile(src, &leeway_structure::CompileOptions::default())
        .ir
        .unwrap_or_else(|| panic!("the test model compiles"))
}

/// A manifest reading every signal from `file` (a CSV source).
fn manifest_of(file: &str) -> String {
    format!(
        "[sources.m]\nfile = \"{file}\"\ntime = [\"secs\", \"nsecs\"]\n\
         [signals]\nu = \"m:u\"\nr = \"m:r\"\nn = \"m:n\"\npsi = \"m:psi\"\n"
    )
}

/// Loads the log at `path` on a thread: its result, or `None` when it
/// takes longer than `limit` (a wait on a pipe).
fn load_within(path: &Path, limit: Duration) -> Option<Result<(), DataError>> {
    let (done, outcome) = std::sync::mpsc::channel();
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        let loaded = load_log(&path, &model(), &LoadOptions::default()).map(|_| ());
        let _ = done.send(loaded);
    });
    outcome.recv_timeout(limit).ok()
}

#[test]
fn a_manifest_larger_than_a_mib_or_without_end_is_refused_unread() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let big = dir.path().join("big.toml");
    std::fs::write(&big, "# a comment\n".repeat(200_000)).unwrap_or_else(|e| panic!("{e}"));
    let e = load_log(&big, &model(), &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("2.4 MB of manifest is refused"));
    assert_eq!(e.location, big.display().to_string());
    assert!(
        e.message.contains("larger than 1 MiB (2400000 bytes)"),
        "{e:?}"
    );
    // A device's size says nothing: its bytes are counted as they come.
    if Path::new("/dev/zero").exists() {
        let zero = dir.path().join("zero.toml");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap_or_else(|e| panic!("{e}"));
        let started = Instant::now();
        let e = load_path(&zero, &model(), &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("/dev/zero is no manifest"));
        assert!(e.message.contains("larger than 1 MiB"), "{e:?}");
        assert!(started.elapsed() < Duration::from_secs(10));
    }
    // Not UTF-8: where the first bad byte is.
    let latin = dir.path().join("latin.toml");
    std::fs::write(&latin, b"[sources.m]\nfile = \"caf\xe9.csv\"\n")
        .unwrap_or_else(|e| panic!("{e}"));
    let e = load_log(&latin, &model(), &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("Latin-1 is refused"));
    assert_eq!(e.location, format!("{}:2:12", latin.display()));
    assert!(e.message.contains("not UTF-8"), "{e:?}");
}

#[test]
fn a_source_that_is_a_device_a_folder_or_a_pipe_is_refused_unopened() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let manifest = dir.path().join("log.toml");
    let mut files = vec![("folder.csv", "a folder")];
    std::fs::create_dir(dir.path().join("folder.csv")).unwrap_or_else(|e| panic!("{e}"));
    if Path::new("/dev/zero").exists() {
        files.push(("/dev/zero", "a device"));
    }
    let fifo = std::process::Command::new("mkfifo")
        .arg(dir.path().join("pipe.csv"))
        .status();
    if fifo.is_ok_and(|s| s.success()) {
        files.push(("pipe.csv", "a pipe (FIFO)"));
    } else {
        eprintln!("no mkfifo here: the pipe is not tried");
    }
    for (file, what) in files {
        std::fs::write(&manifest, manifest_of(file)).unwrap_or_else(|e| panic!("{e}"));
        // A pipe without a writer would be waited on for ever, and
        // /dev/zero read without end: both refused at once.
        let e = load_within(&manifest, Duration::from_secs(20))
            .unwrap_or_else(|| panic!("{file}: the load waits"))
            .err()
            .unwrap_or_else(|| panic!("{file} is refused"));
        assert_eq!(e.location, format!("{}:1:1", manifest.display()), "{e:?}");
        assert!(
            e.message
                .contains(&format!("source `m` is {what}, not a file")),
            "{e:?}"
        );
    }
}

#[test]
fn a_missing_column_is_named_and_the_source_header_is_not_shown() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    // Any readable file may be named: its first line stays unsaid.
    std::fs::write(
        dir.path().join("secret.csv"),
        "token=hunter2,secs,nsecs\n1,2,3\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let manifest = dir.path().join("log.toml");
    std::fs::write(&manifest, manifest_of("secret.csv")).unwrap_or_else(|e| panic!("{e}"));
    let e = load_log(&manifest, &model(), &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("a missing column is refused"));
    let said = format!("{e:?}");
    assert!(e.message.contains("has no column `"), "{said}");
    assert!(e.message.contains("its header row has 3 columns"), "{said}");
    assert!(!said.contains("hunter2"), "{said}");
    assert!(e.location.ends_with("secret.csv:1"), "{said}");
}

#[test]
fn a_source_line_longer_than_a_mib_is_an_error_at_its_line() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let mut text = b"secs,nsecs,u,r,n,psi\n1700000000,0,1,0,0,0\n".to_vec();
    text.extend(std::iter::repeat_n(b'1', 3 << 20));
    std::fs::write(dir.path().join("long.csv"), &text).unwrap_or_else(|e| panic!("{e}"));
    let manifest = dir.path().join("log.toml");
    std::fs::write(&manifest, manifest_of("long.csv")).unwrap_or_else(|e| panic!("{e}"));
    let e = load_log(&manifest, &model(), &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("a 3 MiB line is refused"));
    assert!(e.location.ends_with("long.csv:3"), "{e:?}");
    assert!(e.message.contains("a line longer than 1 MiB"), "{e:?}");
}
