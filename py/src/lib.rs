//! `leeway._leeway`: the native half of the Python package. It compiles
//! models, checks them and estimates from columns handed over by
//! `python/leeway` (numpy float64 arrays, read in place), and answers with the
//! same JSON documents as `leeway check --json` and `leeway estimate --json`,
//! built by the same code ([`leeway_report`]); it simulates and
//! validates with the library functions `leeway simulate` and `leeway
//! validate` call (`simulate.rs`), answering with columns and fits, and
//! analyses one-step residuals as `leeway validate --resid` does
//! (`residuals.rs`); it designs trials as `leeway design` does, answering
//! with its JSON document (`design.rs`); it selects a candidate model's
//! terms as `leeway select` does, answering with its JSON (`select.rs`).
//! The Python half turns
//! those documents into dataclasses and DataFrames and raises the exception
//! classes of `leeway.errors`, so the error hierarchy lives in one place.
//!
//! Built by maturin (pyo3, abi3-py310); the `extension-module` feature is
//! set only by maturin and the crate has no Rust tests, so `cargo test`
//! never links libpython. The stub `_leeway.pyi` is checked by
//! `mypy.stubtest`. The Python half refuses what it would otherwise coerce
//! (date-times outside the time column, durations, booleans, text, complex,
//! categories; options of the wrong type) with located `leeway.errors`, and
//! a native panic reaches Python as `internal-error`, never as
//! `PanicException` (`py/tests/test_fuzz.py`).

// As in the CLI: estimates allocate and free record-sized buffers many
// times a second, and mimalloc reuses freed pages rather than faulting
// fresh ones in (Python's own objects keep Python's allocator).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod data;
mod design;
mod distributed;
mod estimate;
mod failure;
mod logs;
mod model;
mod options;
mod residuals;
mod select;
mod simulate;
mod study;

use pyo3::prelude::*;

/// The native module.
#[pymodule]
fn _leeway(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::Model>()?;
    m.add_function(wrap_pyfunction!(estimate::estimate_json, m)?)?;
    m.add_function(wrap_pyfunction!(select::select_json, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate_columns, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::validate_fits, m)?)?;
    m.add_function(wrap_pyfunction!(residuals::residual_analysis, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<distributed::Dataset>()?;
    m.add_function(wrap_pyfunction!(distributed::estimate_mapped, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_run, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_summary, m)?)?;
    m.add_class::<design::Designed>()?;
    m.add_function(wrap_pyfunction!(logs::read_log, m)?)?;
    Ok(())
}
