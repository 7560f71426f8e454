//! ROS 2 bags in MCAP: signals named `topic.field.path`.
//!
//! [`read::read_bag`] reads the requested fields of a bag in one pass,
//! each with its stamps ([`read::Stamped`]); [`path::FieldPath`] names a
//! signal (`/navigation/twist_body.twist.linear.x`) and
//! [`path::Extract`] says whether to take the number or a quaternion's
//! heading. The container is read record by record ([`container`]:
//! lengths bounded, every CRC checked), its chunks decompressed by the
//! `mcap` crate; the `ros2msg` schemas ([`schema`]) and CDR messages
//! ([`cdr`]) are read here, each path compiled once per channel ([`plan`]). [`write`](mod@write) writes bags of common
//! message types, for tests and examples.
//!
//! ```
//! use leeway_logs::bag::path::{Extract, FieldPath};
//! use leeway_logs::bag::read::{StampKind, read_bag};
//! use leeway_logs::bag::write::{MessageKind, TopicSeries, write_bag};
//! # fn main() -> Result<(), leeway_data::DataError> {
//! # let dir = tempfile::tempdir().expect("a temporary directory");
//! let bag = dir.path().join("ferry.mcap");
//! let t0 = 1_700_000_000_000_000_000; // ns since the epoch
//! write_bag(&bag, &[TopicSeries {
//!     topic: "/imu".into(),
//!     kind: MessageKind::Imu,
//!     frame_id: "imu_link".into(),
//!     stamps: vec![t0, t0 + 100_000_000],
//!     // heading (rad), angular velocity x y z, linear acceleration x y z
//!     columns: vec![vec![0.5, 0.6], vec![0.0; 2], vec![0.0; 2], vec![0.01, 0.02],
//!                   vec![0.0; 2], vec![0.0; 2], vec![9.81; 2]],
//! }])?;
//! let signals = read_bag(&bag, &[
//!     (FieldPath::parse("/imu.orientation")?, Extract::Yaw),
//!     (FieldPath::parse("/imu.angular_velocity.z")?, Extract::Number),
//! ])?;
//! assert_eq!(signals[1].values, [0.01, 0.02]);
//! assert_eq!(signals[1].stamps, [t0, t0 + 100_000_000]);
//! assert_eq!(signals[1].stamp, StampKind::Header);
//! assert!((signals[0].values[1] - 0.6).abs() < 1e-12);
//! # Ok(())
//! # }
//! ```

pub mod cdr;
pub mod container;
pub mod path;
pub mod plan;
pub mod read;
pub mod schema;
pub mod write;

pub use path::{Extract, FieldPath, Segment};
pub use read::{StampKind, Stamped, read_bag};
