//! leeway-logs' integration tests (one binary).

mod bag_damage;
mod bag_errors;
mod bag_fuzz;
mod bag_python;
mod bag_round_trip;
mod bag_schema;
mod bounded_reads;
mod common;
mod manifest_fuzz;
