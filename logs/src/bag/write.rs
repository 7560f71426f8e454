//! Writing ROS 2 bags (MCAP, zstd chunks, `ros2msg` schemas, CDR messages)
//! of a few common message types — for tests and examples: synthetic logs
//! that [`read_bag`](super::read::read_bag) and other ROS tools read.
//!
//! Each [`MessageKind`] takes its values as the columns
//! [`MessageKind::columns`] names, e.g. `twist.linear.x` … `twist.angular.z`.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use leeway_data::error::DataError;
use mcap::records::MessageHeader;
use mcap::{Attachment, Compression, WriteOptions, Writer};

/// A message type the writer knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MessageKind {
    /// `geometry_msgs/msg/TwistStamped`: body velocities.
    TwistStamped,
    /// `geometry_msgs/msg/WrenchStamped`: forces and torques.
    WrenchStamped,
    /// `sensor_msgs/msg/Imu`: the orientation from a heading (a yaw about
    /// z, no roll or pitch), angular velocity, linear acceleration.
    Imu,
    /// `std_msgs/msg/Float64`: one number, no header (stamped by log time).
    Float64,
}

const TIME: &str = "int32 sec\nuint32 nanosec\n";
const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
const VECTOR3: &str = "float64 x\nfloat64 y\nfloat64 z\n";
// With ROS 2's default values, which a reader must skip.
const QUATERNION: &str = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";

impl MessageKind {
    /// The ROS 2 type name, as rosbag2 writes it.
    pub fn type_name(self) -> &'static str {
        match self {
            MessageKind::TwistStamped => "geometry_msgs/msg/TwistStamped",
            MessageKind::WrenchStamped => "geometry_msgs/msg/WrenchStamped",
            MessageKind::Imu => "sensor_msgs/msg/Imu",
            MessageKind::Float64 => "std_msgs/msg/Float64",
        }
    }

    /// The field path of each value [`BagWriter::write`] takes, in order.
    /// For [`MessageKind::Imu`], `orientation` is a heading (rad), read back
    /// with [`Extract::Yaw`](super::path::Extract::Yaw).
    pub fn columns(self) -> &'static [&'static str] {
        match self {
            MessageKind::TwistStamped => &[
                "twist.linear.x",
                "twist.linear.y",
                "twist.linear.z",
                "twist.angular.x",
                "twist.angular.y",
                "twist.angular.z",
            ],
            MessageKind::WrenchStamped => &[
                "wrench.force.x",
                "wrench.force.y",
                "wrench.force.z",
                "wrench.torque.x",
                "wrench.torque.y",
                "wrench.torque.z",
            ],
            MessageKind::Imu => &[
                "orientation",
                "angular_velocity.x",
                "angular_velocity.y",
                "angular_velocity.z",
                "linear_acceleration.x",
                "linear_acceleration.y",
                "linear_acceleration.z",
            ],
            MessageKind::Float64 => &["data"],
        }
    }

    /// The `ros2msg` schema: the type's definition, then each dependency's
    /// after a line of `=` and `MSG: pkg/Type`.
    pub fn schema(self) -> String {
        let (root, dependencies): (&str, &[(&str, &str)]) = match self {
            MessageKind::TwistStamped => (
                "std_msgs/Header header\nTwist twist\n",
                &[
                    ("std_msgs/Header", HEADER),
                    ("builtin_interfaces/Time", TIME),
                    ("geometry_msgs/Twist", "Vector3  linear\nVector3  angular\n"),
                    ("geometry_msgs/Vector3", VECTOR3),
                ],
            ),
            MessageKind::WrenchStamped => (
                "std_msgs/Header header\nWrench wrench\n",
                &[
                    ("std_msgs/Header", HEADER),
                    ("builtin_interfaces/Time", TIME),
                    ("geometry_msgs/Wrench", "Vector3  force\nVector3  torque\n"),
                    ("geometry_msgs/Vector3", VECTOR3),
                ],
            ),
            MessageKind::Imu => (
                "std_msgs/Header header\n\
                 geometry_msgs/Quaternion orientation\n\
                 float64[9] orientation_covariance # Row major about x, y, z axes\n\
                 geometry_msgs/Vector3 angular_velocity\n\
                 float64[9] angular_velocity_covariance\n\
                 geometry_msgs/Vector3 linear_acceleration\n\
                 float64[9] linear_acceleration_covariance\n",
                &[
                    ("std_msgs/Header", HEADER),
                    ("builtin_interfaces/Time", TIME),
                    ("geometry_msgs/Quaternion", QUATERNION),
                    ("geometry_msgs/Vector3", VECTOR3),
                ],
            ),
            MessageKind::Float64 => ("float64 data\n", &[]),
        };
        let mut text = root.to_string();
        for (name, definition) in dependencies {
            text.push_str(&"=".repeat(80));
            text.push_str(&format!("\nMSG: {name}\n{definition}"));
        }
        text
    }

    /// Whether the type has a `std_msgs/Header`.
    fn has_header(self) -> bool {
        self != MessageKind::Float64
    }

    /// The CDR message (little-endian) for one sample.
    fn encode(self, stamp: i64, frame_id: &str, values: &[f64], out: &mut Cdr) {
        out.start();
        if self.has_header() {
            let (sec, nanosec) = split_stamp(stamp);
            out.i32(sec);
            out.u32(nanosec);
            out.string(frame_id);
        }
        match self {
            MessageKind::Imu => {
                let heading = values[0];
                let half = 0.5 * heading;
                for q in [0.0, 0.0, half.sin(), half.cos()] {
                    out.f64(q);
                }
                let covariance = [0.0; 9];
                covariance.iter().for_each(|c| out.f64(*c));
                values[1..4].iter().for_each(|v| out.f64(*v));
                covariance.iter().for_each(|c| out.f64(*c));
                values[4..7].iter().for_each(|v| out.f64(*v));
                covariance.iter().for_each(|c| out.f64(*c));
            }
            _ => values.iter().for_each(|v| out.f64(*v)),
        }
    }
}

/// A stamp in ns → `builtin_interfaces/Time` (sec, nanosec); the seconds
/// were checked to fit an `int32`.
fn split_stamp(stamp: i64) -> (i32, u32) {
    let sec = stamp.div_euclid(1_000_000_000);
    let nanosec = stamp.rem_euclid(1_000_000_000);
    (
        i32::try_from(sec).unwrap_or(i32::MAX),
        u32::try_from(nanosec).unwrap_or(0),
    )
}

/// A CDR message being written (little-endian, plain CDR).
#[derive(Default)]
struct Cdr {
    bytes: Vec<u8>,
}

impl Cdr {
    fn start(&mut self) {
        self.bytes.clear();
        self.bytes.extend_from_slice(&[0x00, 0x01, 0x00, 0x00]);
    }
    /// Pads to a multiple of `size` counted from the payload's start.
    fn align(&mut self, size: usize) {
        let payload = self.bytes.len() - 4;
        let padded = payload.next_multiple_of(size);
        self.bytes.resize(4 + padded, 0);
    }
    fn i32(&mut self, v: i32) {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.align(8);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    fn string(&mut self, s: &str) {
        self.u32(u32::try_from(s.len() + 1).unwrap_or(u32::MAX));
        self.bytes.extend_from_slice(s.as_bytes());
        self.bytes.push(0);
    }
}

/// How a bag is laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BagFormat {
    /// Messages in zstd chunks (rosbag2's default), or written directly in
    /// the data section (`false`).
    pub chunked: bool,
    /// CRC-32s of the chunks, the data section (in `DataEnd`), the summary
    /// (in the footer) and the attachments; `false` writes 0, "not computed".
    pub checksums: bool,
}

impl Default for BagFormat {
    /// Chunked, with every checksum: as rosbag2 writes.
    fn default() -> BagFormat {
        BagFormat {
            chunked: true,
            checksums: true,
        }
    }
}

/// A topic added to a [`BagWriter`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TopicId(usize);

struct Topic {
    channel: u16,
    kind: MessageKind,
    frame_id: String,
    name: String,
    sequence: u32,
}

/// Writes a bag message by message (flat memory: zstd chunks go out as they fill).
pub struct BagWriter {
    writer: Writer<BufWriter<File>>,
    topics: Vec<Topic>,
    cdr: Cdr,
    path: String,
}

fn write_error(path: &str, error: impl std::fmt::Display) -> DataError {
    DataError::new(
        path,
        format!("cannot write the bag: {error}"),
        "check the path and the free space",
    )
}

impl BagWriter {
    /// Creates the bag file at `path` (an MCAP file, profile `ros2`), in
    /// zstd chunks with every checksum.
    pub fn create(path: &Path) -> Result<BagWriter, DataError> {
        BagWriter::create_as(path, BagFormat::default())
    }

    /// Creates the bag file at `path` laid out as `format` says.
    pub fn create_as(path: &Path, format: BagFormat) -> Result<BagWriter, DataError> {
        let shown = path.display().to_string();
        let file = File::create(path).map_err(|e| write_error(&shown, e))?;
        let writer = WriteOptions::new()
            .profile("ros2")
            .library("leeway")
            .use_chunks(format.chunked)
            .compression(format.chunked.then_some(Compression::Zstd))
            .calculate_chunk_crcs(format.checksums)
            .calculate_data_section_crc(format.checksums)
            .calculate_summary_section_crc(format.checksums)
            .calculate_attachment_crcs(format.checksums)
            .create(BufWriter::new(file))
            .map_err(|e| write_error(&shown, e))?;
        Ok(BagWriter {
            writer,
            topics: Vec::new(),
            cdr: Cdr::default(),
            path: shown,
        })
    }

    /// Adds a topic of messages of `kind`, their headers' `frame_id` set to `frame_id`.
    pub fn add_topic(
        &mut self,
        topic: &str,
        kind: MessageKind,
        frame_id: &str,
    ) -> Result<TopicId, DataError> {
        let schema = self
            .writer
            .add_schema(kind.type_name(), "ros2msg", kind.schema().as_bytes())
            .map_err(|e| write_error(&self.path, e))?;
        let channel = self
            .writer
            .add_channel(schema, topic, "cdr", &BTreeMap::new())
            .map_err(|e| write_error(&self.path, e))?;
        self.topics.push(Topic {
            channel,
            kind,
            frame_id: frame_id.to_string(),
            name: topic.to_string(),
            sequence: 0,
        });
        Ok(TopicId(self.topics.len() - 1))
    }

    /// Writes one message: `values` in the order of the kind's
    /// [`MessageKind::columns`], `stamp` in ns since the epoch as its
    /// `header.stamp` and its log time.
    pub fn write(&mut self, topic: TopicId, stamp: i64, values: &[f64]) -> Result<(), DataError> {
        self.write_logged(topic, stamp, stamp, values)
    }

    /// [`BagWriter::write`] with a log time (ns) other than the header's
    /// stamp: a recorder receives a message after its sensor stamped it.
    pub fn write_logged(
        &mut self,
        topic: TopicId,
        stamp: i64,
        log_time: i64,
        values: &[f64],
    ) -> Result<(), DataError> {
        let Some(entry) = self.topics.get_mut(topic.0) else {
            return Err(write_error(&self.path, "a topic id of another writer"));
        };
        let expected = entry.kind.columns().len();
        let at = || format!("{}: topic {}", self.path, entry.name);
        if values.len() != expected {
            return Err(DataError::new(
                at(),
                format!(
                    "{} values for a {}, which takes {expected}",
                    values.len(),
                    entry.kind.type_name()
                ),
                format!("pass {}", entry.kind.columns().join(", ")),
            ));
        }
        let sec = stamp.div_euclid(1_000_000_000);
        let log_time = u64::try_from(log_time).ok();
        let (true, Some(log_time)) = (i32::try_from(sec).is_ok(), log_time) else {
            return Err(DataError::new(
                at(),
                format!(
                    "the stamp {stamp} ns or the log time is outside ROS 2's time (int32 seconds, from 1970)"
                ),
                "stamps are ns since the Unix epoch",
            ));
        };
        entry
            .kind
            .encode(stamp, &entry.frame_id, values, &mut self.cdr);
        let header = MessageHeader {
            channel_id: entry.channel,
            sequence: entry.sequence,
            log_time,
            publish_time: log_time,
        };
        entry.sequence = entry.sequence.wrapping_add(1);
        self.writer
            .write_to_known_channel(&header, &self.cdr.bytes)
            .map_err(|e| write_error(&self.path, e))
    }

    /// Writes an attachment (a file stored in the bag, e.g. a calibration):
    /// readers skip it, its CRC checked.
    pub fn attach(&mut self, name: &str, log_time: u64, data: &[u8]) -> Result<(), DataError> {
        self.writer
            .attach(&Attachment {
                log_time,
                create_time: log_time,
                name: name.to_string(),
                media_type: "application/octet-stream".to_string(),
                data: data.into(),
            })
            .map_err(|e| write_error(&self.path, e))
    }

    /// Writes the summary and closes the file.
    pub fn finish(mut self) -> Result<(), DataError> {
        self.writer
            .finish()
            .map_err(|e| write_error(&self.path, e))?;
        Ok(())
    }
}

/// One topic's messages for [`write_bag`].
#[derive(Clone, Debug, PartialEq)]
pub struct TopicSeries {
    /// The topic (`/imu`).
    pub topic: String,
    /// The message type.
    pub kind: MessageKind,
    /// The headers' `frame_id`.
    pub frame_id: String,
    /// Stamps, ns since the epoch (header stamp and log time).
    pub stamps: Vec<i64>,
    /// One column per [`MessageKind::columns`], each as long as the stamps.
    pub columns: Vec<Vec<f64>>,
}

/// Writes `series` to a bag at `path`, the topics' messages interleaved in
/// stamp order (as a recorder logs them).
pub fn write_bag(path: &Path, series: &[TopicSeries]) -> Result<(), DataError> {
    write_bag_as(path, series, BagFormat::default())
}

/// [`write_bag`] laid out as `format` says (unchunked, without checksums).
pub fn write_bag_as(
    path: &Path,
    series: &[TopicSeries],
    format: BagFormat,
) -> Result<(), DataError> {
    let mut writer = BagWriter::create_as(path, format)?;
    let mut ids = Vec::new();
    for s in series {
        let lengths_agree = s.columns.len() == s.kind.columns().len()
            && s.columns.iter().all(|c| c.len() == s.stamps.len());
        if !lengths_agree {
            return Err(DataError::new(
                format!("{}: topic {}", path.display(), s.topic),
                format!(
                    "{} needs {} columns as long as the stamps",
                    s.kind.type_name(),
                    s.kind.columns().len()
                ),
                format!("pass {}", s.kind.columns().join(", ")),
            ));
        }
        ids.push(writer.add_topic(&s.topic, s.kind, &s.frame_id)?);
    }
    let mut next = vec![0usize; series.len()];
    let mut values = Vec::new();
    // The topic whose next stamp is earliest, until all are written.
    while let Some(k) = (0..series.len())
        .filter(|&k| next[k] < series[k].stamps.len())
        .min_by_key(|&k| series[k].stamps[next[k]])
    {
        let i = next[k];
        values.clear();
        values.extend(series[k].columns.iter().map(|c| c[i]));
        writer.write(ids[k], series[k].stamps[i], &values)?;
        next[k] += 1;
    }
    writer.finish()
}
