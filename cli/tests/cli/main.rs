//! The integration tests of this crate, one binary (each module was a test
//! binary of its own: one link instead of many keeps the test build lean).

mod common;

mod check;
mod csv_layouts;
mod data;
mod delay;
mod design;
mod editor;
mod estimate;
mod logs;
mod output;
mod parquet;
mod readers;
mod reproduce;
mod select;
mod simulate;
mod words;
