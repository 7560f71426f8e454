//! leeway-logs: robot logs as they are written — several sources per
//! experiment (CSV, Parquet, ROS 2 bags in MCAP), each with its own clock
//! and rate, joined on the model's time grid; gaps split an experiment,
//! never bridged.

pub mod bag;
