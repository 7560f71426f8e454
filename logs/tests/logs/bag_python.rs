//! Bags written by Python's `mcap-ros2-support` (an encoder independent of
//! leeway's; `tests/data/make_fixture.py` says what each holds) read back
//! exactly as Python wrote them, with zstd and with lz4 chunks.

use std::path::PathBuf;

use leeway_logs::bag::path::Extract;
use leeway_logs::bag::read::StampKind;

use crate::common::read;

const T0: i64 = 1_700_000_000;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// The fixture's header stamp of message `i` (ns).
fn stamp(i: i64) -> i64 {
    (T0 + i / 10) * 1_000_000_000 + (i % 10) * 100_000_000 + 3
}

#[test]
fn python_bags_read_back_exactly() {
    for name in ["python_zstd.mcap", "python_lz4.mcap"] {
        let signals = read(
            &fixture(name),
            &[
                ("/nav/twist.twist.linear.x", Extract::Number),
                ("/nav/twist.twist.linear.y", Extract::Number),
                ("/nav/twist.twist.angular.z", Extract::Number),
                ("/imu.orientation", Extract::Yaw),
                ("/imu.angular_velocity.z", Extract::Number),
                ("/imu.orientation_covariance[7]", Extract::Number),
                ("/depth.data", Extract::Number),
                ("/scan.ranges[4]", Extract::Number),
                ("/counters.a", Extract::Number),
                ("/counters.b", Extract::Number),
                ("/counters.c", Extract::Number),
                ("/counters.d", Extract::Number),
            ],
        )
        .expect("the Python bag reads");
        let twist: Vec<f64> = (0..12).map(|i| i as f64).collect();
        assert_eq!(
            signals[0].stamps,
            (0..12).map(stamp).collect::<Vec<_>>(),
            "{name}"
        );
        assert_eq!(signals[0].stamp, StampKind::Header);
        assert_eq!(signals[0].message_type, "geometry_msgs/msg/TwistStamped");
        assert_eq!(
            signals[0].values,
            twist.iter().map(|i| 1.5 + i / 8.0).collect::<Vec<_>>()
        );
        assert_eq!(
            signals[1].values,
            twist.iter().map(|i| -0.1 * i).collect::<Vec<_>>()
        );
        assert_eq!(
            signals[2].values,
            twist.iter().map(|i| i * i / 3.0).collect::<Vec<_>>()
        );
        for (i, yaw) in signals[3].values.iter().enumerate() {
            let heading = -3.0 + 0.75 * i as f64;
            let wrapped = (heading + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            assert!(
                (yaw - wrapped).abs() < 1e-12,
                "{name}: yaw {yaw} for heading {heading}"
            );
        }
        assert_eq!(signals[3].values.len(), 8);
        assert_eq!(
            signals[4].values,
            (0..8).map(|i| 0.01 * i as f64).collect::<Vec<_>>()
        );
        assert_eq!(signals[5].values, [7.0; 8]);
        assert_eq!(signals[6].stamp, StampKind::LogTime);
        assert_eq!(
            signals[6].stamps,
            (0..5)
                .map(|i| (T0 + i) * 1_000_000_000 + 5)
                .collect::<Vec<_>>()
        );
        assert_eq!(signals[6].values, [10.0, 9.75, 9.5, 9.25, 9.0]);
        // After a string that grows with i and a float32 sequence.
        assert_eq!(signals[7].values, [2.0, 3.0, 4.0]);
        assert_eq!(signals[8].values, [0.0, -1.0, -2.0, -3.0]);
        assert_eq!(signals[9].values, [0.0, 1000.0, 2000.0, 3000.0]);
        let c: Vec<f64> = (0..4).map(|i| -((1_i64 << 40) * i) as f64).collect();
        assert_eq!(signals[10].values, c);
        assert_eq!(
            signals[11].values,
            (0..4)
                .map(|i| (2_147_483_648_i64 + i) as f64)
                .collect::<Vec<_>>()
        );
        assert_eq!(signals[11].stamp, StampKind::LogTime);
    }
}
