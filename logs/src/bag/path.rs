//! A signal in a bag named `topic.field.path`, and what to take from it.

use std::fmt;

use leeway_data::error::DataError;

/// One step into a message: a field, and an element if it is an array.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Segment {
    /// The field's name.
    pub name: String,
    /// The element, for `ranges[3]` (fixed arrays and sequences).
    pub index: Option<usize>,
}

/// A signal in a bag: `/navigation/twist_body.twist.linear.x` is the field
/// `twist.linear.x` of the messages on topic `/navigation/twist_body`.
///
/// The topic runs up to the first `.` (ROS topic names have no dots); each
/// field after it may pick an array element, `/scan.ranges[3]`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct FieldPath {
    /// The topic, as the bag names it (`/imu`).
    pub topic: String,
    /// The fields from the message down, outermost first.
    pub fields: Vec<Segment>,
}

impl FieldPath {
    /// Parses `topic.field.path`; a bare topic (`/imu`) names the whole message.
    pub fn parse(text: &str) -> Result<FieldPath, DataError> {
        let bad = |message: String| {
            DataError::new(
                text,
                message,
                "write a signal as `/topic.field.subfield`, e.g. \
                 `/navigation/twist_body.twist.linear.x` or `/scan.ranges[3]`",
            )
        };
        let (topic, rest) = match text.split_once('.') {
            Some((topic, rest)) => (topic, Some(rest)),
            None => (text, None),
        };
        if !topic.starts_with('/') || topic.len() < 2 {
            return Err(bad(format!(
                "the topic `{topic}` does not start with `/` (bags name topics in full, `/imu`)"
            )));
        }
        if let Some(c) = topic
            .chars()
            .find(|c| !(c.is_ascii_alphanumeric() || *c == '_' || *c == '/'))
        {
            return Err(bad(format!("the topic `{topic}` holds `{c}`")));
        }
        let fields = match rest {
            Some(rest) => rest
                .split('.')
                .map(parse_segment)
                .collect::<Result<Vec<_>, String>>()
                .map_err(bad)?,
            None => Vec::new(),
        };
        Ok(FieldPath {
            topic: topic.to_string(),
            fields,
        })
    }
}

/// `name` or `name[3]`.
fn parse_segment(text: &str) -> Result<Segment, String> {
    let (name, index) = match text.split_once('[') {
        Some((name, rest)) => {
            let digits = rest
                .strip_suffix(']')
                .ok_or_else(|| format!("`{text}`: `[` without its closing `]`"))?;
            let index = digits
                .parse()
                .map_err(|_| format!("`{text}`: the index `{digits}` is not a whole number"))?;
            (name, Some(index))
        }
        None => (text, None),
    };
    let starts_well = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic());
    if !starts_well || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(if name.is_empty() {
            "an empty field name (two dots, or a dot at the end)".to_string()
        } else {
            format!("`{name}` is not a field name (a letter, then letters, digits or `_`)")
        });
    }
    Ok(Segment {
        name: name.to_string(),
        index,
    })
}

impl fmt::Display for FieldPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.topic)?;
        for segment in &self.fields {
            write!(f, ".{}", segment.name)?;
            if let Some(index) = segment.index {
                write!(f, "[{index}]")?;
            }
        }
        Ok(())
    }
}

/// What a signal takes from the field its path names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Extract {
    /// The number itself: any ROS integer or float (`float32`, `float64`,
    /// `int8` … `uint64`) as an `f64`.
    Number,
    /// The heading of a `geometry_msgs/Quaternion` (x, y, z, w), in rad:
    /// the yaw of the ZYX (yaw–pitch–roll) convention,
    /// `atan2(2(w·z + x·y), 1 − 2(y² + z²))`, in [−π, π].
    ///
    /// The path names the quaternion (`/imu.orientation`,
    /// `/odom.pose.pose.orientation`) or a message with a field
    /// `orientation` holding one (`/imu`, `/odom.pose.pose`). ROS uses ENU
    /// world frames and FLU body frames, so this yaw is counter-clockwise
    /// from east; a model written in NED (clockwise from north) maps it
    /// with its data block's units and signs.
    Yaw,
}
