//! A bag as a source of the log: each requested `topic.field.path` read in
//! one pass over the bag, its stamps checked like any source's.

use crate::manifest::{SignalSpec, SourceSpec};
use crate::series::Series;
use leeway_data::DataError;

/// The series of `wanted` from the bag `source`.
pub fn read(source: &SourceSpec, _wanted: &[&SignalSpec]) -> Result<Vec<Series>, DataError> {
    Err(DataError::new(
        &source.at,
        "bags are not read yet",
        "convert the bag",
    ))
}
