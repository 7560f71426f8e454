//! Frames handed over from Python, read by the runtime's own CSV loader so
//! that a DataFrame is validated exactly as the file `df.to_csv()` would be
//! by `leeway estimate --data`: the same header matching, units, time-step
//! checks, experiment splitting and located errors.
//!
//! The columns are borrowed from numpy without copying and written once, in
//! memory, as CSV text with the shortest round-trip form of every value
//! (`{:?}` of an f64 parses back to the same bits), which the loader parses.
//! This costs one text pass per load and keeps the runtime's validation the
//! only one; a column-oriented entry point in `runtime::data` (taking
//! `&[(&str, &[f64])]`) would remove the pass without changing a result.

use crate::failure::Failure;
use leeway_runtime::data::{FileNotes, LoadOptions, column_name, parse_csv_noted};
use leeway_runtime::{DataError, Experiment};
use leeway_structure::ir::{Ir, Rotation};

/// One frame: its name (the "file" of messages and of the experiment name
/// when it has no experiment column), float64 columns, experiment labels.
pub struct Frame<'a> {
    /// As named in messages.
    pub name: &'a str,
    /// The model's columns the frame has, by data column name.
    pub columns: Vec<(&'a str, &'a [f64])>,
    /// The experiment column, as text.
    pub experiment: Option<&'a [String]>,
}

/// The data columns a model reads (after `data { }` mapping), time first:
/// only these are handed over, so other columns of a frame (notes, labels)
/// are ignored as the CSV loader ignores them.
pub fn model_columns(ir: &Ir) -> Vec<String> {
    let mut signals: Vec<&str> = vec!["time"];
    signals.extend(ir.states.iter().map(String::as_str));
    signals.extend(ir.inputs.iter().map(String::as_str));
    match &ir.rotation {
        Rotation::Planar { heading, .. } => signals.push(heading),
        Rotation::Measured { .. } => signals.extend(ir.rotation_vars.iter().map(String::as_str)),
        Rotation::None => {}
    }
    for c in &ir.components {
        if ir.disturbances[c.disturbance].measured {
            signals.push(&c.name);
        }
    }
    let mut columns: Vec<String> = Vec::new();
    for s in signals {
        let c = column_name(ir, s);
        if !columns.contains(&c) {
            columns.push(c);
        }
    }
    columns
}

/// The frame as CSV text.
fn csv_text(ir: &Ir, frame: &Frame<'_>) -> Result<Vec<u8>, Failure> {
    let rows = frame.columns.first().map_or(0, |(_, c)| c.len());
    if let Some((name, c)) = frame.columns.iter().find(|(_, c)| c.len() != rows) {
        return Err(Failure::data_plain(
            frame.name,
            format!("column `{name}` has {} rows, the others {rows}", c.len()),
        ));
    }
    let mut writer = csv::Writer::from_writer(Vec::new());
    let experiment = frame
        .experiment
        .map(|labels| (column_name(ir, "experiment"), labels));
    let fail = |e: csv::Error| Failure::data_plain(frame.name, format!("cannot hand over: {e}"));
    let mut header: Vec<&str> = frame.columns.iter().map(|(n, _)| *n).collect();
    if let Some((name, _)) = &experiment {
        header.push(name);
    }
    writer.write_record(&header).map_err(fail)?;
    let mut record: Vec<String> = Vec::with_capacity(header.len());
    for k in 0..rows {
        record.clear();
        record.extend(frame.columns.iter().map(|(_, c)| format!("{:?}", c[k])));
        if let Some((_, labels)) = &experiment {
            record.push(labels.get(k).cloned().unwrap_or_default());
        }
        writer.write_record(&record).map_err(fail)?;
    }
    writer
        .into_inner()
        .map_err(|e| Failure::data_plain(frame.name, format!("cannot hand over: {e}")))
}

/// The loader's `file:line[:column (name)]` as the frame's row: line 1 is
/// the header, so line `l` is positional row `l − 2` (from 0, as `iloc`).
fn located(frame: &str, e: DataError) -> DataError {
    let Some(rest) = e
        .location
        .strip_prefix(frame)
        .and_then(|r| r.strip_prefix(':'))
    else {
        return e;
    };
    let mut parts = rest.splitn(2, ':');
    let line = parts.next().and_then(|l| l.parse::<u64>().ok());
    let column = parts.next().and_then(|c| {
        c.split_once(" (")
            .map(|(_, n)| n.trim_end_matches(')').to_string())
    });
    let location = match (line, column) {
        (Some(1), Some(c)) => format!("{frame}: header, column `{c}`"),
        (Some(1), None) => format!("{frame}: header"),
        (Some(l), Some(c)) => format!("{frame}: row {}, column `{c}`", l - 2),
        (Some(l), None) => format!("{frame}: row {}", l - 2),
        _ => return e,
    };
    DataError { location, ..e }
}

/// Every frame's experiments, in order, with what loading noted; the first
/// failing frame raises.
pub fn load(
    ir: &Ir,
    frames: &[Frame<'_>],
    options: &LoadOptions,
) -> Result<(Vec<Experiment>, Vec<FileNotes>), Failure> {
    let mut experiments = Vec::new();
    let mut notes = Vec::new();
    for frame in frames {
        let text = csv_text(ir, frame)?;
        let loaded = parse_csv_noted(frame.name, &text, ir, options)
            .map_err(|e| Failure::data(&located(frame.name, e)))?;
        experiments.extend(loaded.experiments);
        notes.push(loaded.notes);
    }
    Ok((experiments, notes))
}
