//! `leeway.read_log`: a robot log (a manifest of per-topic files, or a ROS 2
//! bag) joined on the model's grid by leeway-logs, the code `--data
//! log.toml` runs, handed to Python as one frame per experiment and the
//! notes of the join (the `data_files` entry of `estimate --json`).

use crate::failure::Failure;
use crate::model::Model;
use crate::options::load_options;
use leeway_data::gaps::GapLimit;
use leeway_data::write;
use numpy::PyArray1;
use pyo3::prelude::*;
use std::path::Path;

/// One experiment's columns, as `leeway_data::write` names them.
type Frame<'py> = (String, Vec<(String, Bound<'py, PyArray1<f64>>)>);

/// Reads and joins the log at `path` for `model` (`max_gap`: seconds, else
/// the default rule); the experiments as columns and the notes as JSON.
#[pyfunction]
#[pyo3(signature = (model, path, max_gap=None, keep=Vec::new()))]
pub fn read_log<'py>(
    py: Python<'py>,
    model: &Model,
    path: &str,
    max_gap: Option<f64>,
    keep: Vec<(Option<f64>, Option<f64>)>,
) -> PyResult<(Vec<Frame<'py>>, String)> {
    let ir = &model.ir;
    let options = load_options(ir, None, None, None)?;
    let options = match max_gap {
        Some(s) => options.with_max_gap(GapLimit::Seconds(s)).map_err(|_| {
            Failure::option(
                format!("max_gap={s} is not a positive number of seconds"),
                Some("give the longest hole to interpolate across, e.g. max_gap=2.0".into()),
            )
        })?,
        None => options,
    };
    for (from, to) in &keep {
        let empty = matches!((from, to), (Some(a), Some(b)) if b <= a);
        let open = from.is_none() && to.is_none();
        let finite = from.is_none_or(f64::is_finite) && to.is_none_or(f64::is_finite);
        if empty || open || !finite {
            return Err(Failure::option(
                format!("keep=({from:?}, {to:?}) is no window: give finite seconds from the log's first stamp, `from` before `to`"),
                Some("e.g. keep=[(0, 700), (850, None)]".into()),
            )
            .into());
        }
    }
    let options = leeway_data::LoadOptions { keep, ..options };
    let loaded = py
        .detach(|| leeway_logs::load_log(Path::new(path), ir, &options))
        .map_err(|e| Failure::data(&e))?;
    // Strings and numbers only: serialising cannot fail.
    let notes = serde_json::to_string(&leeway_report::data_files_json(&[loaded.notes]))
        .unwrap_or_else(|_| "[]".to_string());
    let frames = loaded
        .experiments
        .iter()
        .map(|e| {
            let columns = write::header(ir, 1)
                .into_iter()
                .zip(write::columns(ir, e, 0.0))
                .map(|(name, c)| (name, PyArray1::from_vec(py, c)))
                .collect();
            (e.name.clone(), columns)
        })
        .collect();
    Ok((frames, notes))
}
