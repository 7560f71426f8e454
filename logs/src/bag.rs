//! ROS 2 bags in MCAP: signals named `topic.field.path`.
