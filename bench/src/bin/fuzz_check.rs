//! A reproducible fuzz campaign against the release `leeway` binary: generated
//! and mutated `.som` models through `leeway check`, malformed CSV logs through
//! `leeway estimate` (ls and iv3, alternately), each run under a time limit
//! with its peak memory measured (`/usr/bin/time -f %M`). It counts crashes
//! (a signal, a panic, an exit code other than 0/1/2), timeouts and errors
//! that do not name their file, reports the slowest case and the largest
//! peak memory, and keeps every failing input for a regression test.
//!
//! ```sh
//! cargo build --release -p leeway-cli -p leeway-bench
//! target/release/fuzz-check --models 20000 --csvs 2000 --seed 1 --out /tmp/fuzz
//! ```
//!
//! Options: `--models N`, `--csvs N`, `--seed S` (every case is derived from
//! it), `--timeout SECONDS` (default 5), `--leeway PATH` (default
//! `target/release/leeway`), `--root DIR` (the workspace, for the example
//! models; default `.`), `--out DIR` (scratch files and failing cases),
//! `--from I` (start at model case I: with `--models 1 --csvs 0`, one case
//! of a campaign is rerun and left in `DIR/scratch/case.som`).

use leeway::data::write_csv;
use leeway::model::Interpreter;
use leeway_bench::models;
use leeway_scenarios::study;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// One run of the binary.
struct Run {
    /// Exit code (`None`: killed by a signal).
    code: Option<i32>,
    /// What was printed (stdout then stderr; JSON reports are on stdout).
    stderr: String,
    /// Peak resident memory, KiB.
    peak_kib: u64,
    /// User + system CPU seconds.
    cpu: f64,
    wall: f64,
    timed_out: bool,
}

/// Runs `leeway ARGS` under `/usr/bin/time` with a time limit, killing it
/// (and everything it started) when the limit passes.
fn run(leeway: &Path, args: &[&str], timeout: Duration, scratch: &Path) -> Run {
    let metrics = scratch.join("time.txt");
    let _ = std::fs::remove_file(&metrics);
    let start = Instant::now();
    let child = Command::new("/usr/bin/time")
        .arg("-f")
        .arg("%M %U %S")
        .arg("-o")
        .arg(&metrics)
        .arg("timeout")
        .arg("-s")
        .arg("KILL")
        .arg(format!("{}", timeout.as_secs_f64()))
        .arg(leeway)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let Ok(child) = child else {
        return Run {
            code: None,
            stderr: "cannot start /usr/bin/time".to_string(),
            peak_kib: 0,
            cpu: 0.0,
            wall: 0.0,
            timed_out: false,
        };
    };
    let output = child.wait_with_output();
    let wall = start.elapsed().as_secs_f64();
    let (status, stderr) = match output {
        Ok(o) => (
            o.status.code(),
            format!(
                "{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ),
        ),
        Err(e) => (None, e.to_string()),
    };
    let text = std::fs::read_to_string(&metrics).unwrap_or_default();
    // `/usr/bin/time` writes "Command exited with non-zero status N" first
    // when the command fails; the numbers are on the last line.
    let numbers: Vec<f64> = text
        .lines()
        .last()
        .unwrap_or("")
        .split_whitespace()
        .filter_map(|x| x.parse().ok())
        .collect();
    let peak_kib = numbers.first().copied().unwrap_or(0.0) as u64;
    let cpu = numbers.get(1).copied().unwrap_or(0.0) + numbers.get(2).copied().unwrap_or(0.0);
    // `timeout -s KILL` exits 137 when it killed the command.
    let timed_out = status == Some(137) && wall >= timeout.as_secs_f64() * 0.95;
    Run {
        code: status,
        stderr,
        peak_kib,
        cpu,
        wall,
        timed_out,
    }
}

/// What a campaign found.
#[derive(Default)]
struct Tally {
    cases: usize,
    by_code: std::collections::BTreeMap<String, usize>,
    crashes: Vec<String>,
    timeouts: Vec<String>,
    unlocated: Vec<String>,
    slowest: (f64, f64, String),
    largest: (u64, String),
}

impl Tally {
    fn record(&mut self, name: &str, path: &Path, r: &Run, keep: &Path) {
        self.cases += 1;
        let code = r.code.map_or("signal".to_string(), |c| c.to_string());
        *self.by_code.entry(code).or_default() += 1;
        if r.cpu > self.slowest.0 {
            self.slowest = (r.cpu, r.wall, name.to_string());
        }
        if r.peak_kib > self.largest.0 {
            self.largest = (r.peak_kib, name.to_string());
        }
        let file = path.display().to_string();
        let failing = if r.timed_out {
            self.timeouts.push(name.to_string());
            true
        } else if !matches!(r.code, Some(0..=2)) || r.stderr.contains("panicked") {
            self.crashes.push(format!(
                "{name}: exit {:?}: {}",
                r.code,
                r.stderr.lines().last().unwrap_or("")
            ));
            true
        } else if r.code == Some(2)
            && !r.stderr.contains(&format!("{file}:"))
            && !r.stderr.contains(&format!("`{file}`"))
        {
            // Every error names its file (and a line where there is one).
            self.unlocated.push(format!(
                "{name}: {}",
                r.stderr.lines().find(|l| l.contains("error")).unwrap_or("")
            ));
            true
        } else {
            false
        };
        if failing {
            let _ = std::fs::create_dir_all(keep);
            let _ = std::fs::copy(path, keep.join(name));
        }
    }
    fn report(&self, what: &str) {
        println!(
            "{what}: {} cases, exit codes {:?}; crashes {}, timeouts {}, unlocated errors {}; slowest {} ({:.2} s CPU, {:.2} s wall); largest peak memory {} ({:.1} MB)",
            self.cases,
            self.by_code,
            self.crashes.len(),
            self.timeouts.len(),
            self.unlocated.len(),
            self.slowest.2,
            self.slowest.0,
            self.slowest.1,
            self.largest.1,
            self.largest.0 as f64 / 1024.0
        );
        for c in self
            .crashes
            .iter()
            .chain(&self.timeouts)
            .chain(&self.unlocated)
            .take(20)
        {
            println!("  {c}");
        }
    }
}

/// Tokens a mutation inserts: the language's own, and troublemakers.
const TOKENS: &[&str] = &[
    "|",
    "(",
    ")",
    "*",
    "+",
    "-",
    "/",
    "{",
    "}",
    ",",
    ":",
    ";",
    ".",
    "=",
    "\n",
    " ",
    "state ",
    "input ",
    "der ",
    "next ",
    "step ",
    "nominal ",
    "data ",
    "heading ",
    "integrates ",
    "disturbance ",
    "measured ",
    "unmeasured ",
    "earth(",
    "body(",
    "relative(",
    "rotation ",
    "axes(",
    "water.u",
    "water.v",
    "air.u",
    "|u|",
    "X*",
    "u",
    "v",
    "r",
    "psi",
    "0",
    "1",
    "1e308",
    "1e-307",
    "1e309",
    "-",
    "9999999999999999999999999999999999999999999",
    "\"",
    "\"col\"",
    "//",
    "#",
    "\0",
    "\u{7}",
    "é",
    "\u{202e}",
    "in deg",
    "in knots",
    "model ",
];

/// A random mutation of `text`: byte-level edits, token insertions, line
/// duplication or deletion, truncation.
fn mutate(rng: &mut ChaCha8Rng, text: &[u8]) -> Vec<u8> {
    let mut t = text.to_vec();
    let edits = rng.random_range(1..=8);
    for _ in 0..edits {
        let at = if t.is_empty() {
            0
        } else {
            rng.random_range(0..t.len())
        };
        match rng.random_range(0..9) {
            0 if !t.is_empty() => {
                t.remove(at);
            }
            1 if !t.is_empty() => t[at] = rng.random_range(0..=255u8),
            2..=4 => {
                let tok = TOKENS[rng.random_range(0..TOKENS.len())].as_bytes();
                t.splice(at..at, tok.iter().copied());
            }
            5 => {
                // Duplicate a line many times.
                let lines: Vec<&[u8]> = t.split(|b| *b == b'\n').collect();
                if let Some(line) = lines.get(rng.random_range(0..lines.len().max(1))) {
                    let mut copy = Vec::new();
                    let n = rng.random_range(1..200);
                    for _ in 0..n {
                        copy.extend_from_slice(line);
                        copy.push(b'\n');
                    }
                    t.splice(at..at, copy);
                }
            }
            6 if !t.is_empty() => {
                // Delete a span.
                let end = (at + rng.random_range(1..64)).min(t.len());
                t.drain(at..end);
            }
            7 => t.truncate(at),
            _ => {
                // Repeat a span (long chains, deep nesting).
                let end = (at + rng.random_range(1..16)).min(t.len());
                let span = t[at..end].to_vec();
                let n = rng.random_range(1..2000);
                let mut copy = Vec::with_capacity(span.len() * n);
                for _ in 0..n {
                    copy.extend_from_slice(&span);
                }
                t.splice(end..end, copy);
            }
        }
    }
    t
}

/// A generated model: large, deep, long, wide or strange.
fn generate(rng: &mut ChaCha8Rng) -> Vec<u8> {
    match rng.random_range(0..12) {
        0 => models::many_states(rng.random_range(1..3000), rng.random_bool(0.5)).into_bytes(),
        1 => models::many_media(rng.random_range(1..130), rng.random_range(0..130)).into_bytes(),
        2 => models::wide_common(rng.random_range(2..1200)).into_bytes(),
        3 => models::many_constants(rng.random_range(1..1200)).into_bytes(),
        4 => models::repeated_declarations(rng.random_range(1..8000)).into_bytes(),
        5 => {
            // Deep nesting of parentheses or moduli.
            let d = rng.random_range(1..400);
            let (open, close) = if rng.random_bool(0.5) {
                ("(", ")")
            } else {
                ("|", "|")
            };
            format!(
                "model D {{ state u der u = X*{}u{} }}",
                open.repeat(d),
                close.repeat(d)
            )
            .into_bytes()
        }
        6 => {
            // A long operand chain or a run of signs.
            let n = rng.random_range(1..20_000);
            let op = ["*1", "+1", "/1", "+X*u", "-", "*-"][rng.random_range(0..6)];
            format!("model L {{ state u der u = X*u{} }}", op.repeat(n)).into_bytes()
        }
        7 => {
            // A product of sums (multiplied out).
            let n = rng.random_range(1..16);
            format!(
                "model P {{ state u, v der u = X*{} der v = Y*v }}",
                vec!["(u+v)"; n].join("*")
            )
            .into_bytes()
        }
        8 => {
            // Huge or tiny literals.
            let digits = rng.random_range(1..300_000);
            let lit = match rng.random_range(0..4) {
                0 => "7".repeat(digits),
                1 => format!("1e{}", rng.random_range(-10_000_000_i64..10_000_000)),
                2 => format!("0.{}1", "0".repeat(digits)),
                _ => "1e-9223372036854775808".to_string(),
            };
            format!("model N {{ state u der u = {lit}*X*u nominal {{ X = {lit} }} }}").into_bytes()
        }
        9 => {
            // Random bytes.
            let n = rng.random_range(0..4096);
            (0..n).map(|_| rng.random_range(0..=255u8)).collect()
        }
        10 => {
            // Long names.
            let name = "n".repeat(rng.random_range(1..200_000));
            format!("model M {{ state {name}, {name} der {name} = X*{name} }}").into_bytes()
        }
        _ => {
            // Many media with moduli of products and mixed terms.
            let n = rng.random_range(1..40);
            let mut s =
                String::from("model M {\n step 0.1\n state u, v, r\n heading psi integrates r\n");
            for i in 0..n {
                s += &format!(
                    " disturbance d{i} unmeasured earth(n{i}, e{i})\n m{i} = relative(d{i})\n"
                );
            }
            let terms: Vec<String> = (0..n)
                .map(|i| format!("A{i}*m{i}.u*|m{i}.v| + B{i}*|m{i}.u|"))
                .collect();
            s += &format!(
                " der u = {}\n der v = Y*v\n der r = N*r\n}}\n",
                terms.join(" + ")
            );
            s.into_bytes()
        }
    }
}

/// A malformed (or degenerate) CSV log derived from a valid one.
fn malform(rng: &mut ChaCha8Rng, base: &str) -> Vec<u8> {
    let mut rows: Vec<Vec<String>> = base
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let width = rows.first().map_or(1, Vec::len);
    let edits = rng.random_range(1..=3);
    for _ in 0..edits {
        if rows.is_empty() {
            rows.push(vec![String::new()]);
        }
        let n = rows.len();
        let r = rng.random_range(0..n);
        let c = rng.random_range(0..width);
        match rng.random_range(0..14) {
            kind @ 0..7 => edit_rows(rng, &mut rows, kind, (r, c)),
            kind => edit_columns(rng, &mut rows, kind, (r, c)),
        }
    }
    encode(rng, &rows)
}

/// Cells that break a number or a record.
const CELLS: &[&str] = &[
    "",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e300",
    "-1e308",
    "1e309",
    "abc",
    "\"a,b\"",
    "\"open",
    "0x10",
    "1,5",
    " 1 ",
    "--1",
    "1e",
    "\u{0}",
    "é",
    "99999999999999999999999999999999999",
    "1e-320",
    "0",
    "-0",
];

/// Edits 0–6: a cell, a row removed, repeated or inserted, a field more or less.
fn edit_rows(rng: &mut ChaCha8Rng, rows: &mut Vec<Vec<String>>, kind: u32, (r, c): (usize, usize)) {
    match kind {
        0 => {
            if let Some(x) = rows[r].get_mut(c) {
                *x = CELLS[rng.random_range(0..CELLS.len())].to_string();
            }
        }
        1 => {
            rows.remove(r);
        }
        2 => {
            let copy = rows[r].clone();
            rows.insert(r, copy);
        }
        3 => rows.insert(r, vec![String::new()]),
        4 => rows.insert(r, vec!["# a comment, with \"quotes\"".to_string()]),
        5 => {
            if let Some(row) = rows.get_mut(r) {
                row.push("extra".to_string());
            }
        }
        6 => {
            if let Some(row) = rows.get_mut(r)
                && row.len() > 1
            {
                row.pop();
            }
        }
        _ => {}
    }
}

/// Edits 7–13: a column's values, the header, time stamps, experiments, quoting.
fn edit_columns(
    rng: &mut ChaCha8Rng,
    rows: &mut Vec<Vec<String>>,
    kind: u32,
    (r, c): (usize, usize),
) {
    let n = rows.len();
    match kind {
        7 => {
            // A constant column with one spike.
            for row in rows.iter_mut().skip(1) {
                if let Some(x) = row.get_mut(c) {
                    *x = "10".to_string();
                }
            }
            if let Some(x) = rows.get_mut(r.max(1)).and_then(|row| row.get_mut(c)) {
                *x = format!("1e{}", rng.random_range(2..300));
            }
        }
        8 => {
            // A column scaled (units).
            let f: f64 = format!("1e{}", rng.random_range(-30..30))
                .parse()
                .unwrap_or(1.0);
            for row in rows.iter_mut().skip(1) {
                if let Some(x) = row.get_mut(c) {
                    let v: f64 = x.parse().unwrap_or(0.0);
                    *x = format!("{:e}", v * f);
                }
            }
        }
        9 => {
            // The header: a name dropped, duplicated or renamed.
            if let Some(h) = rows.first_mut() {
                let k = rng.random_range(0..h.len());
                match rng.random_range(0..3) {
                    0 => h[k] = String::new(),
                    1 => h[k] = h[(k + 1) % h.len()].clone(),
                    _ => h[k] = format!("{}x", h[k]),
                }
            }
        }
        10 => {
            // A time stamp out of order or a gap.
            if let Some(x) = rows.get_mut(r.max(1)).and_then(|row| row.get_mut(0)) {
                let v: f64 = x.parse().unwrap_or(0.0);
                *x = format!("{}", v + rng.random_range(-5.0..5.0));
            }
        }
        11 => rows.truncate(rng.random_range(0..n)),
        12 => {
            // Experiments interleaved.
            if let Some(h) = rows.first_mut() {
                h.push("experiment".to_string());
            }
            for (k, row) in rows.iter_mut().enumerate().skip(1) {
                row.push(if (k / 50) % 3 == 1 { "b" } else { "a" }.to_string());
            }
        }
        _ => {
            // A quoted cell holding a line break.
            if let Some(x) = rows.get_mut(r.max(1)).and_then(|row| row.get_mut(c)) {
                *x = format!("\"{x}\n{x}\"");
            }
        }
    }
}

/// The rows as bytes: line ends, a byte-order mark, a cut, a stray byte.
fn encode(rng: &mut ChaCha8Rng, rows: &[Vec<String>]) -> Vec<u8> {
    let crlf = rng.random_bool(0.2);
    let mut text: String = rows
        .iter()
        .map(|r| r.join(",") + if crlf { "\r\n" } else { "\n" })
        .collect();
    if rng.random_bool(0.1) {
        text.insert(0, '\u{feff}');
    }
    let mut bytes = text.into_bytes();
    if rng.random_bool(0.05) {
        let at = rng.random_range(0..bytes.len().max(1));
        bytes.truncate(at);
    }
    if rng.random_bool(0.05) && !bytes.is_empty() {
        let at = rng.random_range(0..bytes.len());
        bytes[at] = rng.random_range(0x80..=0xffu8);
    }
    bytes
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let n_models: usize = opt("--models").and_then(|v| v.parse().ok()).unwrap_or(2000);
    let from: usize = opt("--from").and_then(|v| v.parse().ok()).unwrap_or(0);
    let n_csvs: usize = opt("--csvs").and_then(|v| v.parse().ok()).unwrap_or(200);
    let seed: u64 = opt("--seed").and_then(|v| v.parse().ok()).unwrap_or(1);
    let timeout =
        Duration::from_secs_f64(opt("--timeout").and_then(|v| v.parse().ok()).unwrap_or(5.0));
    let root = PathBuf::from(opt("--root").unwrap_or_else(|| ".".to_string()));
    let leeway =
        PathBuf::from(opt("--leeway").unwrap_or_else(|| "target/release/leeway".to_string()));
    let out = PathBuf::from(opt("--out").unwrap_or_else(|| {
        std::env::temp_dir()
            .join(format!("leeway-fuzz-{seed}"))
            .display()
            .to_string()
    }));
    let scratch = out.join("scratch");
    let keep = out.join("failing");
    if let Err(e) = std::fs::create_dir_all(&scratch) {
        eprintln!("cannot create {}: {e}", scratch.display());
        std::process::exit(2);
    }
    let seeds = seed_models(&root);
    let started = Instant::now();
    let run_ctx = Runner {
        leeway: &leeway,
        timeout,
        scratch: &scratch,
        keep: &keep,
    };
    let models_tally = fuzz_models(&run_ctx, &seeds, seed, from..from + n_models, started);
    let csv_tally = fuzz_csvs(&run_ctx, &root, seed, n_csvs);
    println!(
        "total {:.0} s; failing inputs (if any) in {}",
        started.elapsed().as_secs_f64(),
        keep.display()
    );
    let failed = models_tally.crashes.len()
        + models_tally.timeouts.len()
        + models_tally.unlocated.len()
        + csv_tally.crashes.len()
        + csv_tally.timeouts.len()
        + csv_tally.unlocated.len();
    std::process::exit(i32::from(failed > 0));
}

/// How each case is run: the binary, its time limit, where cases are
/// written and where failing ones are kept.
struct Runner<'a> {
    leeway: &'a Path,
    timeout: Duration,
    scratch: &'a Path,
    keep: &'a Path,
}

/// The example models (valid and broken), the seeds of the mutations.
fn seed_models(root: &Path) -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = Vec::new();
    for dir in ["examples/models", "examples/models/broken"] {
        if let Ok(entries) = std::fs::read_dir(root.join(dir)) {
            let mut paths: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "som"))
                .collect();
            paths.sort();
            seeds.extend(paths.iter().filter_map(|p| std::fs::read(p).ok()));
        }
    }
    if seeds.is_empty() {
        eprintln!("no example models under {}; pass --root", root.display());
        std::process::exit(2);
    }
    seeds
}

/// `leeway check` on generated and mutated models.
fn fuzz_models(
    ctx: &Runner<'_>,
    seeds: &[Vec<u8>],
    seed: u64,
    cases: std::ops::Range<usize>,
    started: Instant,
) -> Tally {
    let mut models_tally = Tally::default();
    let model_path = ctx.scratch.join("case.som");
    for i in cases {
        let mut rng =
            ChaCha8Rng::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i as u64));
        let text = match rng.random_range(0..3) {
            0 => generate(&mut rng),
            1 => {
                let base = &seeds[rng.random_range(0..seeds.len())];
                mutate(&mut rng, base)
            }
            _ => {
                let base = generate(&mut rng);
                mutate(&mut rng, &base)
            }
        };
        if std::fs::write(&model_path, &text).is_err() {
            continue;
        }
        let path = model_path.display().to_string();
        let mut check = vec!["check", path.as_str()];
        if rng.random_bool(0.3) {
            check.push("--json");
        }
        let r = run(ctx.leeway, &check, ctx.timeout, ctx.scratch);
        models_tally.record(&format!("model-{seed}-{i}.som"), &model_path, &r, ctx.keep);
        if (i + 1) % 1000 == 0 {
            eprintln!(
                "{} models in {:.0} s",
                i + 1,
                started.elapsed().as_secs_f64()
            );
        }
    }
    models_tally.report("check");
    models_tally
}

/// `leeway estimate` on malformed logs of the paper's ship.
fn fuzz_csvs(ctx: &Runner<'_>, root: &Path, seed: u64, n_csvs: usize) -> Tally {
    // A valid log of the paper's ship to malform.
    let ship_src =
        std::fs::read_to_string(root.join("examples/models/ship.som")).unwrap_or_default();
    let compiled = leeway::compile(&ship_src, &Default::default());
    let Some(ir) = compiled.ir else {
        eprintln!("examples/models/ship.som does not compile");
        std::process::exit(2);
    };
    let ship = Interpreter::new(ir);
    let (experiment, _) =
        study::estimation_experiment(&ship, &study::InputDesign::default(), 1.0, 600, seed);
    let mut base = Vec::new();
    let _ = write_csv(
        leeway::model::Model::ir(&ship),
        &[&experiment],
        0.0,
        &mut base,
    );
    let base = String::from_utf8_lossy(&base).into_owned();
    let model_arg = root.join("examples/models/ship.som").display().to_string();
    let mut csv_tally = Tally::default();
    let csv_path = ctx.scratch.join("case.csv");
    for i in 0..n_csvs {
        let mut rng =
            ChaCha8Rng::seed_from_u64(seed.wrapping_mul(7_000_003).wrapping_add(i as u64));
        let text = malform(&mut rng, &base);
        if std::fs::write(&csv_path, &text).is_err() {
            continue;
        }
        let path = csv_path.display().to_string();
        let method = if i % 2 == 0 { "ls" } else { "iv3" };
        let r = run(
            ctx.leeway,
            &["estimate", &model_arg, "--data", &path, "--method", method],
            ctx.timeout,
            ctx.scratch,
        );
        csv_tally.record(&format!("csv-{seed}-{i}.csv"), &csv_path, &r, ctx.keep);
    }
    csv_tally.report("estimate");
    csv_tally
}
