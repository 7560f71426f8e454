//! leeway-logs: robot logs as they are written — several sources per
//! experiment (CSV, Parquet, ROS 2 bags in MCAP), each with its own clock
//! and rate, joined on the model's time grid; gaps split an experiment,
//! never bridged.

pub mod bag;
mod bag_source;
pub mod join;
pub mod load;
pub mod manifest;
pub mod series;
pub mod stamps;

pub use load::{is_log, load_log, load_path, open_log, open_path};
