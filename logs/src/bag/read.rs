//! Reading signals from a ROS 2 bag (MCAP, `ros2msg` schemas, CDR
//! messages) in one pass, chunk by chunk: memory holds one chunk and the
//! output vectors, whatever the file's size.

use std::collections::HashMap;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use leeway_data::error::DataError;
use mcap::records::{Channel, Record};

use super::cdr::DecodeError;
use super::container::Container;
use super::path::{Extract, FieldPath, Segment};
use super::plan::{Plan, PlanError};
use super::schema::{BaseType, Count, Schema, short_name};
use crate::stamps::seconds_and_nanos;

/// Where a signal's time stamps come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StampKind {
    /// The message's `header.stamp` (a top-level `header` of type `std_msgs/Header`).
    Header,
    /// The MCAP log time: when the recorder received the message.
    LogTime,
}

/// One requested signal, as the bag holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct Stamped {
    /// Time stamps, ns since the Unix epoch, in the bag's message order.
    pub stamps: Vec<i64>,
    /// The values, one per stamp.
    pub values: Vec<f64>,
    /// Where [`Stamped::stamps`] come from.
    pub stamp: StampKind,
    /// The topic.
    pub topic: String,
    /// The message type, as the bag names it (`geometry_msgs/msg/TwistStamped`).
    pub message_type: String,
}

/// Topics listed in an error, at most.
const LISTED_TOPICS: usize = 20;

/// Reads `requests` from the bag at `path`, in one pass: one [`Stamped`]
/// per request, in order. Stamps are `header.stamp` where the message type
/// has a top-level `std_msgs/Header` named `header`, the log time otherwise.
///
/// Errors (a [`DataError`] naming the file and the topic, message or byte)
/// when the file is not MCAP, is truncated or has a corrupt chunk; when a
/// requested topic is not in the bag (the bag's topics listed); when a field
/// path does not exist (the fields at the level that failed listed) or its
/// value is not a number; when a message is shorter than its schema; when a
/// channel is not `ros2msg`/`cdr`.
///
/// `path` is the `.mcap` file, or a rosbag2 folder holding exactly one.
pub fn read_bag(path: &Path, requests: &[(FieldPath, Extract)]) -> Result<Vec<Stamped>, DataError> {
    let path = &mcap_file(path)?;
    let file = File::open(path).map_err(|e| {
        DataError::new(
            path.display().to_string(),
            format!("cannot open the bag: {e}"),
            "check the path (a ROS 2 bag's data is the .mcap file in its folder)",
        )
    })?;
    let len = file.metadata().map(|m| m.len()).map_err(|e| {
        DataError::new(
            path.display().to_string(),
            format!("cannot read the bag's size: {e}"),
            "check the file system",
        )
    })?;
    let mut pass = Pass::new(path, requests);
    // Every length is bounded by the bytes left, every CRC checked; each
    // chunk is checked whole before any of its messages is decoded, and a
    // CRC mismatch at the end (the data section's, the summary's) refuses
    // the whole file: a damaged bag is an error, never other numbers.
    let mut container = Container::new(
        BufReader::with_capacity(READ_SIZE, file),
        path.display().to_string(),
        len,
    );
    container.read(|record, at| pass.record(record, at))?;
    pass.finish()
}

/// Bytes asked of the file at once.
const READ_SIZE: usize = 1 << 20;

/// The `.mcap` file of a rosbag2 folder (the path itself if it is a file).
fn mcap_file(path: &Path) -> Result<PathBuf, DataError> {
    if !path.is_dir() {
        return Ok(path.to_path_buf());
    }
    let shown = path.display().to_string();
    let entries = std::fs::read_dir(path).map_err(|e| {
        DataError::new(
            &shown,
            format!("cannot list the bag's folder: {e}"),
            "check the path",
        )
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "mcap"))
        .collect();
    files.sort();
    match files.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err(DataError::new(
            shown,
            "the folder holds no .mcap file",
            "record with `ros2 bag record -s mcap`, or `ros2 bag convert` a sqlite3 bag to MCAP",
        )),
        several => Err(DataError::new(
            shown,
            format!(
                "the folder holds {} .mcap files (a split bag): {}",
                several.len(),
                several
                    .iter()
                    .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            "read each file as its own source",
        )),
    }
}

/// A channel with requested signals: how to read its messages.
struct ChannelPlan {
    topic: String,
    /// `header.stamp.sec` and `.nanosec`, for types with a header.
    stamp: Option<(Plan, Plan)>,
    /// (request, plan) for each signal on this channel.
    signals: Vec<(usize, Plan)>,
    /// Messages read so far (for locations).
    messages: u64,
}

/// The state of one pass over a bag.
struct Pass<'a> {
    path: &'a Path,
    requests: &'a [(FieldPath, Extract)],
    out: Vec<Stamped>,
    /// Schemas by id: (name, encoding, text).
    schemas: HashMap<u16, (String, String, Vec<u8>)>,
    /// Every channel seen; `None` for those with nothing requested.
    channels: HashMap<u16, Option<ChannelPlan>>,
    topics: Vec<String>,
}

impl<'a> Pass<'a> {
    fn new(path: &'a Path, requests: &'a [(FieldPath, Extract)]) -> Pass<'a> {
        let out = requests
            .iter()
            .map(|(field, _)| Stamped {
                stamps: Vec::new(),
                values: Vec::new(),
                stamp: StampKind::LogTime,
                topic: field.topic.clone(),
                message_type: String::new(),
            })
            .collect();
        Pass {
            path,
            requests,
            out,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            topics: Vec::new(),
        }
    }

    fn file(&self) -> String {
        self.path.display().to_string()
    }

    /// One record of the file (`at`: its offset, or its chunk's).
    fn record(&mut self, record: Record, at: u64) -> Result<(), DataError> {
        match record {
            Record::Schema { header, data } => {
                self.schemas
                    .entry(header.id)
                    .or_insert_with(|| (header.name, header.encoding, data.into_owned()));
            }
            // The summary repeats the channels: the first record counts.
            Record::Channel(channel) if !self.channels.contains_key(&channel.id) => {
                let plan = self.channel(&channel)?;
                self.channels.insert(channel.id, plan);
            }
            Record::Message { header, data } => {
                self.message(header.channel_id, header.log_time, &data, at)?
            }
            _ => {}
        }
        Ok(())
    }

    /// Compiles the requests on `channel`'s topic against its schema.
    fn channel(&mut self, channel: &Channel) -> Result<Option<ChannelPlan>, DataError> {
        if !self.topics.contains(&channel.topic) {
            self.topics.push(channel.topic.clone());
        }
        let wanted: Vec<usize> = (0..self.requests.len())
            .filter(|&i| self.requests[i].0.topic == channel.topic)
            .collect();
        if wanted.is_empty() {
            return Ok(None);
        }
        let at = format!("{}: topic {}", self.file(), channel.topic);
        let Some((name, encoding, text)) = self.schemas.get(&channel.schema_id) else {
            return Err(DataError::new(
                at,
                format!(
                    "the channel refers to schema {}, which the bag does not define",
                    channel.schema_id
                ),
                "the bag is corrupt or was written without schemas; record it again with rosbag2",
            ));
        };
        if encoding != "ros2msg" || channel.message_encoding != "cdr" {
            return Err(DataError::new(
                at,
                format!(
                    "schema encoding `{encoding}` with message encoding `{}`: leeway reads `ros2msg` schemas with `cdr` messages",
                    channel.message_encoding
                ),
                "record ROS 2 messages with rosbag2's MCAP storage (ros2msg/cdr); IDL schemas are not read",
            ));
        }
        let text = String::from_utf8_lossy(text);
        let schema = Schema::parse(name, &text).map_err(|message| {
            DataError::new(
                at.clone(),
                format!("cannot parse the schema of `{name}`: {message}"),
                "the bag's ros2msg schema is malformed",
            )
        })?;
        let located = |request: usize, error: PlanError| {
            DataError::new(
                format!("{at}, signal {}", self.requests[request].0),
                error.message,
                error.hint,
            )
        };
        let mut signals = Vec::new();
        for &i in &wanted {
            let (field, extract) = &self.requests[i];
            let plan =
                Plan::compile(&schema, &field.fields, *extract).map_err(|e| located(i, e))?;
            signals.push((i, plan));
        }
        let stamp = header_stamp(&schema).map_err(|e| located(wanted[0], e))?;
        for &i in &wanted {
            let out = &mut self.out[i];
            out.stamp = if stamp.is_some() {
                StampKind::Header
            } else {
                StampKind::LogTime
            };
            if out.message_type.is_empty() {
                out.message_type = name.clone();
            }
        }
        Ok(Some(ChannelPlan {
            topic: channel.topic.clone(),
            stamp,
            signals,
            messages: 0,
        }))
    }

    fn message(
        &mut self,
        channel: u16,
        log_time: u64,
        data: &[u8],
        at: u64,
    ) -> Result<(), DataError> {
        let path = self.path;
        let Some(slot) = self.channels.get_mut(&channel) else {
            return Err(DataError::new(
                path.display().to_string(),
                format!(
                    "a message on channel {channel}, which no channel record defines (offset {at})"
                ),
                "the bag is corrupt; recover what is intact with `mcap recover`",
            ));
        };
        let Some(plan) = slot else {
            return Ok(());
        };
        let index = plan.messages;
        plan.messages += 1;
        let located = |error: DecodeError| {
            DataError::new(
                format!("{}: topic {}, message {index}", path.display(), plan.topic),
                error.message(),
                "the message does not match its channel's schema: the bag is corrupt, \
                 or was recorded with another version of the message type",
            )
        };
        let stamp = match &plan.stamp {
            Some((sec, nanosec)) => {
                // Both exact: an int32 and a uint32 are exact in an f64.
                let sec = sec.read(data).map_err(located)? as i64;
                let nanosec = nanosec.read(data).map_err(located)? as i64;
                // As a CSV pair is checked: nanosec is the fraction of the second.
                seconds_and_nanos(sec, nanosec).map_err(|why| {
                    DataError::new(
                        format!("{}: topic {}, message {index}", path.display(), plan.topic),
                        format!("header.stamp: {why}"),
                        "the bag is corrupt, or its publisher wrote an invalid \
                         builtin_interfaces/Time (nanosec below 10^9)",
                    )
                })?
            }
            None => i64::try_from(log_time).unwrap_or(i64::MAX),
        };
        for (request, signal) in &plan.signals {
            let value = signal.read(data).map_err(located)?;
            let out = &mut self.out[*request];
            out.stamps.push(stamp);
            out.values.push(value);
        }
        Ok(())
    }

    fn finish(self) -> Result<Vec<Stamped>, DataError> {
        for (field, _) in self.requests {
            if !self.topics.contains(&field.topic) {
                let mut listed: Vec<&str> = self
                    .topics
                    .iter()
                    .take(LISTED_TOPICS)
                    .map(String::as_str)
                    .collect();
                let more = self.topics.len().saturating_sub(LISTED_TOPICS);
                let more = if more > 0 {
                    format!(" and {more} more")
                } else {
                    String::new()
                };
                listed.sort_unstable();
                return Err(DataError::new(
                    format!("{}: signal {field}", self.file()),
                    format!("the bag has no topic `{}`", field.topic),
                    if listed.is_empty() {
                        "the bag has no topics".to_string()
                    } else {
                        format!("its topics: {}{more}", listed.join(", "))
                    },
                ));
            }
        }
        Ok(self.out)
    }
}

/// Plans for `header.stamp.sec` and `header.stamp.nanosec`, if the root
/// type has a top-level `header` of type `std_msgs/Header`.
fn header_stamp(schema: &Schema) -> Result<Option<(Plan, Plan)>, PlanError> {
    let has_header = schema.fields(&schema.root).is_some_and(|fields| {
        fields.iter().any(|f| {
            f.name == "header"
                && f.count == Count::One
                && f.base == BaseType::Message(short_name("std_msgs/msg/Header"))
        })
    });
    if !has_header {
        return Ok(None);
    }
    let path = |last: &str| -> Result<Plan, PlanError> {
        let fields: Vec<Segment> = ["header", "stamp", last]
            .iter()
            .map(|name| Segment {
                name: name.to_string(),
                index: None,
            })
            .collect();
        Plan::compile(schema, &fields, Extract::Number)
    };
    Ok(Some((path("sec")?, path("nanosec")?)))
}
