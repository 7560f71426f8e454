//! Writes the seeded tanker zigzag campaign (`leeway_scenarios::zigzag`) as CSV
//! files, for users and the docs, and measures the reference fit.
//!
//! ```text
//! cargo run --release -p leeway-bench --bin zigzag -- --out DIR [--seed S] [--noise] [--raw]
//! cargo run --release -p leeway-bench --bin zigzag -- --reference [--seed S]
//! ```
//!
//! `DIR/train-1.csv … train-4.csv` (noisy with `--noise`) and
//! `DIR/val-1.csv … val-6.csv` (always noise-free), columns `time, u, v, r,
//! psi, delta` in SI units (s, m/s, rad/s, rad). `--raw` writes them as a
//! logger would: `#` comment lines (vessel, date, channel units), heading
//! (0–360) and rudder in degrees, timestamps with ±1 ms jitter.
//! `--reference` prints the runs and the least-squares reference fit of the
//! 17-term structure on noise-free and on noisy training runs.

use leeway_scenarios::zigzag;
use leeway_scenarios::zigzag::Campaign;
use leeway_scenarios::zigzag::CampaignOptions;
use leeway_scenarios::zigzag::Noise;
use leeway_scenarios::zigzag::Run;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str =
    "usage: zigzag --out DIR [--seed S] [--noise] [--raw] | zigzag --reference [--seed S]";

struct Args {
    out: Option<PathBuf>,
    seed: u64,
    noise: bool,
    raw: bool,
    reference: bool,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        out: None,
        seed: CampaignOptions::default().seed,
        noise: false,
        raw: false,
        reference: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => args.out = Some(it.next().ok_or("--out needs a directory")?.into()),
            "--seed" => {
                let s = it.next().ok_or("--seed needs a number")?;
                args.seed = s
                    .parse()
                    .map_err(|_| format!("--seed: `{s}` is not a number"))?;
            }
            "--noise" => args.noise = true,
            "--raw" => args.raw = true,
            "--reference" => args.reference = true,
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    if args.out.is_none() && !args.reference {
        return Err("--out DIR or --reference is required".into());
    }
    Ok(args)
}

fn si_csv(run: &Run) -> String {
    let mut s = String::from("time,u,v,r,psi,delta\n");
    for k in 0..run.len() {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            run.time[k], run.u[k], run.v[k], run.r[k], run.psi[k], run.delta[k]
        );
    }
    s
}

fn raw_csv(run: &Run, seed: u64, index: usize, noisy: bool) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(zigzag::run_seed(seed, "raw-jitter", index));
    let z = &run.zigzag;
    let deg = 180.0 / std::f64::consts::PI;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# vessel: tanker model 1:35 (Lpp 9.14 m), free-running zigzag {:.0}/{:.0}, constant propeller rate",
        z.delta_z * deg,
        z.psi_z * deg
    );
    let _ = writeln!(
        s,
        "# date: 2024-06-{:02} run {} (leeway synthetic campaign, seed {seed}{})",
        3 + index % 20,
        run.name,
        if noisy {
            ", measurement noise added"
        } else {
            ""
        }
    );
    let _ = writeln!(
        s,
        "# logger 20 Hz, anti-alias filtered, decimated to 2 Hz; channels: time [s], u [m/s], v [m/s], r [rad/s], psi [deg, 0-360], delta [deg]"
    );
    s.push_str("time,u,v,r,psi,delta\n");
    for k in 0..run.len() {
        let jitter = rng.random_range(-0.001..=0.001);
        let psi = (run.psi[k] * deg).rem_euclid(360.0);
        let _ = writeln!(
            s,
            "{:.3},{:.5},{:.5},{:.6},{:.2},{:.2}",
            run.time[k] + jitter,
            run.u[k],
            run.v[k],
            run.r[k],
            psi,
            run.delta[k] * deg
        );
    }
    s
}

fn write(dir: &std::path::Path, c: &Campaign, args: &Args) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let all = c
        .train
        .iter()
        .map(|r| (r, args.noise))
        .chain(c.validation.iter().map(|r| (r, false)));
    for (i, (run, noisy)) in all.enumerate() {
        let text = if args.raw {
            raw_csv(run, args.seed, i, noisy)
        } else {
            si_csv(run)
        };
        let path = dir.join(format!("{}.csv", run.name));
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        println!("{} ({} samples)", path.display(), run.len());
    }
    Ok(())
}

fn reference(seed: u64) {
    let deg = 180.0 / std::f64::consts::PI;
    let clean = zigzag::campaign(&CampaignOptions {
        seed,
        noise: None,
        ..CampaignOptions::default()
    });
    let noisy = zigzag::campaign(&CampaignOptions {
        seed,
        noise: Some(Noise::default()),
        ..CampaignOptions::default()
    });
    println!("run      angles  samples  u0     speed drop  overshoot");
    for r in clean.train.iter().chain(&clean.validation) {
        let z = &r.zigzag;
        let umin = r.u.iter().copied().fold(f64::MAX, f64::min);
        let dpsi = r.psi.iter().map(|p| (p - z.psi0).abs()).fold(0.0, f64::max);
        println!(
            "{:8} {:2.0}/{:2.0}   {:4}     {:.3}  {:5.1} %     {:4.1}°",
            r.name,
            z.delta_z * deg,
            z.psi_z * deg,
            r.len(),
            r.u[0],
            100.0 * (1.0 - umin / r.u[0].max(umin)),
            dpsi * deg - z.psi_z * deg
        );
    }
    let a = zigzag::reference_fit(&clean.train, &clean.validation);
    let b = zigzag::reference_fit(&noisy.train, &noisy.validation);
    for (label, f) in [
        ("(a) noise-free training", &a),
        ("(b) noisy training    ", &b),
    ] {
        println!(
            "{label}: mean fit u {:.1}  v {:.1}  r {:.1}   per run u: {}",
            f.mean[0],
            f.mean[1],
            f.mean[2],
            f.fits
                .iter()
                .map(|x| format!("{:.1}", x[0]))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    println!("θ (a): {}", fmt_theta(&a.theta));
    println!("θ (b): {}", fmt_theta(&b.theta));
}

fn fmt_theta(theta: &[f64]) -> String {
    zigzag::PARAMETERS
        .iter()
        .zip(theta)
        .map(|(n, t)| format!("{n} = {t:.4e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn main() -> ExitCode {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("error: {e}");
            }
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    if args.reference {
        reference(args.seed);
    }
    if let Some(dir) = &args.out {
        let c = zigzag::campaign(&CampaignOptions {
            seed: args.seed,
            noise: args.noise.then(Noise::default),
            ..CampaignOptions::default()
        });
        if let Err(e) = write(dir, &c, &args) {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    }
    ExitCode::SUCCESS
}
