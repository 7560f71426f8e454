//! What `bag::write` writes, `read_bag` reads back: every value, its stamp
//! and where the stamp came from.

use leeway_logs::bag::path::Extract;
use leeway_logs::bag::read::StampKind;
use leeway_logs::bag::write::{BagWriter, MessageKind};

use crate::common::{T0, ferry_bag, ferry_series, read};

#[test]
fn every_written_column_reads_back_exactly_with_its_stamps() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = ferry_bag(dir.path(), 30);
    for series in ferry_series(30) {
        let paths: Vec<String> = series
            .kind
            .columns()
            .iter()
            .map(|column| format!("{}.{column}", series.topic))
            .collect();
        let requests: Vec<(&str, Extract)> = paths
            .iter()
            .zip(series.kind.columns())
            .map(|(path, column)| {
                let extract = if *column == "orientation" {
                    Extract::Yaw
                } else {
                    Extract::Number
                };
                (path.as_str(), extract)
            })
            .collect();
        let signals = read(&bag, &requests).expect("the bag reads");
        for (signal, (column, written)) in signals
            .iter()
            .zip(series.kind.columns().iter().zip(&series.columns))
        {
            assert_eq!(signal.topic, series.topic);
            assert_eq!(signal.message_type, series.kind.type_name());
            assert_eq!(signal.stamps, series.stamps, "{} {column}", series.topic);
            let expected_kind = if series.kind == MessageKind::Float64 {
                StampKind::LogTime
            } else {
                StampKind::Header
            };
            assert_eq!(signal.stamp, expected_kind);
            if *column == "orientation" {
                // The heading goes through a quaternion: equal to rounding.
                for (read, written) in signal.values.iter().zip(written) {
                    assert!(
                        (read - written).abs() < 1e-12,
                        "yaw {read} for heading {written}"
                    );
                }
                assert_eq!(signal.values.len(), written.len());
            } else {
                assert_eq!(&signal.values, written, "{} {column}", series.topic);
            }
        }
    }
}

#[test]
fn integers_arrays_and_whole_messages_read_as_documented() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = ferry_bag(dir.path(), 2);
    let signals = read(
        &bag,
        &[
            ("/twist.header.stamp.sec", Extract::Number),
            ("/twist.header.stamp.nanosec", Extract::Number),
            ("/imu.orientation_covariance[8]", Extract::Number),
            ("/imu.orientation.w", Extract::Number),
            // A message holding `orientation`: the same heading as the quaternion's.
            ("/imu", Extract::Yaw),
            ("/imu.orientation", Extract::Yaw),
        ],
    )
    .expect("the bag reads");
    assert_eq!(signals[0].values[0], (T0 / 1_000_000_000) as f64);
    assert_eq!(signals[1].values[..2], [7.0, 100_000_007.0]);
    assert!(signals[2].values.iter().all(|v| *v == 0.0));
    assert_eq!(signals[2].values.len(), 40);
    let heading = -3.0_f64;
    assert!((signals[3].values[0] - (0.5 * heading).cos()).abs() < 1e-15);
    assert_eq!(signals[4].values, signals[5].values);
    assert!((signals[4].values[0] - heading).abs() < 1e-12);
}

#[test]
fn a_log_time_other_than_the_header_stamp_is_kept_apart() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = dir.path().join("late.mcap");
    let mut writer = BagWriter::create(&bag).expect("created");
    let twist = writer
        .add_topic("/twist", MessageKind::TwistStamped, "base")
        .expect("added");
    let depth = writer
        .add_topic("/depth", MessageKind::Float64, "")
        .expect("added");
    for i in 0..5 {
        let stamp = T0 + i * 1_000_000;
        // Received 3 ms after the sensor stamped it.
        writer
            .write_logged(twist, stamp, stamp + 3_000_000, &[i as f64; 6])
            .expect("written");
        writer
            .write_logged(depth, stamp, stamp + 3_000_000, &[-(i as f64)])
            .expect("written");
    }
    writer.finish().expect("finished");
    let signals = read(
        &bag,
        &[
            ("/twist.twist.angular.z", Extract::Number),
            ("/depth.data", Extract::Number),
        ],
    )
    .expect("the bag reads");
    let stamps: Vec<i64> = (0..5).map(|i| T0 + i * 1_000_000).collect();
    let logged: Vec<i64> = stamps.iter().map(|s| s + 3_000_000).collect();
    assert_eq!(signals[0].stamps, stamps);
    assert_eq!(signals[1].stamps, logged);
    assert_eq!(signals[1].values, [0.0, -1.0, -2.0, -3.0, -4.0]);
}

#[test]
fn the_writer_refuses_values_that_do_not_fit_the_type() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let mut writer = BagWriter::create(&dir.path().join("bad.mcap")).expect("created");
    let twist = writer
        .add_topic("/twist", MessageKind::TwistStamped, "base")
        .expect("added");
    let error = writer
        .write(twist, T0, &[1.0, 2.0])
        .expect_err("2 values for 6 columns");
    assert!(
        error
            .message
            .contains("2 values for a geometry_msgs/msg/TwistStamped, which takes 6"),
        "{error:?}"
    );
    assert!(error.hint.contains("twist.linear.x"), "{error:?}");
    let error = writer
        .write(twist, i64::MAX, &[0.0; 6])
        .expect_err("past int32 seconds");
    assert!(error.message.contains("outside ROS 2's time"), "{error:?}");
}
