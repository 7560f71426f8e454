//! Writes the synthetic ferry log (`leeway_scenarios::ferry`):
//! `cargo run -p leeway-scenarios --example ferry_log -- DIR [--aligned] [--seed N] [--seconds S] [--bag]`
//! (`--bag`: also `ferry.mcap`, the topics as a ROS 2 bag, and its manifest `ferry-bag.toml`).

use leeway_scenarios::ferry::{FerryLog, write_ferry_bag, write_ferry_log};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(dir) = args.first() else {
        eprintln!("usage: ferry_log DIR [--aligned] [--seed N] [--seconds S]");
        std::process::exit(2);
    };
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse::<f64>().ok())
    };
    let spec = FerryLog {
        aligned: args.iter().any(|a| a == "--aligned"),
        seed: value("--seed").map_or(1, |s| s as u64),
        seconds: value("--seconds").unwrap_or(1200.0),
        ..FerryLog::default()
    };
    let dir = std::path::Path::new(dir);
    if let Err(e) = write_ferry_log(dir, &spec) {
        eprintln!("ferry_log: {e}");
        std::process::exit(1);
    }
    if args.iter().any(|a| a == "--bag")
        && let Err(e) = write_ferry_bag(dir)
    {
        eprintln!("ferry_log: {e}");
        std::process::exit(1);
    }
}
