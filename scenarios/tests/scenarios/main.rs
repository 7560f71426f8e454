//! The integration tests of this crate, one binary (each module was a test
//! binary of its own: one link instead of many keeps the test build lean).

mod delay;
mod distributed;
mod estimation;
mod real_logs;
mod robustness;
mod write_back;
