//! `leeway simulate` with varying disturbances and sensor noise
//! (`--disturbance-std`, `--correlation-time`, `--noise`, `--seed`): the
//! bytes a seed gives, the noise's size, and the errors; without those
//! options, the bytes it always wrote.

use crate::common::*;
use leeway_scenarios::study;
use std::process::Command;

/// An input file of `n` samples (time, forces, the measured wind) from the
/// study's validation input, and θ0 as a parameter file.
fn input(dir: &Scratch, n: usize) -> (String, String) {
    let model = ship();
    let full = csv_text(&model, &[&study::validation_experiment(&model, n)]);
    let input: String = full
        .lines()
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            let mut keep = vec![cells[0]];
            keep.extend(&cells[5..]);
            keep.join(",") + "\n"
        })
        .collect();
    (
        dir.write("in.csv", &input),
        dir.write("truth.json", &true_params()),
    )
}

/// `leeway simulate` of the ship with θ0 on `input` from (4, 0, 0, 0),
/// with a current of (0.2, −0.1) m/s and `extra` options.
fn simulate(input: &str, params: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "simulate",
        SHIP,
        "--params",
        params,
        "--input",
        input,
        "--x0",
        "u=4,v=0,r=0,psi=0",
        "--disturbance",
        "current.north=0.2,current.east=-0.1",
    ];
    args.extend(extra);
    let o = leeway(&args);
    no_panic(&o);
    o
}

/// The CSV's columns by header name.
fn columns(text: &str) -> Vec<(String, Vec<f64>)> {
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect();
    let mut out: Vec<(String, Vec<f64>)> = header.into_iter().map(|h| (h, Vec::new())).collect();
    for line in lines {
        for ((_, column), cell) in out.iter_mut().zip(line.split(',')) {
            column.push(cell.parse().unwrap_or(f64::NAN));
        }
    }
    out
}

fn column<'a>(table: &'a [(String, Vec<f64>)], name: &str) -> &'a [f64] {
    table
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, c)| c.as_slice())
        .unwrap_or_else(|| panic!("no column `{name}`"))
}

/// The sample std of `a − b`.
fn std_of_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let d: Vec<f64> = a.iter().zip(b).map(|(a, b)| a - b).collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    (d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (d.len() - 1) as f64).sqrt()
}

/// FNV-1a of the bytes.
fn fingerprint(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

#[test]
fn without_noise_it_writes_the_bytes_it_always_wrote() {
    let dir = Scratch::new("simulate-plain");
    let (input, params) = input(&dir, 400);
    let plain = simulate(&input, &params, &[]);
    assert_eq!(code(&plain), 0, "{}", stderr(&plain));
    // The output of the command before it had noise options.
    assert_eq!(fingerprint(&plain.stdout), PLAIN_FINGERPRINT);
    // A seed alone, or noises of zero, change nothing.
    for extra in [
        &["--seed", "9"][..],
        &["--disturbance-std", "current=0", "--noise", "u=0,psi=0"],
    ] {
        let o = simulate(&input, &params, extra);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        assert!(o.stdout == plain.stdout, "{extra:?}");
    }
}

/// The fingerprint of the plain simulation's output above, as the command
/// wrote it before `--noise` existed.
const PLAIN_FINGERPRINT: u64 = 8_135_272_023_028_233_587;

#[test]
fn a_seed_gives_the_same_bytes_at_any_thread_count_and_another_seed_others() {
    let dir = Scratch::new("simulate-seed");
    let (input, params) = input(&dir, 300);
    let noisy = |seed: &str, threads: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_leeway"))
            .args([
                "simulate",
                SHIP,
                "--params",
                &params,
                "--input",
                &input,
                "--x0",
                "u=4,v=0,r=0,psi=0",
                "--disturbance",
                "current.north=0.2,current.east=-0.1",
                "--disturbance-std",
                "current=0.05,wind=0.3",
                "--correlation-time",
                "current=60",
                "--noise",
                "u=0.01,v=0.01,r=0.001,psi=0.002,wind=0.1",
                "--seed",
                seed,
            ])
            .current_dir(root())
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .expect("run leeway");
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        o.stdout
    };
    let first = noisy("7", "1");
    assert!(first == noisy("7", "2"));
    assert!(first != noisy("8", "1"));
    // The default seed is 0.
    let o = simulate(
        &input,
        &params,
        &[
            "--disturbance-std",
            "current=0.05,wind=0.3",
            "--correlation-time",
            "current=60",
            "--noise",
            "u=0.01,v=0.01,r=0.001,psi=0.002,wind=0.1",
        ],
    );
    assert!(o.stdout == noisy("0", "2"));
}

#[test]
fn the_written_noise_has_the_std_asked_and_leaves_the_truth() {
    let dir = Scratch::new("simulate-noise");
    let n = 20_000;
    let (input, params) = input(&dir, n);
    let plain = simulate(&input, &params, &[]);
    let noisy = simulate(
        &input,
        &params,
        &["--noise", "u=0.01,r=0.002,psi=0.005,wind.wind_n=0.3"],
    );
    assert_eq!(code(&noisy), 0, "{}", stderr(&noisy));
    let (plain, noisy) = (columns(&stdout(&plain)), columns(&stdout(&noisy)));
    assert_eq!(column(&noisy, "u").len(), n);
    // The sample std of N normal draws is off by about σ/√(2N) (0.5 % at
    // N = 20000): 3 % is six of those.
    for (name, std) in [("u", 0.01), ("r", 0.002), ("psi", 0.005), ("wind_n", 0.3)] {
        let got = std_of_difference(column(&noisy, name), column(&plain, name));
        assert!((got / std - 1.0).abs() < 0.03, "{name}: {got} vs {std}");
    }
    // Sensor noise leaves the craft as it was: a state without noise, the
    // inputs and an unnoised sensor are written as without noise.
    for name in ["v", "tau1", "tau3", "wind_e", "time"] {
        assert_eq!(column(&noisy, name), column(&plain, name), "{name}");
    }
}

#[test]
fn a_varying_current_moves_the_craft_and_gusts_reach_the_anemometer() {
    let dir = Scratch::new("simulate-gusts");
    let (input, params) = input(&dir, 2000);
    let plain = columns(&stdout(&simulate(&input, &params, &[])));
    let o = simulate(
        &input,
        &params,
        &[
            "--disturbance-std",
            "current.north=0.05,wind=0.5",
            "--correlation-time",
            "north=60",
        ],
    );
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let gusty = columns(&stdout(&o));
    // From the same start, the current moves the craft off the plain track.
    assert_eq!(column(&gusty, "u")[0], column(&plain, "u")[0]);
    let drift = std_of_difference(column(&gusty, "v"), column(&plain, "v"));
    assert!(drift > 1e-3, "{drift}");
    // The input's wind is the mean (zero here); the written wind is the
    // gusts the craft felt, std 0.5 (i.i.d.: 2000 draws, off by about
    // 1.6 %; 7 % is over four of those).
    let gusts = std_of_difference(column(&gusty, "wind_e"), column(&plain, "wind_e"));
    assert!((gusts / 0.5 - 1.0).abs() < 0.07, "{gusts}");
    assert_eq!(column(&gusty, "tau2"), column(&plain, "tau2"));
}

#[test]
fn noise_options_that_do_not_fit_are_one_error_with_a_hint() {
    let dir = Scratch::new("simulate-noise-errors");
    let (input, params) = input(&dir, 50);
    for (extra, message, hint) in [
        (
            &["--noise", "u=0.01,w=0.1"][..],
            "--noise `w=0.1`: `w` is not a state, the heading or a measured disturbance of model `Ship`",
            "the measured signals are u, v, r, psi, wind.wind_n, wind.wind_e",
        ),
        (
            &["--noise", "current=0.1"],
            "--noise `current=0.1`: `current` is not measured: no sensor records it",
            "the measured signals are",
        ),
        (
            &["--disturbance-std", "tide=0.1"],
            "--disturbance-std `tide=0.1`: `tide` is not a disturbance component or medium of model `Ship`",
            "the disturbance components are current.north, current.east, wind.wind_n, wind.wind_e; a medium's name (current, wind) stands for all its components",
        ),
        (
            &["--disturbance-std", "current.north=-0.1"],
            "--disturbance-std `current.north=-0.1`: -0.1 is negative: a standard deviation is at least 0",
            "the disturbance components are",
        ),
        (
            &[
                "--disturbance-std",
                "current=0.1",
                "--correlation-time",
                "current=-60",
            ],
            "--correlation-time `current=-60`: -60 is negative: a correlation time is at least 0 s (0: independent samples)",
            "a correlation time shapes a component given a --disturbance-std",
        ),
        (
            &[
                "--disturbance-std",
                "north=0.1",
                "--correlation-time",
                "east=60",
            ],
            "--correlation-time `east=60`: `east` has no standard deviation given: its correlation time would change nothing",
            "a correlation time shapes a component given a --disturbance-std",
        ),
        (
            &["--noise", "u=1e13"],
            "--noise `u=1e13`: 1e13 exceeds 1e12",
            "the measured signals are",
        ),
        (
            &["--noise", "u=small"],
            "--noise `u=small`: `small` is not a number",
            "the measured signals are",
        ),
    ] {
        let o = simulate(&input, &params, extra);
        assert_eq!(code(&o), 2, "{extra:?}: {}", stderr(&o));
        assert!(o.stdout.is_empty(), "{extra:?}");
        let err = stderr(&o);
        let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(
            errors,
            vec![format!("error[invalid-option]: {message}")],
            "{extra:?}"
        );
        assert!(
            err.contains("= help: ") && err.contains(hint),
            "{extra:?}: {err}"
        );
    }
}
