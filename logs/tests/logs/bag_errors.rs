//! Each way a bag or a request can be wrong gives one located error with a hint.

use std::collections::BTreeMap;

use leeway_logs::bag::path::Extract;
use mcap::records::MessageHeader;

use crate::common::{T0, ferry_bag, read};

#[test]
fn a_file_that_is_not_mcap_says_so() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("log.db3");
    std::fs::write(&path, b"SQLite format 3\0 and more bytes than the magic").expect("written");
    let error = read(&path, &[("/twist.twist.linear.x", Extract::Number)]).expect_err("not MCAP");
    assert!(error.message.starts_with("not an MCAP file"), "{error:?}");
    assert!(error.hint.contains("ros2 bag convert"), "{error:?}");
    assert!(error.location.contains("log.db3"), "{error:?}");
}

#[test]
fn a_truncated_bag_says_where() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = ferry_bag(dir.path(), 30);
    let bytes = std::fs::read(&bag).expect("read");
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("written");
    let error = read(&cut, &[("/twist.twist.linear.x", Extract::Number)]).expect_err("truncated");
    assert!(error.message.contains("truncated"), "{error:?}");
    assert!(error.message.contains("(offset "), "{error:?}");
    assert!(error.location.ends_with("cut.mcap"), "{error:?}");
}

#[test]
fn a_corrupt_chunk_is_found_by_its_checksum_or_its_codec() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = ferry_bag(dir.path(), 30);
    let mut bytes = std::fs::read(&bag).expect("read");
    // The middle of the first chunk's zstd data (the schemas come first,
    // the summary last).
    let at = bytes.len() / 3;
    bytes[at] ^= 0x5A;
    let flipped = dir.path().join("flipped.mcap");
    std::fs::write(&flipped, &bytes).expect("written");
    let error = read(&flipped, &[("/twist.twist.linear.x", Extract::Number)]).expect_err("corrupt");
    assert!(
        error.message.contains("corrupt") || error.message.starts_with("chunk CRC mismatch"),
        "{error:?}"
    );
    assert!(error.hint.contains("mcap recover"), "{error:?}");
}

#[test]
fn a_missing_topic_lists_the_bags_topics() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = ferry_bag(dir.path(), 1);
    let error = read(
        &bag,
        &[
            ("/twist.twist.linear.x", Extract::Number),
            ("/gps.latitude", Extract::Number),
        ],
    )
    .expect_err("no /gps");
    assert_eq!(error.message, "the bag has no topic `/gps`");
    assert_eq!(error.hint, "its topics: /depth, /imu, /twist, /wrench");
    assert!(
        error.location.ends_with("ferry.mcap: signal /gps.latitude"),
        "{error:?}"
    );
}

#[test]
fn a_wrong_field_lists_the_fields_at_the_level_that_failed() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = ferry_bag(dir.path(), 1);
    let error = read(&bag, &[("/twist.twist.linaer.x", Extract::Number)]).expect_err("a typo");
    assert_eq!(error.message, "`geometry_msgs/Twist` has no field `linaer`");
    assert_eq!(
        error.hint,
        "its fields: linear (geometry_msgs/Vector3), angular (geometry_msgs/Vector3)"
    );
    assert!(
        error
            .location
            .ends_with("ferry.mcap: topic /twist, signal /twist.twist.linaer.x"),
        "{error:?}"
    );
    let error = read(&bag, &[("/twist.header.frame_id", Extract::Number)]).expect_err("a string");
    assert_eq!(error.message, "`header.frame_id` is a string, not a number");
    let error = read(&bag, &[("/twist.twist.linear", Extract::Number)]).expect_err("a message");
    assert_eq!(
        error.message,
        "`twist.linear` is a `geometry_msgs/Vector3` message, not a number"
    );
    let error = read(&bag, &[("/imu.orientation", Extract::Number)]).expect_err("a quaternion");
    assert!(error.hint.contains("yaw"), "{error:?}");
    let error = read(&bag, &[("/twist", Extract::Yaw)]).expect_err("no orientation");
    assert!(
        error
            .message
            .contains("nor a message with a field `orientation`"),
        "{error:?}"
    );
}

/// A bag written with the `mcap` crate directly: one channel of `encoding`
/// schemas and `message_encoding` messages, holding `payload`.
fn raw_bag(
    dir: &std::path::Path,
    encoding: &str,
    message_encoding: &str,
    payload: &[u8],
) -> std::path::PathBuf {
    let path = dir.join("raw.mcap");
    let file = std::io::BufWriter::new(std::fs::File::create(&path).expect("created"));
    let mut writer = mcap::Writer::new(file).expect("a writer");
    let schema = writer
        .add_schema(
            "geometry_msgs/msg/Vector3",
            encoding,
            b"float64 x\nfloat64 y\nfloat64 z\n",
        )
        .expect("a schema");
    let channel = writer
        .add_channel(schema, "/v", message_encoding, &BTreeMap::new())
        .expect("a channel");
    for sequence in 0..3 {
        let header = MessageHeader {
            channel_id: channel,
            sequence,
            log_time: T0 as u64,
            publish_time: T0 as u64,
        };
        writer
            .write_to_known_channel(&header, payload)
            .expect("a message");
    }
    writer.finish().expect("finished");
    path
}

#[test]
fn a_message_shorter_than_its_schema_names_topic_and_message() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let mut payload = vec![0, 1, 0, 0];
    payload.extend_from_slice(&1.5_f64.to_le_bytes());
    payload.extend_from_slice(&2.5_f64.to_le_bytes());
    let bag = raw_bag(dir.path(), "ros2msg", "cdr", &payload);
    let signals = read(&bag, &[("/v.y", Extract::Number)]).expect("y is there");
    assert_eq!(signals[0].values, [2.5, 2.5, 2.5]);
    assert_eq!(signals[0].stamps, [T0, T0, T0]);
    let error = read(&bag, &[("/v.z", Extract::Number)]).expect_err("z is not");
    assert!(
        error.location.ends_with("raw.mcap: topic /v, message 0"),
        "{error:?}"
    );
    assert_eq!(
        error.message,
        "the message is shorter than its schema: it has 16 payload bytes, its fields need at least 24"
    );
}

#[test]
fn schemas_other_than_ros2msg_with_cdr_are_named() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let bag = raw_bag(dir.path(), "jsonschema", "json", b"{}");
    let error = read(&bag, &[("/v.x", Extract::Number)]).expect_err("JSON");
    assert!(
        error
            .message
            .starts_with("schema encoding `jsonschema` with message encoding `json`"),
        "{error:?}"
    );
    let bag = raw_bag(dir.path(), "ros2idl", "cdr", b"{}");
    let error = read(&bag, &[("/v.x", Extract::Number)]).expect_err("IDL");
    assert!(
        error.message.starts_with("schema encoding `ros2idl`"),
        "{error:?}"
    );
    // Topics nobody asked for are not checked.
    assert!(read(&bag, &[]).expect("nothing asked").is_empty());
}

#[test]
fn a_bag_folder_is_read_through_its_one_mcap_file() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    ferry_bag(dir.path(), 1);
    std::fs::write(
        dir.path().join("metadata.yaml"),
        "rosbag2_bagfile_information: {}",
    )
    .expect("written");
    let signals = read(dir.path(), &[("/depth.data", Extract::Number)]).expect("the folder reads");
    assert_eq!(signals[0].values.len(), 2);
    std::fs::copy(
        dir.path().join("ferry.mcap"),
        dir.path().join("ferry_1.mcap"),
    )
    .expect("copied");
    let error = read(dir.path(), &[("/depth.data", Extract::Number)]).expect_err("a split bag");
    assert_eq!(
        error.message,
        "the folder holds 2 .mcap files (a split bag): ferry.mcap, ferry_1.mcap"
    );
    let empty = tempfile::tempdir().expect("a temporary directory");
    let error = read(empty.path(), &[("/depth.data", Extract::Number)]).expect_err("no file");
    assert_eq!(error.message, "the folder holds no .mcap file");
}

#[test]
fn a_record_claiming_more_bytes_than_the_file_has_is_truncation() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("claims.mcap");
    // The MCAP magic, then a Header record (opcode 1) claiming 900 MB.
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    bytes.push(0x01);
    bytes.extend_from_slice(&900_000_000_u64.to_le_bytes());
    bytes.extend_from_slice(&[0; 64]);
    std::fs::write(&path, &bytes).expect("written");
    let error = read(&path, &[("/twist.twist.linear.x", Extract::Number)]).expect_err("cut short");
    assert!(error.message.contains("truncated"), "{error:?}");
    assert!(
        error
            .message
            .starts_with("a Header record declares 900000000 bytes, and the file has 64"),
        "{error:?}"
    );
    assert!(error.message.ends_with("(offset 8)"), "{error:?}");
    assert_eq!(error.location, path.display().to_string());
}
