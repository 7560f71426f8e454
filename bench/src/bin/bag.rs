//! Writes and reads large ROS 2 bags, for the speed and memory figures of
//! `leeway_logs::bag` (docs/data-files.md), compared with Python's readers
//! (`bench/bag_python.py`) on the same bag:
//!
//! ```sh
//! cargo build --release -p leeway-bench --bin bag
//! target/release/bag write /tmp/big.mcap 10000000   # 3 TwistStamped topics
//! /usr/bin/time -v target/release/bag read /tmp/big.mcap
//! ```
//!
//! `read` takes the signals named after the path, by default 6 (2 per
//! topic: `/nav/twist_body.twist.linear.x` …), and prints the time, the messages
//! and a checksum of the values. `bag sample PATH` writes a small bag of
//! every type the writer knows, 5 messages each, values by formula
//! (`write_sample`), which `bench/bag_python.py check PATH` decodes with
//! Python's readers and compares.

use std::path::Path;
use std::time::Instant;

use leeway_logs::bag::path::{Extract, FieldPath};
use leeway_logs::bag::read::read_bag;
use leeway_logs::bag::write::{BagWriter, MessageKind};

const TOPICS: [&str; 3] = ["/nav/twist_body", "/dvl/twist", "/gps/twist"];
const FIELDS: [&str; 2] = ["twist.linear.x", "twist.angular.z"];

fn write(path: &Path, messages: u64) -> Result<(), String> {
    let mut writer = BagWriter::create(path).map_err(|e| e.to_string())?;
    let topics = TOPICS
        .iter()
        .map(|topic| writer.add_topic(topic, MessageKind::TwistStamped, "base_link"))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())?;
    let t0: i64 = 1_700_000_000_000_000_000;
    for i in 0..messages {
        let k = (i % 3) as usize;
        let t = (i / 3) as f64 * 0.01;
        let values = [
            t.sin(),
            (0.3 * t).cos(),
            0.0,
            0.0,
            0.0,
            0.1 * (0.7 * t).sin(),
        ];
        let stamp = t0 + (i as i64 / 3) * 10_000_000 + k as i64 * 1_000;
        writer
            .write(topics[k], stamp, &values)
            .map_err(|e| e.to_string())?;
    }
    writer.finish().map_err(|e| e.to_string())
}

/// Message `i` of each topic of the sample: stamp `T0 + i·0.1 s + k µs`
/// (topic k), column c = `k + c/8 + i/4`; the Imu's heading is `i/2 - 1`.
fn write_sample(path: &Path) -> Result<(), String> {
    let kinds = [
        ("/twist", MessageKind::TwistStamped),
        ("/wrench", MessageKind::WrenchStamped),
        ("/imu", MessageKind::Imu),
        ("/depth", MessageKind::Float64),
    ];
    let mut writer = BagWriter::create(path).map_err(|e| e.to_string())?;
    let mut ids = Vec::new();
    for (topic, kind) in kinds {
        ids.push(
            writer
                .add_topic(topic, kind, "base_link")
                .map_err(|e| e.to_string())?,
        );
    }
    for i in 0..5_i64 {
        for (k, (_, kind)) in kinds.iter().enumerate() {
            let mut values: Vec<f64> = (0..kind.columns().len())
                .map(|c| k as f64 + c as f64 / 8.0 + i as f64 / 4.0)
                .collect();
            if *kind == MessageKind::Imu {
                values[0] = i as f64 / 2.0 - 1.0;
            }
            let stamp = 1_700_000_000_000_000_000 + i * 100_000_000 + k as i64 * 1_000;
            writer
                .write(ids[k], stamp, &values)
                .map_err(|e| e.to_string())?;
        }
    }
    writer.finish().map_err(|e| e.to_string())
}

fn read(path: &Path, signals: &[&str]) -> Result<(), String> {
    let default: Vec<String> = TOPICS
        .iter()
        .flat_map(|topic| FIELDS.iter().map(move |field| format!("{topic}.{field}")))
        .collect();
    let texts: Vec<String> = if signals.is_empty() {
        default
    } else {
        signals.iter().map(|s| s.to_string()).collect()
    };
    let requests: Vec<(FieldPath, Extract)> = texts
        .iter()
        .map(|text| FieldPath::parse(text).map(|p| (p, Extract::Number)))
        .collect::<Result<_, _>>()
        .map_err(|e| e.to_string())?;
    let start = Instant::now();
    let signals = read_bag(path, &requests).map_err(|e| e.to_string())?;
    let seconds = start.elapsed().as_secs_f64();
    let values: usize = signals.iter().map(|s| s.values.len()).sum();
    let sum: f64 = signals.iter().flat_map(|s| &s.values).sum();
    println!(
        "leeway read_bag: {} signals, {values} values, {seconds:.2} s, checksum {sum:.6}",
        signals.len()
    );
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>()
        .as_slice()
    {
        ["write", path, n] => n
            .parse()
            .map_err(|_| format!("`{n}` is not a message count"))
            .and_then(|n| write(Path::new(path), n)),
        ["read", path, signals @ ..] => read(Path::new(path), signals),
        ["sample", path] => write_sample(Path::new(path)),
        _ => Err(
            "usage: bag write PATH MESSAGES | bag read PATH [SIGNAL...] | bag sample PATH"
                .to_string(),
        ),
    };
    if let Err(error) = result {
        eprintln!("error: {error}");
        std::process::exit(1);
    }
}
