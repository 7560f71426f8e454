//! ROS 2 bags in MCAP: signals named `topic.field.path`.
//!
//! [`read::read_bag`] reads the requested fields of a bag in one pass,
//! each with its stamps ([`read::Stamped`]); [`path::FieldPath`] names a
//! signal (`/navigation/twist_body.twist.linear.x`) and
//! [`path::Extract`] says whether to take the number or a quaternion's
//! heading. The container is the `mcap` crate's; the `ros2msg` schemas
//! ([`schema`]) and CDR messages ([`cdr`]) are read here, each path
//! compiled once per channel ([`plan`]). [`write`] writes bags of common
//! message types, for tests and examples.

pub mod cdr;
pub mod path;
pub mod plan;
pub mod read;
pub mod schema;
pub mod write;

pub use path::{Extract, FieldPath, Segment};
pub use read::{StampKind, Stamped, read_bag};
