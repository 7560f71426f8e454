//! A bag as a source of the log: every requested `topic.field.path` read in
//! one pass over the bag ([`read_bag`]), each signal's stamps checked like
//! any source's (never backwards; a repeated stamp keeps its last sample).

use crate::bag::path::{Extract, FieldPath};
use crate::bag::read::read_bag;
use crate::manifest::{SignalSpec, SourceSpec};
use crate::series::Series;
use leeway_data::DataError;

/// The series of `wanted` from the bag `source`, one per signal.
pub fn read(source: &SourceSpec, wanted: &[&SignalSpec]) -> Result<Vec<Series>, DataError> {
    let requests = wanted
        .iter()
        .map(|s| {
            let path =
                FieldPath::parse(&s.field).map_err(|e| DataError::new(&s.at, e.message, e.hint))?;
            Ok((path, if s.yaw { Extract::Yaw } else { Extract::Number }))
        })
        .collect::<Result<Vec<_>, DataError>>()?;
    let file = source.file.display().to_string();
    read_bag(&source.file, &requests)?
        .into_iter()
        .map(|signal| {
            let mut series = Series {
                file: file.clone(),
                values: vec![Vec::new()],
                ..Series::default()
            };
            for (k, (t, v)) in signal.stamps.iter().zip(&signal.values).enumerate() {
                series.push(*t, std::iter::once(*v), || {
                    format!("{file}: topic `{}`, message {}", signal.topic, k + 1)
                })?;
            }
            Ok(series)
        })
        .collect()
}
