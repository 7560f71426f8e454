//! One source's signals as read: stamps in nanoseconds since the epoch and
//! the values of each requested field, the clock checked — stamps never go
//! backwards (a located error), a repeated stamp keeps its last sample (and
//! is counted for the notes).

use crate::manifest::{Clock, SourceSpec};
use crate::stamps::{Nanos, decimal_nanos, iso_nanos, pair_nanos};
use leeway_data::DataError;
use leeway_data::validate::Table;

/// A source's samples: `values[j][k]` is field `j` at `stamps[k]`.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// The source as named in messages (its file).
    pub file: String,
    /// Strictly increasing.
    pub stamps: Vec<Nanos>,
    /// Per requested field.
    pub values: Vec<Vec<f64>>,
    /// Samples whose stamp repeated the one before (the later kept).
    pub repeated: usize,
}

impl Series {
    /// Appends a sample whose stamp must not precede the last one;
    /// `locate` names it in an error.
    pub fn push(
        &mut self,
        t: Nanos,
        values: impl Iterator<Item = f64>,
        locate: impl FnOnce() -> String,
    ) -> Result<(), DataError> {
        match self.stamps.last() {
            Some(&last) if t < last => {
                return Err(backwards(locate(), t, last));
            }
            Some(&last) if t == last => {
                self.repeated += 1;
                for (col, v) in self.values.iter_mut().zip(values) {
                    if let Some(x) = col.last_mut() {
                        *x = v;
                    }
                }
                return Ok(());
            }
            _ => {}
        }
        self.stamps.push(t);
        for (col, v) in self.values.iter_mut().zip(values) {
            col.push(v);
        }
        Ok(())
    }
}

/// The error of a stamp before its predecessor.
pub fn backwards(at: String, t: Nanos, last: Nanos) -> DataError {
    #[allow(clippy::cast_precision_loss)]
    let by = (last - t) as f64 / 1e9;
    DataError::new(
        at,
        format!(
            "time goes backwards: this stamp ({}) is {} s before the previous one ({})",
            crate::stamps::iso(t),
            leeway_model::number::short_number(by),
            crate::stamps::iso(last)
        ),
        "a source's stamps must increase; a human-readable time column in local time, or with the fraction's leading zeros dropped, goes backwards: read the numeric stamps (e.g. time = [\"secs\", \"nsecs\"])",
    )
}

/// Reads `fields` (columns) and the clock of a CSV or Parquet `table`.
pub fn read_table(
    table: &mut dyn Table,
    source: &SourceSpec,
    fields: &[String],
) -> Result<Series, DataError> {
    let headers = table.headers().to_vec();
    // The header is not shown: a manifest may name any file, and an error
    // says nothing of a file beyond the columns the manifest asked for.
    let find = |name: &str| {
        headers.iter().position(|h| h == name).ok_or_else(|| {
            DataError::new(
                table.header_at(None),
                format!(
                    "source `{}` has no column `{name}` (its header row has {} columns)",
                    source.key,
                    headers.len()
                ),
                format!(
                    "the manifest's `{}` names the source's columns as its header row spells them (case and spaces count)",
                    source.at
                ),
            )
        })
    };
    let clock: Vec<usize> = match &source.clock {
        Clock::Column { name, .. } => vec![find(name)?],
        Clock::Pair { secs, nanos } => vec![find(secs)?, find(nanos)?],
        Clock::Bag => Vec::new(),
    };
    let columns: Vec<usize> = fields.iter().map(|f| find(f)).collect::<Result<_, _>>()?;
    let used: Vec<usize> = clock.iter().chain(&columns).copied().collect();
    table.select(&used);
    let mut series = Series {
        file: table.file().to_string(),
        values: vec![Vec::new(); fields.len()],
        ..Series::default()
    };
    let mut row = Vec::with_capacity(columns.len());
    while table.next_row()? {
        let t = stamp(table, &source.clock, &clock, &headers)?;
        row.clear();
        for (&i, name) in columns.iter().zip(fields) {
            row.push(table.number(i, name)?);
        }
        let position = table.position();
        let at = clock.first().copied().unwrap_or(0);
        series.push(t, row.iter().copied(), || {
            table.at(position, Some((at, &headers[at])))
        })?;
    }
    if series.stamps.len() < 2 {
        return Err(DataError::new(
            table.at(table.first_position(), None),
            format!(
                "source `{}` has {} samples",
                source.key,
                series.stamps.len()
            ),
            "a source needs samples along the experiment",
        ));
    }
    Ok(series)
}

/// The current row's stamp.
fn stamp(
    table: &dyn Table,
    clock: &Clock,
    columns: &[usize],
    headers: &[String],
) -> Result<Nanos, DataError> {
    let at = |i: usize| table.at(table.position(), Some((i, &headers[i])));
    let text = |i: usize| -> Result<String, DataError> {
        Ok(String::from_utf8_lossy(&table.label(i)?).into_owned())
    };
    match (clock, columns) {
        (Clock::Column { unit, .. }, [i]) => {
            if let Some(origin) = table.stamp_origin(*i) {
                let seconds = table.number(*i, &headers[*i])?;
                // Seconds since the column's first stamp, exact below 2⁵³ ns (104 days).
                #[allow(clippy::cast_possible_truncation)]
                return Ok(origin + (seconds * 1e9).round() as Nanos);
            }
            let cell = text(*i)?;
            match decimal_nanos(&cell, *unit) {
                Some(t) => Ok(t),
                None if cell.trim().is_empty() => Err(leeway_data::validate::missing(
                    at(*i),
                    "empty time stamp",
                )),
                None => iso_nanos(&cell).map_err(|why| {
                    DataError::new(
                        at(*i),
                        why,
                        "a time column holds numbers (in its time_unit: s, ms, us, ns) or ISO-8601 text with a UTC offset (2026-05-14T10:22:03.5Z)",
                    )
                }),
            }
        }
        (Clock::Pair { .. }, [s, n]) => pair_nanos(&text(*s)?, &text(*n)?).map_err(|why| {
            DataError::new(
                at(*s),
                why,
                "the two stamp columns hold whole seconds and nanoseconds (ROS's header.stamp.sec and .nanosec)",
            )
        }),
        _ => Err(DataError::new(
            table.file(),
            "this source has no time column",
            "declare its `time` in the manifest",
        )),
    }
}
