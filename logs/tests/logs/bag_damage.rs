//! Damage each checksum or bound catches: a changed value in a bag without
//! chunks (the data section's CRC), a stamp's nanoseconds beyond a second,
//! lengths beyond the file (no large allocation before the error).

use std::path::{Path, PathBuf};

use leeway_logs::bag::path::Extract;
use leeway_logs::bag::write::{BagFormat, write_bag_as};

use crate::common::{T0, ferry_series, read};

const UNCHUNKED: BagFormat = BagFormat {
    chunked: false,
    checksums: true,
};
const BARE: BagFormat = BagFormat {
    chunked: false,
    checksums: false,
};

/// `ferry_series(seconds)` written as `format` to `dir/ferry.mcap`, and its bytes.
fn bag(dir: &Path, seconds: i64, format: BagFormat) -> (PathBuf, Vec<u8>) {
    let path = dir.join("ferry.mcap");
    write_bag_as(&path, &ferry_series(seconds), format).expect("the test bag is written");
    let bytes = std::fs::read(&path).expect("read");
    (path, bytes)
}

/// Where `needle` first occurs in `bytes`.
fn find(bytes: &[u8], needle: &[u8]) -> usize {
    bytes
        .windows(needle.len())
        .position(|w| w == needle)
        .expect("the bytes are in the bag")
}

/// The file's top-level records: (offset, opcode, length of the content).
fn records(bytes: &[u8]) -> Vec<(usize, u8, u64)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 9 <= bytes.len() - 8 {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().expect("8 bytes"));
        out.push((at, bytes[at], len));
        at += 9 + len as usize;
    }
    out
}

/// The first twist's `linear.x` at message `i` (as `ferry_series` makes it).
fn twist_x(i: usize) -> f64 {
    0.1 + i as f64 * 0.01 - 0.3
}

#[test]
fn a_changed_value_in_a_bag_without_chunks_is_found_by_the_data_section_crc() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let (path, mut bytes) = bag(dir.path(), 2, UNCHUNKED);
    let at = find(&bytes, &twist_x(5).to_le_bytes());
    bytes[at] ^= 0x01;
    std::fs::write(&path, &bytes).expect("written");
    let data_end = records(&bytes)
        .into_iter()
        .find(|r| r.1 == 0x0F)
        .expect("a DataEnd record")
        .0;
    let error = read(&path, &[("/twist.twist.linear.x", Extract::Number)])
        .expect_err("the data section's CRC differs");
    assert!(error.location.ends_with("ferry.mcap"), "{error:?}");
    assert!(
        error
            .message
            .starts_with(&format!("data section CRC mismatch (offset {data_end})")),
        "{error:?}"
    );
    assert!(error.hint.contains("copy the file again"), "{error:?}");
}

#[test]
fn without_a_data_section_crc_a_changed_value_cannot_be_seen() {
    // The limit of what a reader can check: documented in docs/data-files.md.
    let dir = tempfile::tempdir().expect("a temporary directory");
    let (path, mut bytes) = bag(dir.path(), 2, BARE);
    let at = find(&bytes, &twist_x(5).to_le_bytes());
    bytes[at] ^= 0x01;
    std::fs::write(&path, &bytes).expect("written");
    let signals = read(&path, &[("/twist.twist.linear.x", Extract::Number)]).expect("read");
    assert_ne!(signals[0].values[5], twist_x(5));
    assert_eq!(signals[0].values[4], twist_x(4));
}

#[test]
fn attachments_summary_and_footer_crcs_are_checked() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("ferry.mcap");
    let mut writer = leeway_logs::bag::write::BagWriter::create(&path).expect("created");
    let twist = writer
        .add_topic(
            "/twist",
            leeway_logs::bag::write::MessageKind::TwistStamped,
            "base_link",
        )
        .expect("a topic");
    writer.write(twist, T0, &[1.0; 6]).expect("written");
    writer
        .attach("calibration.yaml", T0 as u64, b"gain: 2.5\n")
        .expect("attached");
    writer.finish().expect("finished");
    let good = std::fs::read(&path).expect("read");
    let requests = [("/twist.twist.linear.x", Extract::Number)];
    assert_eq!(read(&path, &requests).expect("intact")[0].values, [1.0]);

    let flip = |at: usize| {
        let mut bytes = good.clone();
        bytes[at] ^= 0x20;
        std::fs::write(&path, &bytes).expect("written");
        read(&path, &requests).expect_err("damaged")
    };
    let layout = records(&good);
    let attachment = layout.iter().find(|r| r.1 == 0x09).expect("an attachment");
    let error = flip(find(&good, b"gain: 2.5"));
    assert_eq!(
        error.message,
        format!("attachment CRC mismatch (offset {})", attachment.0),
        "{error:?}"
    );
    // A channel record of the summary (after DataEnd), and the footer's
    // summary_start: both under the footer's CRC.
    let data_end = layout.iter().position(|r| r.1 == 0x0F).expect("DataEnd");
    let channel = layout[data_end..]
        .iter()
        .find(|r| r.1 == 0x04)
        .expect("the summary's channel");
    let footer = layout.iter().find(|r| r.1 == 0x02).expect("a footer");
    for at in [channel.0 + 12, footer.0 + 9] {
        let error = flip(at);
        assert_eq!(
            error.message,
            format!("summary section CRC mismatch (offset {})", footer.0),
            "{error:?}"
        );
    }
}

#[test]
fn a_stamp_of_a_billion_nanoseconds_is_refused_with_its_topic_and_message() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let (path, mut bytes) = bag(dir.path(), 1, BARE);
    // The first message's header.stamp: sec, then nanosec 7 (T0 + 7 ns).
    let sec = i32::try_from(T0 / 1_000_000_000).expect("an int32");
    let mut stamp = sec.to_le_bytes().to_vec();
    stamp.extend_from_slice(&7_u32.to_le_bytes());
    let at = find(&bytes, &stamp) + 4;
    bytes[at..at + 4].copy_from_slice(&1_000_000_000_u32.to_le_bytes());
    std::fs::write(&path, &bytes).expect("written");
    let error =
        read(&path, &[("/twist.twist.linear.x", Extract::Number)]).expect_err("nanosec ≥ 1e9");
    assert!(
        error
            .location
            .ends_with("ferry.mcap: topic /twist, message 0"),
        "{error:?}"
    );
    assert!(
        error
            .message
            .starts_with("header.stamp: nanoseconds `1000000000` outside 0..=999999999"),
        "{error:?}"
    );
}

/// A bag's bytes with one length or size damaged: (what, bytes).
fn damaged_lengths(dir: &Path) -> Vec<(&'static str, Vec<u8>)> {
    let (_, chunked) = bag(dir, 2, BagFormat::default());
    let (_, unchunked) = bag(dir, 2, UNCHUNKED);
    let chunk = records(&chunked)
        .into_iter()
        .find(|r| r.1 == 0x06)
        .expect("a chunk")
        .0;
    let message = records(&unchunked)
        .into_iter()
        .find(|r| r.1 == 0x05)
        .expect("a message")
        .0;
    let set = |bytes: &[u8], at: usize, value: u64| {
        let mut bytes = bytes.to_vec();
        bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
        bytes
    };
    // A chunk's content: start and end times, then its uncompressed size.
    let uncompressed = chunk + 9 + 16;
    vec![
        (
            "a chunk of 2^64-1 bytes",
            set(&chunked, chunk + 1, u64::MAX),
        ),
        (
            "a chunk of 2^64-1 uncompressed bytes",
            set(&chunked, uncompressed, u64::MAX),
        ),
        (
            "a chunk of 1 GiB uncompressed",
            set(&chunked, uncompressed, (1 << 30) - 1),
        ),
        (
            "a message of 2^64-1 bytes",
            set(&unchunked, message + 1, u64::MAX),
        ),
        (
            "a message of 900 MB",
            set(&unchunked, message + 1, 900_000_000),
        ),
    ]
}

/// Run alone under `ulimit -v` by the test below: each damaged length is
/// a located error, and no allocation may approach the limit.
#[test]
#[ignore = "run by damaged_lengths_are_errors_without_a_large_allocation"]
fn damaged_lengths_under_a_memory_limit() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    for (what, bytes) in damaged_lengths(dir.path()) {
        let path = dir.path().join("damaged.mcap");
        std::fs::write(&path, &bytes).expect("written");
        let error = read(&path, &[("/twist.twist.linear.x", Extract::Number)]).expect_err(what);
        assert!(error.location.contains("damaged.mcap"), "{what}: {error:?}");
        assert!(error.message.contains("offset"), "{what}: {error:?}");
    }
}

#[test]
fn damaged_lengths_are_errors_without_a_large_allocation() {
    // The test binary again, its address space limited to 256 MiB: an
    // allocation of the size a damaged length asks for aborts it.
    let exe = std::env::current_exe().expect("the test binary");
    let output = std::process::Command::new("sh")
        .arg("-c")
        .arg(r#"ulimit -v 262144 && exec "$0" --exact "$1" --ignored --test-threads=1"#)
        .arg(exe)
        .arg("bag_damage::damaged_lengths_under_a_memory_limit")
        .output()
        .expect("sh runs");
    assert!(
        output.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        String::from_utf8_lossy(&output.stdout).contains("1 passed"),
        "{}",
        String::from_utf8_lossy(&output.stdout)
    );
}
