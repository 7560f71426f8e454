//! Truncated and bit-flipped bags give errors, never panics.

use std::sync::OnceLock;

use leeway_logs::bag::path::Extract;
use proptest::prelude::*;

use crate::common::{ferry_bag, read};

/// A small valid bag's bytes (a few kB), written once.
fn bag_bytes() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let dir = tempfile::tempdir().expect("a temporary directory");
        std::fs::read(ferry_bag(dir.path(), 2)).expect("read")
    })
}

const REQUESTS: &[(&str, Extract)] = &[
    ("/twist.twist.linear.x", Extract::Number),
    ("/imu", Extract::Yaw),
    ("/depth.data", Extract::Number),
    ("/imu.orientation_covariance[4]", Extract::Number),
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn damaged_bags_never_panic(
        cut in 0.0..1.0f64,
        flips in proptest::collection::vec((0.0..1.0f64, 1u8..=255), 0..4),
    ) {
        let mut bytes = bag_bytes().to_vec();
        for (at, mask) in flips {
            let i = ((at * bytes.len() as f64) as usize).min(bytes.len() - 1);
            bytes[i] ^= mask;
        }
        bytes.truncate(((cut * 1.2).min(1.0) * bytes.len() as f64) as usize);
        let dir = tempfile::tempdir().expect("a temporary directory");
        let path = dir.path().join("damaged.mcap");
        std::fs::write(&path, &bytes).expect("written");
        if let Err(error) = read(&path, REQUESTS) {
            prop_assert!(error.location.contains("damaged.mcap"), "{:?}", error);
            prop_assert!(!error.hint.is_empty());
        }
    }
}
