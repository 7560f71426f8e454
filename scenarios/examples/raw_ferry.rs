//! Writes a ferry's raw ROS 2 topics (`leeway_scenarios::raw_ferry`) with
//! their manifest and model:
//! `cargo run -p leeway-scenarios --example raw_ferry -- DIR [--seed N] [--seconds S]`.

use leeway_scenarios::raw_ferry::{RawFerry, write_raw_ferry};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(dir) = args.first() else {
        eprintln!("usage: raw_ferry DIR [--seed N] [--seconds S]");
        std::process::exit(2);
    };
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse::<f64>().ok())
    };
    let spec = RawFerry {
        seed: value("--seed").map_or(1, |s| s as u64),
        seconds: value("--seconds").unwrap_or(1800.0),
        ..RawFerry::default()
    };
    if let Err(e) = write_raw_ferry(std::path::Path::new(dir), &spec) {
        eprintln!("raw_ferry: {e}");
        std::process::exit(1);
    }
}
