//! leeway-design's integration tests: one binary (one link keeps the test
//! build lean), a module per subject.

mod bounds;
mod common;
mod examples;
mod plan_fuzz;
mod rov;
mod sea_room;
mod several;
mod units;
mod verification;
mod verified;
