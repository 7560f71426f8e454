//! Bags for the tests, written with `logs::bag::write`, and the fuzzers' seeded stream.

use std::path::{Path, PathBuf};

use leeway_logs::bag::path::{Extract, FieldPath};
use leeway_logs::bag::read::{Stamped, read_bag};
use leeway_logs::bag::write::{MessageKind, TopicSeries, write_bag};

/// 2023-11-14 22:13:20 UTC, in ns.
pub const T0: i64 = 1_700_000_000_000_000_000;

/// A bag of four topics: `/twist` (10 Hz), `/wrench` (5 Hz), `/imu`
/// (20 Hz) and `/depth` (2 Hz, no header), over `seconds`.
pub fn ferry_series(seconds: i64) -> Vec<TopicSeries> {
    let series = |topic: &str, kind: MessageKind, period_ms: i64| {
        let n = (seconds * 1000 / period_ms) as usize;
        let stamps: Vec<i64> = (0..n as i64)
            .map(|i| T0 + i * period_ms * 1_000_000 + 7)
            .collect();
        let columns = (0..kind.columns().len())
            .map(|c| {
                (0..n)
                    .map(|i| match (kind, c) {
                        // Headings over the whole circle, wrapped to (−π, π].
                        (MessageKind::Imu, 0) => {
                            let h = -3.0 + 0.37 * i as f64;
                            (h + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                                - std::f64::consts::PI
                        }
                        _ => (c as f64 + 1.0) * 0.1 + i as f64 * 0.01 - 0.3,
                    })
                    .collect()
            })
            .collect();
        TopicSeries {
            topic: topic.to_string(),
            kind,
            frame_id: "base_link".to_string(),
            stamps,
            columns,
        }
    };
    vec![
        series("/twist", MessageKind::TwistStamped, 100),
        series("/wrench", MessageKind::WrenchStamped, 200),
        series("/imu", MessageKind::Imu, 50),
        series("/depth", MessageKind::Float64, 500),
    ]
}

/// `ferry_series(seconds)` written to `dir/ferry.mcap`.
pub fn ferry_bag(dir: &Path, seconds: i64) -> PathBuf {
    let path = dir.join("ferry.mcap");
    write_bag(&path, &ferry_series(seconds)).expect("the test bag is written");
    path
}

/// Reads `paths` (as `FieldPath` text) from `bag`.
pub fn read(bag: &Path, paths: &[(&str, Extract)]) -> Result<Vec<Stamped>, leeway_data::DataError> {
    let requests: Vec<(FieldPath, Extract)> = paths
        .iter()
        .map(|(text, extract)| (FieldPath::parse(text).expect("a valid path"), *extract))
        .collect();
    read_bag(bag, &requests)
}

/// splitmix64: a seeded stream, enough to pick bytes to damage and
/// mutations to make.
pub struct Seeded(pub u64);

impl Seeded {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// In `from..to` (`to > from`).
    pub fn range(&mut self, from: usize, to: usize) -> usize {
        from + (self.next() % (to - from) as u64) as usize
    }
    /// True once in `n` times.
    pub fn one_in(&mut self, n: usize) -> bool {
        self.range(0, n) == 0
    }
    /// One of `items` (not empty).
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.range(0, items.len())]
    }
}
